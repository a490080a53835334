//! The error type of phd-filter.

/// What can go wrong configuring or running a PHD filter. Degenerate boxes are data, not
/// errors: a step skips and counts them.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model (parameter ranges, covariances, tracks).
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// A configuration value outside its range, or two values that do not fit together.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// The parameter's name as it appears in the configuration.
        name: &'static str,
        /// What is wrong with it, including the value.
        reason: String,
    },
    /// [`PhdConfig::for_boxes`](crate::PhdConfig::for_boxes) was given no boxes to scale to.
    #[error("a configuration scaled to boxes needs at least one box")]
    NoBoxes,
}

/// Result with phd-filter's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
