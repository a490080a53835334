//! The radar trackers compared on real traffic: GNN on plots ([`mcmcda::PlotGnn`]) with a
//! constant-velocity filter, a coordinated turn with its rate in the state (EKF or UKF), and
//! two IMMs: CV with two known-rate turns either way (Li & Jilkov 2005, "Survey of maneuvering
//! target tracking, Part V", §3: the standard three-model set), and straight flight with the
//! turn-rate model in the five-component layout.

use mcmcda::{PlotGnn, PlotGnnConfig};
use serde::{Deserialize, Serialize};
use tracker_model::{
    ConstantVelocity2, ConstantVelocityTurnLayout, CoordinatedTurn, CoordinatedTurnRate, CvNoise,
    GaussianFilter, Imm, Mode, SigmaPoints, SingleModel, StateEstimator, TrackSet, TurnNoise,
};

use crate::error::Result;
use crate::radar::{RadarDwell, RotatingRadar};
use crate::tracking::{KinematicScore, ScoreConfig, TruthPoint, score, track_dwells, track_set};
use crate::trajectory::Trajectory;
use mcmcda::BirthPrior;

/// Which tracker.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RadarTracker {
    /// Constant velocity, [e, n, ė, ṅ], EKF (linear motion, range-bearing plots).
    Cv,
    /// Coordinated turn with the rate in the state, [e, n, ė, ṅ, ω], EKF.
    Ct,
    /// The same through the UKF.
    CtUkf,
    /// IMM of CV and known-rate turns at ±ω₀, EKF.
    ImmCvTurns,
    /// IMM of straight flight and the turn-rate model, five components, EKF.
    ImmTurnRate,
}

impl RadarTracker {
    /// Every tracker, in the report's order.
    pub const ALL: [RadarTracker; 5] = [
        RadarTracker::Cv,
        RadarTracker::Ct,
        RadarTracker::CtUkf,
        RadarTracker::ImmCvTurns,
        RadarTracker::ImmTurnRate,
    ];

    /// A short key for metrics.
    pub fn key(self) -> &'static str {
        match self {
            RadarTracker::Cv => "cv",
            RadarTracker::Ct => "ct",
            RadarTracker::CtUkf => "ct_ukf",
            RadarTracker::ImmCvTurns => "imm_cv_turns",
            RadarTracker::ImmTurnRate => "imm_turn_rate",
        }
    }

    /// Its name in tables.
    pub fn name(self) -> &'static str {
        match self {
            RadarTracker::Cv => "GNN + CV (EKF)",
            RadarTracker::Ct => "GNN + CT, ω in state (EKF)",
            RadarTracker::CtUkf => "GNN + CT, ω in state (UKF)",
            RadarTracker::ImmCvTurns => "GNN + IMM CV / CT ±ω₀ (EKF)",
            RadarTracker::ImmTurnRate => "GNN + IMM CV / CT ω in state (EKF)",
        }
    }
}

/// The motion settings every tracker draws on; `q_accel` is the one tuned.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionSettings {
    /// White-acceleration spectral density per axis, (m/s²)²·s.
    pub q_accel: f64,
    /// The turn rate's random-walk density, (rad/s)²/s.
    pub q_turn: f64,
    /// The known-rate IMM's turn rate ω₀, rad/s.
    pub imm_turn_rate_rad_s: f64,
    /// The three-mode IMM's switching matrix (CV, +ω₀, −ω₀) and its start.
    pub switching_cv_turns: [[f64; 3]; 3],
    /// The two-mode IMM's switching matrix (straight, turning) and its start.
    pub switching_turn_rate: [[f64; 2]; 2],
    /// The UKF's sigma points.
    pub sigma_points: SigmaPoints,
}

/// What one tracker did on one radar run.
#[derive(Debug, Clone)]
pub struct TrackerOutcome {
    /// Errors and breaks against the truth.
    pub score: KinematicScore,
    /// Its tracks, one point per revolution.
    pub tracks: TrackSet,
    /// Births refused for want of room.
    pub births_refused: u64,
}

/// What a run needs besides the tracker.
#[derive(Clone, Copy)]
pub struct RadarScene<'a> {
    /// The radar.
    pub radar: &'a RotatingRadar,
    /// Its dwells.
    pub dwells: &'a [RadarDwell],
    /// The aircraft.
    pub trajectories: &'a [Trajectory],
    /// The aircraft in view per revolution ([`crate::truth_points`]).
    pub truth: &'a [TruthPoint],
    /// How tracks start.
    pub birth: BirthPrior,
    /// How they are scored.
    pub score: ScoreConfig,
}

fn cv(q: f64) -> Result<ConstantVelocity2> {
    Ok(ConstantVelocity2::new(
        1.0,
        CvNoise::WhiteAcceleration { q },
    )?)
}

fn run_with<E: StateEstimator<N>, const N: usize>(
    estimator: E,
    gnn: PlotGnnConfig,
    scene: &RadarScene<'_>,
) -> Result<TrackerOutcome> {
    let mut tracker = PlotGnn::new(estimator, gnn)?;
    let run = track_dwells(&mut tracker, scene.radar, scene.dwells, scene.birth)?;
    Ok(TrackerOutcome {
        score: score(scene.trajectories, scene.truth, &run, &scene.score),
        tracks: track_set(&run)?,
        births_refused: run.births_refused,
    })
}

/// The CV filter of [`RadarTracker::Cv`].
pub(crate) fn cv_estimator(motion: &MotionSettings) -> Result<SingleModel<ConstantVelocity2>> {
    Ok(SingleModel {
        motion: cv(motion.q_accel)?,
        filter: GaussianFilter::Extended,
    })
}

/// The turn-rate filter of [`RadarTracker::Ct`] (EKF) or [`RadarTracker::CtUkf`].
pub(crate) fn ct_estimator(
    motion: &MotionSettings,
    unscented: bool,
) -> Result<SingleModel<CoordinatedTurnRate>> {
    let filter = if unscented {
        GaussianFilter::Unscented(motion.sigma_points)
    } else {
        GaussianFilter::Extended
    };
    Ok(SingleModel {
        motion: CoordinatedTurnRate::new(turn_noise(motion))?,
        filter,
    })
}

fn turn_noise(motion: &MotionSettings) -> TurnNoise {
    TurnNoise {
        q_accel: motion.q_accel,
        q_turn: motion.q_turn,
    }
}

/// The IMM of [`RadarTracker::ImmCvTurns`].
pub(crate) fn imm_cv_turns(motion: &MotionSettings) -> Result<Imm<4>> {
    let w = motion.imm_turn_rate_rad_s;
    let modes: Vec<Mode<4>> = vec![
        Box::new(cv(motion.q_accel)?),
        Box::new(CoordinatedTurn::new(w, motion.q_accel)?),
        Box::new(CoordinatedTurn::new(-w, motion.q_accel)?),
    ];
    imm_with(modes, &motion.switching_cv_turns)
}

/// The IMM of [`RadarTracker::ImmTurnRate`].
fn imm_turn_rate(motion: &MotionSettings) -> Result<Imm<5>> {
    let noise = turn_noise(motion);
    let modes: Vec<Mode<5>> = vec![
        Box::new(ConstantVelocityTurnLayout::new(noise)?),
        Box::new(CoordinatedTurnRate::new(noise)?),
    ];
    imm_with(modes, &motion.switching_turn_rate)
}

/// An EKF IMM over `modes` with this switching matrix, starting from its stationary
/// distribution.
fn imm_with<const N: usize, const R: usize>(
    modes: Vec<Mode<N>>,
    switching: &[[f64; R]; R],
) -> Result<Imm<N>> {
    let rows: Vec<Vec<f64>> = switching.iter().map(|r| r.to_vec()).collect();
    Ok(Imm::new(modes, &rows, GaussianFilter::Extended)?
        .with_start_probabilities(&stationary(switching))?)
}

/// Runs `tracker` with `motion` and `gnn` on `scene`.
pub fn run_tracker(
    tracker: RadarTracker,
    motion: &MotionSettings,
    gnn: PlotGnnConfig,
    scene: &RadarScene<'_>,
) -> Result<TrackerOutcome> {
    match tracker {
        RadarTracker::Cv => run_with(cv_estimator(motion)?, gnn, scene),
        RadarTracker::Ct => run_with(ct_estimator(motion, false)?, gnn, scene),
        RadarTracker::CtUkf => run_with(ct_estimator(motion, true)?, gnn, scene),
        RadarTracker::ImmCvTurns => run_with(imm_cv_turns(motion)?, gnn, scene),
        RadarTracker::ImmTurnRate => run_with(imm_turn_rate(motion)?, gnn, scene),
    }
}

/// The switching chain's stationary distribution (power iteration from uniform): how often
/// each mode holds in the long run, the natural start for a target seen for the first time.
fn stationary<const R: usize>(switching: &[[f64; R]; R]) -> Vec<f64> {
    let mut p = vec![1.0 / R as f64; R];
    for _ in 0..10_000 {
        let next: Vec<f64> = (0..R)
            .map(|j| (0..R).map(|i| p[i] * switching[i][j]).sum())
            .collect();
        let change: f64 = next.iter().zip(&p).map(|(a, b)| (a - b).abs()).sum();
        p = next;
        if change < 1e-15 {
            break;
        }
    }
    let total: f64 = p.iter().sum();
    p.iter().map(|v| v / total).collect()
}
