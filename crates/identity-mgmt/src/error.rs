//! The one error type of identity-mgmt.

use tracker_model::TrackId;

use crate::belief::IdentityId;

/// What can go wrong building or updating a belief matrix. Every variant carries the
/// offending values so that a caller can fix the input without reading the source.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model; every configuration parameter of this crate is
    /// reported as [`tracker_model::Error::InvalidParameter`].
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// An input has the wrong number of entries.
    #[error("{what} has {got} entries, expected {expected}")]
    Shape {
        /// Which input.
        what: &'static str,
        /// The number of entries required.
        expected: usize,
        /// The number of entries given.
        got: usize,
    },
    /// A matrix or vector entry is negative or not finite.
    #[error("{what} entry ({row}, {col}) = {value} must be finite and ≥ 0")]
    InvalidEntry {
        /// Which input.
        what: &'static str,
        /// Row (or vector index).
        row: usize,
        /// Column (0 for a vector).
        col: usize,
        /// The entry.
        value: f64,
    },
    /// A vector that must be a probability vector does not sum to 1.
    #[error("{what} sums to {sum}, not 1")]
    NotProbability {
        /// Which vector, e.g. "local information".
        what: &'static str,
        /// Its sum.
        sum: f64,
    },
    /// A matrix that must be doubly stochastic is not.
    #[error("{what} is not doubly stochastic: a row or column sum is off by {max_error}")]
    NotDoublyStochastic {
        /// Which matrix.
        what: &'static str,
        /// The largest deviation of a row or column sum from 1.
        max_error: f64,
    },
    /// A track that the belief matrix does not hold.
    #[error("unknown track {track:?}")]
    UnknownTrack {
        /// The track asked for.
        track: TrackId,
    },
    /// An identity that the belief matrix does not know.
    #[error("unknown identity {identity}")]
    UnknownIdentity {
        /// The identity asked for.
        identity: IdentityId,
    },
    /// A track id that is already held.
    #[error("track {track:?} is already held")]
    DuplicateTrack {
        /// The repeated id.
        track: TrackId,
    },
    /// An identity id that is already known.
    #[error("identity {identity} is already known")]
    DuplicateIdentity {
        /// The repeated id.
        identity: IdentityId,
    },
    /// Row and column targets of a scaling problem have different totals.
    #[error("row targets total {row_total} but column targets total {col_total}")]
    MarginalMismatch {
        /// Σ row targets.
        row_total: f64,
        /// Σ column targets.
        col_total: f64,
    },
    /// No matrix with the zero pattern of the input meets the targets (no perfect matching of
    /// the positive entries, or a maximum flow short of the total mass).
    #[error(
        "not scalable: the positive entries can carry only {carried} of the required mass \
         {required}"
    )]
    NotScalable {
        /// The largest mass the positive pattern can carry (the matched rows in the square
        /// case, the maximum flow otherwise).
        carried: f64,
        /// The mass the targets require.
        required: f64,
    },
    /// Two distributions to fuse share no identity with positive probability.
    #[error("the two beliefs to fuse have disjoint supports")]
    DisjointSupports,
    /// A sample joins a track piece that does not exist or joins a piece twice.
    #[error("MCMC sample {sample}: {reason}")]
    BadSample {
        /// Index of the sample.
        sample: usize,
        /// What is wrong with it.
        reason: String,
    },
}

/// Result with identity-mgmt's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
