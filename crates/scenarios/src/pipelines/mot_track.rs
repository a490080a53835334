//! `mot-track`: runs `cargo xtask track`'s code path on bundled MOTChallenge detections with
//! each tracker and scores the output against the ground truth, so the command is exercised by
//! the suite and its accuracy is in the report.

use anyhow::Result;
use eval_metrics::{EvalConfig, EvalReport, evaluate};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use tracker_model::TrackSet;

use crate::{Env, Metrics, Pipeline, Section, Table, fmt_num};
use mot::text::parse_detections;
use mot::track::{TrackerKind, track_detections};

/// The `mot-track` pipeline.
pub struct MotTrack;

/// Its parameters.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Detections, relative to the workspace root.
    detections: String,
    /// Ground truth, relative to the workspace root.
    gt: String,
    /// Trackers to run.
    trackers: Vec<TrackerKind>,
}

/// One tracker's result.
pub struct TrackerResult {
    tracker: TrackerKind,
    n_tracks: usize,
    report: EvalReport,
}

/// Every tracker's result on the detections.
pub struct Output {
    params: Params,
    n_detections: usize,
    n_truth_boxes: usize,
    results: Vec<TrackerResult>,
}

impl Pipeline for MotTrack {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, _: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let detections =
            parse_detections(&env.inputs.read_to_string(&p.detections)?, &p.detections)?;
        let gt_rows = parse_detections(&env.inputs.read_to_string(&p.gt)?, &p.gt)?;
        let gt = TrackSet::from_mot_rows(&gt_rows)?;
        env.progress.set_length(p.trackers.len() as u64);
        let mut results = Vec::with_capacity(p.trackers.len());
        for &tracker in &p.trackers {
            let tracks = track_detections(tracker, &detections, &Default::default(), env.seed)?;
            results.push(TrackerResult {
                tracker,
                n_tracks: tracks.len(),
                report: evaluate(&gt, &tracks, &EvalConfig::default())?,
            });
            env.progress.advance(1);
        }
        Ok(Output {
            params: p.clone(),
            n_detections: detections.len(),
            n_truth_boxes: gt.n_points(),
            results,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for r in &out.results {
            for (key, value) in [
                ("mota", r.report.clear.mota),
                ("idf1", r.report.identity.idf1),
                ("hota", r.report.hota.hota),
                ("tracks", r.n_tracks as f64),
            ] {
                metrics.insert(format!("{}_{key}", r.tracker), value);
            }
        }
        metrics
    }

    fn present(out: &Output) -> Section {
        let mut table = Table::new(
            &format!(
                "{} detections of {} ground-truth boxes",
                out.n_detections, out.n_truth_boxes
            ),
            &[
                "tracker", "tracks", "MOTA", "IDF1", "HOTA", "IDSW", "FP", "FN",
            ],
        );
        for r in &out.results {
            let (c, i, h) = (&r.report.clear, &r.report.identity, &r.report.hota);
            table.row(vec![
                r.tracker.to_string(),
                r.n_tracks.to_string(),
                fmt_num(c.mota),
                fmt_num(i.idf1),
                fmt_num(h.hota),
                c.id_switches.to_string(),
                c.false_positives.to_string(),
                c.false_negatives.to_string(),
            ]);
        }
        Section {
            title: "cargo xtask track on MOTChallenge detections".into(),
            summary: format!(
                "{} tracked with the default model scaled to the median box width, scored \
                 against {} (IoU ≥ 0.5).",
                out.params.detections, out.params.gt
            ),
            tables: vec![table],
            figures: vec![],
        }
    }
}
