//! `mcmcda-online`: sliding-window MCMCDA on the long online example.

use anyhow::Result;
use eval_metrics::{AssociationScores, OspaConfig, association_scores};
use mcmcda::{
    McmcdaConfig, OnlineConfig, OnlineResult, OnlineStep, OnlineTracker, measurement_labels,
};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use tracker_model::{Simulation, SimulationConfig, TrackPoint, TrackSet, Vec2};

use crate::{
    Chart, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style, Table, fmt_num,
};

/// The `mcmcda-online` pipeline.
pub struct Online;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    simulation: SimulationConfig,
    /// The tracker's model (its p_d, rates and noise should match the simulation).
    model: McmcdaConfig,
    online: OnlineConfig,
    /// OSPA cut-off c (order 2).
    ospa_cutoff: f64,
}

/// The scores, the per-scan series and the trajectories of one online run.
pub struct Output {
    simulation: SimulationConfig,
    online: OnlineConfig,
    ospa_cutoff: f64,
    /// Scans tracked.
    n_scans: usize,
    /// Wall-clock seconds spent pushing the scans.
    seconds: f64,
    /// Association scores of the final associations.
    scores: AssociationScores,
    /// (frame, OSPA of the online estimates).
    ospa_series: Vec<(f64, f64)>,
    /// (frame, number of tracks reported).
    count_est: Vec<(f64, f64)>,
    /// (frame, number of true targets).
    count_true: Vec<(f64, f64)>,
    /// Mean OSPA of the smoothed final tracks.
    mean_ospa_smoothed: f64,
    /// Final tracks.
    n_tracks: usize,
    /// True targets.
    n_targets: usize,
    /// The true trajectories' positions.
    truth_paths: Vec<Vec<(f64, f64)>>,
    /// The final tracks' positions.
    track_paths: Vec<Vec<(f64, f64)>>,
}

/// The mean of the series' values (0 when empty).
fn mean(v: &[(f64, f64)]) -> f64 {
    v.iter().map(|p| p.1).sum::<f64>() / v.len().max(1) as f64
}

/// Runs the online tracker over the scans: its steps, its final result and the seconds taken.
fn track(
    p: &Params,
    sim: &Simulation,
    rng: &mut ChaCha8Rng,
    env: &Env<'_>,
) -> Result<(Vec<OnlineStep>, OnlineResult, f64)> {
    let model = p.model.check()?;
    env.progress.set_length(sim.scans.len() as u64);
    let first = sim.scans.first().map_or(0, |s| s.frame);
    let mut tracker = OnlineTracker::new(model.clone(), first, p.online, rng.random())?;
    let start = env.clock.now_s();
    let mut steps = Vec::with_capacity(sim.scans.len());
    for scan in &sim.scans {
        let points: Vec<Vec2> = scan.measurements.iter().map(|m| m.value).collect();
        steps.push(tracker.push_scan(scan.frame, &points)?);
        env.progress.advance(1);
    }
    let seconds = env.clock.now_s() - start;
    Ok((steps, tracker.finish()?, seconds))
}

/// Per step: (frame, OSPA), (frame, tracks reported), (frame, true targets).
type StepSeries = (Vec<(f64, f64)>, Vec<(f64, f64)>, Vec<(f64, f64)>);

/// OSPA and counts of the online estimates at each step.
fn step_series(steps: &[OnlineStep], truth: &TrackSet, cfg: &OspaConfig) -> Result<StepSeries> {
    let truth_by_frame = truth.by_frame();
    let mut ospa_series = Vec::new();
    let mut count_est = Vec::new();
    let mut count_true = Vec::new();
    for step in steps {
        let truth: Vec<Vec2> = truth_by_frame
            .get(&step.frame)
            .map(|v| v.iter().map(|(_, tp)| tp.location.position()).collect())
            .unwrap_or_default();
        let est: Vec<Vec2> = step.estimates.iter().map(|(_, p)| *p).collect();
        let x = f64::from(step.frame);
        ospa_series.push((x, eval_metrics::ospa(&truth, &est, cfg)?.distance));
        count_est.push((x, est.len() as f64));
        count_true.push((x, truth.len() as f64));
    }
    Ok((ospa_series, count_est, count_true))
}

/// Each track's positions.
fn paths(tracks: &TrackSet) -> Vec<Vec<(f64, f64)>> {
    let position = |tp: &TrackPoint| {
        let q = tp.location.position();
        (q.x, q.y)
    };
    tracks
        .tracks()
        .iter()
        .map(|t| t.points().iter().map(position).collect())
        .collect()
}

impl Pipeline for Online {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let sim = p.simulation.check()?.simulate(rng)?;
        let (steps, result, seconds) = track(p, &sim, rng, env)?;
        let cfg = OspaConfig {
            cutoff: p.ospa_cutoff,
            order: 2.0,
        };
        let (ospa_series, count_est, count_true) = step_series(&steps, &sim.truth, &cfg)?;
        let tracks: Vec<Vec<u32>> = result.associations.iter().map(|(_, t)| t.clone()).collect();
        let labels = measurement_labels(&result.problem, &tracks)?;
        let scores = association_scores(&sim.scans, &labels)?;
        let final_ospa = eval_metrics::ospa_over_time(&sim.truth, &result.tracks, &cfg)?;
        let mean_ospa_smoothed = final_ospa.iter().map(|(_, o)| o.distance).sum::<f64>()
            / final_ospa.len().max(1) as f64;
        Ok(Output {
            simulation: p.simulation.clone(),
            online: p.online,
            ospa_cutoff: p.ospa_cutoff,
            n_scans: sim.scans.len(),
            seconds,
            scores,
            ospa_series,
            count_est,
            count_true,
            mean_ospa_smoothed,
            n_tracks: result.tracks.len(),
            n_targets: sim.truth.len(),
            truth_paths: paths(&sim.truth),
            track_paths: paths(&result.tracks),
        })
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let m = Self::metrics(out);
        vec![
            Headline::of_metrics(&m, "online MCMCDA: association F1", ("f1", None), None),
            Headline::of_metrics(
                &m,
                "online MCMCDA: mean OSPA of the online estimates",
                ("mean_ospa_online", None),
                None,
            ),
        ]
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        metrics.insert("f1".into(), out.scores.f1);
        metrics.insert("precision".into(), out.scores.precision);
        metrics.insert("recall".into(), out.scores.recall);
        metrics.insert("mean_ospa_online".into(), mean(&out.ospa_series));
        metrics.insert("mean_ospa_smoothed".into(), out.mean_ospa_smoothed);
        metrics.insert("mean_tracks_reported".into(), mean(&out.count_est));
        metrics.insert("mean_targets_true".into(), mean(&out.count_true));
        metrics.insert("n_tracks".into(), out.n_tracks as f64);
        metrics.insert("n_targets".into(), out.n_targets as f64);
        metrics
    }

    fn present(out: &Output) -> Section {
        let sim = &out.simulation;
        Section {
            title: "Online MCMCDA: the long example of TAC 2009".into(),
            summary: format!(
                "Region [{}, {}] × [{}, {}], {} scans, λ_b V = {}, p_z = {}, p_d = {}, \
                 λ_f V = {}. After each scan the chain runs {} samples on the last {} scans; a \
                 track is reported while its last measurement is at most {} scans old. OSPA \
                 uses c = {}, p = 2.",
                sim.region.lower().x,
                sim.region.upper().x,
                sim.region.lower().y,
                sim.region.upper().y,
                sim.n_scans,
                sim.births_per_scan,
                sim.p_disappear,
                sim.p_detect,
                sim.clutter_per_scan,
                out.online.samples_per_scan,
                out.online.window,
                out.online.coast_scans,
                out.ospa_cutoff
            ),
            tables: vec![table(out)],
            figures: figures(out),
        }
    }
}

/// The scores of the run.
fn table(out: &Output) -> Table {
    let mut table = Table::new("Online MCMCDA's scores", &["quantity", "value"]);
    let scores = &out.scores;
    for (name, value) in [
        (
            "association F1 (final associations)",
            format!("{:.4}", scores.f1),
        ),
        (
            "precision / recall",
            format!("{:.4} / {:.4}", scores.precision, scores.recall),
        ),
        (
            "mean OSPA, online estimates",
            fmt_num(mean(&out.ospa_series)),
        ),
        (
            "mean OSPA, smoothed final tracks",
            fmt_num(out.mean_ospa_smoothed),
        ),
        (
            "mean number of tracks reported",
            fmt_num(mean(&out.count_est)),
        ),
        ("mean number of targets", fmt_num(mean(&out.count_true))),
        (
            "tracks / targets in total",
            format!("{} / {}", out.n_tracks, out.n_targets),
        ),
        (
            "scans per second (this run)",
            format!("{:.0}", out.n_scans as f64 / out.seconds),
        ),
    ] {
        table.row(vec![name.into(), value]);
    }
    table
}

/// The shortest track drawn: the final tracks include hundreds of two- and three-scan tracks
/// of clutter, which would bury the picture.
const MIN_DRAWN_SCANS: usize = 5;

/// Tracks over the truth, OSPA over time, and the number of tracks against the truth.
fn figures(out: &Output) -> Vec<Figure> {
    // Only the first series of each kind is named, so the legend has one entry per kind.
    let name = |i: usize, label: &'static str| if i == 0 { label } else { "" };
    // Targets walk out of the region and smoothed tracks run a little past its edge; the
    // map shows the region only (the scene's outskirts made it a small square in the middle).
    let region = &out.simulation.region;
    let inside = |&(x, y): &(f64, f64)| region.contains(&tracker_model::Vec2::new(x, y));
    let drawn: Vec<Vec<(f64, f64)>> = out
        .track_paths
        .iter()
        .filter(|pts| pts.len() >= MIN_DRAWN_SCANS)
        .map(|pts| pts.iter().copied().filter(inside).collect())
        .collect();
    let mut series: Vec<Series> = drawn
        .iter()
        .enumerate()
        .map(|(i, pts)| {
            let label = name(i, "tracks of 5 scans or more");
            Series::new(label, pts.clone(), Style::Line, i % 7)
        })
        .collect();
    // The truth on top, thin and grey, so that a track that follows it shows on both sides.
    series.extend(out.truth_paths.iter().enumerate().map(|(i, pts)| {
        Series::new(
            name(i, "true trajectories"),
            pts.iter().copied().filter(inside).collect(),
            Style::ThinLine,
            7,
        )
        .in_front()
    }));
    let corners = [region.lower(), region.upper()].map(|c| (c.x, c.y));
    series.push(Series::new("", corners.to_vec(), Style::Markers, 7));
    let tracks_chart = Chart::new(
        &format!(
            "{} of {} tracks (5 scans or more; colours) under the true trajectories (grey)",
            drawn.len(),
            out.track_paths.len()
        ),
        "x (region units)",
        "y (region units)",
        series,
    )
    .with_equal_aspect();
    let ospa_chart = Chart::new(
        "OSPA of the online estimates",
        "scan",
        "OSPA (region units; c, p = 2)",
        vec![Series::new(
            "online MCMCDA",
            out.ospa_series.clone(),
            Style::Line,
            0,
        )],
    );
    let count_chart = Chart::new(
        "Number of tracks against the number of targets",
        "scan",
        "count",
        vec![
            Series::new("targets", out.count_true.clone(), Style::Line, 7),
            Series::new("tracks reported", out.count_est.clone(), Style::Line, 0),
        ],
    );
    vec![
        Figure::new("tracks", "Final tracks and true trajectories", tracks_chart),
        Figure::new("ospa", "OSPA at each scan", ospa_chart),
        Figure::new(
            "count",
            "Number of tracks over time against the truth",
            count_chart,
        ),
    ]
}
