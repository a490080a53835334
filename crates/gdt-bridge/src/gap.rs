//! Gap recovery: the trajectory of an object between the end of one track segment (A) and the
//! start of the next (B), by the goal-directed model or by a baseline.

use nalgebra::{Matrix2, Matrix2x4, Matrix4, Vector2, Vector4};
use serde::{Deserialize, Serialize};
use tracker_model::{
    ConstantVelocity2, CvNoise, Frame, Gaussian, PositionMeasurement2, TransitionModel, Vec2,
    ensure_non_negative, ensure_positive, position_measurement,
};

use crate::baselines::{
    BSpline, BSplineConfig, GcvConfig, SmoothingSpline, gap_knots, linear, lsq_bspline,
    natural_cubic_spline,
};
use crate::error::{Error, Result, invalid_parameter};
use crate::goal::{Goal, GoalDirected};
use crate::link::end_state;

/// A position observed at a frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    /// The frame.
    pub frame: Frame,
    /// Where the object was seen.
    pub position: Vec2,
}

/// The motion and noise model GDT recovers with; [`GdtConfig::check`] turns it into the
/// [`GdtModel`] every recovery and linking function takes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GdtConfig {
    /// White-acceleration spectral density per frame (pixels² / frame³).
    pub accel_psd: f64,
    /// Position measurement variance per axis (pixels²); also the goal's Π.
    pub measurement_variance: f64,
    /// Prior velocity variance per axis at segment A's first frame.
    pub initial_velocity_variance: f64,
}

impl GdtConfig {
    /// Checks every field and builds the models the settings describe: constant velocity
    /// with one frame per step, and a position measurement.
    pub fn check(&self) -> Result<GdtModel> {
        ensure_non_negative(self.accel_psd, "accel_psd")?;
        ensure_positive(self.measurement_variance, "measurement_variance")?;
        ensure_positive(self.initial_velocity_variance, "initial_velocity_variance")?;
        Ok(GdtModel {
            config: *self,
            motion: ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q: self.accel_psd })?,
            sensor: position_measurement(self.measurement_variance)?,
        })
    }
}

/// A checked [`GdtConfig`] with the models it describes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GdtModel {
    config: GdtConfig,
    motion: ConstantVelocity2,
    sensor: PositionMeasurement2,
}

impl GdtModel {
    /// The settings it was built from.
    pub fn config(&self) -> &GdtConfig {
        &self.config
    }

    /// Constant velocity, one frame per step.
    pub fn motion(&self) -> &ConstantVelocity2 {
        &self.motion
    }

    /// The position measurement (variance `measurement_variance` per axis).
    pub fn sensor(&self) -> &PositionMeasurement2 {
        &self.sensor
    }

    /// The prior of a segment's first state: its first position with the measurement
    /// variance, zero velocity with `initial_velocity_variance`.
    pub(crate) fn prior(&self, first: Vec2) -> Result<Gaussian<4>> {
        let cfg = &self.config;
        Ok(Gaussian::new(
            Vector4::new(first.x, first.y, 0.0, 0.0),
            Matrix4::from_diagonal(&Vector4::new(
                cfg.measurement_variance,
                cfg.measurement_variance,
                cfg.initial_velocity_variance,
                cfg.initial_velocity_variance,
            )),
        )?)
    }
}

impl Default for GdtConfig {
    fn default() -> Self {
        Self {
            accel_psd: 0.05,
            measurement_variance: 4.0,
            initial_velocity_variance: 25.0,
        }
    }
}

/// A recovered gap: a position (and, for GDT, a covariance) at every missing frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecoveredGap {
    /// The missing frames, ascending.
    pub frames: Vec<Frame>,
    /// Recovered positions.
    pub positions: Vec<Vec2>,
    /// Position covariances (GDT only; empty for the baselines).
    pub covariances: Vec<Matrix2<f64>>,
}

/// Checks that a segment's frames strictly increase.
pub(crate) fn check_frames(segment: &[Observation]) -> Result<()> {
    match segment.windows(2).find(|w| w[1].frame <= w[0].frame) {
        Some(w) => Err(Error::FramesOutOfOrder {
            frame: w[1].frame,
            last: w[0].frame,
        }),
        None => Ok(()),
    }
}

/// Checks that a segment's frames strictly increase and its positions are finite.
fn check_segment(segment: &[Observation]) -> Result<()> {
    check_frames(segment)?;
    match segment
        .iter()
        .find(|o| !(o.position.x.is_finite() && o.position.y.is_finite()))
    {
        Some(o) => Err(Error::NonFiniteObservation { frame: o.frame }),
        None => Ok(()),
    }
}

/// The longest gap any recovery accepts: 2²⁰ frames (about 41 hours at 7 fps). A recovery
/// returns a position per missing frame, so a longer gap (for instance a frame number near
/// `u32::MAX` in B) is refused with [`Error::GapTooLong`] rather than allocated.
pub const MAX_GAP_FRAMES: u32 = 1 << 20;

/// Checks the two segments and returns the missing frames between them.
fn missing_frames(a: &[Observation], b: &[Observation]) -> Result<Vec<Frame>> {
    let (Some(last_a), Some(first_b)) = (a.last(), b.first()) else {
        return Err(Error::SegmentTooShort { len: 0, min: 1 });
    };
    for seg in [a, b] {
        check_segment(seg)?;
    }
    // Compared without `last_a + 1`, which overflows at u32::MAX.
    if first_b.frame <= last_a.frame || first_b.frame - last_a.frame < 2 {
        return Err(Error::NoGap {
            last_a: last_a.frame,
            first_b: first_b.frame,
        });
    }
    let n_missing = first_b.frame - last_a.frame - 1;
    if n_missing > MAX_GAP_FRAMES {
        return Err(Error::GapTooLong {
            frames: u64::from(n_missing),
            max: MAX_GAP_FRAMES,
        });
    }
    Ok((last_a.frame + 1..first_b.frame).collect())
}

/// Recovers the gap with the goal-directed model: a Kalman filter over segment A (prior: its
/// first position with the measurement variance, zero velocity with
/// `initial_velocity_variance`) gives the state at A's last frame; the goal is B's first
/// observation, T frames later; the conditioned model's forward prediction gives the position
/// and its covariance at every missing frame.
///
/// ```
/// use gdt_bridge::{GdtConfig, Observation, recover_gdt};
/// use tracker_model::Vec2;
///
/// let seen = |frame: u32| Observation { frame, position: Vec2::new(f64::from(frame), 5.0) };
/// let (a, b): (Vec<_>, Vec<_>) = ((0..5).map(seen).collect(), (8..12).map(seen).collect());
/// let gap = recover_gdt(&a, &b, &GdtConfig::default().check()?)?;
/// assert_eq!(gap.frames, [5, 6, 7]);
/// # Ok::<(), gdt_bridge::Error>(())
/// ```
pub fn recover_gdt(a: &[Observation], b: &[Observation], model: &GdtModel) -> Result<RecoveredGap> {
    let first_b = b.first().ok_or(Error::SegmentTooShort { len: 0, min: 1 })?;
    let goal = Goal {
        observation: Matrix2x4::identity(),
        value: first_b.position,
        covariance: Matrix2::identity() * model.config.measurement_variance,
    };
    recover_with_goal(a, b, model, &goal)
}

/// Beyond Oh & Jung (2015): the goal is B's full state (position and velocity) at its first frame,
/// estimated by a Kalman filter run backwards in time over all of B, so the recovery also
/// knows the direction in which the object leaves the gap.
pub fn recover_gdt_goal_state(
    a: &[Observation],
    b: &[Observation],
    model: &GdtModel,
) -> Result<RecoveredGap> {
    let last_b = b
        .last()
        .ok_or(Error::SegmentTooShort { len: 0, min: 1 })?
        .frame;
    // B's frames must increase before they are reversed below.
    check_frames(b)?;
    // Time reversal: frame f becomes last_b − f, and the velocity changes sign.
    let reversed: Vec<Observation> = b
        .iter()
        .rev()
        .map(|o| Observation {
            frame: last_b - o.frame,
            position: o.position,
        })
        .collect();
    let backward = end_state(&reversed, model)?;
    let flip = Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, -1.0, -1.0));
    let goal = Goal {
        observation: Matrix4::identity(),
        value: flip * backward.mean(),
        covariance: flip * backward.covariance() * flip,
    };
    recover_with_goal(a, b, model, &goal)
}

/// Filters A, conditions the constant-velocity model on `goal` at B's first frame and predicts
/// the missing frames.
fn recover_with_goal<const M: usize>(
    a: &[Observation],
    b: &[Observation],
    model: &GdtModel,
    goal: &Goal<4, M>,
) -> Result<RecoveredGap> {
    let frames = missing_frames(a, b)?;
    let start = end_state(a, model)?;
    let horizon = frames.len() + 1;
    let f = model.motion.transition_matrix(1);
    let q = model.motion.process_noise(1);
    let model = GoalDirected::new(&vec![f; horizon], &vec![q; horizon], goal, &start)?;
    let moments = model.predict();
    let hidden = &moments[1..horizon];
    Ok(RecoveredGap {
        positions: hidden
            .iter()
            .map(|m| Vector2::new(m.mean[0], m.mean[1]))
            .collect(),
        covariances: hidden
            .iter()
            .map(|m| m.covariance.fixed_view::<2, 2>(0, 0).into_owned())
            .collect(),
        frames,
    })
}

/// The interpolation baselines. Their tuning (λ, the window) is chosen per gap from the
/// observed frames only, never from the hidden positions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum Baseline {
    /// A straight line from A's last to B's first observation.
    Linear,
    /// A natural cubic spline through every observation of both segments (a knot at every
    /// observation; it interpolates the noise).
    NaturalCubicSpline,
    /// A least-squares cubic B-spline over both segments (unit weights) on Oh & Jung's knot
    /// rule, [`gap_knots`].
    LeastSquaresBSpline(BSplineConfig),
    /// The cubic smoothing spline over every observation of both segments, per axis, with λ
    /// chosen by generalized cross-validation ([`SmoothingSpline::fit_gcv`]).
    SmoothingSpline(GcvConfig),
    /// A least-squares cubic polynomial through the last n observations of A and the first n
    /// of B, per axis, n chosen by cross-validation on the observations ([`WindowConfig`]).
    WindowCubic(WindowConfig),
    /// A least-squares cubic B-spline on the last n observations of A and the first n of B,
    /// per axis, with clamped knots at the window's ends and two interior knots at A's last
    /// and B's first frame (so the gap is one cubic piece joined C² to one piece per side);
    /// n chosen by cross-validation ([`WindowConfig`]).
    WindowBSpline(WindowConfig),
}

/// The window sizes the window fits choose from, per gap, by cross-validation on the
/// observations. Pseudo-gaps of the real gap's length L are cut inside each segment (every
/// ⌈L/2⌉ observations, wherever at least the fit's minimum is left on both sides); each
/// candidate n is fitted to the n observations before and after each pseudo-gap (fewer where
/// the segment ends) and scored by its squared error on the hidden observations, summed over
/// all pseudo-gaps; the least wins (ties: the earlier candidate). When neither segment is long
/// enough for a pseudo-gap, the ⌈L/2⌉ observations of each segment nearest the gap are held
/// out instead, and when that is impossible too, the first usable candidate is taken.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WindowConfig {
    /// Candidate numbers of observations per side.
    pub candidates: Vec<usize>,
}

impl Default for WindowConfig {
    fn default() -> Self {
        Self {
            candidates: vec![3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50, 70, 100],
        }
    }
}

/// Which window fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum WindowKind {
    Cubic,
    BSpline,
}

impl WindowKind {
    /// The fewest observations per side for which the fit is determined (Schoenberg-Whitney):
    /// the B-spline's 6 coefficients need 3 per side, the cubic's 4 need 2.
    fn min_per_side(self) -> usize {
        match self {
            WindowKind::Cubic => 2,
            WindowKind::BSpline => 3,
        }
    }
}

/// Fits a window of `n` observations per side and predicts both axes at `at`.
fn window_predict(
    a: &[Observation],
    b: &[Observation],
    n: usize,
    kind: WindowKind,
    at: &[f64],
) -> Result<[Vec<f64>; 2]> {
    let wa = &a[a.len().saturating_sub(n)..];
    let wb = &b[..n.min(b.len())];
    let (Some(first), Some(last_a), Some(first_b), Some(last)) =
        (wa.first(), wa.last(), wb.first(), wb.last())
    else {
        return Err(Error::SegmentTooShort { len: 0, min: 1 });
    };
    let (t0, t1) = (f64::from(first.frame), f64::from(last.frame));
    let mut knots = vec![t0; 4];
    if kind == WindowKind::BSpline {
        knots.extend([f64::from(last_a.frame), f64::from(first_b.frame)]);
    }
    knots.extend([t1; 4]);
    let samples: Vec<&Observation> = wa.iter().chain(wb).collect();
    let times: Vec<f64> = samples.iter().map(|o| f64::from(o.frame)).collect();
    let weights = vec![1.0; times.len()];
    let axis = |k: usize| -> Result<Vec<f64>> {
        let values: Vec<f64> = samples.iter().map(|o| o.position[k]).collect();
        let spline = BSpline::fit_lsq(&times, &values, &weights, &knots)?;
        Ok(at.iter().map(|&x| spline.value(x)).collect())
    };
    Ok([axis(0)?, axis(1)?])
}

/// The cross-validation folds of a gap of `n_missing` frames (see [`WindowConfig`]).
fn cv_folds<'a>(
    a: &'a [Observation],
    b: &'a [Observation],
    n_missing: usize,
    min: usize,
) -> Vec<Fold<'a>> {
    let mut folds: Vec<Fold<'a>> = Vec::new();
    let len = n_missing.max(1);
    let stride = len.div_ceil(2);
    // Pseudo-gaps of the same length inside each segment.
    for seg in [a, b] {
        let mut start = min;
        while start + len + min <= seg.len() {
            let (before, rest) = seg.split_at(start);
            let (hidden, after) = rest.split_at(len);
            folds.push((before, hidden, &hidden[..0], after));
            start += stride;
        }
    }
    if folds.is_empty() {
        // Hold out the observations nearest the real gap instead.
        let hold = len
            .div_ceil(2)
            .min(a.len().saturating_sub(min))
            .min(b.len().saturating_sub(min));
        if hold > 0 {
            let (fit_a, held_a) = a.split_at(a.len() - hold);
            let (held_b, fit_b) = b.split_at(hold);
            folds.push((fit_a, held_a, held_b, fit_b));
        }
    }
    folds
}

/// A cross-validation fold: observations fitted before, held out (in one or two runs), fitted
/// after.
type Fold<'a> = (
    &'a [Observation],
    &'a [Observation],
    &'a [Observation],
    &'a [Observation],
);

/// The cross-validation error of each candidate window of a window fit (`method` must be
/// [`Baseline::WindowCubic`] or [`Baseline::WindowBSpline`]) on the gap between `a` and `b`:
/// the Euclidean error (the error the recovery is judged by) summed over the held-out
/// observations of every fold (see [`WindowConfig`]), `None` for a candidate too small for the
/// fit or that some fold's data cannot determine. All zero when there is no fold. Summing
/// these over the gaps of a scene chooses one window for the scene from its observations.
pub fn window_cv_errors(
    a: &[Observation],
    b: &[Observation],
    method: &Baseline,
) -> Result<Vec<Option<f64>>> {
    let (kind, config) = match method {
        Baseline::WindowCubic(config) => (WindowKind::Cubic, config),
        Baseline::WindowBSpline(config) => (WindowKind::BSpline, config),
        _ => {
            return Err(invalid_parameter(
                "method",
                format!("{method:?} has no window to cross-validate"),
            ));
        }
    };
    let frames = missing_frames(a, b)?;
    Ok(cv_errors(a, b, frames.len(), kind, config))
}

/// [`window_cv_errors`] for a checked gap.
fn cv_errors(
    a: &[Observation],
    b: &[Observation],
    n_missing: usize,
    kind: WindowKind,
    config: &WindowConfig,
) -> Vec<Option<f64>> {
    let min = kind.min_per_side();
    let folds = cv_folds(a, b, n_missing, min);
    config
        .candidates
        .iter()
        .map(|&n| {
            if n < min {
                return None;
            }
            let mut total = 0.0;
            for (before, held_1, held_2, after) in &folds {
                let held: Vec<&Observation> = held_1.iter().chain(held_2.iter()).collect();
                let at: Vec<f64> = held.iter().map(|o| f64::from(o.frame)).collect();
                let [xs, ys] = window_predict(before, after, n, kind, &at).ok()?;
                total += held
                    .iter()
                    .zip(xs.iter().zip(&ys))
                    .map(|(o, (x, y))| (o.position.x - x).hypot(o.position.y - y))
                    .sum::<f64>();
            }
            Some(total)
        })
        .collect()
}

/// The window size cross-validation picks for a gap of `n_missing` frames (see
/// [`WindowConfig`]): the candidate with the least error (ties: the earlier one), the first
/// usable candidate when there is no fold.
fn choose_window(
    a: &[Observation],
    b: &[Observation],
    n_missing: usize,
    kind: WindowKind,
    config: &WindowConfig,
) -> Result<usize> {
    let min = kind.min_per_side();
    if !config.candidates.iter().any(|&n| n >= min) {
        return Err(invalid_parameter(
            "candidates",
            format!(
                "{:?}: the window fit needs a candidate of at least {min} observations per side",
                config.candidates
            ),
        ));
    }
    let errors = cv_errors(a, b, n_missing, kind, config);
    let mut best: Option<(usize, f64)> = None;
    for (&n, e) in config.candidates.iter().zip(errors) {
        if let Some(e) = e
            && best.is_none_or(|(_, b)| e < b)
        {
            best = Some((n, e));
        }
    }
    best.map(|(n, _)| n).ok_or(Error::RankDeficientFit)
}

/// Recovers the gap with a baseline, per coordinate.
pub fn recover_baseline(
    a: &[Observation],
    b: &[Observation],
    method: &Baseline,
) -> Result<RecoveredGap> {
    let frames = missing_frames(a, b)?;
    let samples: Vec<&Observation> = a.iter().chain(b).collect();
    let times: Vec<f64> = samples.iter().map(|o| f64::from(o.frame)).collect();
    let at: Vec<f64> = frames.iter().map(|&f| f64::from(f)).collect();
    let values = |axis: usize| -> Vec<f64> { samples.iter().map(|o| o.position[axis]).collect() };
    let per_axis = |fit: &dyn Fn(&[f64]) -> Result<Vec<f64>>| -> Result<[Vec<f64>; 2]> {
        Ok([fit(&values(0))?, fit(&values(1))?])
    };
    let [xs, ys] = match method {
        Baseline::Linear => {
            let (la, fb) = (a[a.len() - 1], b[0]);
            let ends = [f64::from(la.frame), f64::from(fb.frame)];
            let axis = |k: usize| linear(&ends, &[la.position[k], fb.position[k]], &at);
            [axis(0)?, axis(1)?]
        }
        Baseline::NaturalCubicSpline => per_axis(&|v| natural_cubic_spline(&times, v, &at))?,
        Baseline::LeastSquaresBSpline(cfg) => {
            let gap = (f64::from(a[a.len() - 1].frame), f64::from(b[0].frame));
            let knots = gap_knots(&times, gap, cfg.interior_knots_per_side);
            let weights = vec![1.0; times.len()];
            per_axis(&|v| lsq_bspline(&times, v, &weights, &knots, &at))?
        }
        Baseline::SmoothingSpline(cfg) => per_axis(&|v| {
            let spline = SmoothingSpline::fit_gcv(&times, v, cfg)?;
            Ok(at.iter().map(|&x| spline.value(x)).collect())
        })?,
        Baseline::WindowCubic(cfg) => {
            let n = choose_window(a, b, frames.len(), WindowKind::Cubic, cfg)?;
            window_predict(a, b, n, WindowKind::Cubic, &at)?
        }
        Baseline::WindowBSpline(cfg) => {
            let n = choose_window(a, b, frames.len(), WindowKind::BSpline, cfg)?;
            window_predict(a, b, n, WindowKind::BSpline, &at)?
        }
    };
    Ok(RecoveredGap {
        frames,
        positions: xs
            .into_iter()
            .zip(ys)
            .map(|(x, y)| Vector2::new(x, y))
            .collect(),
        covariances: Vec::new(),
    })
}
