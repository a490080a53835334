//! Gap recovery: the trajectory of an object between the end of one track segment (A) and the
//! start of the next (B), by the goal-directed model or by a baseline.

use nalgebra::{Matrix2, Matrix2x4, Matrix4, Vector2, Vector4};
use serde::{Deserialize, Serialize};
use tracker_model::{ConstantVelocity2, CvNoise, Frame, TransitionModel, Vec2};

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

/// The motion and noise model GDT recovers with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GdtConfig {
    /// White-acceleration spectral density per frame (pixels² / frame³).
    pub accel_psd: f64,
    /// Position measurement variance per axis (pixels²); also the goal's Π.
    pub measurement_variance: f64,
    /// Prior velocity variance per axis at segment A's first frame.
    pub initial_velocity_variance: f64,
}

impl GdtConfig {
    /// The constant-velocity model (one frame per step) these settings describe.
    pub fn motion(&self) -> Result<ConstantVelocity2> {
        Ok(ConstantVelocity2::new(
            1.0,
            CvNoise::WhiteAcceleration { q: self.accel_psd },
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

/// Checks the two segments and returns the missing frames between them.
fn missing_frames(a: &[Observation], b: &[Observation]) -> Result<Vec<Frame>> {
    let (Some(last_a), Some(first_b)) = (a.last(), b.first()) else {
        return Err(Error::Invalid(
            "both segments need at least one observation".into(),
        ));
    };
    for seg in [a, b] {
        if seg.windows(2).any(|w| w[1].frame <= w[0].frame) {
            return Err(Error::Invalid(
                "segment frames must strictly increase".into(),
            ));
        }
        if seg
            .iter()
            .any(|o| !(o.position.x.is_finite() && o.position.y.is_finite()))
        {
            return Err(Error::Invalid("segment positions must be finite".into()));
        }
    }
    if first_b.frame <= last_a.frame + 1 {
        return Err(Error::Invalid(format!(
            "segment B starts at frame {}, so nothing is missing after frame {}",
            first_b.frame, last_a.frame
        )));
    }
    Ok((last_a.frame + 1..first_b.frame).collect())
}

/// Recovers the gap with the goal-directed model: a Kalman filter over segment A (prior: its
/// first position with the measurement variance, zero velocity with
/// `initial_velocity_variance`) gives the state at A's last frame; the goal is B's first observation, T frames later; the conditioned
/// model's forward prediction gives the position and its covariance at every missing frame.
pub fn recover_gdt(a: &[Observation], b: &[Observation], cfg: &GdtConfig) -> Result<RecoveredGap> {
    let first_b = b
        .first()
        .ok_or_else(|| Error::Invalid("segment B is empty".into()))?;
    let goal = Goal {
        observation: Matrix2x4::identity(),
        value: first_b.position,
        covariance: Matrix2::identity() * cfg.measurement_variance,
    };
    recover_with_goal(a, b, cfg, &goal)
}

/// Beyond the seed: the goal is B's full state (position and velocity) at its first frame,
/// estimated by a Kalman filter run backwards in time over all of B, so the recovery also
/// knows the direction in which the object leaves the gap.
pub fn recover_gdt_goal_state(
    a: &[Observation],
    b: &[Observation],
    cfg: &GdtConfig,
) -> Result<RecoveredGap> {
    let last_b = b
        .last()
        .ok_or_else(|| Error::Invalid("segment B is empty".into()))?
        .frame;
    // Time reversal: frame f becomes last_b − f, and the velocity changes sign.
    let reversed: Vec<Observation> = b
        .iter()
        .rev()
        .map(|o| Observation {
            frame: last_b - o.frame,
            position: o.position,
        })
        .collect();
    let backward = end_state(&reversed, cfg)?;
    let flip = Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, -1.0, -1.0));
    let goal = Goal {
        observation: Matrix4::identity(),
        value: flip * backward.mean(),
        covariance: flip * backward.covariance() * flip,
    };
    recover_with_goal(a, b, cfg, &goal)
}

/// Filters A, conditions the constant-velocity model on `goal` at B's first frame and predicts
/// the missing frames.
fn recover_with_goal<const M: usize>(
    a: &[Observation],
    b: &[Observation],
    cfg: &GdtConfig,
    goal: &Goal<4, M>,
) -> Result<RecoveredGap> {
    let frames = missing_frames(a, b)?;
    let motion = cfg.motion()?;
    let start = end_state(a, cfg)?;
    let horizon = frames.len() + 1;
    let f = motion.transition_matrix(1);
    let q = motion.process_noise(1);
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
#[serde(rename_all = "snake_case")]
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
