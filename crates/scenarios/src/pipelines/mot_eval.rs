//! `mot-eval`: scores a bundled MOTChallenge sequence with eval-metrics and sets the numbers
//! beside those py-motmetrics computed for the same files, so the report shows the agreement.

use std::collections::BTreeMap;

use anyhow::{Context, Result};
use eval_metrics::{EvalConfig, EvalReport, evaluate};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

use crate::mot::parse_evaluation_pair;
use crate::{Env, Metrics, Pipeline, Section, Table, fmt_num};

/// The `mot-eval` pipeline.
pub struct MotEval;

/// Its parameters.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Ground truth, relative to the workspace root.
    gt: String,
    /// Tracker output, relative to the workspace root.
    pred: String,
    /// py-motmetrics' numbers for the same files (JSON), relative to the workspace root.
    reference: String,
}

/// Our report and py-motmetrics' summary of the same files.
pub struct Output {
    params: Params,
    report: EvalReport,
    /// Per row of [`rows`]: py-motmetrics' value in our convention, where it has one.
    reference: Vec<Option<f64>>,
}

/// A py-motmetrics summary key and the conversion of its value to our convention.
type Reference = Option<(&'static str, fn(f64) -> f64)>;

/// (name, ours, py-motmetrics key and how to turn its value into ours)
fn rows(report: &EvalReport) -> [(&'static str, f64, Reference); 16] {
    let (c, i, h) = (&report.clear, &report.identity, &report.hota);
    [
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
    ]
}

/// Ours and theirs agree when they differ by at most 1e-9 (a NaN never agrees).
fn agrees(ours: f64, theirs: f64) -> bool {
    (ours - theirs).abs() <= 1e-9
}

impl Pipeline for MotEval {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, _: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let read = |path: &str| env.inputs.read_to_string(path);
        let (gt, pred) = parse_evaluation_pair((&read(&p.gt)?, &p.gt), (&read(&p.pred)?, &p.pred))?;
        let report = evaluate(&gt, &pred, &EvalConfig::default())?;
        let summary: BTreeMap<String, serde_json::Value> =
            serde_json::from_str(&read(&p.reference)?)
                .with_context(|| format!("parsing {}", p.reference))?;
        let reference = rows(&report)
            .iter()
            .map(|(_, _, key)| {
                key.map(|(k, convert)| {
                    summary
                        .get(k)
                        .and_then(serde_json::Value::as_f64)
                        .map(convert)
                        .with_context(|| format!("{} lacks {k}", p.reference))
                })
                .transpose()
            })
            .collect::<Result<_>>()?;
        env.progress.advance(1);
        Ok(Output {
            params: p.clone(),
            report,
            reference,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        let mut n_disagree = 0.0;
        for ((name, ours, _), theirs) in rows(&out.report).into_iter().zip(&out.reference) {
            let key = name
                .split_whitespace()
                .next()
                .unwrap_or(name)
                .to_lowercase();
            metrics.insert(key, ours);
            if theirs.is_some_and(|v| !agrees(ours, v)) {
                n_disagree += 1.0;
            }
        }
        metrics.insert("metrics_disagreeing_with_motmetrics".into(), n_disagree);
        metrics
    }

    fn present(out: &Output) -> Section {
        let mut table = Table::new(
            &format!("{} against {} (IoU ≥ 0.5)", out.params.pred, out.params.gt),
            &["metric", "eval-metrics", "py-motmetrics 1.4.0", "agree"],
        );
        for ((name, ours, _), theirs) in rows(&out.report).into_iter().zip(&out.reference) {
            let (theirs, agree) = match theirs {
                Some(v) if agrees(ours, *v) => (fmt_num(*v), "yes"),
                Some(v) => (fmt_num(*v), "NO"),
                None => ("—".to_string(), ""),
            };
            table.row(vec![name.into(), fmt_num(ours), theirs, agree.into()]);
        }
        Section {
            title: "Evaluation metrics against py-motmetrics".into(),
            summary: "A synthetic MOTChallenge sequence (8 people, 60 frames, misses, false alarms, identity \
                      changes and a fragment) scored by eval-metrics and by py-motmetrics; HOTA and \
                      fragmentations have no py-motmetrics counterpart here."
                .into(),
            tables: vec![table],
            figures: Vec::new(),
        }
    }
}
