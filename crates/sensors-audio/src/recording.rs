//! Multichannel audio: owned recordings, borrowed frames, and WAV reading and writing.

use std::io::{Read, Seek, Write};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A multichannel recording: one `f32` vector per microphone, all the same length, sampled at
/// `sample_rate_hz`; sample 0 was taken at `start_s` seconds of the sensor's clock (map it to
/// tracker frames with a [`tracker_model::FrameClock`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Recording {
    /// Samples per second per channel.
    pub sample_rate_hz: u32,
    /// Time of sample 0, seconds.
    pub start_s: f64,
    /// One vector of samples per channel.
    pub channels: Vec<Vec<f32>>,
}

impl Recording {
    /// A recording after checking it: at least one channel, equal lengths, finite samples and
    /// a non-zero sample rate.
    pub fn new(sample_rate_hz: u32, start_s: f64, channels: Vec<Vec<f32>>) -> Result<Self> {
        let rec = Self {
            sample_rate_hz,
            start_s,
            channels,
        };
        rec.check()?;
        Ok(rec)
    }

    /// Checks the invariants [`Recording::new`] establishes (the fields are public).
    pub fn check(&self) -> Result<()> {
        if self.sample_rate_hz == 0 {
            return Err(Error::ZeroSampleRate);
        }
        tracker_model::ensure_in_range(self.start_s, f64::MIN, f64::MAX, "start_s")?;
        let refs: Vec<&[f32]> = self.channels.iter().map(Vec::as_slice).collect();
        check_channels(&refs, None, None)
    }

    /// Samples per channel.
    pub fn n_samples(&self) -> usize {
        self.channels.first().map_or(0, Vec::len)
    }

    /// Number of channels.
    pub fn n_channels(&self) -> usize {
        self.channels.len()
    }

    /// Duration in seconds.
    pub fn duration_s(&self) -> f64 {
        self.n_samples() as f64 / f64::from(self.sample_rate_hz)
    }

    /// Reads a WAV file from any reader (16/24/32-bit integer PCM scaled to [−1, 1], or 32-bit
    /// float). The caller opens the file, so this crate touches no file system itself.
    pub fn read_wav<R: Read>(reader: R, start_s: f64) -> Result<Self> {
        let mut wav = hound::WavReader::new(reader)?;
        let spec = wav.spec();
        let n_ch = usize::from(spec.channels);
        if n_ch == 0 {
            return Err(Error::NoChannels);
        }
        let interleaved: Vec<f32> = match spec.sample_format {
            hound::SampleFormat::Float => wav.samples::<f32>().collect::<Result<_, _>>()?,
            hound::SampleFormat::Int => {
                let scale = 1.0 / f64::from(1_u32 << (spec.bits_per_sample.clamp(1, 32) - 1));
                wav.samples::<i32>()
                    .map(|s| s.map(|v| (f64::from(v) * scale) as f32))
                    .collect::<Result<_, _>>()?
            }
        };
        let mut channels = vec![Vec::with_capacity(interleaved.len() / n_ch); n_ch];
        for (i, s) in interleaved.into_iter().enumerate() {
            channels[i % n_ch].push(s);
        }
        Self::new(spec.sample_rate, start_s, channels)
    }

    /// Writes the recording as 32-bit float WAV (lossless for `f32` samples).
    pub fn write_wav<W: Write + Seek>(&self, writer: W) -> Result<()> {
        self.check()?;
        let n_ch = u16::try_from(self.n_channels()).map_err(|_| {
            Error::Unsupported(format!("{} channels exceed WAV's 65535", self.n_channels()))
        })?;
        // The header stores bytes per second in 32 bits (hound computes it unchecked).
        if u64::from(self.sample_rate_hz) * u64::from(n_ch) * 4 > u64::from(u32::MAX) {
            return Err(Error::Unsupported(format!(
                "{} Hz × {n_ch} channels × 4 bytes per second overflow the WAV header's 32-bit \
                 byte rate",
                self.sample_rate_hz
            )));
        }
        let spec = hound::WavSpec {
            channels: n_ch,
            sample_rate: self.sample_rate_hz,
            bits_per_sample: 32,
            sample_format: hound::SampleFormat::Float,
        };
        let mut wav = hound::WavWriter::new(writer, spec)?;
        for i in 0..self.n_samples() {
            for ch in &self.channels {
                wav.write_sample(ch[i])?;
            }
        }
        wav.finalize()?;
        Ok(())
    }
}

/// Checks a set of channels: at least one, `expected_channels` of them if given, all of equal
/// length (`expected_len` if given, shorter is [`Error::FrameTooShort`]) and finite.
pub(crate) fn check_channels(
    channels: &[&[f32]],
    expected_channels: Option<usize>,
    expected_len: Option<usize>,
) -> Result<()> {
    let Some(first) = channels.first() else {
        return Err(Error::NoChannels);
    };
    if let Some(expected) = expected_channels
        && expected != channels.len()
    {
        return Err(Error::ChannelCountMismatch {
            expected,
            got: channels.len(),
        });
    }
    let len = expected_len.unwrap_or(first.len());
    for (channel, ch) in channels.iter().enumerate() {
        if ch.len() < len && expected_len.is_some() {
            return Err(Error::FrameTooShort {
                frame_len: ch.len(),
                required: len,
            });
        }
        if ch.len() != len {
            return Err(Error::ChannelLengthMismatch {
                channel,
                expected: len,
                got: ch.len(),
            });
        }
        if let Some((index, &value)) = ch.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::NonFiniteSample {
                channel,
                index,
                value,
            });
        }
    }
    Ok(())
}
