//! The error type of phd-filter.

/// What can go wrong configuring or running a PHD filter. Degenerate boxes are data, not
/// errors: a step skips and counts them.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model (covariances, tracks), and a configuration value outside
    /// its range or two values that do not fit together
    /// ([`tracker_model::Error::InvalidParameter`]).
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// [`PhdConfig::for_boxes`](crate::PhdConfig::for_boxes) was given no boxes to scale to.
    #[error("a configuration scaled to boxes needs at least one box")]
    NoBoxes,
}

/// Result with phd-filter's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A configuration value outside its range, or two values that do not fit together, as
/// tracker-model's parameter checks report it.
pub(crate) fn invalid_parameter(name: &'static str, reason: String) -> Error {
    Error::Model(tracker_model::Error::InvalidParameter { name, reason })
}
