//! The MCMCDA experiments of TAC 2009:
//! * `mcmcda-batch`: for each number of targets K, simulated scenarios are tracked by
//!   multi-scan MCMCDA (started from the greedy nearest-neighbour filter), by GNN, and by an
//!   oracle that knows the true associations; all are scored by association F1 and by the
//!   GOSPA of their smoothed states;
//! * `mcmcda-sweep`: F1 of MCMCDA and GNN against p_d and against the clutter rate;
//! * `mcmcda-online`: sliding-window MCMCDA on the long online example.

use std::time::Instant;

use anyhow::Result;
use eval_metrics::{OspaConfig, association_scores, gospa_over_time};
use indicatif::ProgressBar;
use mcmcda::{
    McmcdaConfig, NearestNeighbourConfig, OnlineConfig, OnlineTracker, Partition, Problem,
    greedy_initial_partition, measurement_labels, nearest_neighbour_tracks, run_chains,
    smoothed_tracks, tracks_by_origin,
};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::{Point2, Scan, SimulationConfig, TrackSet};

use crate::plot::{Axes, Series, Style, chart};
use crate::report::{Plot, Section, Table, fmt_num};
use crate::scenario::{Metrics, PipelineOutput, Scenario};

/// How every scenario of a batch experiment is tracked.
#[derive(Debug, Deserialize)]
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

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BatchParams {
    /// Numbers of targets K; births per scan are K / T.
    targets: Vec<u32>,
    /// Scenarios per K.
    runs: usize,
    /// The simulated world (births_per_scan is set from K).
    simulation: SimulationConfig,
    trackers: Trackers,
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

/// Simulates one scenario with K targets and scores every tracker on it. The world and the
/// tracker's model share p_d and the clutter rate (both set here when given).
fn run_once(
    simulation: &SimulationConfig,
    trackers: &Trackers,
    k: u32,
    rng: &mut ChaCha8Rng,
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
    let window = 0..=problem.n_scans() - 1;
    let truth_tracks = tracks_by_origin(&sim.scans);
    let start = Instant::now();
    let init = greedy_initial_partition(&model, &problem, window.clone())?;
    let run = run_chains(&init, trackers.chains, trackers.samples, rng.random())?;
    let seconds = start.elapsed().as_secs_f64();
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

/// Runs `run_once` for every (setting, run) in parallel, each on its own generator stream.
fn run_grid(
    scenario: &Scenario,
    progress: &ProgressBar,
    settings: &[(SimulationConfig, u32)],
    runs: usize,
    trackers: &Trackers,
) -> Result<Vec<RunScores>> {
    anyhow::ensure!(
        runs > 0 && !settings.is_empty(),
        "runs and settings must be non-empty"
    );
    progress.set_length((settings.len() * runs) as u64);
    let base = scenario.rng();
    (0..settings.len() * runs)
        .into_par_iter()
        .map(|task| {
            let mut rng = base.clone();
            rng.set_stream(task as u64);
            let (simulation, k) = &settings[task / runs];
            let out = run_once(simulation, trackers, *k, &mut rng);
            progress.inc(1);
            out
        })
        .collect()
}

pub fn batch(scenario: &Scenario, progress: &ProgressBar) -> Result<PipelineOutput> {
    let p: BatchParams = scenario.params()?;
    let settings: Vec<(SimulationConfig, u32)> = p
        .targets
        .iter()
        .map(|&k| (p.simulation.clone(), k))
        .collect();
    let results = run_grid(scenario, progress, &settings, p.runs, &p.trackers)?;
    let t = &p.trackers;

    let mut metrics = Metrics::new();
    let mut table = Table::new(
        &format!(
            "Mean over {} scenarios per K ({} scans, {} chain(s) × {} samples)",
            p.runs, p.simulation.n_scans, t.chains, t.samples
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
                p.simulation.p_detect,
                p.simulation.clutter_per_scan,
                t.model.p_disappear,
                t.model.max_gap,
                t.model.max_speed,
                t.gospa_cutoff
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

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepParams {
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

pub fn sweep(scenario: &Scenario, progress: &ProgressBar) -> Result<PipelineOutput> {
    let p: SweepParams = scenario.params()?;
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
    let results = run_grid(scenario, progress, &settings, p.runs, &p.trackers)?;
    let mut metrics = Metrics::new();
    let mut table = Table::new(
        &format!(
            "Association F1, mean over {} scenarios per point, K = {}",
            p.runs, p.targets
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
    let mut curves = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
    for (i, (sim, _)) in settings.iter().enumerate() {
        let group = &results[i * p.runs..(i + 1) * p.runs];
        let mean =
            |f: &dyn Fn(&RunScores) -> f64| group.iter().map(f).sum::<f64>() / group.len() as f64;
        let by_pd = i < p.p_detect.len();
        let (name, key, x) = if by_pd {
            ("p_d", "pd", sim.p_detect)
        } else {
            ("λ_f V", "clutter", sim.clutter_per_scan)
        };
        let f1 = [mean(&|r| r.mcmcda.f1), mean(&|r| r.gnn.f1)];
        let gospa = [mean(&|r| r.mcmcda.gospa), mean(&|r| r.gnn.gospa)];
        for (m, method) in ["mcmcda", "gnn"].iter().enumerate() {
            metrics.insert(format!("{key}_{x}_f1_{method}"), f1[m]);
            metrics.insert(format!("{key}_{x}_gospa_{method}"), gospa[m]);
            curves[usize::from(!by_pd) * 2 + m].push((x, f1[m]));
        }
        table.row(vec![
            name.into(),
            fmt_num(x),
            format!("{:.4}", f1[0]),
            format!("{:.4}", f1[1]),
            fmt_num(gospa[0]),
            fmt_num(gospa[1]),
        ]);
    }
    let [pd_mcmc, pd_gnn, cl_mcmc, cl_gnn] = curves;
    let f1_chart = |title: &str, x: &str, mcmc, gnn| {
        chart(
            &Axes { title, x, y: "F1" },
            &[
                Series::new("MCMCDA", mcmc, Style::Line, 0),
                Series::new("GNN", gnn, Style::Line, 1),
            ],
        )
    };
    let pd_plot = f1_chart(
        "Association F1 against the detection probability",
        "p_d",
        pd_mcmc,
        pd_gnn,
    )?;
    let clutter_plot = f1_chart(
        "Association F1 against the clutter rate",
        "false alarms per scan (λ_f V)",
        cl_mcmc,
        cl_gnn,
    )?;
    Ok(PipelineOutput {
        metrics,
        section: Section {
            title: "Multi-scan MCMCDA: detection and clutter sweep".into(),
            summary: format!(
                "The batch setting with K = {} targets: p_d is varied with λ_f V = {}, then                  λ_f V with p_d = {}. The tracker's model uses the true p_d and clutter rate.",
                p.targets, p.simulation.clutter_per_scan, p.simulation.p_detect
            ),
            tables: vec![table],
            plots: vec![
                Plot {
                    name: "f1-pd".into(),
                    caption: "F1 against p_d".into(),
                    svg: pd_plot,
                },
                Plot {
                    name: "f1-clutter".into(),
                    caption: "F1 against the clutter rate".into(),
                    svg: clutter_plot,
                },
            ],
        },
    })
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct OnlineParams {
    simulation: SimulationConfig,
    /// The tracker's model (its p_d, rates and noise should match the simulation).
    model: McmcdaConfig,
    online: OnlineConfig,
    /// OSPA cut-off c (order 2).
    ospa_cutoff: f64,
}

pub fn online(scenario: &Scenario, progress: &ProgressBar) -> Result<PipelineOutput> {
    let p: OnlineParams = scenario.params()?;
    let mut rng = scenario.rng();
    let sim = p.simulation.check()?.simulate(&mut rng)?;
    let model = p.model.check()?;
    progress.set_length(sim.scans.len() as u64);
    let first = sim.scans.first().map_or(0, |s| s.frame);
    let mut tracker = OnlineTracker::new(model.clone(), first, p.online, rng.random())?;
    let truth_by_frame = sim.truth.by_frame();
    let cfg = OspaConfig {
        cutoff: p.ospa_cutoff,
        order: 2.0,
    };
    let start = Instant::now();
    let mut steps = Vec::with_capacity(sim.scans.len());
    for scan in &sim.scans {
        let points: Vec<Point2> = scan.measurements.iter().map(|m| m.value).collect();
        steps.push(tracker.push_scan(scan.frame, &points)?);
        progress.inc(1);
    }
    let seconds = start.elapsed().as_secs_f64();
    let result = tracker.finish()?;
    let mut ospa_series = Vec::new();
    let mut count_est = Vec::new();
    let mut count_true = Vec::new();
    for step in &steps {
        let truth: Vec<Point2> = truth_by_frame
            .get(&step.frame)
            .map(|v| v.iter().map(|(_, tp)| tp.location.position()).collect())
            .unwrap_or_default();
        let est: Vec<Point2> = step.estimates.iter().map(|(_, p)| *p).collect();
        let x = f64::from(step.frame);
        ospa_series.push((x, eval_metrics::ospa(&truth, &est, &cfg)?.distance));
        count_est.push((x, est.len() as f64));
        count_true.push((x, truth.len() as f64));
    }
    let tracks: Vec<Vec<u32>> = result.associations.iter().map(|(_, t)| t.clone()).collect();
    let labels = measurement_labels(&result.problem, &tracks);
    let scores = association_scores(&sim.scans, &labels)?;
    let final_ospa = eval_metrics::ospa_over_time(&sim.truth, &result.tracks, &cfg)?;
    let mean = |v: &[(f64, f64)]| v.iter().map(|p| p.1).sum::<f64>() / v.len().max(1) as f64;
    let final_mean =
        final_ospa.iter().map(|(_, o)| o.distance).sum::<f64>() / final_ospa.len().max(1) as f64;
    let mut metrics = Metrics::new();
    metrics.insert("f1".into(), scores.f1);
    metrics.insert("precision".into(), scores.precision);
    metrics.insert("recall".into(), scores.recall);
    metrics.insert("mean_ospa_online".into(), mean(&ospa_series));
    metrics.insert("mean_ospa_smoothed".into(), final_mean);
    metrics.insert("mean_tracks_reported".into(), mean(&count_est));
    metrics.insert("mean_targets_true".into(), mean(&count_true));
    metrics.insert("n_tracks".into(), result.tracks.len() as f64);
    metrics.insert("n_targets".into(), sim.truth.len() as f64);
    let mut table = Table::new(
        &format!(
            "Online MCMCDA over {} scans (window {}, {} samples per scan)",
            sim.scans.len(),
            p.online.window,
            p.online.samples_per_scan
        ),
        &["quantity", "value"],
    );
    for (name, value) in [
        (
            "association F1 (final associations)",
            format!("{:.4}", scores.f1),
        ),
        (
            "precision / recall",
            format!("{:.4} / {:.4}", scores.precision, scores.recall),
        ),
        ("mean OSPA, online estimates", fmt_num(mean(&ospa_series))),
        ("mean OSPA, smoothed final tracks", fmt_num(final_mean)),
        ("mean number of tracks reported", fmt_num(mean(&count_est))),
        ("mean number of targets", fmt_num(mean(&count_true))),
        (
            "tracks / targets in total",
            format!("{} / {}", result.tracks.len(), sim.truth.len()),
        ),
        (
            "scans per second (this run)",
            format!("{:.0}", sim.scans.len() as f64 / seconds),
        ),
    ] {
        table.row(vec![name.into(), value]);
    }
    let position = |tp: &tracker_model::TrackPoint| {
        let q = tp.location.position();
        (q.x, q.y)
    };
    // Only the first series of each kind is named, so the legend has one entry per kind.
    let name = |i: usize, label: &'static str| if i == 0 { label } else { "" };
    let mut series: Vec<Series> = sim
        .truth
        .tracks()
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let points = t.points().iter().map(position).collect();
            Series::new(name(i, "true trajectories"), points, Style::ThinLine, 7)
        })
        .collect();
    series.extend(result.tracks.tracks().iter().enumerate().map(|(i, t)| {
        let points = t.points().iter().map(position).collect();
        Series::new(name(i, "tracks"), points, Style::Line, i % 7)
    }));
    let tracks_plot = chart(
        &Axes {
            title: "Tracks (colours) over the true trajectories (grey)",
            x: "x",
            y: "y",
        },
        &series,
    )?;
    let ospa_plot = chart(
        &Axes {
            title: "OSPA of the online estimates",
            x: "scan",
            y: "OSPA (c, p = 2)",
        },
        &[Series::new("online MCMCDA", ospa_series, Style::Line, 0)],
    )?;
    let count_plot = chart(
        &Axes {
            title: "Number of tracks against the number of targets",
            x: "scan",
            y: "count",
        },
        &[
            Series::new("targets", count_true, Style::Line, 7),
            Series::new("tracks reported", count_est, Style::Line, 0),
        ],
    )?;
    Ok(PipelineOutput {
        metrics,
        section: Section {
            title: "Online MCMCDA: the long example of TAC 2009".into(),
            summary: format!(
                "Region [0, 100]², {} scans, λ_b V = {}, p_z = {}, p_d = {}, λ_f V = {}. After \
                 each scan the chain runs on the last {} scans; a track is reported while its \
                 last measurement is at most {} scans old. OSPA uses c = {}, p = 2.",
                p.simulation.n_scans,
                p.simulation.births_per_scan,
                p.simulation.p_disappear,
                p.simulation.p_detect,
                p.simulation.clutter_per_scan,
                p.online.window,
                p.online.coast_scans,
                p.ospa_cutoff
            ),
            tables: vec![table],
            plots: vec![
                Plot {
                    name: "tracks".into(),
                    caption: "Final tracks and true trajectories".into(),
                    svg: tracks_plot,
                },
                Plot {
                    name: "ospa".into(),
                    caption: "OSPA at each scan".into(),
                    svg: ospa_plot,
                },
                Plot {
                    name: "count".into(),
                    caption: "Number of tracks over time against the truth".into(),
                    svg: count_plot,
                },
            ],
        },
    })
}
