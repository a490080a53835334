//! The error type of mcmcda.

/// What can go wrong setting up or running data association.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model (covariances, parameters, Kalman filtering).
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// Inputs that do not fit together (frames out of order, wrong lengths, bad partitions).
    #[error("invalid input: {0}")]
    Invalid(String),
}

/// Result with mcmcda's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
