//! Gap recovery: the trajectory of an object between the end of one track segment (A) and the
//! start of the next (B), by the goal-directed model or by a baseline.

use nalgebra::{Matrix2, Matrix2x4, Matrix4, Vector2, Vector4};
use serde::{Deserialize, Serialize};
use tracker_model::{
    ConstantVelocity2, CvNoise, Frame, Gaussian, PositionMeasurement2, TransitionModel, Vec2,
    ensure_non_negative, ensure_positive, position_measurement,
};

use crate::baselines::{BSplineConfig, linear, lsq_bspline, natural_cubic_spline};
use crate::error::{Error, Result};
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

/// Checks the two segments and returns the missing frames between them.
fn missing_frames(a: &[Observation], b: &[Observation]) -> Result<Vec<Frame>> {
    let (Some(last_a), Some(first_b)) = (a.last(), b.first()) else {
        return Err(Error::SegmentTooShort { len: 0, min: 1 });
    };
    for seg in [a, b] {
        check_segment(seg)?;
    }
    if first_b.frame <= last_a.frame + 1 {
        return Err(Error::NoGap {
            last_a: last_a.frame,
            first_b: first_b.frame,
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

/// The interpolation baselines.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum Baseline {
    /// A straight line from A's last to B's first observation.
    Linear,
    /// A natural cubic spline through every observation of both segments.
    NaturalCubicSpline,
    /// A least-squares cubic B-spline over both segments (unit weights).
    LeastSquaresBSpline(BSplineConfig),
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
    let coordinate = |axis: usize| -> Result<Vec<f64>> {
        let values: Vec<f64> = samples.iter().map(|o| o.position[axis]).collect();
        match method {
            Baseline::Linear => {
                let (la, fb) = (a[a.len() - 1], b[0]);
                linear(
                    &[f64::from(la.frame), f64::from(fb.frame)],
                    &[la.position[axis], fb.position[axis]],
                    &at,
                )
            }
            Baseline::NaturalCubicSpline => natural_cubic_spline(&times, &values, &at),
            Baseline::LeastSquaresBSpline(cfg) => {
                let gap = (f64::from(a[a.len() - 1].frame), f64::from(b[0].frame));
                lsq_bspline(&times, &values, &vec![1.0; times.len()], gap, cfg, &at)
            }
        }
    };
    let (xs, ys) = (coordinate(0)?, coordinate(1)?);
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
