//! The MCMCDA experiments of TAC 2009:
//! * `mcmcda-batch`: for each number of targets K, simulated scenarios are tracked by
//!   multi-scan MCMCDA (started from the greedy nearest-neighbour filter), by GNN, and by an
//!   oracle that knows the true associations; all are scored by association F1 and by the
//!   GOSPA of their smoothed states;
//! * `mcmcda-sweep`: F1 of MCMCDA and GNN against p_d and against the clutter rate;
//! * `mcmcda-online`: sliding-window MCMCDA on the long online example.

use anyhow::Result;
use eval_metrics::{OspaConfig, association_scores, gospa_over_time};
use mcmcda::{
    McmcdaConfig, NearestNeighbourConfig, Partition, Problem, greedy_initial_partition,
    measurement_labels, nearest_neighbour_tracks, run_chains, smoothed_tracks, tracks_by_origin,
};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::{Scan, SimulationConfig, TrackSet};

use crate::{Clock, Env};

mod batch;
mod online;
mod sweep;

pub use batch::Batch;
pub use online::Online;
pub use sweep::Sweep;

/// How every scenario of a batch experiment is tracked.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Trackers {
    /// MCMC samples per chain.
    samples: u64,
    /// Independent chains per scenario.
    chains: usize,
    /// GOSPA cut-off c (order 2, α = 2).
    gospa_cutoff: f64,
    /// The tracker's model (births_per_scan is set from K).
    model: McmcdaConfig,
    /// The GNN baseline.
    gnn: NearestNeighbourConfig,
}

/// Scores of one tracker on one scenario.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Scores {
    /// Association F1.
    pub f1: f64,
    /// Mean GOSPA per frame.
    pub gospa: f64,
    /// Mean per frame of GOSPA's parts: missed targets, false estimates, Σ d² of pairs.
    pub missed: f64,
    /// Mean number of false estimates per frame.
    pub false_targets: f64,
    /// Mean Σ d² of assigned pairs per frame.
    pub localisation: f64,
}

/// One scenario's results.
struct RunScores {
    mcmcda: Scores,
    gnn: Scores,
    init: Scores,
    oracle: Scores,
    /// MAP log posterior minus the true partition's (when the truth is feasible in Ω).
    map_minus_truth: Option<f64>,
    seconds: f64,
}

/// The mean of `f` over `group`.
fn group_mean(group: &[RunScores], f: &dyn Fn(&RunScores) -> f64) -> f64 {
    group.iter().map(f).sum::<f64>() / group.len() as f64
}

/// F1 of `tracks` against the scans' origins and mean GOSPA of their smoothed states.
pub(crate) fn score(
    model: &mcmcda::Model,
    problem: &Problem,
    scans: &[Scan],
    truth: &TrackSet,
    tracks: &[Vec<u32>],
    cutoff: f64,
) -> Result<Scores> {
    let labels = measurement_labels(problem, tracks);
    let f1 = association_scores(scans, &labels)?.f1;
    let estimate = smoothed_tracks(model, problem, tracks, 0)?;
    let per_frame = gospa_over_time(truth, &estimate, &OspaConfig { cutoff, order: 2.0 })?;
    let mean = |f: &dyn Fn(&eval_metrics::Gospa) -> f64| {
        per_frame.iter().map(|(_, g)| f(g)).sum::<f64>() / per_frame.len().max(1) as f64
    };
    Ok(Scores {
        f1,
        gospa: mean(&|g| g.distance),
        missed: mean(&|g| g.n_missed as f64),
        false_targets: mean(&|g| g.n_false as f64),
        localisation: mean(&|g| g.localisation),
    })
}

/// Simulates one scenario with K targets and scores every tracker on it. The world and the
/// tracker's model share p_d and the clutter rate (both set here when given).
fn run_once(
    simulation: &SimulationConfig,
    trackers: &Trackers,
    k: u32,
    rng: &mut ChaCha8Rng,
    clock: &dyn Clock,
) -> Result<RunScores> {
    let births = f64::from(k) / f64::from(simulation.n_scans);
    let sim = SimulationConfig {
        births_per_scan: births,
        ..simulation.clone()
    }
    .check()?
    .simulate(rng)?;
    let model = McmcdaConfig {
        births_per_scan: births,
        p_detect: simulation.p_detect,
        clutter_per_scan: simulation.clutter_per_scan,
        ..trackers.model.clone()
    }
    .check()?;
    let problem = Problem::from_scans(&model, &sim.scans)?;
    let window = problem.all_scans()?;
    let truth_tracks = tracks_by_origin(&sim.scans);
    let start = clock.now_s();
    let init = greedy_initial_partition(&model, &problem, window.clone())?;
    let run = run_chains(&init, trackers.chains, trackers.samples, rng.random())?;
    let seconds = clock.now_s() - start;
    let gnn = nearest_neighbour_tracks(&model, &problem, window.clone(), &trackers.gnn)?;
    let map_minus_truth = Partition::from_tracks(&model, &problem, window, &truth_tracks)
        .ok()
        .map(|t| run.log_posterior - t.log_posterior());
    let s = |tracks: &[Vec<u32>]| {
        score(
            &model,
            &problem,
            &sim.scans,
            &sim.truth,
            tracks,
            trackers.gospa_cutoff,
        )
    };
    Ok(RunScores {
        mcmcda: s(&run.tracks)?,
        gnn: s(&gnn)?,
        init: s(&init.canonical())?,
        oracle: s(&truth_tracks)?,
        map_minus_truth,
        seconds,
    })
}

/// Runs `run_once` for every (setting, run) in parallel, each on its own stream of `base`.
fn run_grid(
    base: &ChaCha8Rng,
    env: &Env<'_>,
    settings: &[(SimulationConfig, u32)],
    runs: usize,
    trackers: &Trackers,
) -> Result<Vec<RunScores>> {
    anyhow::ensure!(
        runs > 0 && !settings.is_empty(),
        "runs and settings must be non-empty"
    );
    env.progress.set_length((settings.len() * runs) as u64);
    (0..settings.len() * runs)
        .into_par_iter()
        .map(|task| {
            let mut rng = base.clone();
            rng.set_stream(task as u64);
            let (simulation, k) = &settings[task / runs];
            let out = run_once(simulation, trackers, *k, &mut rng, env.clock);
            env.progress.advance(1);
            out
        })
        .collect()
}
