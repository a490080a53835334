//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in a DMTIM run.
#[derive(Debug, Error)]
pub enum Error {
    /// A parameter or shared check from tracker-model: a configuration value outside its
    /// range is [`tracker_model::Error::InvalidParameter`].
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// The per-sensor tracker failed.
    #[error("sensor {sensor}: tracker: {source}")]
    Tracker {
        /// The sensor's index.
        sensor: usize,
        /// What MCMCDA reported.
        source: mcmcda::Error,
    },
    /// An identity update failed where no recovery rule applies.
    #[error("sensor {sensor}: identity management: {source}")]
    Identity {
        /// The sensor's index.
        sensor: usize,
        /// What identity-mgmt reported.
        source: identity_mgmt::Error,
    },
}

/// Result with this crate's [`enum@Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// A configuration value outside its range, as tracker-model's parameter checks report it.
pub(crate) fn invalid(name: &'static str, reason: String) -> Error {
    Error::Model(tracker_model::Error::InvalidParameter { name, reason })
}
