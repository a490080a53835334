//! 8-bit grey and RGB frames: row-major, channels interleaved, no padding.

use crate::error::{Error, Result};

/// Channel layout of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PixelFormat {
    /// One 8-bit luma channel.
    Grey,
    /// Three 8-bit channels, red, green, blue.
    Rgb,
}

impl PixelFormat {
    /// Channels per pixel.
    pub fn channels(self) -> usize {
        match self {
            Self::Grey => 1,
            Self::Rgb => 3,
        }
    }
}

/// One video frame. Invariant: width, height ≥ 1 and `data.len() = width·height·channels`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VideoFrame {
    width: usize,
    height: usize,
    format: PixelFormat,
    data: Vec<u8>,
}

impl VideoFrame {
    /// A frame from its pixels (row-major, channels interleaved).
    pub fn new(width: usize, height: usize, format: PixelFormat, data: Vec<u8>) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::ZeroSize { width, height });
        }
        let expected = width * height * format.channels();
        if data.len() != expected {
            return Err(Error::BufferSize {
                len: data.len(),
                expected,
                width,
                height,
                channels: format.channels(),
            });
        }
        Ok(Self {
            width,
            height,
            format,
            data,
        })
    }

    /// A frame filled with one value in every channel.
    pub fn filled(width: usize, height: usize, format: PixelFormat, value: u8) -> Result<Self> {
        Self::new(
            width,
            height,
            format,
            vec![value; width * height * format.channels()],
        )
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Channel layout.
    pub fn format(&self) -> PixelFormat {
        self.format
    }

    /// Channels per pixel.
    pub fn channels(&self) -> usize {
        self.format.channels()
    }

    /// The pixels.
    pub fn data(&self) -> &[u8] {
        &self.data
    }

    /// The pixels, mutable.
    pub fn data_mut(&mut self) -> &mut [u8] {
        &mut self.data
    }

    /// Consumes the frame into its pixels.
    pub fn into_data(self) -> Vec<u8> {
        self.data
    }

    /// The channels of pixel (x, y).
    pub fn pixel(&self, x: usize, y: usize) -> &[u8] {
        let c = self.channels();
        let i = (y * self.width + x) * c;
        &self.data[i..i + c]
    }

    /// A grey copy: luma Y = 0.299 R + 0.587 G + 0.114 B (ITU-R BT.601), rounded.
    pub fn to_grey(&self) -> Self {
        match self.format {
            PixelFormat::Grey => self.clone(),
            PixelFormat::Rgb => Self {
                width: self.width,
                height: self.height,
                format: PixelFormat::Grey,
                data: self
                    .data
                    .chunks_exact(3)
                    .map(|p| {
                        (0.299 * f32::from(p[0])
                            + 0.587 * f32::from(p[1])
                            + 0.114 * f32::from(p[2]))
                        .round() as u8
                    })
                    .collect(),
            },
        }
    }
}

/// Checks that every frame has the first one's size and format.
pub fn check_sequence(frames: &[VideoFrame]) -> Result<()> {
    let Some(first) = frames.first() else {
        return Ok(());
    };
    for (index, f) in frames.iter().enumerate() {
        if f.width != first.width || f.height != first.height || f.format != first.format {
            return Err(Error::FrameChanged {
                index,
                width: f.width,
                height: f.height,
                channels: f.channels(),
                expected_width: first.width,
                expected_height: first.height,
                expected_channels: first.channels(),
            });
        }
    }
    Ok(())
}
