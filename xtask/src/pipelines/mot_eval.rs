//! `mot-eval`: scores a bundled MOTChallenge sequence with eval-metrics and sets the numbers
//! beside those py-motmetrics computed for the same files, so the report shows the agreement.

use std::collections::BTreeMap;

use anyhow::{Context, Result};
use eval_metrics::{EvalConfig, evaluate};
use indicatif::ProgressBar;
use serde::Deserialize;

use crate::eval::load;
use crate::report::{Section, Table, fmt_num};
use crate::scenario::{Metrics, PipelineOutput, Scenario};
use crate::workspace_root;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Params {
    /// Ground truth, relative to the workspace root.
    gt: String,
    /// Tracker output, relative to the workspace root.
    pred: String,
    /// py-motmetrics' numbers for the same files (JSON), relative to the workspace root.
    reference: String,
}

/// A py-motmetrics summary key and the conversion of its value to our convention.
type Reference = Option<(&'static str, fn(f64) -> f64)>;

pub fn run(scenario: &Scenario, progress: &ProgressBar) -> Result<PipelineOutput> {
    let p: Params = scenario.params()?;
    let root = workspace_root();
    let (gt, pred) = load(&root.join(&p.gt), &root.join(&p.pred))?;
    let report = evaluate(&gt, &pred, &EvalConfig::default())?;
    let reference_path = root.join(&p.reference);
    let reference: BTreeMap<String, serde_json::Value> = serde_json::from_str(
        &std::fs::read_to_string(&reference_path)
            .with_context(|| format!("reading {}", reference_path.display()))?,
    )?;
    let (c, i, h) = (&report.clear, &report.identity, &report.hota);
    // (name, ours, py-motmetrics key and how to turn its value into ours)
    let rows: [(&str, f64, Reference); 16] = [
        ("MOTA", c.mota, Some(("mota", |v| v))),
        (
            "MOTP (mean IoU; motmetrics reports 1 − IoU)",
            c.motp,
            Some(("motp", |v| 1.0 - v)),
        ),
        ("IDF1", i.idf1, Some(("idf1", |v| v))),
        ("IDP", i.idp, Some(("idp", |v| v))),
        ("IDR", i.idr, Some(("idr", |v| v))),
        (
            "TP",
            c.true_positives as f64,
            Some(("num_detections", |v| v)),
        ),
        (
            "FP",
            c.false_positives as f64,
            Some(("num_false_positives", |v| v)),
        ),
        ("FN", c.false_negatives as f64, Some(("num_misses", |v| v))),
        ("IDSW", c.id_switches as f64, Some(("num_switches", |v| v))),
        ("Recall", c.recall, Some(("recall", |v| v))),
        ("Precision", c.precision, Some(("precision", |v| v))),
        ("HOTA", h.hota, None),
        ("DetA", h.det_a, None),
        ("AssA", h.ass_a, None),
        ("LocA", h.loc_a, None),
        ("Frag", c.fragmentations as f64, None),
    ];
    let mut table = Table::new(
        &format!("{} against {} (IoU ≥ 0.5)", p.pred, p.gt),
        &["metric", "eval-metrics", "py-motmetrics 1.4.0", "agree"],
    );
    let mut metrics = Metrics::new();
    let mut n_disagree = 0.0;
    for (name, ours, reference_key) in rows {
        let key = name
            .split_whitespace()
            .next()
            .unwrap_or(name)
            .to_lowercase();
        metrics.insert(key, ours);
        let (theirs, agree) = match reference_key {
            Some((k, convert)) => {
                let v = reference
                    .get(k)
                    .and_then(serde_json::Value::as_f64)
                    .with_context(|| format!("reference lacks {k}"))?;
                let v = convert(v);
                let ok = (ours - v).abs() <= 1e-9;
                n_disagree += f64::from(u8::from(!ok));
                (fmt_num(v), if ok { "yes" } else { "NO" })
            }
            None => ("—".to_string(), ""),
        };
        table.row(vec![name.into(), fmt_num(ours), theirs, agree.into()]);
    }
    metrics.insert("metrics_disagreeing_with_motmetrics".into(), n_disagree);
    progress.inc(1);
    Ok(PipelineOutput {
        metrics,
        section: Section {
            title: "Evaluation metrics against py-motmetrics".into(),
            summary: "A synthetic MOTChallenge sequence (8 people, 60 frames, misses, false alarms, identity \
                      changes and a fragment) scored by eval-metrics and by py-motmetrics; HOTA and \
                      fragmentations have no py-motmetrics counterpart here."
                .into(),
            tables: vec![table],
            plots: Vec::new(),
        },
    })
}
