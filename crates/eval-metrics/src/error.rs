//! The error type of eval-metrics.

use std::fmt;

/// Which side of an evaluation an input comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The ground truth.
    Truth,
    /// The tracker's estimates.
    Estimate,
}

impl fmt::Display for Side {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Side::Truth => "truth",
            Side::Estimate => "estimate",
        })
    }
}

/// What can go wrong when scoring.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model (bad boxes, tracks, parsing), and a parameter outside
    /// its valid range ([`tracker_model::Error::InvalidParameter`]).
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// IoU similarity on a point: IoU needs boxes on both sides.
    #[error(
        "IoU similarity needs boxes, but the {side} contains a point; use a distance similarity"
    )]
    IouNeedsBoxes {
        /// The side with the point.
        side: Side,
    },
    /// Two inputs that must have the same length do not.
    #[error("{what}: expected {expected}, got {got}")]
    LengthMismatch {
        /// What was counted, e.g. "MAE estimates (one per truth point)".
        what: &'static str,
        /// The length the other input implies.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A scan whose labels do not match its measurements one to one.
    #[error("scan {scan} has {n_measurements} measurements but {n_labels} labels")]
    ScanLabelsMismatch {
        /// The scan's index.
        scan: usize,
        /// Its measurements.
        n_measurements: usize,
        /// The labels given for it.
        n_labels: usize,
    },
}

/// Result with eval-metrics' [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A parameter outside its valid range, as tracker-model's parameter checks report it.
pub(crate) fn invalid_parameter(name: &'static str, reason: String) -> Error {
    Error::Model(tracker_model::Error::InvalidParameter { name, reason })
}
