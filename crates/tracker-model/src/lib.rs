//! # tracker-model
//!
//! The shared vocabulary of the tracking toolkit; every algorithm crate speaks it and nothing
//! here touches files, the clock or the terminal.
//!
//! * [`Gaussian`] states, [`TransitionModel`] / [`ObservationModel`] traits whose default
//!   methods give prediction and the Joseph-form Kalman update, [`filter`] over a sequence with
//!   missing measurements and the Rauch-Tung-Striebel [`smooth`]er; [`anees_interval_95`] for
//!   consistency checks.
//! * Models: [`ConstantVelocity2`] (white-acceleration or the MCMCDA paper's G-matrix noise,
//!   exact over a gap of k scans), [`RandomWalk`], [`LinearTransition`], [`LinearObservation`]
//!   with position-only and full-state shortcuts.
//! * Nonlinear models and filters, in seconds: [`MotionModel`] / [`MeasurementModel`]
//!   (f, h, Jacobians, angle-aware residuals and means); [`GaussianFilter`]: the EKF (the Kalman
//!   filter on linear models) and the UKF with scaled [`SigmaPoints`]; [`CoordinatedTurn`]
//!   (known rate), [`CoordinatedTurnRate`] (rate in the state), [`ConstantVelocityTurnLayout`],
//!   [`ConstantVelocity3`]; radar plots [`RangeBearing`] and [`RangeBearingElevation`]; the
//!   [`Imm`]; and [`StateEstimator`], one interface over [`SingleModel`] and [`Imm`] for
//!   trackers. All equal filterpy 2.0.0 to 1e-9 (`tests/filterpy_reference.rs`).
//! * Geometry: [`Region`] (with its volume V), [`BoundingBox`] with IoU, [`bearing_rad`].
//! * [`LikelihoodGrid`]: normalisation, weighted-sum and product fusion, peak extraction;
//!   [`BearingProfile`]s (audio beamforms, video angle profiles) at a [`SensorPose`] projected
//!   onto a grid.
//! * [`Scan`]s of [`Measurement`]s with their hidden [`Origin`], and the [`Track`] /
//!   [`TrackSet`] output type that every tracker returns and every metric reads.
//! * The MCMCDA scenario [`SimulationConfig`] → [`Simulator`] (Oh, Russell & Sastry 2009).
//! * The one tracker interface: [`Detection`] in; [`Tracker`] (step by frame, then finish)
//!   or [`BatchTracker`] (a whole window); [`Online`] runs the first as the second.
//! * MOTChallenge rows: [`parse_mot`], [`format_mot`], conversions to and from [`TrackSet`].
//! * [`assignment`]: optimal one-to-one matching (SciPy's solver, via `lsap`).
//! * [`LocalDetector`] / [`LocalDetectorFactory`]: the interface of per-object detectors
//!   trained online, shared by trackers (phd-filter) and detectors (sensors-video).
//!
//! Filtering and smoothing your own position measurements (one per second, one missing):
//!
//! ```
//! use nalgebra::{Matrix4, Vector2, Vector4};
//! use tracker_model::{ConstantVelocity2, CvNoise, Gaussian, filter, position_measurement, smooth};
//!
//! let xy = |x, y| Some(Vector2::new(x, y));
//! let positions = [xy(0.1, -0.1), xy(1.0, 0.6), None, xy(2.9, 1.4), xy(4.1, 2.0)];
//! let motion = ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q: 0.01 })?;
//! let sensor = position_measurement(0.25)?; // σ = 0.5 per axis
//! let prior = Gaussian::new(Vector4::new(0.0, 0.0, 1.0, 0.5), Matrix4::identity() * 10.0)?;
//! let run = filter(&motion, &sensor, &prior, &positions)?;
//! let smoothed = smooth(&motion, &run)?;
//! // The missed second is filled in between its neighbours, close to (2, 1).
//! let gap = smoothed[2].mean();
//! assert!((gap[0] - 2.0).abs() < 0.3 && (gap[1] - 1.0).abs() < 0.3);
//! # Ok::<(), tracker_model::Error>(())
//! ```
//!
//! An aircraft turning at 3°/s seen by a radar, through an IMM of straight flight and the
//! turn-rate model, each mode an EKF:
//!
//! ```
//! use nalgebra::{SMatrix, SVector, Vector2};
//! use tracker_model::{
//!     ConstantVelocityTurnLayout, CoordinatedTurnRate, Gaussian, GaussianFilter, Imm, Mode,
//!     MeasurementModel, MotionModel, RangeBearing, TurnNoise,
//! };
//!
//! let noise = TurnNoise { q_accel: 1.0, q_turn: 1e-5 };
//! let modes: Vec<Mode<5>> = vec![
//!     Box::new(ConstantVelocityTurnLayout::new(noise)?),
//!     Box::new(CoordinatedTurnRate::new(noise)?),
//! ];
//! let switching = [vec![0.95, 0.05], vec![0.10, 0.90]];
//! let imm = Imm::new(modes, &switching, GaussianFilter::Extended)?;
//! let radar = RangeBearing::<5>::at([0.0, 0.0], 30.0, 0.002)?;
//! let turn = CoordinatedTurnRate::new(TurnNoise { q_accel: 0.0, q_turn: 0.0 })?;
//! let mut truth = SVector::<f64, 5>::new(-20_000.0, 5_000.0, 200.0, 0.0, 3f64.to_radians());
//! let prior = Gaussian::new(truth, SMatrix::<f64, 5, 5>::from_diagonal(
//!     &SVector::<f64, 5>::new(1e4, 1e4, 400.0, 400.0, 1e-3)))?;
//! let mut belief = imm.start(prior, &[0.5, 0.5])?;
//! for _ in 0..15 {
//!     truth = turn.propagate(&truth, 4.0);
//!     let z: Vector2<f64> = radar.measure(&truth); // noise-free plots, for the example
//!     belief = imm.update(&radar, &imm.predict(&belief, 4.0)?, &z)?.state;
//! }
//! // The turning mode takes over.
//! assert!(belief.probabilities()[1] > 0.9);
//! # Ok::<(), tracker_model::Error>(())
//! ```
//!
//! Invariants: a [`Gaussian`] always has a finite mean and a symmetric positive-definite
//! covariance; a failed factorisation is an [`Error`], never a panic; randomness comes only from
//! the generator the caller passes in.

pub mod assignment;
mod bearing;
mod consistency;
mod detector;
mod error;
mod estimator;
mod gaussian;
mod geometry;
mod grid;
mod imm;
mod kalman;
pub mod matrix_rows;
mod models;
mod mot;
mod motion;
mod nonlinear;
mod radar;
mod simulate;
mod track;
mod tracking;

#[cfg(test)]
mod tests;

pub use bearing::{BearingProfile, GridNormalisation, ProjectionConfig, SensorPose};
pub use consistency::{GATE_CHI2_2D, anees_interval_95, chi_square_quantile_wh};
pub use detector::{LocalDetector, LocalDetectorFactory};
pub use error::{
    Error, Result, ensure_in_range, ensure_non_negative, ensure_open_probability, ensure_positive,
};
pub use estimator::{Scored, SingleModel, StateEstimator};
pub use gaussian::{
    CholeskyFactor, Gaussian, LN_2PI, check_finite_matrix, check_positive_semidefinite,
    check_symmetric, cholesky_checked,
};
pub use geometry::{BoundingBox, Region, Region2, Vec2, bearing_rad, wrap_angle_rad};
pub use grid::{LikelihoodGrid, Peak, PeakConfig};
pub use imm::{Imm, ImmState, ImmUpdated, MAX_IMM_MODES, Mode};
pub use kalman::{FilterRun, FilterStep, filter, rts_step, smooth};
pub use models::{
    ConstantVelocity2, CvNoise, CvState, FullStateMeasurement, Innovation, LinearObservation,
    LinearTransition, ObservationModel, PositionMeasurement2, RandomWalk, TransitionModel, Updated,
    axes_uncoupled, full_state_measurement, position_measurement,
};
pub use mot::{MotFile, MotRow, format_mot, parse_mot, read_mot};
pub use motion::{
    ConstantVelocity3, ConstantVelocityTurnLayout, CoordinatedTurn, CoordinatedTurnRate,
    MAX_TURN_RATE_RAD_S, TurnNoise,
};
pub use nonlinear::{
    GaussianFilter, MAX_SIGMA_KAPPA, MeasurementModel, MeasurementPrediction, MotionModel,
    SigmaPoints,
};
pub use radar::{RadarSite, RangeBearing, RangeBearingElevation};
pub use simulate::{Simulation, SimulationConfig, Simulator};
pub use track::{
    Frame, FrameClock, Location, Measurement, Origin, Scan, Track, TrackId, TrackPoint, TrackSet,
};
pub use tracking::{
    BatchTracker, Detection, DetectionId, FrameDetections, Online, Stamp, TrackState, Tracker,
    scans_of,
};
