//! Delay-and-sum beamforming over B beams (Kushwaha et al. 2008; our §5.1 reconstruction), in
//! the time domain (band-pass FIR, then windowed-sinc fractional steering delays) and in the
//! frequency domain (steered response power over FFT bins, optionally PHAT-weighted), and the
//! adaptive minimum-variance distortionless response (MVDR, Capon 1969) over the same bins.
//!
//! Sign convention: a plane wave from direction u reaches microphone m (at r_m from the array
//! centre) τ_m = (r_m · u)/c seconds *early*, x_m(t) = s(t + τ_m), so steering *delays* each
//! channel by τ_m: y(t) = Σ_m x_m(t − τ_m), or Y(f) = Σ_m X_m(f) e^{−j2πfτ_m}. (Our §5.1 note
//! writes "+"; with τ defined as an advance that would steer to the opposite direction. The
//! tests check the sign against the simulator's geometric propagation, an independent route.)

use std::f64::consts::TAU;
use std::sync::Arc;

use nalgebra::DMatrix;
use realfft::num_complex::Complex;
use realfft::{RealFftPlanner, RealToComplex};
use serde::{Deserialize, Serialize};
use tracker_model::{Error as ModelError, Frame, FrameClock};

use crate::array::{MicArray, SOUND_SPEED_MPS};
use crate::error::{Error, Result};
use crate::interp::{bandpass_fir, fractional_taps};
use crate::recording::{Recording, check_channels};
use tracker_model::{BearingProfile, SensorPose};

/// How the beam energies are computed: delay-and-sum in the time or the frequency domain, or
/// MVDR over the frequency-domain bins.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Band-pass FIR per channel, fractional delays by windowed-sinc interpolation, sum, energy.
    TimeDomain,
    /// FFT per channel, phase-shift steering per bin in the band, energy by Parseval.
    #[default]
    FrequencyDomain,
    /// Minimum-variance distortionless response (Capon 1969, "High-resolution
    /// frequency-wavenumber spectrum analysis", Proc. IEEE 57(8)): per FFT bin k in the band,
    /// the spatial covariance R_k of the channels' spectra, averaged over frames with
    /// forgetting factor α (`mvdr_forgetting`) and loaded with ε·tr(R_k)/M on its diagonal
    /// (`mvdr_loading`), gives beam b the power 1/(d_{k,b}ᴴ R_k⁻¹ d_{k,b}) of the filter
    /// that passes b's plane wave unchanged and minimises everything else; the energy is the
    /// Parseval-weighted sum over bins times M², so that one noise-free plane wave peaks at
    /// (1 + ε/M) times the delay-and-sum energy. Two sources inside one delay-and-sum beam give two peaks when
    /// they are uncorrelated and well above the noise. The covariance carries over from frame
    /// to frame: frames must come in time order ([`Beamformer::reset`] forgets them;
    /// [`Beamformer::beamform`] starts afresh), and its mean age is α/(1 − α) hops, so a
    /// moving source's bearing lags by about that much.
    Mvdr,
}

/// Spectral weighting of the frequency-domain beamformer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Weighting {
    /// Plain steered response power: loud bins dominate.
    #[default]
    Plain,
    /// Phase transform: every bin of every channel scaled to unit magnitude, so all bins in
    /// the band count equally (SRP-PHAT; the stronger estimator under reverberation). Only for
    /// [`Method::FrequencyDomain`].
    Phat,
}

/// Analysis window of the frequency-domain beamformer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Window {
    /// No taper: energies equal the time-domain ones by Parseval (circular shifts aside).
    Rectangular,
    /// Hann taper: less leakage from strong out-of-band components (engine harmonics).
    #[default]
    Hann,
}

/// Beamformer parameters; [`BeamformConfig::check`] turns them into a [`Beamformer`] for one
/// array. Defaults: the papers' 36 beams of 10°; our choices 16 kHz, 512-sample frames without overlap
/// and a 200–4000 Hz band (see docs/audio.md for why).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BeamformConfig {
    /// Number of beams B, beam b steered to b·360°/B in the array frame.
    pub n_beams: usize,
    /// Sample rate of the input, Hz.
    pub sample_rate_hz: u32,
    /// Samples per frame.
    pub frame_len: usize,
    /// Samples between frame starts.
    pub hop: usize,
    /// Pass band [low, high] in Hz; energy outside it is ignored.
    pub band_hz: [f64; 2],
    /// Speed of sound, m/s.
    pub sound_speed_mps: f64,
    /// Time- or frequency-domain delay-and-sum, or MVDR.
    pub method: Method,
    /// Plain or PHAT (frequency domain only).
    pub weighting: Weighting,
    /// Analysis window (frequency domain and MVDR).
    pub window: Window,
    /// Length of the band-pass FIR (time domain only; odd).
    pub fir_taps: usize,
    /// Zero crossings each side of the fractional-delay sinc (time domain only).
    pub interp_half_width: usize,
    /// MVDR: the weight α ∈ [0, 1) of the past in the running covariance,
    /// R ← α R + (1 − α) x xᴴ (0: this frame alone, a rank-one estimate).
    pub mvdr_forgetting: f64,
    /// MVDR: diagonal loading ε ∈ [10⁻⁹, 10⁹], as a fraction of the mean channel power
    /// tr(R)/M (keeps R invertible and the beams robust to array errors; larger is closer to
    /// delay-and-sum).
    pub mvdr_loading: f64,
}

impl Default for BeamformConfig {
    fn default() -> Self {
        Self {
            n_beams: 36,
            sample_rate_hz: 16_000,
            frame_len: 512,
            hop: 512,
            band_hz: [200.0, 4000.0],
            sound_speed_mps: SOUND_SPEED_MPS,
            method: Method::FrequencyDomain,
            weighting: Weighting::Plain,
            window: Window::Hann,
            fir_taps: 65,
            interp_half_width: 4,
            mvdr_forgetting: 0.8,
            mvdr_loading: 0.01,
        }
    }
}

/// The beam energies of one frame: the node's report (the "beamform"). `energies[b]` is the
/// mean power of the beam steered to `b`·2π/B (array frame) over the frame, in squared input
/// units (dimensionless under PHAT; under MVDR the power of its filter, from a covariance that
/// remembers earlier frames); `time_s` is the frame's centre on the recording's clock.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Beamform {
    /// Centre of the frame, seconds.
    pub time_s: f64,
    /// One energy per beam.
    pub energies: Vec<f64>,
}

/// A direction of arrival read off a beamform.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Doa {
    /// Bearing in the array frame, radians in [0, 2π), refined between beams.
    pub bearing_rad: f64,
    /// The peak beam's index.
    pub beam: usize,
    /// The peak beam's energy.
    pub energy: f64,
}

/// How several peaks are picked from one beamform.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PeakSearch {
    /// At most this many peaks, strongest first.
    pub max_peaks: usize,
    /// A peak must rise at least this fraction of the beamform's range (max − min) above its
    /// minimum: the floor of a small array's broad beams carries no information.
    pub min_relative: f64,
}

impl Default for PeakSearch {
    fn default() -> Self {
        Self {
            max_peaks: 4,
            min_relative: 0.1,
        }
    }
}

/// How beam energies become a bearing profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum EnergyScaling {
    /// The energies as they are.
    Raw,
    /// Energies minus their minimum over beams (§5.1's option): a small array's beams are so
    /// broad that every beam hears a source; the floor would spread evidence everywhere.
    #[default]
    MinSubtracted,
}

impl Beamform {
    /// Number of beams.
    pub fn n_beams(&self) -> usize {
        self.energies.len()
    }

    /// Direction of beam `b` in the array frame, radians.
    pub fn beam_angle_rad(&self, b: usize) -> f64 {
        TAU * b as f64 / self.energies.len().max(1) as f64
    }

    /// The tracker frame nearest to this beamform's time stamp.
    pub fn frame(&self, clock: &FrameClock) -> Result<Frame> {
        Ok(clock.frame_at(self.time_s)?)
    }

    /// The strongest direction: the argmax beam refined by a parabola through it and its two
    /// (circular) neighbours. `None` for a flat beamform (no direction at all).
    pub fn doa(&self) -> Option<Doa> {
        let (beam, _) = self
            .energies
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))?;
        let min = self.energies.iter().copied().fold(f64::INFINITY, f64::min);
        (self.energies[beam] > min).then(|| self.refine(beam))
    }

    /// Up to `search.max_peaks` local maxima (circular), strongest first, each refined like
    /// [`Beamform::doa`]. Empty for a flat beamform.
    pub fn peaks(&self, search: &PeakSearch) -> Vec<Doa> {
        let n = self.energies.len();
        let e = &self.energies;
        let min = e.iter().copied().fold(f64::INFINITY, f64::min);
        let max = e.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if n < 3 || max <= min || max.is_nan() {
            return self.doa().into_iter().collect();
        }
        let floor = min + search.min_relative * (max - min);
        let mut found: Vec<Doa> = (0..n)
            .filter(|&b| {
                let (prev, next) = (e[(b + n - 1) % n], e[(b + 1) % n]);
                // ≥ on one side, > on the other: a two-beam plateau yields one peak.
                e[b] >= prev && e[b] > next && e[b] >= floor
            })
            .map(|b| self.refine(b))
            .collect();
        found.sort_by(|a, b| b.energy.total_cmp(&a.energy).then(a.beam.cmp(&b.beam)));
        found.truncate(search.max_peaks);
        found
    }

    fn refine(&self, beam: usize) -> Doa {
        let n = self.energies.len();
        let step = TAU / n as f64;
        let mut offset = 0.0;
        if n >= 3 {
            let (l, c, r) = (
                self.energies[(beam + n - 1) % n],
                self.energies[beam],
                self.energies[(beam + 1) % n],
            );
            let denom = l - 2.0 * c + r;
            if denom < 0.0 {
                offset = (0.5 * (l - r) / denom).clamp(-0.5, 0.5);
            }
        }
        Doa {
            bearing_rad: ((beam as f64 + offset) * step).rem_euclid(TAU),
            beam,
            energy: self.energies[beam],
        }
    }

    /// The bearing profile of this beamform for a node at `pose` (beam b points at world
    /// bearing heading + b·2π/B), ready to be projected onto a likelihood grid.
    pub fn bearing_profile(
        &self,
        pose: SensorPose,
        scaling: EnergyScaling,
    ) -> Result<BearingProfile> {
        let min = self.energies.iter().copied().fold(f64::INFINITY, f64::min);
        let values = match scaling {
            EnergyScaling::Raw => self.energies.clone(),
            EnergyScaling::MinSubtracted => self.energies.iter().map(|e| e - min).collect(),
        };
        Ok(BearingProfile::full_circle(pose, values)?)
    }
}

/// A checked beamformer for one array; holds its scratch buffers, so beamforming a frame does
/// not allocate. Clone it to use on several threads. MVDR keeps state (its running
/// covariance): one time-ordered stream of frames per `Beamformer`, and a clone copies the
/// covariance.
#[derive(Clone)]
pub struct Beamformer {
    config: BeamformConfig,
    n_mics: usize,
    engine: Engine,
}

#[derive(Clone)]
enum Engine {
    Time(TimeDomain),
    Freq(FreqDomain),
    Mvdr(Mvdr),
}

/// The MVDR engine: the frequency-domain front end (its band spectra) and the running
/// covariance per bin.
#[derive(Clone)]
struct Mvdr {
    freq: FreqDomain,
    /// Running covariance per bin, M × M.
    cov: Vec<DMatrix<Complex<f64>>>,
    /// Scratch: the loaded covariance and its Cholesky factor (M × M), and the bin's array
    /// manifold d_{k,b,m} = e^{+j2πf_kτ_{m,b}} (the conjugate steering phases), then L⁻¹ d
    /// (M × B).
    loaded: DMatrix<Complex<f64>>,
    solved: DMatrix<Complex<f64>>,
    /// Whether `cov` holds a frame yet.
    primed: bool,
    forgetting: f64,
    loading: f64,
}

#[derive(Clone)]
struct TimeDomain {
    fir: Vec<f32>,
    /// Fractional-delay taps, [beam][mic][2·half].
    taps: Vec<f32>,
    /// First filtered sample each (beam, mic) tap set reads.
    starts: Vec<usize>,
    n_taps: usize,
    n_out: usize,
    filtered: Vec<Vec<f32>>,
    beam: Vec<f32>,
}

#[derive(Clone)]
struct FreqDomain {
    fft: Arc<dyn RealToComplex<f64>>,
    window: Vec<f64>,
    first_bin: usize,
    n_bins: usize,
    /// Steering phases e^{−j2πf_kτ_{m,b}}, [beam][bin][mic].
    steer: Vec<Complex<f64>>,
    /// Parseval weight of each bin in the band (1 for DC and Nyquist, 2 otherwise) / (L Σw²).
    bin_weight: Vec<f64>,
    input: Vec<f64>,
    spectrum: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
    /// Band spectra of all channels, [bin][mic].
    band: Vec<Complex<f64>>,
    phat: bool,
}

impl std::fmt::Debug for Beamformer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Beamformer")
            .field("config", &self.config)
            .field("n_mics", &self.n_mics)
            .finish_non_exhaustive()
    }
}

impl BeamformConfig {
    /// Checks the parameters against `array` and precomputes filters and steering tables.
    pub fn check(&self, array: &MicArray) -> Result<Beamformer> {
        let fs = self.check_common()?;
        let n_mics = array.n_mics();
        // advances[b·M + m] in samples.
        let advances: Vec<f64> = (0..self.n_beams)
            .flat_map(|b| {
                array.arrival_advances_s(TAU * b as f64 / self.n_beams as f64, self.sound_speed_mps)
            })
            .map(|t| t * fs)
            .collect();
        // The largest inter-microphone delay must fit in a frame with room to spare.
        let spread = (array.aperture_m() / self.sound_speed_mps * fs).ceil() as usize;
        let engine = match self.method {
            Method::TimeDomain => Engine::Time(self.time_domain(&advances, spread, n_mics, fs)?),
            Method::FrequencyDomain | Method::Mvdr => {
                let freq = self.freq_domain(&advances, spread, n_mics, fs)?;
                if self.method == Method::Mvdr {
                    Engine::Mvdr(self.mvdr(freq, n_mics)?)
                } else {
                    Engine::Freq(freq)
                }
            }
        };
        Ok(Beamformer {
            config: self.clone(),
            n_mics,
            engine,
        })
    }

    /// Checks what every method needs (sample rate, beams, hop, sound speed, band) and returns
    /// the sample rate in hertz.
    fn check_common(&self) -> Result<f64> {
        if self.sample_rate_hz == 0 {
            return Err(Error::ZeroSampleRate);
        }
        let fs = f64::from(self.sample_rate_hz);
        if self.n_beams == 0 {
            return Err(ModelError::InvalidParameter {
                name: "n_beams",
                reason: "must be at least 1".into(),
            }
            .into());
        }
        if self.hop == 0 {
            return Err(ModelError::InvalidParameter {
                name: "hop",
                reason: "must be at least 1 sample".into(),
            }
            .into());
        }
        tracker_model::ensure_positive(self.sound_speed_mps, "sound_speed_mps")?;
        let [lo, hi] = self.band_hz;
        tracker_model::ensure_in_range(lo, 0.0, fs / 2.0, "band_hz[0]")?;
        tracker_model::ensure_in_range(hi, 0.0, fs / 2.0, "band_hz[1]")?;
        if hi <= lo {
            return Err(ModelError::InvalidParameter {
                name: "band_hz",
                reason: format!("[{lo}, {hi}]: the upper edge must exceed the lower"),
            }
            .into());
        }
        Ok(fs)
    }

    /// The time-domain delay-and-sum engine (Kushwaha et al. 2008): the band-pass FIR and,
    /// per (beam, microphone), the windowed-sinc fractional-delay taps that delay the channel
    /// by its advance (`advances` in samples), after checking that the frame holds the FIR,
    /// the delays and the array's `spread`.
    fn time_domain(
        &self,
        advances: &[f64],
        spread: usize,
        n_mics: usize,
        fs: f64,
    ) -> Result<TimeDomain> {
        let [lo, hi] = self.band_hz;
        let max_adv = advances.iter().fold(0.0_f64, |m, a| m.max(a.abs()));
        if self.weighting == Weighting::Phat {
            return Err(Error::Unsupported(
                "PHAT weighting needs the frequency-domain beamformer".into(),
            ));
        }
        if self.fir_taps.is_multiple_of(2) {
            return Err(ModelError::InvalidParameter {
                name: "fir_taps",
                reason: format!(
                    "{} must be odd (a linear-phase FIR with an integer delay)",
                    self.fir_taps
                ),
            }
            .into());
        }
        let half = self.interp_half_width;
        if half == 0 {
            return Err(ModelError::InvalidParameter {
                name: "interp_half_width",
                reason: "must be at least 1".into(),
            }
            .into());
        }
        let margin = max_adv.ceil() as usize + half;
        let required = self.fir_taps + 2 * margin + spread.max(1);
        if self.frame_len < required {
            return Err(Error::FrameTooShort {
                frame_len: self.frame_len,
                required,
            });
        }
        let n_filtered = self.frame_len - self.fir_taps + 1;
        let n_out = n_filtered - 2 * margin;
        let mut taps = vec![0.0_f32; advances.len() * 2 * half];
        let mut starts = Vec::with_capacity(advances.len());
        let mut buf = vec![0.0; 2 * half];
        for (k, a) in advances.iter().enumerate() {
            // Output n reads filtered position n + margin − a (a delay by the advance).
            let pos = margin as f64 - a;
            let i0 = pos.floor();
            fractional_taps(pos - i0, half, &mut buf);
            starts.push(i0 as usize + 1 - half);
            for (t, b) in taps[k * 2 * half..(k + 1) * 2 * half].iter_mut().zip(&buf) {
                *t = *b as f32;
            }
        }
        Ok(TimeDomain {
            fir: bandpass_fir(self.fir_taps, lo, hi, fs)
                .into_iter()
                .map(|v| v as f32)
                .collect(),
            taps,
            starts,
            n_taps: 2 * half,
            n_out,
            filtered: vec![vec![0.0; n_filtered]; n_mics],
            beam: vec![0.0; n_out],
        })
    }

    /// The frequency-domain engine (steered response power over the FFT bins in the band,
    /// Kushwaha et al. 2008; PHAT-weighted on request): the FFT plan, the window, the bins of
    /// the band, the steering phases e^{−j2πf_kτ_{m,b}} and the Parseval weights, after
    /// checking that the frame holds twice the array's `spread` and that the band holds a bin.
    fn freq_domain(
        &self,
        advances: &[f64],
        spread: usize,
        n_mics: usize,
        fs: f64,
    ) -> Result<FreqDomain> {
        let [lo, hi] = self.band_hz;
        let required = 2 * spread + 2;
        if self.frame_len < required {
            return Err(Error::FrameTooShort {
                frame_len: self.frame_len,
                required,
            });
        }
        let l = self.frame_len;
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(l);
        let window: Vec<f64> = match self.window {
            Window::Rectangular => vec![1.0; l],
            // Periodic Hann.
            Window::Hann => (0..l)
                .map(|i| 0.5 - 0.5 * (TAU * i as f64 / l as f64).cos())
                .collect(),
        };
        let w2: f64 = window.iter().map(|w| w * w).sum();
        let df = fs / l as f64;
        let first_bin = (lo / df).ceil() as usize;
        let last_bin = ((hi / df).floor() as usize).min(l / 2);
        if last_bin < first_bin {
            return Err(ModelError::InvalidParameter {
                name: "band_hz",
                reason: format!(
                    "[{lo}, {hi}] contains no FFT bin of a {l}-sample frame ({df} Hz apart)"
                ),
            }
            .into());
        }
        let n_bins = last_bin - first_bin + 1;
        let mut steer = Vec::with_capacity(self.n_beams * n_bins * n_mics);
        for b in 0..self.n_beams {
            for k in first_bin..=last_bin {
                for m in 0..n_mics {
                    let phase = -TAU * k as f64 / l as f64 * advances[b * n_mics + m];
                    steer.push(Complex::from_polar(1.0, phase));
                }
            }
        }
        let bin_weight = (first_bin..=last_bin)
            .map(|k| {
                let edge = k == 0 || (l.is_multiple_of(2) && k == l / 2);
                (if edge { 1.0 } else { 2.0 }) / (l as f64 * w2)
            })
            .collect();
        Ok(FreqDomain {
            input: fft.make_input_vec(),
            spectrum: fft.make_output_vec(),
            scratch: fft.make_scratch_vec(),
            fft,
            window,
            first_bin,
            n_bins,
            steer,
            bin_weight,
            band: vec![Complex::new(0.0, 0.0); n_bins * n_mics],
            phat: self.weighting == Weighting::Phat,
        })
    }

    /// The MVDR engine on `freq`'s bins: checks α and ε and tabulates the manifolds.
    fn mvdr(&self, freq: FreqDomain, n_mics: usize) -> Result<Mvdr> {
        if freq.phat {
            return Err(Error::Unsupported(
                "PHAT weighting is for delay-and-sum; MVDR whitens by its covariance".into(),
            ));
        }
        if !(self.mvdr_forgetting.is_finite() && (0.0..1.0).contains(&self.mvdr_forgetting)) {
            return Err(ModelError::InvalidParameter {
                name: "mvdr_forgetting",
                reason: format!("{}: it must lie in [0, 1)", self.mvdr_forgetting),
            }
            .into());
        }
        tracker_model::ensure_in_range(self.mvdr_loading, 1e-9, 1e9, "mvdr_loading")?;
        let (n_beams, n_bins) = (self.n_beams, freq.n_bins);
        Ok(Mvdr {
            cov: vec![DMatrix::zeros(n_mics, n_mics); n_bins],
            loaded: DMatrix::zeros(n_mics, n_mics),
            solved: DMatrix::zeros(n_mics, n_beams),
            primed: false,
            forgetting: self.mvdr_forgetting,
            loading: self.mvdr_loading,
            freq,
        })
    }
}

impl Beamformer {
    /// The checked configuration.
    pub fn config(&self) -> &BeamformConfig {
        &self.config
    }

    /// Beam energies of one frame: one slice of exactly `frame_len` finite samples per
    /// microphone, in the array's order. Written into `energies` (resized to B).
    pub fn frame_energies_into(
        &mut self,
        channels: &[&[f32]],
        energies: &mut Vec<f64>,
    ) -> Result<()> {
        check_channels(channels, Some(self.n_mics), Some(self.config.frame_len))?;
        energies.clear();
        energies.resize(self.config.n_beams, 0.0);
        match &mut self.engine {
            Engine::Time(td) => td.run(channels, energies),
            Engine::Freq(fd) => fd.run(channels, energies),
            Engine::Mvdr(mv) => mv.run(channels, energies),
        }
        Ok(())
    }

    /// Forgets the frames seen so far (MVDR's running covariance; the other methods keep no
    /// state).
    pub fn reset(&mut self) {
        if let Engine::Mvdr(mv) = &mut self.engine {
            mv.primed = false;
        }
    }

    /// Beam energies of one frame (see [`Beamformer::frame_energies_into`]).
    pub fn frame_energies(&mut self, channels: &[&[f32]]) -> Result<Vec<f64>> {
        let mut out = Vec::new();
        self.frame_energies_into(channels, &mut out)?;
        Ok(out)
    }

    /// Beamforms a whole recording: frames start every `hop` samples while a full frame fits;
    /// each [`Beamform`] is time-stamped with its frame's centre.
    pub fn beamform(&mut self, recording: &Recording) -> Result<Vec<Beamform>> {
        recording.check()?;
        if recording.sample_rate_hz != self.config.sample_rate_hz {
            return Err(ModelError::InvalidParameter {
                name: "sample_rate_hz",
                reason: format!(
                    "the recording is sampled at {} Hz but the beamformer was configured for {} Hz",
                    recording.sample_rate_hz, self.config.sample_rate_hz
                ),
            }
            .into());
        }
        if recording.n_channels() != self.n_mics {
            return Err(Error::ChannelCountMismatch {
                expected: self.n_mics,
                got: recording.n_channels(),
            });
        }
        self.reset();
        let (l, hop) = (self.config.frame_len, self.config.hop);
        let fs = f64::from(self.config.sample_rate_hz);
        let mut out = Vec::new();
        let mut start = 0;
        while start + l <= recording.n_samples() {
            let frame: Vec<&[f32]> = recording
                .channels
                .iter()
                .map(|c| &c[start..start + l])
                .collect();
            let mut energies = Vec::new();
            self.frame_energies_into(&frame, &mut energies)?;
            out.push(Beamform {
                time_s: recording.start_s + (start as f64 + l as f64 / 2.0) / fs,
                energies,
            });
            start += hop;
        }
        Ok(out)
    }
}

impl TimeDomain {
    fn run(&mut self, channels: &[&[f32]], energies: &mut [f64]) {
        // Band-pass each channel ("valid" part only: no invented samples at the frame edges).
        for (z, x) in self.filtered.iter_mut().zip(channels) {
            z.iter_mut().for_each(|v| *v = 0.0);
            for (j, &h) in self.fir.iter().enumerate() {
                let n = z.len();
                for (zi, xi) in z.iter_mut().zip(&x[j..j + n]) {
                    *zi += h * xi;
                }
            }
        }
        let n_mics = self.filtered.len();
        let n_out = self.n_out;
        for (b, e) in energies.iter_mut().enumerate() {
            self.beam.iter_mut().for_each(|v| *v = 0.0);
            for (m, z) in self.filtered.iter().enumerate() {
                let k = b * n_mics + m;
                let taps = &self.taps[k * self.n_taps..(k + 1) * self.n_taps];
                let start = self.starts[k];
                for (j, &t) in taps.iter().enumerate() {
                    let src = &z[start + j..start + j + n_out];
                    for (y, x) in self.beam.iter_mut().zip(src) {
                        *y += t * x;
                    }
                }
            }
            let sum: f32 = self
                .beam
                .chunks(64)
                .map(|c| c.iter().map(|v| v * v).sum::<f32>())
                .sum();
            *e = f64::from(sum) / n_out as f64;
        }
    }
}

impl FreqDomain {
    fn run(&mut self, channels: &[&[f32]], energies: &mut [f64]) {
        self.load_band(channels);
        let n_mics = channels.len();
        let per_beam = self.n_bins * n_mics;
        for (b, e) in energies.iter_mut().enumerate() {
            let steer = &self.steer[b * per_beam..(b + 1) * per_beam];
            let mut total = 0.0;
            for k in 0..self.n_bins {
                let s = &steer[k * n_mics..(k + 1) * n_mics];
                let x = &self.band[k * n_mics..(k + 1) * n_mics];
                let mut acc = Complex::new(0.0, 0.0);
                for (a, c) in x.iter().zip(s) {
                    acc += a * c;
                }
                total += self.bin_weight[k] * acc.norm_sqr();
            }
            *e = total;
        }
    }

    /// The windowed spectra of every channel over the band, into `band` ([bin][mic]).
    fn load_band(&mut self, channels: &[&[f32]]) {
        let n_mics = channels.len();
        for (m, x) in channels.iter().enumerate() {
            for ((inp, &xv), w) in self.input.iter_mut().zip(x.iter()).zip(&self.window) {
                *inp = f64::from(xv) * w;
            }
            // Lengths come from the same plan, so the FFT cannot fail.
            let _ = self.fft.process_with_scratch(
                &mut self.input,
                &mut self.spectrum,
                &mut self.scratch,
            );
            for k in 0..self.n_bins {
                let mut v = self.spectrum[self.first_bin + k];
                if self.phat {
                    // Unit magnitude per bin; a silent bin stays silent.
                    let a = v.norm();
                    v = if a > 1e-30 {
                        v / a
                    } else {
                        Complex::new(0.0, 0.0)
                    };
                }
                self.band[k * n_mics + m] = v;
            }
        }
    }
}

impl Mvdr {
    fn run(&mut self, channels: &[&[f32]], energies: &mut [f64]) {
        let fd = &mut self.freq;
        fd.load_band(channels);
        let n_mics = channels.len();
        let gain = (n_mics * n_mics) as f64;
        let (alpha, fresh) = if self.primed {
            (self.forgetting, 1.0 - self.forgetting)
        } else {
            (0.0, 1.0)
        };
        self.primed = true;
        for k in 0..fd.n_bins {
            let x = &fd.band[k * n_mics..(k + 1) * n_mics];
            let cov = &mut self.cov[k];
            for i in 0..n_mics {
                for j in 0..n_mics {
                    cov[(i, j)] = cov[(i, j)] * alpha + x[i] * x[j].conj() * fresh;
                }
            }
            let power = (0..n_mics).map(|i| cov[(i, i)].re).sum::<f64>() / n_mics as f64;
            if !(power > SILENT_POWER && power.is_finite()) {
                // A silent bin has no direction (delay-and-sum gives it 0 too); its memory is
                // cleared, so that a long silence does not decay into subnormal numbers.
                cov.fill(Complex::new(0.0, 0.0));
                continue;
            }
            // The scratch matrix is factorised in place and taken back (no allocation).
            let mut loaded = std::mem::replace(&mut self.loaded, DMatrix::zeros(0, 0));
            loaded.copy_from(cov);
            for i in 0..n_mics {
                loaded[(i, i)] += self.loading * power;
            }
            // Hermitian positive definite by the loading, so the factorisation exists; with
            // R = L Lᴴ, dᴴ R⁻¹ d = ‖L⁻¹ d‖², ≥ 0 by construction.
            let Some(chol) = loaded.cholesky() else {
                self.loaded = DMatrix::zeros(n_mics, n_mics);
                continue;
            };
            // The manifold, column b = beam b's conjugate steering phases at bin k.
            let per_beam = fd.n_bins * n_mics;
            for (b, mut column) in self.solved.column_iter_mut().enumerate() {
                let steer = &fd.steer[b * per_beam + k * n_mics..][..n_mics];
                for (d, s) in column.iter_mut().zip(steer) {
                    *d = s.conj();
                }
            }
            let solved = chol.l_dirty().solve_lower_triangular_mut(&mut self.solved);
            self.loaded = chol.unpack_dirty();
            if !solved {
                continue;
            }
            for (b, e) in energies.iter_mut().enumerate() {
                let q: f64 = self.solved.column(b).iter().map(|z| z.norm_sqr()).sum();
                if q > 0.0 && q.is_finite() {
                    *e += fd.bin_weight[k] * gain / q;
                }
            }
        }
    }
}

/// Mean channel power per bin below which MVDR treats the bin as silent.
const SILENT_POWER: f64 = 1e-150;
