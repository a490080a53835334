//! # mcmcda
//!
//! Markov chain Monte Carlo data association (Oh, Russell & Sastry, IEEE TAC 54(3), 2009) for
//! an unknown number of targets in clutter:
//!
//! * [`McmcdaConfig`] → [`Model`]: the posterior of TAC eq. 9 and the proposal parameters;
//! * [`Problem`]: measurements by scan with the neighbourhoods L(y, t, d) (eq. 27);
//! * [`Partition`]: a feasible ω with incremental log posterior;
//! * [`Chain`] / [`run_chains`]: Algorithm 3 with all eight moves and exact proposal
//!   probabilities, MAP and MMSE, independent chains in parallel;
//! * [`OnlineTracker`]: Algorithm 4, sliding-window MCMCDA with persistent track labels;
//! * [`single_scan_mcmcda`]: Algorithms 1-2, JPDA probabilities β for a known number of
//!   targets by MCMC, and [`jpda_exact`] by enumeration;
//! * baselines: [`nearest_neighbour_tracks`] (GNN with M-of-N confirmation, and the greedy
//!   filter [`greedy_initial_partition`] that starts the chain);
//! * [`smoothed_tracks`], [`measurement_labels`], [`tracks_by_origin`]: from partitions to
//!   trajectories and scores;
//! * [`mod@reference`]: the log posterior from per-scan counts and partition enumeration.
//!
//! ```
//! use mcmcda::{McmcdaConfig, Partition, Problem, run_chains};
//! use rand::SeedableRng;
//! use tracker_model::SimulationConfig;
//! let sim = SimulationConfig::default().check().unwrap()
//!     .simulate(&mut rand_chacha::ChaCha8Rng::seed_from_u64(1)).unwrap();
//! let model = McmcdaConfig::default().check().unwrap();
//! let problem = Problem::from_scans(&model, &sim.scans).unwrap();
//! let start = Partition::empty(&model, &problem, 0..=problem.n_scans() - 1).unwrap();
//! let run = run_chains(&start, 2, 20_000, 7).unwrap();
//! assert!(!run.tracks.is_empty());
//! ```

mod config;
mod error;
mod estimates;
mod nearest;
mod online;
mod partition;
mod problem;
mod proposal;
pub mod reference;
mod sampler;
mod single_scan;
mod track_filter;

#[cfg(test)]
mod tests;

pub use config::{GapDistribution, McmcdaConfig, Model, Move, MoveWeights, TrackEnd, TrackInit};
pub use error::{Error, Result};
pub use estimates::{measurement_labels, smoothed_tracks, tracks_by_origin};
pub use nearest::{
    Assignment, NearestNeighbourConfig, greedy_initial_partition, nearest_neighbour_tracks,
};
pub use online::{OnlineConfig, OnlineResult, OnlineStep, OnlineTracker};
pub use partition::Partition;
pub use problem::{MeasId, Problem};
pub use sampler::{Chain, McmcdaRun, MoveStats, run_chains};
pub use single_scan::{JpdaResult, SingleScanConfig, jpda_exact, single_scan_mcmcda};
