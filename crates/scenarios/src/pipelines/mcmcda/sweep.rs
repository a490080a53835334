//! `mcmcda-sweep`: F1 and GOSPA of MCMCDA and GNN against p_d and against the clutter rate.

use std::collections::BTreeMap;

use anyhow::Result;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use tracker_model::SimulationConfig;

use super::fresh::comparisons;
use super::{Seeds, Stat, Trackers, Tuned, Tuning, Variant, paired, pm, run_grid, ties_and_losses};
use crate::fresh::{self, Comparison};
use crate::stats::Verdict;
use crate::{Chart, Claim, Env, Figure, Metrics, Pipeline, Section, Series, Style, Table, fmt_num};

/// The `mcmcda-sweep` pipeline.
pub struct Sweep;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Number of targets K.
    targets: u32,
    /// Scenarios per point.
    runs: usize,
    /// Detection probabilities to sweep (clutter as in `simulation`).
    p_detect: Vec<f64>,
    /// Expected false alarms per scan to sweep (p_d as in `simulation`).
    clutter: Vec<f64>,
    simulation: SimulationConfig,
    trackers: Trackers,
    /// GNN's tuning (its own seed), per point of the sweep.
    tuning: Tuning,
    /// The fresh scenarios' seed (`runs` per point, streams of ChaCha8(fresh_seed)).
    fresh_seed: u64,
    /// Each fresh comparison's verdict, recorded from its first run.
    #[serde(default)]
    fresh_verdicts: BTreeMap<String, Verdict>,
}

/// Means over the scenarios of one point of the sweep.
pub struct Point {
    /// Whether p_d (rather than the clutter rate) is varied.
    by_pd: bool,
    /// The varied value.
    x: f64,
    /// Mean F1 of MCMCDA and GNN, with 95 % half-widths.
    f1: [(f64, f64); 2],
    /// Mean GOSPA of MCMCDA and GNN, with 95 % half-widths.
    gospa: [(f64, f64); 2],
    /// Paired MCMCDA − GNN differences of F1 and GOSPA.
    f1_diff: (f64, f64),
    gospa_diff: (f64, f64),
    /// GNN's tuned settings.
    tuned: Tuned,
}

impl Point {
    /// (name in the table, name in the metric keys).
    fn names(&self) -> (&'static str, &'static str) {
        if self.by_pd {
            ("p_d", "pd")
        } else {
            ("λ_f V", "clutter")
        }
    }
}

/// The points of both sweeps, p_d first, and the settings the report quotes.
pub struct Output {
    targets: u32,
    runs: usize,
    p_detect: f64,
    clutter_per_scan: f64,
    tuning: Tuning,
    points: Vec<Point>,
    /// The fresh scenarios' comparisons per point, with the seed and the recorded verdicts.
    fresh: Vec<Comparison>,
    fresh_seed: u64,
    fresh_verdicts: BTreeMap<String, Verdict>,
}

/// The simulation at every point: the p_d sweep, then the clutter sweep.
fn sweep_settings(p: &Params) -> Vec<(SimulationConfig, u32)> {
    let at_pd = p.p_detect.iter().map(|&p_detect| SimulationConfig {
        p_detect,
        ..p.simulation.clone()
    });
    let at_clutter = p.clutter.iter().map(|&clutter_per_scan| SimulationConfig {
        clutter_per_scan,
        ..p.simulation.clone()
    });
    at_pd
        .chain(at_clutter)
        .map(|sim| (sim, p.targets))
        .collect()
}

impl Pipeline for Sweep {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let settings = sweep_settings(p);
        let seeds = Seeds {
            reported: rng,
            fresh: p.fresh_seed,
        };
        let (tuned, [results, fresh_results]) = run_grid(
            &seeds,
            env,
            &settings,
            p.runs,
            &[Variant::Truth],
            &p.trackers,
            &p.tuning,
        )?;
        let points = settings
            .iter()
            .zip(tuned)
            .enumerate()
            .map(|(i, ((sim, _), tuned))| {
                let group = &results[i * p.runs..(i + 1) * p.runs];
                let (m, g) = (
                    Stat::of(group, |r| r.mcmcda[0]),
                    Stat::of(group, |r| r.gnn[0]),
                );
                let by_pd = i < p.p_detect.len();
                Point {
                    by_pd,
                    x: if by_pd {
                        sim.p_detect
                    } else {
                        sim.clutter_per_scan
                    },
                    f1: [m.f1, g.f1],
                    gospa: [m.gospa, g.gospa],
                    f1_diff: paired(group, |r| r.mcmcda[0].f1 - r.gnn[0].f1),
                    gospa_diff: paired(group, |r| r.mcmcda[0].gospa - r.gnn[0].gospa),
                    tuned: tuned[0],
                }
            })
            .collect::<Vec<Point>>();
        let fresh: Vec<Comparison> = points
            .iter()
            .enumerate()
            .flat_map(|(i, pt)| {
                let (name, key) = pt.names();
                comparisons(
                    &format!("{name} = {}", pt.x),
                    &format!("{key}_{}", pt.x),
                    &fresh_results[i * p.runs..(i + 1) * p.runs],
                    0,
                )
            })
            .collect();
        fresh::check_verdicts(&fresh, &p.fresh_verdicts)?;
        Ok(Output {
            targets: p.targets,
            runs: p.runs,
            p_detect: p.simulation.p_detect,
            clutter_per_scan: p.simulation.clutter_per_scan,
            tuning: p.tuning.clone(),
            points,
            fresh,
            fresh_seed: p.fresh_seed,
            fresh_verdicts: p.fresh_verdicts.clone(),
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for pt in &out.points {
            let (_, key) = pt.names();
            let x = pt.x;
            let mut put = |name: String, (mean, ci): (f64, f64)| {
                metrics.insert(format!("{name}_ci95"), ci);
                metrics.insert(name, mean);
            };
            for (m, method) in ["mcmcda", "gnn"].iter().enumerate() {
                put(format!("{key}_{x}_f1_{method}"), pt.f1[m]);
                put(format!("{key}_{x}_gospa_{method}"), pt.gospa[m]);
            }
            put(format!("{key}_{x}_f1_mcmcda_minus_gnn"), pt.f1_diff);
            put(format!("{key}_{x}_gospa_mcmcda_minus_gnn"), pt.gospa_diff);
            for (what, c) in [("f1", &pt.tuned.by_f1), ("gospa", &pt.tuned.by_gospa)] {
                let prefix = format!("{key}_{x}_gnn_tuned_for_{what}");
                metrics.insert(format!("{prefix}_m"), f64::from(c.confirm_hits));
                metrics.insert(format!("{prefix}_n"), f64::from(c.confirm_window));
                metrics.insert(
                    format!("{prefix}_max_gap"),
                    f64::from(c.max_gap.unwrap_or(0)),
                );
            }
        }
        fresh::metrics(&out.fresh, &mut metrics);
        metrics
    }

    fn present(out: &Output) -> Section {
        let mut table = Table::new(
            &format!(
                "Mean ± 95 % CI over {} scenarios per point, K = {}; GNN tuned per point",
                out.runs, out.targets
            ),
            &[
                "varied",
                "value",
                "F1 MCMCDA",
                "F1 GNN",
                "F1 MCMCDA − GNN",
                "GOSPA MCMCDA",
                "GOSPA GNN",
                "GNN for F1: M/N, gap",
                "GNN for GOSPA: M/N, gap",
            ],
        );
        let cfg = |c: &mcmcda::NearestNeighbourConfig| {
            format!(
                "{}/{}, {}",
                c.confirm_hits,
                c.confirm_window,
                c.max_gap.unwrap_or(0)
            )
        };
        for pt in &out.points {
            table.row(vec![
                pt.names().0.into(),
                fmt_num(pt.x),
                pm(pt.f1[0], 4),
                pm(pt.f1[1], 4),
                pm(pt.f1_diff, 4),
                pm(pt.gospa[0], 1),
                pm(pt.gospa[1], 1),
                cfg(&pt.tuned.by_f1),
                cfg(&pt.tuned.by_gospa),
            ]);
        }
        Section {
            title: "Multi-scan MCMCDA: detection and clutter sweep".into(),
            summary: format!(
                "The batch setting with K = {} targets: p_d is varied with λ_f V = {}, then \
                 λ_f V with p_d = {}. Both trackers' models use the true p_d and clutter rate. \
                 GNN uses the log-likelihood-ratio costs (Blackman 2004) and its M-of-N \
                 confirmation and deletion gap are tuned per point on {} tuning scenarios of \
                 seed {} (F1 with the F1-best settings, GOSPA with the GOSPA-best); the reported \
                 scenarios come from the scenario seed. Means ± 1.96·s/√n; differences are \
                 paired. On the reported scenarios, shown and not claimed: {} The claims are \
                 made on {} fresh scenarios per point of seed {} (drawn once after the tuning \
                 and these results were frozen), each by a paired 95 % t interval: {} (table \
                 below).",
                out.targets,
                out.clutter_per_scan,
                out.p_detect,
                out.tuning.runs,
                out.tuning.seed,
                verdict(out),
                out.runs,
                out.fresh_seed,
                fresh::tally_text(&out.fresh),
            ),
            tables: vec![
                table,
                super::fresh::table(&out.fresh, &out.fresh_verdicts, out.fresh_seed),
            ],
            figures: figures(out),
        }
    }

    fn claims(out: &Output) -> Vec<Claim> {
        claims(out)
    }
}

/// Where MCMCDA wins and loses, in words: a difference counts as significant when its
/// paired 95 % interval excludes 0.
fn verdict(out: &Output) -> String {
    let describe = |what: &str, diff: fn(&Point) -> (f64, f64), sign: f64| {
        let (mut ties, mut losses) = (Vec::new(), Vec::new());
        for pt in &out.points {
            let (d, ci) = diff(pt);
            let text = format!("{} = {} ({d:+.4} ± {ci:.4})", pt.names().0, fmt_num(pt.x));
            if sign * d + ci < 0.0 {
                losses.push(text);
            } else if sign * d - ci <= 0.0 {
                ties.push(text);
            }
        }
        let mut s = format!("{what}: MCMCDA is significantly better at every other point");
        if ties.is_empty() && losses.is_empty() {
            s = format!("{what}: MCMCDA is significantly better at every point");
        }
        s.push_str(&ties_and_losses(&ties, &losses));
        s
    };
    format!(
        "{}{}",
        describe("F1 MCMCDA − GNN", |pt| pt.f1_diff, 1.0),
        describe("GOSPA MCMCDA − GNN", |pt| pt.gospa_diff, -1.0)
    )
}

/// The claims: each fresh comparison's verdict is the recorded one (the reported scenarios'
/// orderings are shown in the summary, not claimed).
fn claims(out: &Output) -> Vec<Claim> {
    fresh::claims(
        &out.fresh,
        &out.fresh_verdicts,
        &format!("seed {}", out.fresh_seed),
    )
}

/// F1 of both trackers against p_d and against the clutter rate.
fn figures(out: &Output) -> Vec<Figure> {
    // The mean, and its 95 % CI as thin lines either side (sign −1, +1).
    let curve = |by_pd: bool, m: usize, side: f64| -> Vec<(f64, f64)> {
        out.points
            .iter()
            .filter(|pt| pt.by_pd == by_pd)
            .map(|pt| (pt.x, pt.f1[m].0 + side * pt.f1[m].1))
            .collect()
    };
    let f1_chart = |title: &str, x: &str, by_pd: bool| {
        let mut series = Vec::new();
        for (m, name) in [(0, "MCMCDA"), (1, "GNN (tuned)")] {
            series.push(Series::new(name, curve(by_pd, m, 0.0), Style::Line, m));
            for side in [-1.0, 1.0] {
                series.push(Series::new("", curve(by_pd, m, side), Style::ThinLine, m));
            }
        }
        Chart::new(
            &format!("{title} (thin: 95 % CI of the mean)"),
            x,
            "F1",
            series,
        )
    };
    vec![
        Figure::new(
            "f1-pd",
            "F1 against p_d",
            f1_chart(
                "Association F1 against the detection probability",
                "p_d",
                true,
            ),
        ),
        Figure::new(
            "f1-clutter",
            "F1 against the clutter rate",
            f1_chart(
                "Association F1 against the clutter rate",
                "false alarms per scan (λ_f V)",
                false,
            ),
        ),
    ]
}
