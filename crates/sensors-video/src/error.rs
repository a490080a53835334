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
    #[error(
        "unsupported pixel format {format} in {source_name}: only 8-bit grey or RGB (YUV 4:2:0, \
         4:4:4 or mono in y4m) is read; convert it, e.g. `ffmpeg -i IN -pix_fmt rgb24 OUT.png` \
         (drops alpha, 16 to 8 bits) or `ffmpeg -i IN -pix_fmt yuv420p OUT.y4m`"
    )]
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
        /// The incomplete frame: its 0-based index in a stream, its frame number in a folder.
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
    #[error("frame folder {} holds no .png, .pgm, .ppm or .jpg image", path.display())]
    EmptySequence {
        /// The folder.
        path: PathBuf,
    },
    /// An image of a frame folder whose file name has no digits to take the frame number from,
    /// or a number too large for a frame.
    #[error("image {path} has no frame number (digits) in its file name")]
    NoFrameNumber {
        /// The file.
        path: PathBuf,
    },
    /// Two images of a frame folder with the same frame number (`1.png` and `001.png`).
    #[error("images {} and {} both have frame number {frame}", paths[0].display(), paths[1].display())]
    DuplicateFrame {
        /// The frame number.
        frame: u32,
        /// The two files.
        paths: [PathBuf; 2],
    },
    /// An image of a frame folder whose size differs from the first image's.
    #[error("image {} is {} x {}, but the folder's first image is {} x {}", path.display(), size.0, size.1, expected.0, expected.1)]
    SizeMismatch {
        /// The image.
        path: PathBuf,
        /// Its size (width, height).
        size: (u32, u32),
        /// The first image's size.
        expected: (u32, u32),
    },
    /// A frame asked of a folder that has no image of it.
    #[error("frame folder {} has no image of frame {frame}", dir.display())]
    NoSuchFrame {
        /// The frame.
        frame: u32,
        /// The folder.
        dir: PathBuf,
    },
    /// An I/O failure.
    #[error("I/O error on {path}: {error}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error (in the message, so not also a source: a chain printer such as
        /// anyhow's `{:#}` would repeat it).
        error: std::io::Error,
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
