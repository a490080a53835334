//! The one error type of sensors-video.

use std::path::PathBuf;

/// Everything that can go wrong in sensors-video. Messages name the offending file, frame,
/// size or value.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A parameter or shared type from tracker-model was rejected.
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// A frame with no pixels.
    #[error("frame has zero size ({width} x {height})")]
    ZeroSize {
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
    /// A pixel buffer whose length does not match width · height · channels.
    #[error(
        "pixel buffer has {len} bytes, expected {expected} for {width} x {height} x {channels}"
    )]
    BufferSize {
        /// Bytes given.
        len: usize,
        /// Bytes expected.
        expected: usize,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// Channels per pixel.
        channels: usize,
    },
    /// A frame whose size or channel count differs from the sequence's first frame.
    #[error(
        "frame {index} is {width} x {height} x {channels}, but the sequence is {expected_width} x {expected_height} x {expected_channels}"
    )]
    FrameChanged {
        /// 0-based index of the offending frame.
        index: usize,
        /// Its width.
        width: usize,
        /// Its height.
        height: usize,
        /// Its channel count.
        channels: usize,
        /// The sequence's width.
        expected_width: usize,
        /// The sequence's height.
        expected_height: usize,
        /// The sequence's channel count.
        expected_channels: usize,
    },
    /// A pixel format this crate does not read (only 8-bit grey and 8-bit RGB / YUV).
    #[error("unsupported pixel format {format} in {source_name}")]
    UnsupportedPixelFormat {
        /// The format found, e.g. "Rgba8" or "C420p10".
        format: String,
        /// The file or stream.
        source_name: String,
    },
    /// A file that ends in the middle of a frame.
    #[error("{source_name} is truncated: frame {frame} is incomplete")]
    Truncated {
        /// The file or stream.
        source_name: String,
        /// 0-based index of the incomplete frame.
        frame: usize,
    },
    /// A malformed YUV4MPEG2 stream.
    #[error("malformed YUV4MPEG2 stream {source_name}: {reason}")]
    Y4m {
        /// The file or stream.
        source_name: String,
        /// What the decoder reported.
        reason: String,
    },
    /// An image file that could not be decoded or encoded.
    #[error("image {path}: {reason}")]
    Image {
        /// The file.
        path: PathBuf,
        /// What the image crate reported.
        reason: String,
    },
    /// An image sequence folder with no readable frames.
    #[error("no PNG/PGM/PPM frames in {path}")]
    EmptySequence {
        /// The folder.
        path: PathBuf,
    },
    /// An I/O failure.
    #[error("I/O error on {path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A frame whose size or channel count does not match the model it is fed to.
    #[error(
        "frame is {width} x {height} x {channels}, the model expects {expected_width} x {expected_height} x {expected_channels}"
    )]
    FrameMismatch {
        /// The frame's width.
        width: usize,
        /// The frame's height.
        height: usize,
        /// The frame's channels.
        channels: usize,
        /// The model's width.
        expected_width: usize,
        /// The model's height.
        expected_height: usize,
        /// The model's channels.
        expected_channels: usize,
    },
}

/// Result with this crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;
