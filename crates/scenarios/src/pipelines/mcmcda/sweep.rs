//! `mcmcda-sweep`: F1 and GOSPA of MCMCDA and GNN against p_d and against the clutter rate.

use anyhow::Result;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use tracker_model::SimulationConfig;

use super::{RunScores, Trackers, group_mean, run_grid};
use crate::{Chart, Env, Figure, Metrics, Pipeline, Section, Series, Style, Table, fmt_num};

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
}

/// Means over the scenarios of one point of the sweep.
pub struct Point {
    /// Whether p_d (rather than the clutter rate) is varied.
    by_pd: bool,
    /// The varied value.
    x: f64,
    /// Mean F1 of MCMCDA and GNN.
    f1: [f64; 2],
    /// Mean GOSPA of MCMCDA and GNN.
    gospa: [f64; 2],
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
    points: Vec<Point>,
}

impl Pipeline for Sweep {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let mut settings: Vec<(SimulationConfig, u32)> = Vec::new();
        for &p_detect in &p.p_detect {
            let sim = SimulationConfig {
                p_detect,
                ..p.simulation.clone()
            };
            settings.push((sim, p.targets));
        }
        for &clutter_per_scan in &p.clutter {
            let sim = SimulationConfig {
                clutter_per_scan,
                ..p.simulation.clone()
            };
            settings.push((sim, p.targets));
        }
        let results = run_grid(rng, env, &settings, p.runs, &p.trackers)?;
        let points = settings
            .iter()
            .enumerate()
            .map(|(i, (sim, _))| {
                let group = &results[i * p.runs..(i + 1) * p.runs];
                let mean = |f: &dyn Fn(&RunScores) -> f64| group_mean(group, f);
                let by_pd = i < p.p_detect.len();
                Point {
                    by_pd,
                    x: if by_pd {
                        sim.p_detect
                    } else {
                        sim.clutter_per_scan
                    },
                    f1: [mean(&|r| r.mcmcda.f1), mean(&|r| r.gnn.f1)],
                    gospa: [mean(&|r| r.mcmcda.gospa), mean(&|r| r.gnn.gospa)],
                }
            })
            .collect();
        Ok(Output {
            targets: p.targets,
            runs: p.runs,
            p_detect: p.simulation.p_detect,
            clutter_per_scan: p.simulation.clutter_per_scan,
            points,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for pt in &out.points {
            let (_, key) = pt.names();
            let x = pt.x;
            for (m, method) in ["mcmcda", "gnn"].iter().enumerate() {
                metrics.insert(format!("{key}_{x}_f1_{method}"), pt.f1[m]);
                metrics.insert(format!("{key}_{x}_gospa_{method}"), pt.gospa[m]);
            }
        }
        metrics
    }

    fn present(out: &Output) -> Section {
        let mut table = Table::new(
            &format!(
                "Association F1, mean over {} scenarios per point, K = {}",
                out.runs, out.targets
            ),
            &[
                "varied",
                "value",
                "F1 MCMCDA",
                "F1 GNN",
                "GOSPA MCMCDA",
                "GOSPA GNN",
            ],
        );
        for pt in &out.points {
            table.row(vec![
                pt.names().0.into(),
                fmt_num(pt.x),
                format!("{:.4}", pt.f1[0]),
                format!("{:.4}", pt.f1[1]),
                fmt_num(pt.gospa[0]),
                fmt_num(pt.gospa[1]),
            ]);
        }
        Section {
            title: "Multi-scan MCMCDA: detection and clutter sweep".into(),
            summary: format!(
                "The batch setting with K = {} targets: p_d is varied with λ_f V = {}, then                  λ_f V with p_d = {}. The tracker's model uses the true p_d and clutter rate.",
                out.targets, out.clutter_per_scan, out.p_detect
            ),
            tables: vec![table],
            figures: figures(out),
        }
    }
}

/// F1 of both trackers against p_d and against the clutter rate.
fn figures(out: &Output) -> Vec<Figure> {
    let curve = |by_pd: bool, m: usize| -> Vec<(f64, f64)> {
        out.points
            .iter()
            .filter(|pt| pt.by_pd == by_pd)
            .map(|pt| (pt.x, pt.f1[m]))
            .collect()
    };
    let f1_chart = |title: &str, x: &str, by_pd: bool| {
        Chart::new(
            title,
            x,
            "F1",
            vec![
                Series::new("MCMCDA", curve(by_pd, 0), Style::Line, 0),
                Series::new("GNN", curve(by_pd, 1), Style::Line, 1),
            ],
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
