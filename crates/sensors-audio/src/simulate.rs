//! A free-field acoustic simulator for tests and scenarios: point sources moving along paths,
//! exact propagation delays (the emission time solved for a moving source) with windowed-sinc
//! fractional-delay interpolation, 1/r spreading, an optional ground reflection by an image
//! source, and diffuse background noise at a chosen SNR. It generates the scene from the
//! truth, as a renderer would; the beamformers see only the microphone signals.

use std::f64::consts::TAU;

use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use tracker_model::{Error as ModelError, Vec2};

use crate::array::{MicArray, SOUND_SPEED_MPS};
use crate::error::{Error, Result};
use crate::interp::SincTable;
use crate::recording::Recording;
use tracker_model::SensorPose;

/// Where a source is over time (world coordinates, metres).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum SourcePath {
    /// A source standing still.
    Fixed {
        /// Its position.
        position: Vec2,
    },
    /// Piecewise-linear motion through waypoints at increasing times; the source rests at the
    /// first and last waypoints before and after them.
    Waypoints {
        /// Waypoint times, seconds, strictly increasing.
        times_s: Vec<f64>,
        /// Waypoint positions, one per time.
        positions: Vec<Vec2>,
    },
}

impl SourcePath {
    /// The position at time `t_s`.
    pub fn position(&self, t_s: f64) -> Vec2 {
        match self {
            Self::Fixed { position } => *position,
            Self::Waypoints { times_s, positions } => {
                let i = times_s.partition_point(|&t| t <= t_s);
                if i == 0 {
                    positions[0]
                } else if i >= times_s.len() {
                    positions[positions.len() - 1]
                } else {
                    let f = (t_s - times_s[i - 1]) / (times_s[i] - times_s[i - 1]);
                    positions[i - 1] + (positions[i] - positions[i - 1]) * f
                }
            }
        }
    }

    fn check(&self) -> Result<()> {
        match self {
            Self::Fixed { position } => {
                if !position.iter().all(|v| v.is_finite()) {
                    return Err(ModelError::NonFinite {
                        what: "source position",
                    }
                    .into());
                }
            }
            Self::Waypoints { times_s, positions } => {
                if times_s.is_empty() {
                    return Err(ModelError::Empty { what: "waypoints" }.into());
                }
                if times_s.len() != positions.len() {
                    return Err(ModelError::ShapeMismatch(format!(
                        "{} waypoint times but {} positions",
                        times_s.len(),
                        positions.len()
                    ))
                    .into());
                }
                if positions
                    .iter()
                    .flat_map(|p| p.iter())
                    .any(|v| !v.is_finite())
                    || times_s.iter().any(|t| !t.is_finite())
                {
                    return Err(ModelError::NonFinite { what: "waypoints" }.into());
                }
                if times_s.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(ModelError::InvalidParameter {
                        name: "times_s",
                        reason: "waypoint times must increase strictly".into(),
                    }
                    .into());
                }
            }
        }
        Ok(())
    }
}

/// What a source emits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum SourceSignal {
    /// A vehicle-like sound: harmonics k·f0 (k = 1..n) with amplitude ∝ k^(−rolloff) and random
    /// phases (engine firing), plus pink broadband noise (tyres, wind) carrying
    /// `noise_fraction` of the power.
    Vehicle {
        /// Firing frequency f0, Hz.
        fundamental_hz: f64,
        /// Number of harmonics.
        n_harmonics: usize,
        /// Amplitude roll-off exponent.
        rolloff: f64,
        /// Share of the power in broadband noise, in [0, 1].
        noise_fraction: f64,
    },
    /// White Gaussian noise.
    WhiteNoise,
    /// Pink (1/f) noise.
    PinkNoise,
    /// The caller's samples at the simulation's sample rate; sample k is emitted at k/f_s
    /// seconds (silence before and after). Not rescaled: `level` multiplies it.
    User {
        /// The samples.
        samples: Vec<f32>,
    },
}

/// One point source.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Source {
    /// Where it is.
    pub path: SourcePath,
    /// Height above the ground, metres.
    pub height_m: f64,
    /// RMS amplitude at 1 m (a gain on `User` signals).
    pub level: f64,
    /// What it emits.
    pub signal: SourceSignal,
}

/// Spatial structure of the background noise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum NoiseField {
    /// Independent white noise per microphone (electronic noise).
    Uncorrelated,
    /// Independent white plane waves from `n_directions` equally spaced horizontal directions
    /// (random offset): a 2-D approximation of a diffuse field such as distant traffic or
    /// construction, correlated between close microphones as real ambient noise is.
    Diffuse {
        /// Number of plane waves.
        n_directions: usize,
    },
}

/// Background noise scaled to a signal-to-noise ratio: noise power per microphone =
/// (mean source power over the microphones) / 10^(snr_db/10).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BackgroundNoise {
    /// SNR in dB.
    pub snr_db: f64,
    /// Spatial structure.
    pub field: NoiseField,
}

/// Simulator parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimulationConfig {
    /// Output sample rate, Hz.
    pub sample_rate_hz: u32,
    /// Speed of sound, m/s.
    pub sound_speed_mps: f64,
    /// Height of the (horizontal) array above the ground: the papers' tripods, 1 m.
    pub array_height_m: f64,
    /// Ground reflection coefficient for the image source (`None`: free field).
    pub ground_reflection: Option<f64>,
    /// Background noise (`None`: noise-free).
    pub noise: Option<BackgroundNoise>,
    /// Zero crossings each side of the interpolating sinc.
    pub interp_half_width: usize,
}

impl Default for SimulationConfig {
    fn default() -> Self {
        Self {
            sample_rate_hz: 16_000,
            sound_speed_mps: SOUND_SPEED_MPS,
            array_height_m: 1.0,
            ground_reflection: None,
            noise: None,
            interp_half_width: 16,
        }
    }
}

impl SimulationConfig {
    /// Checks the parameters.
    pub fn check(&self) -> Result<()> {
        if self.sample_rate_hz == 0 {
            return Err(Error::ZeroSampleRate);
        }
        tracker_model::ensure_positive(self.sound_speed_mps, "sound_speed_mps")?;
        tracker_model::ensure_non_negative(self.array_height_m, "array_height_m")?;
        if let Some(g) = self.ground_reflection {
            tracker_model::ensure_in_range(g, -1.0, 1.0, "ground_reflection")?;
        }
        if let Some(noise) = &self.noise {
            tracker_model::ensure_in_range(noise.snr_db, -100.0, 200.0, "snr_db")?;
            if let NoiseField::Diffuse { n_directions: 0 } = noise.field {
                return Err(ModelError::InvalidParameter {
                    name: "n_directions",
                    reason: "a diffuse field needs at least one direction".into(),
                }
                .into());
            }
        }
        if self.interp_half_width == 0 {
            return Err(ModelError::InvalidParameter {
                name: "interp_half_width",
                reason: "must be at least 1".into(),
            }
            .into());
        }
        Ok(())
    }
}

/// Simulates what the array at `pose` records for `duration_s` seconds from `sources` (time 0
/// is the recording's first sample). Random signals and noise come from `rng`.
pub fn simulate<R: Rng + ?Sized>(
    array: &MicArray,
    pose: &SensorPose,
    sources: &[Source],
    duration_s: f64,
    config: &SimulationConfig,
    rng: &mut R,
) -> Result<Recording> {
    config.check()?;
    tracker_model::ensure_positive(duration_s, "duration_s")?;
    let fs = f64::from(config.sample_rate_hz);
    let c = config.sound_speed_mps;
    let n = (duration_s * fs).round() as usize;
    if n == 0 {
        return Err(ModelError::InvalidParameter {
            name: "duration_s",
            reason: format!("{duration_s} s is less than one sample"),
        }
        .into());
    }
    let half = config.interp_half_width;
    let table = SincTable::new(half, 512);
    let (sh, ch) = pose.heading_rad.sin_cos();
    let mics: Vec<Vec2> = array
        .positions_m()
        .iter()
        .map(|p| pose.position + Vec2::new(ch * p[0] - sh * p[1], sh * p[0] + ch * p[1]))
        .collect();
    let mut channels = vec![vec![0.0_f32; n]; mics.len()];
    for (idx, src) in sources.iter().enumerate() {
        src.path.check()?;
        tracker_model::ensure_non_negative(src.height_m, "height_m")?;
        tracker_model::ensure_non_negative(src.level, "level")?;
        // The longest path decides how early the emitted signal must start.
        let far = farthest_distance(&src.path, &mics) + src.height_m + config.array_height_m;
        let lead_s = far / c + (half as f64 + 2.0) / fs;
        let (signal, t0) =
            emitted(&src.signal, src.level, lead_s, duration_s, fs, rng).map_err(|e| match e {
                Error::Model(ModelError::InvalidParameter { name, reason }) => {
                    Error::Model(ModelError::InvalidParameter {
                        name,
                        reason: format!("source {idx}: {reason}"),
                    })
                }
                other => other,
            })?;
        // Direct path, then the image source below the ground.
        let mut paths = vec![(src.height_m, 1.0)];
        if let Some(g) = config.ground_reflection {
            paths.push((-src.height_m, g));
        }
        for (mic, out) in mics.iter().zip(channels.iter_mut()) {
            for (z_src, gain) in &paths {
                let dz = z_src - config.array_height_m;
                let dist = |t: f64| {
                    let d = src.path.position(t) - mic;
                    (d.norm_squared() + dz * dz).sqrt()
                };
                for (i, o) in out.iter_mut().enumerate() {
                    let t = i as f64 / fs;
                    // Emission time: t_e = t − |p(t_e) − mic|/c, a contraction (speed ≪ c).
                    let mut te = t - dist(t) / c;
                    for _ in 0..4 {
                        te = t - dist(te) / c;
                    }
                    let r = dist(te).max(1e-3);
                    let v = table.interpolate(&signal, (te - t0) * fs);
                    *o += (gain * v / r) as f32;
                }
            }
        }
    }
    if let Some(noise) = &config.noise {
        add_noise(&mut channels, array, noise, config, &table, rng)?;
    }
    Recording::new(config.sample_rate_hz, 0.0, channels)
}

fn farthest_distance(path: &SourcePath, mics: &[Vec2]) -> f64 {
    let points: Vec<Vec2> = match path {
        SourcePath::Fixed { position } => vec![*position],
        SourcePath::Waypoints { positions, .. } => positions.clone(),
    };
    points
        .iter()
        .flat_map(|p| mics.iter().map(move |m| (p - m).norm()))
        .fold(0.0, f64::max)
}

/// The emitted signal and the emission time of its sample 0.
fn emitted<R: Rng + ?Sized>(
    signal: &SourceSignal,
    level: f64,
    lead_s: f64,
    duration_s: f64,
    fs: f64,
    rng: &mut R,
) -> Result<(Vec<f32>, f64)> {
    if let SourceSignal::User { samples } = signal {
        if let Some((index, &value)) = samples.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::NonFiniteSample {
                channel: 0,
                index,
                value,
            });
        }
        return Ok((
            samples
                .iter()
                .map(|v| (f64::from(*v) * level) as f32)
                .collect(),
            0.0,
        ));
    }
    let t0 = -lead_s;
    let n = ((lead_s + duration_s) * fs).ceil() as usize + 4;
    let mut x: Vec<f64> = match signal {
        SourceSignal::WhiteNoise => white(n, rng),
        SourceSignal::PinkNoise => pink(n, rng),
        SourceSignal::Vehicle {
            fundamental_hz,
            n_harmonics,
            rolloff,
            noise_fraction,
        } => {
            tracker_model::ensure_in_range(
                *fundamental_hz,
                f64::MIN_POSITIVE,
                fs / 2.0,
                "fundamental_hz",
            )?;
            tracker_model::ensure_in_range(*noise_fraction, 0.0, 1.0, "noise_fraction")?;
            tracker_model::ensure_non_negative(*rolloff, "rolloff")?;
            let mut tonal = vec![0.0; n];
            for k in 1..=*n_harmonics {
                let f = k as f64 * fundamental_hz;
                if f >= fs / 2.0 {
                    break;
                }
                let amp = (k as f64).powf(-rolloff);
                let phase = TAU * rng.random::<f64>();
                for (i, v) in tonal.iter_mut().enumerate() {
                    *v += amp * (TAU * f * (t0 + i as f64 / fs) + phase).sin();
                }
            }
            normalise_rms(&mut tonal);
            let mut noise = pink(n, rng);
            normalise_rms(&mut noise);
            let (a, b) = ((1.0 - noise_fraction).sqrt(), noise_fraction.sqrt());
            tonal
                .iter()
                .zip(&noise)
                .map(|(t, w)| a * t + b * w)
                .collect()
        }
        SourceSignal::User { .. } => unreachable!("handled above"),
    };
    normalise_rms(&mut x);
    Ok((x.iter().map(|v| (v * level) as f32).collect(), t0))
}

fn white<R: Rng + ?Sized>(n: usize, rng: &mut R) -> Vec<f64> {
    (0..n).map(|_| StandardNormal.sample(rng)).collect()
}

/// Pink noise by Paul Kellet's refined filter bank on white noise (±0.05 dB from 1/f above
/// ~10 Hz at 44.1 kHz; the slope holds at other rates over the audio band).
fn pink<R: Rng + ?Sized>(n: usize, rng: &mut R) -> Vec<f64> {
    let mut b = [0.0_f64; 7];
    (0..n)
        .map(|_| {
            let w: f64 = StandardNormal.sample(rng);
            b[0] = 0.99886 * b[0] + w * 0.055_517_9;
            b[1] = 0.99332 * b[1] + w * 0.075_075_9;
            b[2] = 0.96900 * b[2] + w * 0.153_852;
            b[3] = 0.86650 * b[3] + w * 0.310_485_6;
            b[4] = 0.55000 * b[4] + w * 0.532_952_2;
            b[5] = -0.7616 * b[5] - w * 0.016_898;
            let out = b.iter().sum::<f64>() + w * 0.5362;
            b[6] = w * 0.115_926;
            out
        })
        .collect()
}

fn normalise_rms(x: &mut [f64]) {
    let rms = (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt();
    if rms > 0.0 {
        x.iter_mut().for_each(|v| *v /= rms);
    }
}

fn add_noise<R: Rng + ?Sized>(
    channels: &mut [Vec<f32>],
    array: &MicArray,
    noise: &BackgroundNoise,
    config: &SimulationConfig,
    table: &SincTable,
    rng: &mut R,
) -> Result<()> {
    let n = channels.first().map_or(0, Vec::len);
    let signal_power = mean_power(channels);
    if signal_power.is_nan() || signal_power <= 0.0 {
        return Err(ModelError::InvalidParameter {
            name: "snr_db",
            reason: "an SNR needs a signal, but the sources are silent at the array".into(),
        }
        .into());
    }
    let fs = f64::from(config.sample_rate_hz);
    let mut field = vec![vec![0.0_f32; n]; channels.len()];
    match noise.field {
        NoiseField::Uncorrelated => {
            for ch in &mut field {
                for v in ch.iter_mut() {
                    *v = StandardNormal.sample(rng);
                }
            }
        }
        NoiseField::Diffuse { n_directions } => {
            let half = config.interp_half_width;
            let margin = array.aperture_m() / config.sound_speed_mps * fs + half as f64 + 2.0;
            let pad = margin.ceil() as usize;
            let offset = rng.random::<f64>();
            for d in 0..n_directions {
                let theta = TAU * (d as f64 + offset) / n_directions as f64;
                let wave: Vec<f32> = (0..n + 2 * pad)
                    .map(|_| StandardNormal.sample(rng))
                    .collect();
                let adv = array.arrival_advances_s(theta, config.sound_speed_mps);
                for (ch, a) in field.iter_mut().zip(&adv) {
                    for (i, v) in ch.iter_mut().enumerate() {
                        // The wave reaches this microphone a seconds early: x(t) = s(t + a).
                        *v += table.interpolate(&wave, (i + pad) as f64 + a * fs) as f32;
                    }
                }
            }
        }
    }
    let noise_power = mean_power(&field);
    let target = signal_power / 10_f64.powf(noise.snr_db / 10.0);
    let gain = if noise_power > 0.0 {
        (target / noise_power).sqrt()
    } else {
        0.0
    };
    for (ch, f) in channels.iter_mut().zip(&field) {
        for (v, w) in ch.iter_mut().zip(f) {
            *v += (f64::from(*w) * gain) as f32;
        }
    }
    Ok(())
}

/// Mean square over all channels and samples.
pub(crate) fn mean_power(channels: &[Vec<f32>]) -> f64 {
    let count: usize = channels.iter().map(Vec::len).sum();
    let sum: f64 = channels
        .iter()
        .flatten()
        .map(|v| f64::from(*v).powi(2))
        .sum();
    if count == 0 { 0.0 } else { sum / count as f64 }
}
