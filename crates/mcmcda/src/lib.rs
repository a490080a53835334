//! # mcmcda
//!
//! Markov chain Monte Carlo data association (Oh, Russell & Sastry, IEEE TAC 54(3), 2009) for
//! an unknown number of targets in clutter:
//!
//! * [`McmcdaConfig`] → [`Model`]: the posterior of Oh, Russell & Sastry 2009 eq. 9 and the
//!   proposal parameters;
//! * [`Problem`]: measurements by scan with the neighbourhoods L(y, t, d) (eq. 27), or
//!   without them for the nearest-neighbour baseline ([`Problem::without_neighbourhoods`]);
//!   [`Problem::all_scans`] is the window of a whole-problem run;
//! * [`batch_mcmcda`] with a [`BatchConfig`]: the whole problem in one call (greedy start,
//!   then Algorithm 3's chains with all eight moves and exact proposal probabilities, MAP and
//!   MMSE, independent chains in parallel), returning a [`McmcdaRun`];
//! * [`chain`]: the sampler's parts for a caller who builds its own start (a
//!   [`chain::Partition`], a feasible ω with incremental log posterior) and runs
//!   [`chain::run_chains`] or a [`chain::Chain`] by hand;
//! * [`OnlineTracker`]: Algorithm 4, sliding-window MCMCDA with persistent track labels;
//!   [`OnlineTracker::drain_committed`] streams the final track pieces out and forgets old
//!   scans, so a run of any length holds constant memory;
//! * [`single_scan_mcmcda`]: Algorithms 1-2, JPDA probabilities β for a known number of
//!   targets by MCMC, and [`jpda_exact`] by enumeration;
//! * baselines: [`nearest_neighbour_tracks`] (GNN with the log-likelihood-ratio costs of
//!   [`AssignmentCost`], M-of-N confirmation and deletion after a gap, and the greedy
//!   filter [`chain::greedy_initial_partition`] that starts the chain);
//! * [`PlotGnn`]: GNN on radar plots in dwells with any `tracker_model::StateEstimator`
//!   (Kalman, EKF, UKF, IMM) and any measurement model (range-bearing radars); [`PointGnn`]
//!   runs it on point detections behind the one tracker interface;
//! * the one tracker interface of tracker-model: [`OnlineTracker`] and [`JpdaTracker`] are
//!   `tracker_model::Tracker`s (and [`PointGnn`]), [`BatchMcmcda`] and [`Gnn`] `tracker_model::BatchTracker`s;
//! * [`smoothed_tracks`], [`measurement_labels`], [`tracks_by_origin`]: from partitions to
//!   trajectories and scores;
//! * [`mod@reference`]: the log posterior from per-scan counts and partition enumeration.
//!
//! Tracking your point measurements, one list per scan, by batch MCMCDA with the default model
//! (the paper's batch experiment: a 1000 × 1000 region, p_d = 0.9, speeds up to 100 per scan):
//!
//! ```
//! use mcmcda::{BatchConfig, McmcdaConfig, Problem, batch_mcmcda};
//! use tracker_model::Vec2;
//!
//! // Two targets in straight lines, and a false alarm at (400, 800) that neither track takes.
//! let scans = [
//!     vec![Vec2::new(100.0, 200.0), Vec2::new(700.0, 300.0)],
//!     vec![Vec2::new(130.0, 210.0), Vec2::new(680.0, 325.0)],
//!     vec![Vec2::new(160.0, 220.0), Vec2::new(400.0, 800.0), Vec2::new(660.0, 350.0)],
//!     vec![Vec2::new(190.0, 230.0), Vec2::new(640.0, 375.0)],
//! ];
//! let model = McmcdaConfig::default().check()?;
//! let mut problem = Problem::empty(&model, 0);
//! for (frame, points) in (0..).zip(&scans) { problem.push_scan(frame, points)?; }
//! let run = batch_mcmcda(&model, &problem, &BatchConfig::default())?;
//! assert!(run.tracks.len() == 2 && run.tracks.iter().all(|track| track.len() == 4));
//! # Ok::<(), mcmcda::Error>(())
//! ```
//!
//! [`smoothed_tracks`] turns `run.tracks` into trajectories (a `tracker_model::TrackSet`).

mod batch;
mod config;
mod error;
mod estimates;
mod nearest;
mod neighbours;
mod online;
mod partition;
mod plots;
mod problem;
mod proposal;
pub mod reference;
mod sampler;
mod single_scan;
mod track_filter;
mod trackers;

#[cfg(test)]
mod tests;

pub use batch::{BatchConfig, batch_mcmcda};
pub use config::{GapDistribution, McmcdaConfig, Model, Move, MoveWeights, TrackEnd, TrackInit};
pub use error::{Error, MAX_CHAINS, MAX_SAMPLES, Result};
pub use estimates::{measurement_labels, smoothed_tracks, tracks_by_origin};
pub use nearest::{Assignment, AssignmentCost, NearestNeighbourConfig, nearest_neighbour_tracks};
pub use online::{
    CommittedPiece, MAX_WINDOW, OnlineConfig, OnlineResult, OnlineStep, OnlineTracker,
};
pub use plots::{
    BirthPrior, Dwell, MAX_DWELL_PLOTS, MAX_PLOT_TRACKS, PlotGnn, PlotGnnConfig, PlotTrackState,
    PointGnn, View,
};
pub use problem::{MeasId, Problem};
pub use sampler::{McmcdaRun, MoveStats};

/// The sampler's parts, beside the front door of [`batch_mcmcda`]: the greedy start, a feasible
/// partition ω with its incremental log posterior, one chain of Algorithm 3 (Oh, Russell &
/// Sastry 2009) and independent chains in parallel.
pub mod chain {
    pub use crate::nearest::greedy_initial_partition;
    pub use crate::partition::Partition;
    pub use crate::sampler::{Chain, run_chains};
}
pub use single_scan::{JpdaResult, SingleScanConfig, jpda_exact, single_scan_mcmcda};
pub use trackers::{BatchMcmcda, Gnn, JpdaAssociation, JpdaTracker};
