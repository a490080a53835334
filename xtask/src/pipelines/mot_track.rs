//! `mot-track`: runs `cargo xtask track`'s code path on bundled MOTChallenge detections with
//! each tracker and scores the output against the ground truth, so the command is exercised by
//! the suite and its accuracy is in the report.

use anyhow::Result;
use eval_metrics::{EvalConfig, evaluate};
use indicatif::ProgressBar;
use serde::Deserialize;
use tracker_model::{MotRow, TrackSet};

use crate::report::{Section, Table, fmt_num};
use crate::scenario::{Metrics, PipelineOutput, Scenario};
use crate::track::{Tracker, read_detections, track_detections};
use crate::workspace_root;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Params {
    /// Detections, relative to the workspace root.
    detections: String,
    /// Ground truth, relative to the workspace root.
    gt: String,
    /// Trackers to run.
    trackers: Vec<Tracker>,
}

pub fn run(scenario: &Scenario, progress: &ProgressBar) -> Result<PipelineOutput> {
    let p: Params = scenario.params()?;
    let root = workspace_root();
    let detections = read_detections(&root.join(&p.detections))?;
    let gt_rows: Vec<MotRow> = read_detections(&root.join(&p.gt))?;
    let gt = TrackSet::from_mot_rows(&gt_rows)?;
    progress.set_length(p.trackers.len() as u64);
    let mut metrics = Metrics::new();
    let mut table = Table::new(
        &format!(
            "{} detections of {} ground-truth boxes",
            detections.len(),
            gt.n_points()
        ),
        &[
            "tracker", "tracks", "MOTA", "IDF1", "HOTA", "IDSW", "FP", "FN",
        ],
    );
    for tracker in &p.trackers {
        let tracks = track_detections(
            *tracker,
            &detections,
            &Default::default(),
            scenario.file.seed,
        )?;
        let r = evaluate(&gt, &tracks, &EvalConfig::default())?;
        let name = format!("{tracker:?}").to_lowercase();
        for (key, value) in [
            ("mota", r.clear.mota),
            ("idf1", r.identity.idf1),
            ("hota", r.hota.hota),
            ("tracks", tracks.len() as f64),
        ] {
            metrics.insert(format!("{name}_{key}"), value);
        }
        table.row(vec![
            name,
            tracks.len().to_string(),
            fmt_num(r.clear.mota),
            fmt_num(r.identity.idf1),
            fmt_num(r.hota.hota),
            r.clear.id_switches.to_string(),
            r.clear.false_positives.to_string(),
            r.clear.false_negatives.to_string(),
        ]);
        progress.inc(1);
    }
    Ok(PipelineOutput {
        metrics,
        section: Section {
            title: "cargo xtask track on MOTChallenge detections".into(),
            summary: format!(
                "{} tracked with the default model scaled to the median box width, scored \
                 against {} (IoU ≥ 0.5).",
                p.detections, p.gt
            ),
            tables: vec![table],
            plots: vec![],
        },
    })
}
