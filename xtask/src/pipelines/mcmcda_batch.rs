//! `mcmcda-batch`: the TAC 2009 batch experiment. For each number of targets K, simulated
//! scenarios are tracked by multi-scan MCMCDA (started from the greedy nearest-neighbour
//! filter), by GNN, and by an oracle that knows the true associations; all three are scored
//! by association F1 and by the GOSPA of their smoothed states.

use std::time::Instant;

use anyhow::Result;
use eval_metrics::{OspaConfig, association_scores, gospa_over_time};
use indicatif::ProgressBar;
use mcmcda::{
    McmcdaConfig, NearestNeighbourConfig, Partition, Problem, greedy_initial_partition,
    measurement_labels, nearest_neighbour_tracks, run_chains, smoothed_tracks, tracks_by_origin,
};
use rand::RngExt;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::{Scan, SimulationConfig, TrackSet};

use crate::plot::{Axes, Series, Style, chart};
use crate::report::{Plot, Section, Table, fmt_num};
use crate::scenario::{Metrics, PipelineOutput, Scenario};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Params {
    /// Numbers of targets K; births per scan are K / T.
    targets: Vec<u32>,
    /// Scenarios per K.
    runs: usize,
    /// MCMC samples per chain.
    samples: u64,
    /// Independent chains per scenario.
    chains: usize,
    /// GOSPA cut-off c (order 2, α = 2).
    gospa_cutoff: f64,
    /// The simulated world (births_per_scan is set from K).
    simulation: SimulationConfig,
    /// The tracker's model (births_per_scan is set from K).
    model: McmcdaConfig,
    /// The GNN baseline.
    gnn: NearestNeighbourConfig,
}

/// Scores of one tracker on one scenario.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Scores {
    pub f1: f64,
    pub gospa: f64,
    /// Mean per frame of GOSPA's parts: missed targets, false estimates, Σ d² of pairs.
    pub missed: f64,
    pub false_targets: f64,
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

const METHODS: [&str; 4] = ["mcmcda", "gnn", "init", "oracle"];

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

pub fn run(scenario: &Scenario, progress: &ProgressBar) -> Result<PipelineOutput> {
    let p: Params = scenario.params()?;
    anyhow::ensure!(
        p.runs > 0 && !p.targets.is_empty(),
        "runs and targets must be non-empty"
    );
    progress.set_length((p.targets.len() * p.runs) as u64);
    let base = scenario.rng();
    let tasks: Vec<(usize, u32, usize)> = p
        .targets
        .iter()
        .enumerate()
        .flat_map(|(i, &k)| (0..p.runs).map(move |r| (i, k, r)))
        .collect();
    let results: Vec<RunScores> = tasks
        .par_iter()
        .map(|&(i, k, r)| {
            let mut rng = base.clone();
            rng.set_stream((i * p.runs + r) as u64);
            let births = f64::from(k) / f64::from(p.simulation.n_scans);
            let sim = SimulationConfig {
                births_per_scan: births,
                ..p.simulation.clone()
            }
            .check()?
            .simulate(&mut rng)?;
            let model = McmcdaConfig {
                births_per_scan: births,
                ..p.model.clone()
            }
            .check()?;
            let problem = Problem::from_scans(&model, &sim.scans)?;
            let window = 0..=problem.n_scans() - 1;
            let truth_tracks = tracks_by_origin(&sim.scans);
            let start = Instant::now();
            let init = greedy_initial_partition(&model, &problem, window.clone())?;
            let run = run_chains(&init, p.chains, p.samples, rng.random())?;
            let seconds = start.elapsed().as_secs_f64();
            let gnn = nearest_neighbour_tracks(&model, &problem, window.clone(), &p.gnn)?;
            let map_minus_truth =
                Partition::from_tracks(&model, &problem, window.clone(), &truth_tracks)
                    .ok()
                    .map(|t| run.log_posterior - t.log_posterior());
            let s = |tracks: &[Vec<u32>]| {
                score(
                    &model,
                    &problem,
                    &sim.scans,
                    &sim.truth,
                    tracks,
                    p.gospa_cutoff,
                )
            };
            let out = RunScores {
                mcmcda: s(&run.tracks)?,
                gnn: s(&gnn)?,
                init: s(&init.canonical())?,
                oracle: s(&truth_tracks)?,
                map_minus_truth,
                seconds,
            };
            progress.inc(1);
            Ok(out)
        })
        .collect::<Result<_>>()?;

    let mut metrics = Metrics::new();
    let mut table = Table::new(
        &format!(
            "Mean over {} scenarios per K ({} scans, {} chain(s) × {} samples)",
            p.runs, p.simulation.n_scans, p.chains, p.samples
        ),
        &[
            "K",
            "F1 MCMCDA",
            "F1 GNN",
            "F1 NNF (init)",
            "GOSPA MCMCDA",
            "GOSPA GNN",
            "GOSPA oracle",
            "MCMCDA / oracle",
            "MAP − truth log post.",
            "time per run (s)",
        ],
    );
    let mut parts = Table::new(
        "GOSPA's parts, mean per frame: cardinality errors cost c²/2 each",
        &[
            "K",
            "tracker",
            "missed targets",
            "false estimates",
            "Σ d² of pairs",
        ],
    );
    let mut f1_series = vec![Vec::new(); 3];
    let mut gospa_series = vec![Vec::new(); 4];
    for (i, &k) in p.targets.iter().enumerate() {
        let group = &results[i * p.runs..(i + 1) * p.runs];
        let mean =
            |f: &dyn Fn(&RunScores) -> f64| group.iter().map(f).sum::<f64>() / group.len() as f64;
        let pick = |m: usize, r: &RunScores| match m {
            0 => r.mcmcda,
            1 => r.gnn,
            2 => r.init,
            _ => r.oracle,
        };
        let f1: Vec<f64> = (0..4).map(|m| mean(&|r| pick(m, r).f1)).collect();
        let gospa: Vec<f64> = (0..4).map(|m| mean(&|r| pick(m, r).gospa)).collect();
        for m in 0..4 {
            metrics.insert(format!("k{k}_f1_{}", METHODS[m]), f1[m]);
            metrics.insert(format!("k{k}_gospa_{}", METHODS[m]), gospa[m]);
            gospa_series[m].push((f64::from(k), gospa[m]));
            if m < 3 {
                f1_series[m].push((f64::from(k), f1[m]));
            }
        }
        for (m, name) in ["MCMCDA", "GNN", "NNF (init)", "oracle"].iter().enumerate() {
            parts.row(vec![
                k.to_string(),
                (*name).into(),
                format!("{:.2}", mean(&|r| pick(m, r).missed)),
                format!("{:.2}", mean(&|r| pick(m, r).false_targets)),
                fmt_num(mean(&|r| pick(m, r).localisation)),
            ]);
        }
        let gaps: Vec<f64> = group.iter().filter_map(|r| r.map_minus_truth).collect();
        let gap = gaps.iter().sum::<f64>() / gaps.len().max(1) as f64;
        if !gaps.is_empty() {
            metrics.insert(format!("k{k}_map_minus_truth"), gap);
        }
        table.row(vec![
            k.to_string(),
            format!("{:.4}", f1[0]),
            format!("{:.4}", f1[1]),
            format!("{:.4}", f1[2]),
            fmt_num(gospa[0]),
            fmt_num(gospa[1]),
            fmt_num(gospa[3]),
            format!("{:.3}", gospa[0] / gospa[3]),
            if gaps.is_empty() {
                "–".into()
            } else {
                format!("{gap:+.2} ({} of {})", gaps.len(), group.len())
            },
            format!("{:.3}", mean(&|r| r.seconds)),
        ]);
    }
    let names = ["MCMCDA", "GNN", "NNF (init)", "oracle"];
    let f1_plot = chart(
        &Axes {
            title: "Association F1 against the number of targets",
            x: "targets K",
            y: "F1",
        },
        &f1_series
            .into_iter()
            .enumerate()
            .map(|(m, pts)| Series::new(names[m], pts, Style::Line, m))
            .collect::<Vec<_>>(),
    )?;
    let gospa_plot = chart(
        &Axes {
            title: "Mean GOSPA against the number of targets",
            x: "targets K",
            y: "GOSPA (c, p = 2)",
        },
        &gospa_series
            .into_iter()
            .enumerate()
            .map(|(m, pts)| Series::new(names[m], pts, Style::Line, m))
            .collect::<Vec<_>>(),
    )?;
    Ok(PipelineOutput {
        metrics,
        section: Section {
            title: "Multi-scan MCMCDA: batch experiment of TAC 2009".into(),
            summary: format!(
                "Region [0, 1000]², T = {} scans, p_d = {}, λ_f V = {}, p_z = {}, d̄ = {}, v̄ = {}. \
                 Association F1 counts links between consecutive measurements of a track; GOSPA \
                 (c = {}, p = 2, α = 2) is averaged over frames of the Kalman-smoothed tracks. \
                 The oracle uses the true associations with the same smoother. \"MAP − truth\" \
                 is the MAP's log posterior minus the true partition's (positive: the sampler \
                 found a partition the model prefers to the truth).",
                p.simulation.n_scans,
                p.model.p_detect,
                p.model.clutter_per_scan,
                p.model.p_disappear,
                p.model.max_gap,
                p.model.max_speed,
                p.gospa_cutoff
            ),
            tables: vec![table, parts],
            plots: vec![
                Plot {
                    name: "f1".into(),
                    caption: "Association F1 of MCMCDA, GNN and the NNF initialisation".into(),
                    svg: f1_plot,
                },
                Plot {
                    name: "gospa".into(),
                    caption: "Mean GOSPA of each tracker and the oracle".into(),
                    svg: gospa_plot,
                },
            ],
        },
    })
}
