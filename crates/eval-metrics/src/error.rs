//! The error type of eval-metrics.

/// What can go wrong when scoring.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model (bad boxes, tracks, parsing).
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// A parameter outside its valid range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// What is wrong, with the value.
        reason: String,
    },
    /// Inputs that cannot be compared (different lengths, boxes against points with IoU, ...).
    #[error("incompatible inputs: {0}")]
    Incompatible(String),
}

/// Result with eval-metrics' [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
