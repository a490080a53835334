//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in a DMTIM run.
#[derive(Debug, Error)]
pub enum Error {
    /// A parameter or shared check from tracker-model.
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
    /// A configuration value is invalid.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// The field.
        name: &'static str,
        /// Why.
        reason: String,
    },
}

/// Result with this crate's [`enum@Error`].
pub type Result<T> = std::result::Result<T, Error>;

pub(crate) fn invalid(name: &'static str, reason: String) -> Error {
    Error::InvalidParameter { name, reason }
}
