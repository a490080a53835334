//! The error type of air-traffic.

/// What can go wrong reading traffic or simulating a radar.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A parameter outside its range, a non-finite value.
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// A tracker failed (a bad configuration, a dwell out of order).
    #[error(transparent)]
    Tracker(#[from] mcmcda::Error),
    /// The collection is not the JSON the `traffic` package writes.
    #[error("ADS-B collection: {0}")]
    Collection(String),
}

/// Result with this crate's error.
pub type Result<T> = std::result::Result<T, Error>;
