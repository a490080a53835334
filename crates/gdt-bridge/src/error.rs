//! The error type of gdt-bridge.

/// What can go wrong recovering a gap.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model (covariances, Kalman filtering).
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// Inputs whose sizes or times do not fit together.
    #[error("invalid input: {0}")]
    Invalid(String),
}

/// Result with gdt-bridge's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
