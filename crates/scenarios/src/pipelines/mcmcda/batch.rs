//! `mcmcda-batch`: MCMCDA, GNN, the NNF initialisation and the oracle against the number of
//! targets K.

use anyhow::Result;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use tracker_model::SimulationConfig;

use super::{RunScores, Scores, Trackers, group_mean, run_grid};
use crate::{Chart, Env, Figure, Metrics, Pipeline, Section, Series, Style, Table, fmt_num};

/// The `mcmcda-batch` pipeline.
pub struct Batch;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Numbers of targets K; births per scan are K / T.
    targets: Vec<u32>,
    /// Scenarios per K.
    runs: usize,
    /// The simulated world (births_per_scan is set from K).
    simulation: SimulationConfig,
    trackers: Trackers,
}

/// Metric names of the trackers, in the order of [`KSummary::means`].
const METHODS: [&str; 4] = ["mcmcda", "gnn", "init", "oracle"];
/// Display names of the trackers, in the same order.
const NAMES: [&str; 4] = ["MCMCDA", "GNN", "NNF (init)", "oracle"];

/// Means over the scenarios of one K.
pub struct KSummary {
    /// Number of targets.
    k: u32,
    /// Scenarios averaged.
    runs: usize,
    /// Mean scores of MCMCDA, GNN, the NNF initialisation and the oracle.
    means: [Scores; 4],
    /// Mean MAP − truth log posterior over the scenarios whose truth is feasible, if any.
    map_minus_truth: Option<f64>,
    /// Scenarios whose truth is feasible.
    n_feasible: usize,
    /// Mean seconds of MCMCDA per scenario.
    seconds: f64,
}

/// The per-K means and the settings the report quotes.
pub struct Output {
    runs: usize,
    simulation: SimulationConfig,
    trackers: Trackers,
    groups: Vec<KSummary>,
}

/// The means over one K's scenarios.
fn summarise(k: u32, group: &[RunScores]) -> KSummary {
    let mean = |f: &dyn Fn(&RunScores) -> f64| group_mean(group, f);
    let pick = |m: usize, r: &RunScores| match m {
        0 => r.mcmcda,
        1 => r.gnn,
        2 => r.init,
        _ => r.oracle,
    };
    let means = [0, 1, 2, 3].map(|m| Scores {
        f1: mean(&|r| pick(m, r).f1),
        gospa: mean(&|r| pick(m, r).gospa),
        missed: mean(&|r| pick(m, r).missed),
        false_targets: mean(&|r| pick(m, r).false_targets),
        localisation: mean(&|r| pick(m, r).localisation),
    });
    let gaps: Vec<f64> = group.iter().filter_map(|r| r.map_minus_truth).collect();
    let gap = gaps.iter().sum::<f64>() / gaps.len().max(1) as f64;
    KSummary {
        k,
        runs: group.len(),
        means,
        map_minus_truth: (!gaps.is_empty()).then_some(gap),
        n_feasible: gaps.len(),
        seconds: mean(&|r| r.seconds),
    }
}

impl Pipeline for Batch {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let settings: Vec<(SimulationConfig, u32)> = p
            .targets
            .iter()
            .map(|&k| (p.simulation.clone(), k))
            .collect();
        let results = run_grid(rng, env, &settings, p.runs, &p.trackers)?;
        let groups = p
            .targets
            .iter()
            .enumerate()
            .map(|(i, &k)| summarise(k, &results[i * p.runs..(i + 1) * p.runs]))
            .collect();
        Ok(Output {
            runs: p.runs,
            simulation: p.simulation.clone(),
            trackers: p.trackers.clone(),
            groups,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for g in &out.groups {
            let k = g.k;
            for (m, method) in METHODS.iter().enumerate() {
                metrics.insert(format!("k{k}_f1_{method}"), g.means[m].f1);
                metrics.insert(format!("k{k}_gospa_{method}"), g.means[m].gospa);
            }
            if let Some(gap) = g.map_minus_truth {
                metrics.insert(format!("k{k}_map_minus_truth"), gap);
            }
        }
        metrics
    }

    fn present(out: &Output) -> Section {
        let (sim, t) = (&out.simulation, &out.trackers);
        Section {
            title: "Multi-scan MCMCDA: batch experiment of TAC 2009".into(),
            summary: format!(
                "Region [0, 1000]², T = {} scans, p_d = {}, λ_f V = {}, p_z = {}, d̄ = {}, v̄ = {}. \
                 Association F1 counts links between consecutive measurements of a track; GOSPA \
                 (c = {}, p = 2, α = 2) is averaged over frames of the Kalman-smoothed tracks. \
                 The oracle uses the true associations with the same smoother. \"MAP − truth\" \
                 is the MAP's log posterior minus the true partition's (positive: the sampler \
                 found a partition the model prefers to the truth).",
                sim.n_scans,
                sim.p_detect,
                sim.clutter_per_scan,
                t.model.p_disappear,
                t.model.max_gap,
                t.model.max_speed,
                t.gospa_cutoff
            ),
            tables: vec![summary_table(out), parts_table(out)],
            figures: figures(out),
        }
    }
}

/// F1, GOSPA, MAP − truth and time per K.
fn summary_table(out: &Output) -> Table {
    let t = &out.trackers;
    let mut table = Table::new(
        &format!(
            "Mean over {} scenarios per K ({} scans, {} chain(s) × {} samples)",
            out.runs, out.simulation.n_scans, t.chains, t.samples
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
    for g in &out.groups {
        let [mcmcda, gnn, init, oracle] = &g.means;
        table.row(vec![
            g.k.to_string(),
            format!("{:.4}", mcmcda.f1),
            format!("{:.4}", gnn.f1),
            format!("{:.4}", init.f1),
            fmt_num(mcmcda.gospa),
            fmt_num(gnn.gospa),
            fmt_num(oracle.gospa),
            format!("{:.3}", mcmcda.gospa / oracle.gospa),
            match g.map_minus_truth {
                None => "–".into(),
                Some(gap) => format!("{gap:+.2} ({} of {})", g.n_feasible, g.runs),
            },
            format!("{:.3}", g.seconds),
        ]);
    }
    table
}

/// GOSPA's parts per K and tracker.
fn parts_table(out: &Output) -> Table {
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
    for g in &out.groups {
        for (s, name) in g.means.iter().zip(NAMES) {
            parts.row(vec![
                g.k.to_string(),
                name.into(),
                format!("{:.2}", s.missed),
                format!("{:.2}", s.false_targets),
                fmt_num(s.localisation),
            ]);
        }
    }
    parts
}

/// F1 (without the oracle) and GOSPA against K.
fn figures(out: &Output) -> Vec<Figure> {
    let series = |n: usize, f: fn(&Scores) -> f64| -> Vec<Series> {
        (0..n)
            .map(|m| {
                let pts = out
                    .groups
                    .iter()
                    .map(|g| (f64::from(g.k), f(&g.means[m])))
                    .collect();
                Series::new(NAMES[m], pts, Style::Line, m)
            })
            .collect()
    };
    let f1_chart = Chart::new(
        "Association F1 against the number of targets",
        "targets K",
        "F1",
        series(3, |s| s.f1),
    );
    let gospa_chart = Chart::new(
        "Mean GOSPA against the number of targets",
        "targets K",
        "GOSPA (c, p = 2)",
        series(4, |s| s.gospa),
    );
    vec![
        Figure::new(
            "f1",
            "Association F1 of MCMCDA, GNN and the NNF initialisation",
            f1_chart,
        ),
        Figure::new(
            "gospa",
            "Mean GOSPA of each tracker and the oracle",
            gospa_chart,
        ),
    ]
}
