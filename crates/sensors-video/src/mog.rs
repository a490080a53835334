//! The adaptive background mixture model of KaewTraKulPong & Bowden (AVBS 2001), with OpenCV
//! `bgsegm` MOG defaults, and shadow detection after Horprasert et al. (1999).
//!
//! Per pixel, K Gaussians with weight ω_k, mean μ_k and one variance σ²_{k,c} per channel,
//! kept sorted by ω/√(Σ_c σ²) (Stauffer & Grimson 1999, the paper's §2). For a pixel value x
//! and N frames seen before it:
//! * match: the first component with ‖x − μ_k‖² < λ²·Σ_c σ²_{k,c} (λ = 2.5);
//! * matched (p̂_k = 1 for it, 0 for the others):
//!   - N < L, the paper's expected sufficient statistics (its eq. 5–7):
//!     ω_k ← ω_k + (p̂_k − ω_k)/(N+1), and for the match, with c_k its number of matches
//!     (counting the frame that created it) after this one: μ ← μ + (x − μ)/c_k,
//!     σ² ← σ² + ((x − μ_old)² − σ²)/c_k;
//!   - N ≥ L, the L-recent window (KaewTraKulPong & Bowden 2001, eqs. 8–10):
//!     ω_k ← ω_k + (p̂_k − ω_k)/L, and for the match ρ = 1/(L·ω_k) with the updated ω_k:
//!     μ ← μ + ρ(x − μ), σ² ← σ² + ρ((x − μ_old)² − σ²);
//!   - every variance is floored at σ²_min = 15² (OpenCV's `minVar`);
//! * no match: the lowest-ranked component (or an unused slot) becomes μ = x, σ² = 30²,
//!   ω = 0.05, c = 1, and the weights are renormalised to sum 1 (OpenCV: no decay of the
//!   others in this case);
//! * the background is the first B components with B = min{b : Σ_{k<b} ω_k > T} (T = 0.7);
//!   the pixel is background when the component it matched (or the new one) ranks among them,
//!   after the update, as in OpenCV.
//! * shadow (Horprasert's colour model as the paper uses it): a foreground pixel is shadow
//!   when, for some background component, the brightness distortion a = x·μ/‖μ‖² lies in
//!   [τ_lo, τ_hi] and the chromaticity distortion ‖x − aμ‖² < λ²·Σ_c σ²_c. On grey frames
//!   chromaticity carries no information and only the brightness test remains, so darker
//!   objects read as shadow: enable it for colour.
//!
//! Every pixel is independent, so rows run in parallel with rayon and the result is
//! bit-identical for any thread count.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tracker_model::{ensure_in_range, ensure_open_probability, ensure_positive};

use crate::error::{Error, Result};
use crate::frame::{PixelFormat, VideoFrame};

/// Mask label of a background pixel.
pub const BACKGROUND: u8 = 0;
/// Mask label of a shadow pixel (OpenCV MOG2's value).
pub const SHADOW: u8 = 127;
/// Mask label of a foreground pixel.
pub const FOREGROUND: u8 = 255;

/// Shadow detection parameters (Horprasert et al. 1999; the bounds are ours, \[I\]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShadowConfig {
    /// Label shadows at all.
    pub enabled: bool,
    /// Lowest brightness distortion a a shadow can have (τ_lo; 0.5).
    pub min_brightness: f64,
    /// Highest brightness distortion (τ_hi; 1: a shadow is darker than the background).
    pub max_brightness: f64,
    /// Chromaticity threshold in standard deviations: ‖x − aμ‖² < λ_cd²·Σ_c σ²_c.
    pub max_chromaticity_sigmas: f64,
}

impl Default for ShadowConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            min_brightness: 0.5,
            max_brightness: 1.0,
            max_chromaticity_sigmas: 1.5,
        }
    }
}

/// Parameters of the mixture, with OpenCV `bgsegm::createBackgroundSubtractorMOG` defaults.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MogConfig {
    /// L: frames of the first phase and length of the recent window (200).
    pub history: usize,
    /// K: Gaussians per pixel (5; at most 16).
    pub n_mixtures: usize,
    /// T: weight the background components must exceed together (0.7).
    pub background_ratio: f64,
    /// λ: match threshold in standard deviations (2.5).
    pub match_sigmas: f64,
    /// Standard deviation of a new component, grey levels (30).
    pub initial_sigma: f64,
    /// Weight of a new component before renormalisation (0.05).
    pub initial_weight: f64,
    /// Floor of every standard deviation, grey levels (15).
    pub min_sigma: f64,
    /// Shadow detection.
    pub shadows: ShadowConfig,
}

impl Default for MogConfig {
    fn default() -> Self {
        Self {
            history: 200,
            n_mixtures: 5,
            background_ratio: 0.7,
            match_sigmas: 2.5,
            initial_sigma: 30.0,
            initial_weight: 0.05,
            min_sigma: 15.0,
            shadows: ShadowConfig::default(),
        }
    }
}

/// The checked parameters the update runs on, in f32.
#[derive(Debug, Clone, Copy)]
struct Params {
    k: usize,
    l: f32,
    t: f32,
    lambda2: f32,
    var0: f32,
    w0: f32,
    var_min: f32,
    shadows: bool,
    tau_lo: f32,
    tau_hi: f32,
    cd2: f32,
}

impl MogConfig {
    fn check(&self) -> Result<Params> {
        if self.history == 0 {
            return Err(tracker_model::Error::InvalidParameter {
                name: "history",
                reason: "must be at least 1".to_string(),
            }
            .into());
        }
        if !(1..=16).contains(&self.n_mixtures) {
            return Err(tracker_model::Error::InvalidParameter {
                name: "n_mixtures",
                reason: format!("{} is outside 1..=16", self.n_mixtures),
            }
            .into());
        }
        ensure_open_probability(self.background_ratio, "background_ratio")?;
        ensure_positive(self.match_sigmas, "match_sigmas")?;
        ensure_positive(self.initial_sigma, "initial_sigma")?;
        ensure_open_probability(self.initial_weight, "initial_weight")?;
        ensure_positive(self.min_sigma, "min_sigma")?;
        ensure_in_range(
            self.shadows.min_brightness,
            0.0,
            1.0,
            "shadows.min_brightness",
        )?;
        ensure_in_range(
            self.shadows.max_brightness,
            self.shadows.min_brightness,
            1.0,
            "shadows.max_brightness",
        )?;
        ensure_positive(
            self.shadows.max_chromaticity_sigmas,
            "shadows.max_chromaticity_sigmas",
        )?;
        Ok(Params {
            k: self.n_mixtures,
            l: self.history as f32,
            t: self.background_ratio as f32,
            lambda2: (self.match_sigmas * self.match_sigmas) as f32,
            var0: (self.initial_sigma * self.initial_sigma) as f32,
            w0: self.initial_weight as f32,
            var_min: (self.min_sigma * self.min_sigma) as f32,
            shadows: self.shadows.enabled,
            tau_lo: self.shadows.min_brightness as f32,
            tau_hi: self.shadows.max_brightness as f32,
            cd2: (self.shadows.max_chromaticity_sigmas * self.shadows.max_chromaticity_sigmas)
                as f32,
        })
    }
}

#[derive(Debug, Clone, Copy)]
struct Comp<const C: usize> {
    w: f32,
    n: f32,
    mean: [f32; C],
    var: [f32; C],
}

impl<const C: usize> Default for Comp<C> {
    fn default() -> Self {
        Self {
            w: 0.0,
            n: 0.0,
            mean: [0.0; C],
            var: [0.0; C],
        }
    }
}

#[derive(Debug, Clone)]
enum State {
    Grey(Vec<Comp<1>>),
    Rgb(Vec<Comp<3>>),
}

/// One Gaussian of a pixel's mixture, for inspection.
#[derive(Debug, Clone, PartialEq)]
pub struct ComponentState {
    /// ω.
    pub weight: f32,
    /// μ per channel.
    pub mean: Vec<f32>,
    /// σ² per channel.
    pub variance: Vec<f32>,
    /// c: frames this component matched, counting the one that created it.
    pub matches: f32,
}

/// A per-pixel label image: [`BACKGROUND`], [`SHADOW`] or [`FOREGROUND`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ForegroundMask {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major labels.
    pub labels: Vec<u8>,
}

impl ForegroundMask {
    /// Pixels labelled foreground (shadows excluded).
    pub fn count_foreground(&self) -> usize {
        self.labels.iter().filter(|&&l| l == FOREGROUND).count()
    }

    /// Pixels labelled shadow.
    pub fn count_shadow(&self) -> usize {
        self.labels.iter().filter(|&&l| l == SHADOW).count()
    }
}

/// The background model of one camera: construct with [`BackgroundModel::new`], then feed
/// frames in order to [`BackgroundModel::apply`].
#[derive(Debug, Clone)]
pub struct BackgroundModel {
    params: Params,
    width: usize,
    height: usize,
    format: PixelFormat,
    state: State,
    used: Vec<u8>,
    n_frames: u64,
}

impl BackgroundModel {
    /// A model for frames of one size and format; checks the config.
    pub fn new(
        config: &MogConfig,
        width: usize,
        height: usize,
        format: PixelFormat,
    ) -> Result<Self> {
        let params = config.check()?;
        if width == 0 || height == 0 {
            return Err(Error::ZeroSize { width, height });
        }
        let n = width * height * params.k;
        let state = match format {
            PixelFormat::Grey => State::Grey(vec![Comp::default(); n]),
            PixelFormat::Rgb => State::Rgb(vec![Comp::default(); n]),
        };
        Ok(Self {
            params,
            width,
            height,
            format,
            state,
            used: vec![0; width * height],
            n_frames: 0,
        })
    }

    /// Frames seen so far (N).
    pub fn n_frames(&self) -> u64 {
        self.n_frames
    }

    /// Pixel (x, y)'s components in rank order (highest ω/σ first).
    pub fn components(&self, x: usize, y: usize) -> Vec<ComponentState> {
        let i = y * self.width + x;
        let (k, used) = (self.params.k, usize::from(self.used[i]));
        fn view<const C: usize>(c: &Comp<C>) -> ComponentState {
            ComponentState {
                weight: c.w,
                mean: c.mean.to_vec(),
                variance: c.var.to_vec(),
                matches: c.n,
            }
        }
        match &self.state {
            State::Grey(s) => s[i * k..i * k + used].iter().map(view).collect(),
            State::Rgb(s) => s[i * k..i * k + used].iter().map(view).collect(),
        }
    }

    /// Classifies a frame and updates the model with it.
    pub fn apply(&mut self, frame: &VideoFrame) -> Result<ForegroundMask> {
        let mut mask = ForegroundMask {
            width: self.width,
            height: self.height,
            labels: vec![0; self.width * self.height],
        };
        self.apply_into(frame, &mut mask)?;
        Ok(mask)
    }

    /// As [`apply`](Self::apply), writing into an existing mask of the right size.
    pub fn apply_into(&mut self, frame: &VideoFrame, mask: &mut ForegroundMask) -> Result<()> {
        if frame.width() != self.width
            || frame.height() != self.height
            || frame.format() != self.format
        {
            return Err(Error::FrameMismatch {
                width: frame.width(),
                height: frame.height(),
                channels: frame.channels(),
                expected_width: self.width,
                expected_height: self.height,
                expected_channels: self.format.channels(),
            });
        }
        mask.width = self.width;
        mask.height = self.height;
        mask.labels.resize(self.width * self.height, 0);
        // The phase switch of the paper: sufficient statistics while N < L, then the window.
        let phase1 = (self.n_frames as f32) < self.params.l;
        let rate_w = if phase1 {
            1.0 / (self.n_frames as f32 + 1.0)
        } else {
            1.0 / self.params.l
        };
        let (w, p) = (self.width, &self.params);
        match &mut self.state {
            State::Grey(s) => run_rows::<1>(
                s,
                &mut self.used,
                frame.data(),
                &mut mask.labels,
                w,
                rate_w,
                phase1,
                p,
            ),
            State::Rgb(s) => run_rows::<3>(
                s,
                &mut self.used,
                frame.data(),
                &mut mask.labels,
                w,
                rate_w,
                phase1,
                p,
            ),
        }
        self.n_frames += 1;
        Ok(())
    }
}

#[expect(clippy::too_many_arguments, reason = "internal kernel entry point")]
fn run_rows<const C: usize>(
    state: &mut [Comp<C>],
    used: &mut [u8],
    data: &[u8],
    labels: &mut [u8],
    width: usize,
    rate_w: f32,
    phase1: bool,
    p: &Params,
) {
    let k = p.k;
    state
        .par_chunks_mut(width * k)
        .zip(used.par_chunks_mut(width))
        .zip(data.par_chunks(width * C))
        .zip(labels.par_chunks_mut(width))
        .for_each(|(((st, us), row), out)| {
            for x in 0..width {
                out[x] = update_pixel::<C>(
                    &row[x * C..x * C + C],
                    &mut st[x * k..x * k + k],
                    &mut us[x],
                    rate_w,
                    phase1,
                    p,
                );
            }
        });
}

#[inline]
fn var_sum<const C: usize>(c: &Comp<C>) -> f32 {
    c.var.iter().sum()
}

/// Ranking key ω/√(Σσ²), compared squared to avoid the root (ω ≥ 0).
#[inline]
fn ranks_above<const C: usize>(a: &Comp<C>, b: &Comp<C>) -> bool {
    a.w * a.w * var_sum(b) > b.w * b.w * var_sum(a)
}

/// One pixel of one frame (KaewTraKulPong & Bowden 2001, §2): the matched or new component
/// updated, the order by ω/σ restored, and the pixel labelled by where its component falls
/// among the first B (background), or as a shadow of one of them.
#[inline]
fn update_pixel<const C: usize>(
    x: &[u8],
    comps: &mut [Comp<C>],
    used: &mut u8,
    rate_w: f32,
    phase1: bool,
    p: &Params,
) -> u8 {
    let mut xs = [0f32; C];
    for (v, &b) in xs.iter_mut().zip(x) {
        *v = f32::from(b);
    }
    let k = match first_match(&xs, &comps[..usize::from(*used)], p) {
        Some(k) => update_matched(&xs, comps, usize::from(*used), k, rate_w, phase1, p),
        None => replace_weakest(&xs, comps, used, p),
    };
    let nu = usize::from(*used);
    // Only component k changed its key relative to the others (the rest were scaled alike),
    // so one bubble pass either way restores the order.
    let mut pos = k;
    while pos > 0 && ranks_above(&comps[pos], &comps[pos - 1]) {
        comps.swap(pos, pos - 1);
        pos -= 1;
    }
    while pos + 1 < nu && ranks_above(&comps[pos + 1], &comps[pos]) {
        comps.swap(pos, pos + 1);
        pos += 1;
    }
    let mut cum = 0.0;
    let mut b = nu;
    for (i, c) in comps[..nu].iter().enumerate() {
        cum += c.w;
        if cum > p.t {
            b = i + 1;
            break;
        }
    }
    if pos < b {
        BACKGROUND
    } else if p.shadows && is_shadow(&xs, &comps[..b], p) {
        SHADOW
    } else {
        FOREGROUND
    }
}

/// The first component (in ω/σ order) within λ standard deviations of `xs`.
#[inline]
#[expect(
    clippy::needless_range_loop,
    reason = "channel loops index x and μ together, as the equations do"
)]
fn first_match<const C: usize>(xs: &[f32; C], comps: &[Comp<C>], p: &Params) -> Option<usize> {
    comps.iter().position(|c| {
        let mut d2 = 0.0;
        for ch in 0..C {
            let d = xs[ch] - c.mean[ch];
            d2 += d * d;
        }
        d2 < p.lambda2 * var_sum(c)
    })
}

/// Weights towards the match k (the others towards 0), and k's mean and variance towards
/// `xs` at 1/n in the first L frames, 1/(L ω) after (the paper's two phases).
#[inline]
#[expect(
    clippy::needless_range_loop,
    reason = "channel loops index x, μ and σ² together, as the equations do"
)]
fn update_matched<const C: usize>(
    xs: &[f32; C],
    comps: &mut [Comp<C>],
    nu: usize,
    k: usize,
    rate_w: f32,
    phase1: bool,
    p: &Params,
) -> usize {
    for (i, c) in comps[..nu].iter_mut().enumerate() {
        let target = if i == k { 1.0 } else { 0.0 };
        c.w += (target - c.w) * rate_w;
    }
    let c = &mut comps[k];
    c.n += 1.0;
    let rho = if phase1 { 1.0 / c.n } else { 1.0 / (p.l * c.w) };
    for ch in 0..C {
        let d = xs[ch] - c.mean[ch];
        c.mean[ch] += rho * d;
        c.var[ch] = (c.var[ch] + rho * (d * d - c.var[ch])).max(p.var_min);
    }
    k
}

/// No match: a new component at `xs` (the last, weakest one replaced when all K are used),
/// weights renormalised; returns its index.
#[inline]
fn replace_weakest<const C: usize>(
    xs: &[f32; C],
    comps: &mut [Comp<C>],
    used: &mut u8,
    p: &Params,
) -> usize {
    let nu = usize::from(*used);
    let k = if nu < p.k {
        *used += 1;
        nu
    } else {
        nu - 1
    };
    comps[k] = Comp {
        w: p.w0,
        n: 1.0,
        mean: *xs,
        var: [p.var0; C],
    };
    let nu = usize::from(*used);
    let sum: f32 = comps[..nu].iter().map(|c| c.w).sum();
    for c in &mut comps[..nu] {
        c.w /= sum;
    }
    k
}

/// Whether `xs` is a shadow on one of the background components: a brightness ratio a in
/// [τ_lo, τ_hi] and a colour distance from a·μ within the shadow threshold.
#[inline]
#[expect(
    clippy::needless_range_loop,
    reason = "channel loops index x and μ together, as the equations do"
)]
fn is_shadow<const C: usize>(xs: &[f32; C], background: &[Comp<C>], p: &Params) -> bool {
    background.iter().any(|c| {
        let (mut xm, mut mm) = (0.0, 0.0);
        for ch in 0..C {
            xm += xs[ch] * c.mean[ch];
            mm += c.mean[ch] * c.mean[ch];
        }
        if mm <= 0.0 {
            return false;
        }
        let a = xm / mm;
        if !(a >= p.tau_lo && a <= p.tau_hi) {
            return false;
        }
        let mut cd2 = 0.0;
        for ch in 0..C {
            let d = xs[ch] - a * c.mean[ch];
            cd2 += d * d;
        }
        cd2 < p.cd2 * var_sum(c)
    })
}
