//! The one error type of image-detector.

/// Everything that can go wrong in image-detector. Messages name the offending value.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A parameter or shared type from tracker-model was rejected.
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// A plane whose buffer does not match its size.
    #[error(
        "plane buffer has {len} values, expected {expected} for {width} x {height} x {channels}"
    )]
    BufferSize {
        /// Values given.
        len: usize,
        /// Values expected.
        expected: usize,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// Channels per pixel.
        channels: usize,
    },
    /// An image too small for one HOG block, or with an unsupported channel count.
    #[error("image of {width} x {height} x {channels} is not usable: {reason}")]
    BadImage {
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// Channels per pixel.
        channels: usize,
        /// Why.
        reason: &'static str,
    },
    /// `detect_all` / `confirm_all` given a different number of boxes than detectors.
    #[error("{detectors} detectors but {boxes} boxes: one box per detector")]
    BoxCount {
        /// Detectors given.
        detectors: usize,
        /// Boxes given.
        boxes: usize,
    },
}

/// Result with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
