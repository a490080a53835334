//! `mot-eval`: scores a bundled MOTChallenge sequence with eval-metrics and sets the numbers
//! beside those py-motmetrics and TrackEval (the reference implementation of HOTA; Luiten et
//! al. 2021) computed for the same files, so the report shows the agreement and the suite
//! checks it.

use std::collections::BTreeMap;

use anyhow::{Context, Result};
use eval_metrics::{EvalConfig, EvalReport, evaluate};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

use crate::{Claim, Env, Metrics, Pipeline, Section, Table, fmt_num};
use mot::text::parse_evaluation_pair;

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
    /// TrackEval's numbers for the same files (JSON), relative to the workspace root.
    trackeval: String,
}

/// Our report and py-motmetrics' summary of the same files.
pub struct Output {
    params: Params,
    report: EvalReport,
    /// Per row of [`rows`]: py-motmetrics' value in our convention, where it has one.
    reference: Vec<Option<f64>>,
    /// Per row of [`rows`]: TrackEval's value, where it has one.
    trackeval: Vec<Option<f64>>,
}

/// A py-motmetrics summary key and the conversion of its value to our convention.
type Reference = Option<(&'static str, fn(f64) -> f64)>;

/// One row: name, ours, py-motmetrics' key and conversion, TrackEval's key.
type Row = (&'static str, f64, Reference, Option<&'static str>);

/// The rows of the comparison table.
fn rows(report: &EvalReport) -> [Row; 23] {
    let (c, i, h) = (&report.clear, &report.identity, &report.hota);
    let same = |v| v;
    [
        ("MOTA", c.mota, Some(("mota", same)), Some("MOTA")),
        (
            "MOTP (mean IoU; motmetrics reports 1 − IoU)",
            c.motp,
            Some(("motp", |v| 1.0 - v)),
            Some("MOTP"),
        ),
        ("MODA", c.moda, None, Some("MODA")),
        ("IDF1", i.idf1, Some(("idf1", same)), Some("IDF1")),
        ("IDP", i.idp, Some(("idp", same)), Some("IDP")),
        ("IDR", i.idr, Some(("idr", same)), Some("IDR")),
        (
            "TP",
            c.true_positives as f64,
            Some(("num_detections", same)),
            Some("CLR_TP"),
        ),
        (
            "FP",
            c.false_positives as f64,
            Some(("num_false_positives", same)),
            Some("CLR_FP"),
        ),
        (
            "FN",
            c.false_negatives as f64,
            Some(("num_misses", same)),
            Some("CLR_FN"),
        ),
        (
            "IDSW",
            c.id_switches as f64,
            Some(("num_switches", same)),
            Some("IDSW"),
        ),
        ("Recall", c.recall, Some(("recall", same)), Some("CLR_Re")),
        (
            "Precision",
            c.precision,
            Some(("precision", same)),
            Some("CLR_Pr"),
        ),
        ("HOTA", h.hota, None, Some("HOTA")),
        ("DetA", h.det_a, None, Some("DetA")),
        ("AssA", h.ass_a, None, Some("AssA")),
        ("LocA", h.loc_a, None, Some("LocA")),
        ("DetRe", h.det_re, None, Some("DetRe")),
        ("DetPr", h.det_pr, None, Some("DetPr")),
        ("AssRe", h.ass_re, None, Some("AssRe")),
        ("AssPr", h.ass_pr, None, Some("AssPr")),
        ("Frag", c.fragmentations as f64, None, Some("Frag")),
        (
            "MT (matched in > 80 % of its frames)",
            c.mostly_tracked as f64,
            None,
            Some("MT"),
        ),
        (
            "ML (matched in < 20 % of its frames)",
            c.mostly_lost as f64,
            None,
            Some("ML"),
        ),
    ]
}

/// How many rows with a reference value disagree with it.
fn disagreements(report: &EvalReport, reference: &[Option<f64>]) -> usize {
    rows(report)
        .iter()
        .zip(reference)
        .filter(|((_, ours, _, _), theirs)| theirs.is_some_and(|v| !agrees(*ours, v)))
        .count()
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
        let trackeval: BTreeMap<String, serde_json::Value> =
            serde_json::from_str(&read(&p.trackeval)?)
                .with_context(|| format!("parsing {}", p.trackeval))?;
        let trackeval = rows(&report)
            .iter()
            .map(|(_, _, _, key)| {
                key.map(|k| {
                    trackeval
                        .get(k)
                        .and_then(serde_json::Value::as_f64)
                        .with_context(|| format!("{} lacks {k}", p.trackeval))
                })
                .transpose()
            })
            .collect::<Result<_>>()?;
        let reference = rows(&report)
            .iter()
            .map(|(_, _, key, _)| {
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
            trackeval,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        let mut n_disagree = 0.0;
        for ((name, ours, _, _), theirs) in rows(&out.report).into_iter().zip(&out.reference) {
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
        metrics.insert(
            "metrics_disagreeing_with_trackeval".into(),
            disagreements(&out.report, &out.trackeval) as f64,
        );
        metrics
    }

    fn claims(out: &Output) -> Vec<Claim> {
        let checked = |v: &[Option<f64>]| v.iter().flatten().count();
        vec![
            Claim::new(
                format!(
                    "every metric with a py-motmetrics counterpart ({}) agrees with it within 1e-9",
                    checked(&out.reference)
                ),
                disagreements(&out.report, &out.reference) == 0,
            ),
            Claim::new(
                format!(
                    "every metric with a TrackEval counterpart ({}, HOTA, Frag and MT/ML among \
                     them) agrees with it within 1e-9",
                    checked(&out.trackeval)
                ),
                disagreements(&out.report, &out.trackeval) == 0,
            ),
        ]
    }

    fn present(out: &Output) -> Section {
        let mut table = Table::new(
            &format!("{} against {} (IoU ≥ 0.5)", out.params.pred, out.params.gt),
            &[
                "metric",
                "eval-metrics",
                "py-motmetrics 1.4.0",
                "agree",
                "TrackEval (sn-trackeval 0.4.0)",
                "agree",
            ],
        );
        let cell = |ours: f64, theirs: &Option<f64>| match theirs {
            Some(v) if agrees(ours, *v) => (fmt_num(*v), "yes"),
            Some(v) => (fmt_num(*v), "NO"),
            None => ("—".to_string(), ""),
        };
        for (((name, ours, _, _), reference), trackeval) in rows(&out.report)
            .into_iter()
            .zip(&out.reference)
            .zip(&out.trackeval)
        {
            let (m, m_agree) = cell(ours, reference);
            let (t, t_agree) = cell(ours, trackeval);
            table.row(vec![
                name.into(),
                fmt_num(ours),
                m,
                m_agree.into(),
                t,
                t_agree.into(),
            ]);
        }
        Section {
            title: "Evaluation metrics against py-motmetrics and TrackEval".into(),
            summary: "A synthetic MOTChallenge sequence (8 people, 60 frames, noisy boxes so IoU < 1, misses, \
                      false alarms, identity changes and a fragment) scored by eval-metrics, by \
                      py-motmetrics (testdata/gen_reference.py) and by TrackEval's HOTA, CLEAR and \
                      Identity classes (testdata/gen_trackeval_reference.py). Conventions are \
                      TrackEval's: MT > 80 % and ML < 20 % of a truth object's frames matched, Frag \
                      = tracked runs less one per object, and a frame with no truth or no estimates \
                      neither matches nor breaks a run."
                .into(),
            tables: vec![table],
            figures: Vec::new(),
        }
    }
}
