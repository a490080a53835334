//! The error type of phd-filter.

/// What can go wrong configuring or running a PHD filter.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model.
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// A parameter outside its range, or inputs that do not fit together.
    #[error("invalid input: {0}")]
    Invalid(String),
}

/// Result with phd-filter's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
