//! The error type of box-trackers.

use tracker_model::Frame;

/// What can go wrong building or stepping a box tracker.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// From the shared model: a setting outside its range
    /// ([`tracker_model::Error::InvalidParameter`]), a point where a box is needed, a
    /// non-finite box or score.
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// A step names a frame at or before the previous step's.
    #[error(
        "frame {frame} is stepped after frame {previous}; a box tracker takes frames in \
         increasing order, one step each"
    )]
    FramesOutOfOrder {
        /// The frame stepped.
        frame: Frame,
        /// The previous step's frame.
        previous: Frame,
    },
}

/// The crate's result.
pub type Result<T> = std::result::Result<T, Error>;
