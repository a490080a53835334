//! The MCMCDA experiments of TAC 2009:
//! * `mcmcda-batch`: for each number of targets K, simulated scenarios are tracked by
//!   multi-scan MCMCDA (started from the greedy nearest-neighbour filter), by GNN, and by an
//!   oracle that knows the true associations; all are scored by association F1 and by the
//!   GOSPA of their smoothed states. MCMCDA and GNN also run with a model mis-specified by a
//!   factor of 2 in p_d, the clutter rate and Q;
//! * `mcmcda-sweep`: F1 of MCMCDA and GNN against p_d and against the clutter rate;
//! * `mcmcda-online`: sliding-window MCMCDA on the long online example.
//!
//! GNN is the fair baseline: log-likelihood-ratio costs from the same model (Blackman 2004;
//! see `mcmcda::AssignmentCost`), and its M-of-N confirmation and deletion gap chosen per
//! setting and per model variant on tuning scenarios drawn from a separate seed
//! (`[params.tuning]`), once for the best F1 and once for the best GOSPA. The reported
//! scenarios come from the scenario's own seed; MCMCDA is not tuned at all (it uses the
//! model). Means are reported with a 95 % normal-approximation interval, 1.96·s/√n over
//! the n scenarios.

use anyhow::Result;
use eval_metrics::{OspaConfig, association_scores, gospa_over_time};
use mcmcda::{
    McmcdaConfig, NearestNeighbourConfig, Problem,
    chain::{Partition, greedy_initial_partition, run_chains},
    measurement_labels, nearest_neighbour_tracks, smoothed_tracks, tracks_by_origin,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::{ConstantVelocity2, CvNoise, Scan, SimulationConfig, TrackSet};

use crate::{Clock, Env};

mod batch;
mod fresh;
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
    /// The GNN baseline; confirm_hits, confirm_window and max_gap are replaced by the tuned
    /// ones.
    gnn: NearestNeighbourConfig,
}

/// How GNN's confirmation and deletion are tuned.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Tuning {
    /// Seed of the tuning scenarios (the reported ones use the scenario's seed).
    seed: u64,
    /// Tuning scenarios per setting.
    runs: usize,
    /// Confirmation windows N to try; M runs over 2..=N.
    confirm_windows: Vec<u32>,
    /// Deletion gaps to try (scans; capped at d̄ by the tracker).
    max_gaps: Vec<u32>,
}

impl Tuning {
    /// Every candidate (M, N, deletion gap).
    fn candidates(&self, base: &NearestNeighbourConfig) -> Vec<NearestNeighbourConfig> {
        let mut out = Vec::new();
        for &n in &self.confirm_windows {
            for m in 2..=n {
                for &g in &self.max_gaps {
                    out.push(NearestNeighbourConfig {
                        confirm_hits: m,
                        confirm_window: n,
                        max_gap: Some(g),
                        ..*base
                    });
                }
            }
        }
        out
    }
}

/// The model the trackers are given: the truth, or the truth mis-specified by a factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Variant {
    /// p_d and the clutter rate of the simulation, Q of the tracker's model.
    Truth,
    /// p_d ÷ f, clutter × f, Q × f: expects worse detection, more clutter, more manoeuvre.
    Pessimistic(f64),
    /// p_d × f (clamped to ≤ 0.99), clutter ÷ f, Q ÷ f.
    Optimistic(f64),
}

impl Variant {
    /// Name in metric keys.
    pub(crate) fn key(self) -> &'static str {
        match self {
            Variant::Truth => "",
            Variant::Pessimistic(_) => "_pessimistic",
            Variant::Optimistic(_) => "_optimistic",
        }
    }

    /// Name in the report.
    pub(crate) fn label(self) -> String {
        match self {
            Variant::Truth => "true model".into(),
            Variant::Pessimistic(f) => format!("p_d ÷ {f}, clutter × {f}, Q × {f}"),
            Variant::Optimistic(f) => {
                format!("p_d × {f} (≤ {P_DETECT_MAX}), clutter ÷ {f}, Q ÷ {f}")
            }
        }
    }
}

/// The largest p_d an optimistic model uses (p_d must stay inside (0, 1)).
const P_DETECT_MAX: f64 = 0.99;

/// The trackers' model for one scenario: births from K, p_d and clutter from the simulation,
/// then mis-specified as `variant` says.
fn tracker_model(
    base: &McmcdaConfig,
    simulation: &SimulationConfig,
    births: f64,
    variant: Variant,
) -> Result<mcmcda::Model> {
    let (p_factor, c_factor, q_factor) = match variant {
        Variant::Truth => (1.0, 1.0, 1.0),
        Variant::Pessimistic(f) => (1.0 / f, f, f),
        Variant::Optimistic(f) => (f, 1.0 / f, 1.0 / f),
    };
    let noise = match base.motion.noise() {
        CvNoise::WhiteAcceleration { q } => CvNoise::WhiteAcceleration { q: q * q_factor },
        CvNoise::Discrete {
            acceleration_covariance,
        } => CvNoise::Discrete {
            acceleration_covariance: acceleration_covariance * q_factor,
        },
    };
    Ok(McmcdaConfig {
        births_per_scan: births,
        p_detect: (simulation.p_detect * p_factor).min(P_DETECT_MAX),
        clutter_per_scan: simulation.clutter_per_scan * c_factor,
        motion: ConstantVelocity2::new(base.motion.dt_s(), noise)?,
        ..base.clone()
    }
    .check()?)
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

/// GNN's scores on one scenario: F1 with the F1-tuned settings, GOSPA and its parts with the
/// GOSPA-tuned ones.
fn gnn_scores(by_f1: Scores, by_gospa: Scores) -> Scores {
    Scores {
        f1: by_f1.f1,
        ..by_gospa
    }
}

/// One scenario's results.
pub(crate) struct RunScores {
    /// MCMCDA and GNN under each model variant, in the order given.
    pub mcmcda: Vec<Scores>,
    pub gnn: Vec<Scores>,
    pub init: Scores,
    pub oracle: Scores,
    /// MAP log posterior minus the true partition's (when the truth is feasible in Ω).
    pub map_minus_truth: Option<f64>,
    pub seconds: f64,
}

pub(crate) use crate::stats::mean_ci;

/// "mean ± half-width" with `digits` decimals.
pub(crate) fn pm((mean, ci): (f64, f64), digits: usize) -> String {
    format!("{mean:.digits$} ± {ci:.digits$}")
}

/// Means (with 95 % half-widths for F1 and GOSPA) of one tracker over a group of runs.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Stat {
    pub f1: (f64, f64),
    pub gospa: (f64, f64),
    pub missed: f64,
    pub false_targets: f64,
    pub localisation: f64,
}

impl Stat {
    /// The statistics of `pick` over `group`.
    pub(crate) fn of(group: &[RunScores], pick: impl Fn(&RunScores) -> Scores) -> Self {
        let all: Vec<Scores> = group.iter().map(pick).collect();
        let mean = |f: fn(&Scores) -> f64| all.iter().map(f).sum::<f64>() / all.len() as f64;
        Self {
            f1: mean_ci(all.iter().map(|s| s.f1)),
            gospa: mean_ci(all.iter().map(|s| s.gospa)),
            missed: mean(|s| s.missed),
            false_targets: mean(|s| s.false_targets),
            localisation: mean(|s| s.localisation),
        }
    }
}

/// Mean and 95 % half-width over `group` of a per-run difference, e.g. MCMCDA − GNN (paired:
/// both trackers ran on the same scenarios).
pub(crate) fn paired(group: &[RunScores], f: impl Fn(&RunScores) -> f64) -> (f64, f64) {
    mean_ci(group.iter().map(f))
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
    let labels = measurement_labels(problem, tracks)?;
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

/// A simulated scenario with K targets and the births per scan that K gives.
fn simulate(
    simulation: &SimulationConfig,
    k: u32,
    rng: &mut ChaCha8Rng,
) -> Result<(tracker_model::Simulation, f64)> {
    let births = f64::from(k) / f64::from(simulation.n_scans);
    let sim = SimulationConfig {
        births_per_scan: births,
        ..simulation.clone()
    }
    .check()?
    .simulate(rng)?;
    Ok((sim, births))
}

/// GNN's tuned settings for one setting and model variant: (best F1, best GOSPA).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Tuned {
    pub by_f1: NearestNeighbourConfig,
    pub by_gospa: NearestNeighbourConfig,
    /// Mean tuning F1 and GOSPA of the chosen settings.
    pub tuning_f1: f64,
    pub tuning_gospa: f64,
}

/// Tunes GNN's M-of-N and deletion gap for every setting and variant on `tuning.runs`
/// scenarios of stream `task` of ChaCha8(tuning.seed); the result is indexed [setting][variant].
fn tune(
    env: &Env<'_>,
    settings: &[(SimulationConfig, u32)],
    variants: &[Variant],
    trackers: &Trackers,
    tuning: &Tuning,
) -> Result<Vec<Vec<Tuned>>> {
    anyhow::ensure!(tuning.runs > 0, "tuning.runs must be positive");
    let candidates = tuning.candidates(&trackers.gnn);
    anyhow::ensure!(!candidates.is_empty(), "no GNN candidates to tune");
    let base = ChaCha8Rng::seed_from_u64(tuning.seed);
    let runs = tuning.runs;
    // Per (setting, run): scores[variant][candidate].
    let per_run: Vec<Vec<Vec<Scores>>> = (0..settings.len() * runs)
        .into_par_iter()
        .map(|task| {
            let mut rng = base.clone();
            rng.set_stream(task as u64);
            let (simulation, k) = &settings[task / runs];
            let (sim, births) = simulate(simulation, *k, &mut rng)?;
            let out = variants
                .iter()
                .map(|&v| {
                    let model = tracker_model(&trackers.model, simulation, births, v)?;
                    let problem = Problem::from_scans(&model, &sim.scans)?;
                    candidates
                        .iter()
                        .map(|c| {
                            let tracks = nearest_neighbour_tracks(
                                &model,
                                &problem,
                                problem.all_scans()?,
                                c,
                            )?;
                            score(
                                &model,
                                &problem,
                                &sim.scans,
                                &sim.truth,
                                &tracks,
                                trackers.gospa_cutoff,
                            )
                        })
                        .collect::<Result<Vec<_>>>()
                })
                .collect::<Result<Vec<_>>>();
            env.progress.advance(1);
            out
        })
        .collect::<Result<_>>()?;
    let mut out = Vec::with_capacity(settings.len());
    for i in 0..settings.len() {
        let group = &per_run[i * runs..(i + 1) * runs];
        let mut row = Vec::with_capacity(variants.len());
        for v in 0..variants.len() {
            let mean = |c: usize, f: fn(&Scores) -> f64| {
                group.iter().map(|r| f(&r[v][c])).sum::<f64>() / runs as f64
            };
            // Ties go to the first candidate in grid order.
            let (mut best_f1, mut best_gospa) = (0, 0);
            for c in 1..candidates.len() {
                if mean(c, |s| s.f1) > mean(best_f1, |s| s.f1) {
                    best_f1 = c;
                }
                if mean(c, |s| s.gospa) < mean(best_gospa, |s| s.gospa) {
                    best_gospa = c;
                }
            }
            row.push(Tuned {
                by_f1: candidates[best_f1],
                by_gospa: candidates[best_gospa],
                tuning_f1: mean(best_f1, |s| s.f1),
                tuning_gospa: mean(best_gospa, |s| s.gospa),
            });
        }
        out.push(row);
    }
    Ok(out)
}

/// Simulates one scenario with K targets and scores every tracker on it, under every model
/// variant (MCMCDA and GNN; the NNF start, the MAP − truth gap and the oracle use the true
/// model).
fn run_once(
    simulation: &SimulationConfig,
    trackers: &Trackers,
    k: u32,
    variants: &[Variant],
    tuned: &[Tuned],
    rng: &mut ChaCha8Rng,
    clock: &dyn Clock,
) -> Result<RunScores> {
    let (sim, births) = simulate(simulation, k, rng)?;
    let truth_tracks = tracks_by_origin(&sim.scans);
    let mut out = RunScores {
        mcmcda: Vec::new(),
        gnn: Vec::new(),
        init: Scores::default(),
        oracle: Scores::default(),
        map_minus_truth: None,
        seconds: 0.0,
    };
    for (&variant, tuned) in variants.iter().zip(tuned) {
        let model = tracker_model(&trackers.model, simulation, births, variant)?;
        let problem = Problem::from_scans(&model, &sim.scans)?;
        let window = problem.all_scans()?;
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
        let start = clock.now_s();
        let init = greedy_initial_partition(&model, &problem, window.clone())?;
        let run = run_chains(&init, trackers.chains, trackers.samples, rng.random())?;
        let seconds = clock.now_s() - start;
        let gnn_f1 = nearest_neighbour_tracks(&model, &problem, window.clone(), &tuned.by_f1)?;
        let gnn_gospa =
            nearest_neighbour_tracks(&model, &problem, window.clone(), &tuned.by_gospa)?;
        out.mcmcda.push(s(&run.tracks)?);
        out.gnn.push(gnn_scores(s(&gnn_f1)?, s(&gnn_gospa)?));
        if variant == Variant::Truth {
            out.seconds = seconds;
            out.init = s(&init.canonical())?;
            out.oracle = s(&truth_tracks)?;
            out.map_minus_truth = Partition::from_tracks(&model, &problem, window, &truth_tracks)
                .ok()
                .map(|t| run.log_posterior - t.log_posterior());
        }
    }
    Ok(out)
}

/// The seeds of one experiment: the reported scenarios' generator, and the fresh seed whose
/// scenarios carry the claims.
pub(crate) struct Seeds<'a> {
    /// The reported scenarios' generator (from the scenario's seed).
    pub reported: &'a ChaCha8Rng,
    /// The fresh scenarios' seed.
    pub fresh: u64,
}

/// The runs of the reported scenarios and of the fresh ones, setting by setting.
type ReportedAndFresh = [Vec<RunScores>; 2];

/// Tunes GNN, then runs `run_once` for every (set, setting, run) in parallel, the reported
/// set on the streams of `seeds.reported`, the fresh set on those of ChaCha8(`seeds.fresh`).
/// Returns the tuned settings [setting][variant] and each set's runs, setting by setting.
fn run_grid(
    seeds: &Seeds<'_>,
    env: &Env<'_>,
    settings: &[(SimulationConfig, u32)],
    runs: usize,
    variants: &[Variant],
    trackers: &Trackers,
    tuning: &Tuning,
) -> Result<(Vec<Vec<Tuned>>, ReportedAndFresh)> {
    anyhow::ensure!(
        runs > 0 && !settings.is_empty() && variants.first() == Some(&Variant::Truth),
        "runs and settings must be non-empty, and the first variant the true model"
    );
    crate::seeds::check_disjoint(&[
        ("tuning", &[tuning.seed]),
        ("reported", &[env.seed]),
        ("fresh", &[seeds.fresh]),
    ])?;
    env.progress
        .set_length((settings.len() * (2 * runs + tuning.runs)) as u64);
    let tuned = tune(env, settings, variants, trackers, tuning)?;
    let fresh = ChaCha8Rng::seed_from_u64(seeds.fresh);
    let n = settings.len() * runs;
    let mut all: Vec<RunScores> = (0..2 * n)
        .into_par_iter()
        .map(|task| {
            let mut rng = if task < n {
                seeds.reported.clone()
            } else {
                fresh.clone()
            };
            rng.set_stream((task % n) as u64);
            let i = (task % n) / runs;
            let (simulation, k) = &settings[i];
            let out = run_once(
                simulation, trackers, *k, variants, &tuned[i], &mut rng, env.clock,
            );
            env.progress.advance(1);
            out
        })
        .collect::<Result<_>>()?;
    let fresh_runs = all.split_off(n);
    Ok((tuned, [all, fresh_runs]))
}

/// The end of a verdict sentence: where MCMCDA and the tuned GNN do not differ significantly,
/// where GNN is significantly better, and the full stop.
pub(crate) fn ties_and_losses(ties: &[String], losses: &[String]) -> String {
    let mut s = String::new();
    if !ties.is_empty() {
        s.push_str(&format!(
            "; no significant difference at {}",
            ties.join(", ")
        ));
    }
    if !losses.is_empty() {
        s.push_str(&format!(
            "; the tuned GNN is significantly better at {}",
            losses.join(", ")
        ));
    }
    s + ". "
}
