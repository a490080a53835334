//! Frame I/O: folders of PNG/PGM/PPM images (through the `image` crate) and YUV4MPEG2 streams
//! (through the `y4m` crate), so that any video converts with
//! `ffmpeg -i in.mp4 -pix_fmt yuv420p -f yuv4mpegpipe -`.
//!
//! Colour in y4m is Y'CbCr with BT.601 full-range coefficients (what ffmpeg writes for
//! `yuvj*` and what most y4m tools assume); chroma planes of 4:2:0 and 4:2:2 streams are
//! upsampled by pixel replication. `Cmono` streams read as grey frames, every other 8-bit
//! stream as RGB; 10- and 12-bit streams are an [`Error::UnsupportedPixelFormat`].

use std::cell::Cell;
use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::rc::Rc;

use crate::error::{Error, Result};
use crate::frame::{PixelFormat, VideoFrame, check_sequence};

fn image_err(path: &Path, e: &image::ImageError) -> Error {
    Error::Image {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

/// Reads one PNG/PGM/PPM file as an 8-bit grey or RGB frame; any other pixel format (16-bit,
/// alpha) is an [`Error::UnsupportedPixelFormat`], never silently converted.
pub fn read_image(path: &Path) -> Result<VideoFrame> {
    let bytes = std::fs::read(path).map_err(|error| Error::Io {
        path: path.to_path_buf(),
        error,
    })?;
    decode_image(&bytes, path)
}

/// Decodes one PNG/PGM/PPM image held in memory (the format is guessed from its first bytes);
/// `source` labels errors. Decoding keeps the `image` crate's default limits (512 MiB per
/// allocation), so a header that claims an enormous size is an error, not an allocation.
pub fn decode_image(bytes: &[u8], source: &Path) -> Result<VideoFrame> {
    let truncated = || Error::Truncated {
        source_name: source.display().to_string(),
        frame: 0,
    };
    let img = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|error| Error::Io {
            path: source.to_path_buf(),
            error,
        })?
        .decode()
        .map_err(|e| match &e {
            image::ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
                truncated()
            }
            image::ImageError::Decoding(d) if d.to_string().contains("unexpected end of file") => {
                truncated()
            }
            _ => image_err(source, &e),
        })?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    match img {
        image::DynamicImage::ImageLuma8(b) => {
            VideoFrame::new(w, h, PixelFormat::Grey, b.into_raw())
        }
        image::DynamicImage::ImageRgb8(b) => VideoFrame::new(w, h, PixelFormat::Rgb, b.into_raw()),
        other => Err(Error::UnsupportedPixelFormat {
            format: format!("{:?}", other.color()),
            source_name: source.display().to_string(),
        }),
    }
}

/// Writes a frame; the format follows the extension (`.png`, `.pgm`, `.ppm`).
pub fn write_image(frame: &VideoFrame, path: &Path) -> Result<()> {
    let colour = match frame.format() {
        PixelFormat::Grey => image::ExtendedColorType::L8,
        PixelFormat::Rgb => image::ExtendedColorType::Rgb8,
    };
    image::save_buffer(
        path,
        frame.data(),
        frame.width() as u32,
        frame.height() as u32,
        colour,
    )
    .map_err(|e| image_err(path, &e))
}

/// Reads every image of a folder ([`FrameFolder`]) in frame-number order. All frames must
/// share the first one's size and format ([`Error::SizeMismatch`], [`Error::FrameChanged`]).
pub fn read_image_sequence(dir: &Path) -> Result<Vec<VideoFrame>> {
    let folder = FrameFolder::open(dir)?;
    let frames = folder
        .frames()
        .map(|f| folder.load(f))
        .collect::<Result<Vec<_>>>()?;
    check_sequence(&frames)?;
    Ok(frames)
}

/// A folder of frames, the one frame-folder reader: the image of each frame number (the last
/// run of digits of the file name, so MOTChallenge's `img1/000001.png` is frame 1), checked
/// for equal sizes from the headers alone and decoded one at a time by [`FrameFolder::load`],
/// so memory does not grow with the folder. PNG, PGM and PPM decode; a `.jpg` is listed so that
/// its error says to convert it (the workspace builds `image` without JPEG).
#[derive(Debug, Clone)]
pub struct FrameFolder {
    dir: PathBuf,
    frames: BTreeMap<u32, PathBuf>,
    size: (u32, u32),
}

/// The extensions listed (lower case).
const FOLDER_EXTENSIONS: [&str; 5] = ["png", "pgm", "ppm", "jpg", "jpeg"];

/// The frame number of a file: the last run of ASCII digits of its stem.
pub(crate) fn frame_number(path: &Path) -> Option<u32> {
    let stem = path.file_stem()?.to_str()?;
    let end = stem.rfind(|c: char| c.is_ascii_digit())? + 1;
    let start = stem[..end]
        .rfind(|c: char| !c.is_ascii_digit())
        .map_or(0, |i| i + 1);
    stem[start..end].parse().ok()
}

fn is_jpeg(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "jpg" | "jpeg"))
}

/// An image error with a hint for JPEG files (not built in).
fn folder_image_err(path: &Path, reason: String) -> Error {
    let reason = if is_jpeg(path) {
        format!(
            "{reason}; JPEG is not built into this tool (the image crate has PNG and PNM \
             only): convert the folder to PNG, e.g. `mogrify -format png *.jpg`"
        )
    } else {
        reason
    };
    Error::Image {
        path: path.to_path_buf(),
        reason,
    }
}

/// An image's size from its header alone.
fn header_size(path: &Path) -> Result<(u32, u32)> {
    let err = |e: &dyn std::fmt::Display| folder_image_err(path, e.to_string());
    image::ImageReader::open(path)
        .map_err(|e| err(&e))?
        .with_guessed_format()
        .map_err(|e| err(&e))?
        .into_dimensions()
        .map_err(|e| err(&e))
}

impl FrameFolder {
    /// Lists `dir`'s images by frame number and reads each one's header (not its pixels) to
    /// check that all have the first one's size.
    pub fn open(dir: &Path) -> Result<Self> {
        let io = |error| Error::Io {
            path: dir.to_path_buf(),
            error,
        };
        let mut frames: BTreeMap<u32, PathBuf> = BTreeMap::new();
        for entry in std::fs::read_dir(dir).map_err(io)? {
            let path = entry.map_err(io)?.path();
            let wanted = path
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| FOLDER_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()));
            if !wanted || !path.is_file() {
                continue;
            }
            let frame =
                frame_number(&path).ok_or_else(|| Error::NoFrameNumber { path: path.clone() })?;
            if let Some(other) = frames.insert(frame, path.clone()) {
                let mut paths = [other, path];
                paths.sort();
                return Err(Error::DuplicateFrame { frame, paths });
            }
        }
        let mut size = None;
        for path in frames.values() {
            let this = header_size(path)?;
            match size {
                None => size = Some(this),
                Some(expected) if expected != this => {
                    return Err(Error::SizeMismatch {
                        path: path.clone(),
                        size: this,
                        expected,
                    });
                }
                Some(_) => {}
            }
        }
        let Some(size) = size else {
            return Err(Error::EmptySequence {
                path: dir.to_path_buf(),
            });
        };
        Ok(Self {
            dir: dir.to_path_buf(),
            frames,
            size,
        })
    }

    /// The folder with its frames renumbered so that the first image is frame `first` (the
    /// others keep their distance from it): for names that count from 0 against detections
    /// that count from 1, or names that are not frame numbers at all.
    pub fn renumbered(mut self, first: u32) -> Result<Self> {
        let (Some(&lo), Some(&hi)) = (self.frames.keys().next(), self.frames.keys().last()) else {
            return Ok(self);
        };
        let shift = i64::from(first) - i64::from(lo);
        if i64::from(hi) + shift > i64::from(u32::MAX) {
            return Err(tracker_model::Error::InvalidParameter {
                name: "first_frame",
                reason: format!(
                    "{first} takes the last image (frame {hi}) past frame number {}",
                    u32::MAX
                ),
            }
            .into());
        }
        self.frames = std::mem::take(&mut self.frames)
            .into_iter()
            .map(|(frame, path)| ((i64::from(frame) + shift) as u32, path))
            .collect();
        Ok(self)
    }

    /// [`FrameFolder::open`], then [`FrameFolder::renumbered`] from `first` when given.
    pub fn open_numbered(dir: &Path, first: Option<u32>) -> Result<Self> {
        let folder = Self::open(dir)?;
        match first {
            Some(first) => folder.renumbered(first),
            None => Ok(folder),
        }
    }

    /// The first frame number, if there is an image.
    pub fn first(&self) -> Option<u32> {
        self.frames.keys().next().copied()
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The frame numbers, in order.
    pub fn frames(&self) -> impl Iterator<Item = u32> + '_ {
        self.frames.keys().copied()
    }

    /// Whether the folder has an image of `frame`.
    pub fn contains(&self, frame: u32) -> bool {
        self.frames.contains_key(&frame)
    }

    /// The number of images.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether the folder has no image (never, for a folder [`FrameFolder::open`] returned).
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The images' size (width, height).
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Decodes the image of `frame`; [`Error::NoSuchFrame`] when the folder has none.
    pub fn load(&self, frame: u32) -> Result<VideoFrame> {
        let path = self.frames.get(&frame).ok_or_else(|| Error::NoSuchFrame {
            frame,
            dir: self.dir.clone(),
        })?;
        let bytes = std::fs::read(path).map_err(|error| Error::Io {
            path: path.clone(),
            error,
        })?;
        let decoded = decode_image(&bytes, path).map_err(|e| match e {
            Error::Image { path, reason } => folder_image_err(&path, reason),
            // A lone image is frame 0 of itself; in a folder it is the frame it is named for.
            Error::Truncated { source_name, .. } => Error::Truncated {
                source_name,
                frame: frame as usize,
            },
            other => other,
        })?;
        let size = (decoded.width(), decoded.height());
        if size != (self.size.0 as usize, self.size.1 as usize) {
            // The file changed since `open` read its header.
            return Err(Error::SizeMismatch {
                path: path.clone(),
                size: (size.0 as u32, size.1 as u32),
                expected: self.size,
            });
        }
        Ok(decoded)
    }
}

/// Writes frames as `prefix000000.ext`, `prefix000001.ext`, … in `dir`.
pub fn write_image_sequence(
    frames: &[VideoFrame],
    dir: &Path,
    prefix: &str,
    ext: &str,
) -> Result<()> {
    check_sequence(frames)?;
    for (i, f) in frames.iter().enumerate() {
        write_image(f, &dir.join(format!("{prefix}{i:06}.{ext}")))?;
    }
    Ok(())
}

/// Counts the bytes that pass, so that a stream ending inside a frame (which the `y4m` crate
/// reports as a plain end of file) can be told from one ending between frames.
struct CountingReader<R> {
    inner: R,
    count: Rc<Cell<u64>>,
}

impl<R: Read> Read for CountingReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.count.set(self.count.get() + n as u64);
        Ok(n)
    }
}

/// BT.601 full-range Y'CbCr → RGB, rounded and clamped.
fn ycbcr_to_rgb(y: u8, cb: u8, cr: u8) -> [u8; 3] {
    let (y, cb, cr) = (f32::from(y), f32::from(cb) - 128.0, f32::from(cr) - 128.0);
    let c = |v: f32| v.round().clamp(0.0, 255.0) as u8;
    [
        c(y + 1.402 * cr),
        c(y - 0.344_136 * cb - 0.714_136 * cr),
        c(y + 1.772 * cb),
    ]
}

/// RGB → BT.601 full-range Y'CbCr, rounded and clamped.
fn rgb_to_ycbcr(p: &[u8]) -> [u8; 3] {
    let (r, g, b) = (f32::from(p[0]), f32::from(p[1]), f32::from(p[2]));
    let c = |v: f32| v.round().clamp(0.0, 255.0) as u8;
    let y = 0.299 * r + 0.587 * g + 0.114 * b;
    [c(y), c(128.0 + (b - y) / 1.772), c(128.0 + (r - y) / 1.402)]
}

/// The largest frame side a y4m header may declare (8K video is 7680 wide): the `y4m` crate
/// multiplies the declared sizes without overflow checks before its own limits apply.
const MAX_Y4M_SIDE: usize = 32_768;

/// Reads the stream header (up to its newline) and checks every declared width and height
/// (`W…`, `H…`; the last of each counts) before the `y4m` crate sees them. Returns the header
/// bytes and the reader positioned after them.
fn checked_y4m_header<R: Read>(mut reader: R, source_name: &str) -> Result<(Vec<u8>, R)> {
    const MAX_HEADER: usize = 4096;
    let mut header = Vec::new();
    let mut byte = [0_u8; 1];
    while header.len() < MAX_HEADER {
        match reader.read(&mut byte) {
            Ok(0) => break,
            Ok(_) => {
                header.push(byte[0]);
                if byte[0] == b'\n' {
                    break;
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => {
                return Err(Error::Y4m {
                    source_name: source_name.to_string(),
                    reason: e.to_string(),
                });
            }
        }
    }
    if header.len() == MAX_HEADER && header.last() != Some(&b'\n') {
        return Err(Error::Y4m {
            source_name: source_name.to_string(),
            reason: format!("the stream header is longer than {MAX_HEADER} bytes"),
        });
    }
    for token in header.split(|b| b.is_ascii_whitespace()).skip(1) {
        let (Some(&tag), Some(value)) = (token.first(), token.get(1..)) else {
            continue;
        };
        if tag != b'W' && tag != b'H' {
            continue;
        }
        let side = std::str::from_utf8(value)
            .ok()
            .and_then(|v| v.parse::<usize>().ok());
        if side.is_none_or(|v| v > MAX_Y4M_SIDE) {
            return Err(Error::Y4m {
                source_name: source_name.to_string(),
                reason: format!(
                    "the header declares {}{}: frame sides must be whole numbers of at most \
                     {MAX_Y4M_SIDE} pixels",
                    char::from(tag),
                    String::from_utf8_lossy(value)
                ),
            });
        }
    }
    Ok((header, reader))
}

/// Reads a whole YUV4MPEG2 stream. `source_name` labels errors.
pub fn read_y4m<R: Read>(reader: R, source_name: &str) -> Result<Vec<VideoFrame>> {
    let count = Rc::new(Cell::new(0));
    let counting = CountingReader {
        inner: reader,
        count: Rc::clone(&count),
    };
    let y4m_err = |e: &y4m::Error| Error::Y4m {
        source_name: source_name.to_string(),
        reason: e.to_string(),
    };
    let (header, rest) = checked_y4m_header(counting, source_name)?;
    let mut dec = match y4m::decode(std::io::Cursor::new(header).chain(rest)) {
        Ok(d) => d,
        Err(y4m::Error::EOF) => {
            return Err(Error::Truncated {
                source_name: source_name.to_string(),
                frame: 0,
            });
        }
        Err(e) => return Err(y4m_err(&e)),
    };
    let (w, h) = (dec.get_width(), dec.get_height());
    if w == 0 || h == 0 {
        return Err(Error::ZeroSize {
            width: w,
            height: h,
        });
    }
    let cs = dec.get_colorspace();
    // Chroma subsampling as (horizontal, vertical) shifts.
    let (sx, sy, grey) = match cs {
        y4m::Colorspace::Cmono => (0, 0, true),
        y4m::Colorspace::C420
        | y4m::Colorspace::C420jpeg
        | y4m::Colorspace::C420paldv
        | y4m::Colorspace::C420mpeg2 => (1, 1, false),
        y4m::Colorspace::C422 => (1, 0, false),
        y4m::Colorspace::C444 => (0, 0, false),
        other => {
            return Err(Error::UnsupportedPixelFormat {
                format: format!("{other:?}"),
                source_name: source_name.to_string(),
            });
        }
    };
    let cw = (w + (1 << sx) - 1) >> sx;
    let mut frames = Vec::new();
    loop {
        let before = count.get();
        let f = match dec.read_frame() {
            Ok(f) => f,
            Err(y4m::Error::EOF) if count.get() == before => break,
            Err(y4m::Error::EOF) => {
                return Err(Error::Truncated {
                    source_name: source_name.to_string(),
                    frame: frames.len(),
                });
            }
            Err(e) => return Err(y4m_err(&e)),
        };
        let yp = f.get_y_plane();
        let frame = if grey {
            VideoFrame::new(w, h, PixelFormat::Grey, yp.to_vec())?
        } else {
            let (up, vp) = (f.get_u_plane(), f.get_v_plane());
            let mut data = Vec::with_capacity(w * h * 3);
            for y in 0..h {
                for x in 0..w {
                    let ci = (y >> sy) * cw + (x >> sx);
                    data.extend_from_slice(&ycbcr_to_rgb(yp[y * w + x], up[ci], vp[ci]));
                }
            }
            VideoFrame::new(w, h, PixelFormat::Rgb, data)?
        };
        frames.push(frame);
    }
    Ok(frames)
}

/// Writes frames as YUV4MPEG2 at `fps` frames per second: grey frames as `Cmono`, RGB frames as
/// `C444` (BT.601 full range; a round trip moves a channel by at most 2 levels).
pub fn write_y4m<W: Write>(
    frames: &[VideoFrame],
    fps: usize,
    writer: W,
    source_name: &str,
) -> Result<()> {
    check_sequence(frames)?;
    let Some(first) = frames.first() else {
        return Err(Error::Y4m {
            source_name: source_name.to_string(),
            reason: "no frames to write".to_string(),
        });
    };
    let y4m_err = |e: &y4m::Error| Error::Y4m {
        source_name: source_name.to_string(),
        reason: e.to_string(),
    };
    let cs = match first.format() {
        PixelFormat::Grey => y4m::Colorspace::Cmono,
        PixelFormat::Rgb => y4m::Colorspace::C444,
    };
    let mut enc = y4m::encode(
        first.width(),
        first.height(),
        y4m::Ratio::new(fps.max(1), 1),
    )
    .with_colorspace(cs)
    .write_header(writer)
    .map_err(|e| y4m_err(&e))?;
    let empty: &[u8] = &[];
    for f in frames {
        match f.format() {
            PixelFormat::Grey => enc.write_frame(&y4m::Frame::new([f.data(), empty, empty], None)),
            PixelFormat::Rgb => {
                let n = f.width() * f.height();
                let mut planes = vec![0u8; 3 * n];
                for (i, p) in f.data().chunks_exact(3).enumerate() {
                    let [y, u, v] = rgb_to_ycbcr(p);
                    planes[i] = y;
                    planes[n + i] = u;
                    planes[2 * n + i] = v;
                }
                enc.write_frame(&y4m::Frame::new(
                    [&planes[..n], &planes[n..2 * n], &planes[2 * n..]],
                    None,
                ))
            }
        }
        .map_err(|e| y4m_err(&e))?;
    }
    Ok(())
}
