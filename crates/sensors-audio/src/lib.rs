//! # sensors-audio
//!
//! The acoustic half of the audio-video tracker of Kushwaha, Oh, Amundson, Koutsoukos and
//! Ledeczi (MFI 2008): each node carries a small planar microphone array, beamforms with
//! delay-and-sum over 36 beams of 10°, and reports the beam energies over angle (the
//! "beamform"); their maximum points at the source. Our reconstruction of the method is in the
//! algorithm reference §5.1; choices and numbers in `docs/audio.md`.
//!
//! * [`MicArray`]: any planar geometry; the papers' 10 cm × 6 cm four-microphone rectangle is
//!   the [`Default`], [`MicArray::uniform_circular`] builds circular arrays.
//! * [`Recording`]: multichannel `f32` samples with a sample rate and a start time; WAV in
//!   and out through `hound` on any reader or writer. Frames are plain `&[&[f32]]`.
//! * [`simulate`]: point sources on paths (exact propagation delay, windowed-sinc fractional
//!   delays, 1/r, optional ground reflection), vehicle-like, white, pink or user signals,
//!   diffuse background noise at an SNR; the generator is an argument.
//! * [`BeamformConfig`] → [`Beamformer`]: time-domain delay-and-sum (FIR band-pass,
//!   fractional delays) or frequency-domain steered response power (`realfft`), optionally
//!   PHAT-weighted, or the adaptive MVDR (Capon) over the same bins, over B beams; output one
//!   [`Beamform`] per frame with its time stamp.
//! * [`Beamform::doa`] (argmax + parabolic refinement), [`Beamform::peaks`] (several
//!   sources), [`Beamform::bearing_profile`] → [`BearingProfile::project`] onto a
//!   `tracker_model::LikelihoodGrid`.
//!
//! Beamforming a four-channel recording of the default array to find where a source is:
//!
//! ```
//! use std::f64::consts::TAU;
//! use sensors_audio::{BeamformConfig, MicArray, Recording, SOUND_SPEED_MPS};
//!
//! // 0.2 s at 16 kHz, one channel per microphone (from a WAV file, `Recording::read_wav`);
//! // here two tones arriving from 50°, each microphone hearing them early by its advance.
//! let array = MicArray::default(); // 10 cm × 6 cm, four microphones
//! let sound = |t: f64| (TAU * 700.0 * t).sin() + (TAU * 1900.0 * t).sin();
//! let advances = array.arrival_advances_s(50_f64.to_radians(), SOUND_SPEED_MPS);
//! let channels = advances.iter()
//!     .map(|tau| (0..3200).map(|n| sound(f64::from(n) / 16e3 + tau) as f32).collect())
//!     .collect();
//! let recording = Recording::new(16_000, 0.0, channels)?;
//! let beamforms = BeamformConfig::default().check(&array)?.beamform(&recording)?;
//! let doa = beamforms[0].doa().expect("a source was heard");
//! assert!((doa.bearing_rad - 50_f64.to_radians()).abs() < 5_f64.to_radians());
//! # Ok::<(), sensors_audio::Error>(())
//! ```
//!
//! The same from a simulated recording ([`simulate`]): a white-noise source 20 m away at 50°
//! from a node facing +x, beamformed in the frequency domain:
//!
//! ```
//! use rand::SeedableRng;
//! use sensors_audio::{BeamformConfig, MicArray, SensorPose, SimulationConfig, Source,
//!                     SourcePath, SourceSignal, simulate};
//! use tracker_model::Vec2;
//!
//! let array = MicArray::default(); // 10 cm × 6 cm, four microphones
//! let pose = SensorPose { position: Vec2::new(0.0, 0.0), heading_rad: 0.0 };
//! let bearing = 50_f64.to_radians();
//! let source = Source {
//!     path: SourcePath::Fixed { position: Vec2::new(20.0 * bearing.cos(), 20.0 * bearing.sin()) },
//!     height_m: 1.0,
//!     level: 1.0,
//!     signal: SourceSignal::WhiteNoise,
//! };
//! let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
//! let recording = simulate(&array, &pose, &[source], 0.2, &SimulationConfig::default(), &mut rng)?;
//! let mut beamformer = BeamformConfig::default().check(&array)?;
//! let beamforms = beamformer.beamform(&recording)?;
//! let doa = beamforms[0].doa().expect("a source was heard");
//! assert!((doa.bearing_rad - bearing).abs() < 5_f64.to_radians());
//! # Ok::<(), sensors_audio::Error>(())
//! ```
//!
//! Invariants: randomness comes only from the generator passed in; bad input (no channels, a
//! channel count different from the array's, NaN samples, frames too short for the array, a
//! zero sample rate) is an [`Error`], never a panic; this crate opens no file itself.

mod array;
mod beamform;
mod error;
mod interp;
mod recording;
mod simulate;

#[cfg(test)]
mod tests;

pub use array::{MicArray, SOUND_SPEED_MPS};
pub use beamform::{
    Beamform, BeamformConfig, Beamformer, Doa, EnergyScaling, Method, PeakSearch, Weighting, Window,
};
// The bearing-profile types live in tracker-model (the video crate produces them too).
pub use error::{Error, Result};
pub use recording::Recording;
pub use simulate::{
    BackgroundNoise, NoiseField, SimulationConfig, Source, SourcePath, SourceSignal, simulate,
};
pub use tracker_model::{BearingProfile, GridNormalisation, ProjectionConfig, SensorPose};
