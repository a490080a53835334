//! `evaluate`: eval-metrics on MOTChallenge arrays or files, every number under the name
//! py-motmetrics or TrackEval gives it (and the papers' SR, FAF, OSPA and GOSPA).

use std::collections::BTreeSet;
use std::path::PathBuf;

use eval_metrics::{EvalConfig, EvalReport, MatchConfig, OspaConfig};
use mot::text::{EvaluationPair, evaluation_pair_of_rows};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tracker_model::{BoundingBox, MotRow, TrackSet};

use crate::arrays::table;
use crate::errors::{IntoPy, invalid};

const MOT: &str = "(K, 6..10): frame, id, left, top, width, height[, conf, x, y, z]";

/// A file path, or an array of MOTChallenge rows.
enum Source {
    File(PathBuf),
    Rows(Vec<MotRow>),
}

fn source(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Source> {
    if let Ok(path) = obj.extract::<PathBuf>() {
        return Ok(Source::File(path));
    }
    let t = table(obj, name, (6, 10), MOT)?;
    let rows = t
        .iter()
        .enumerate()
        .map(|(i, r)| mot_row(r).map_err(|e| invalid(format!("{name} row {i}: {e}"))))
        .collect::<PyResult<_>>()?;
    Ok(Source::Rows(rows))
}

fn mot_row(r: &[f64]) -> Result<MotRow, String> {
    let integer = |v: f64, what: &str| {
        if v.fract() == 0.0 && v.abs() < 2f64.powi(52) {
            Ok(v)
        } else {
            Err(format!("{what} {v} is not an integer"))
        }
    };
    let frame = integer(r[0], "frame")?;
    if !(0.0..=f64::from(u32::MAX)).contains(&frame) {
        return Err(format!("frame {frame} is out of range 0..=4294967295"));
    }
    let bbox = BoundingBox::new(r[2], r[3], r[4], r[5]).map_err(|e| e.to_string())?;
    Ok(MotRow {
        frame: frame as u32,
        id: integer(r[1], "id")? as i64,
        bbox,
        confidence: r.get(6).copied().unwrap_or(1.0),
        world: [-1.0; 3],
    })
}

/// The rows of `source`, the name errors give it, and notes (a skipped header).
fn rows(source: Source, name: &str) -> PyResult<(Vec<MotRow>, String, Vec<String>)> {
    match source {
        Source::File(path) => {
            let text = std::fs::read_to_string(&path)
                .map_err(|e| invalid(format!("cannot read {}: {e}", path.display())))?;
            let file = path.display().to_string();
            let (rows, notes) = mot::text::read_rows(&text, &file).or_raise()?;
            Ok((rows, file, notes))
        }
        Source::Rows(rows) => Ok((rows, name.to_string(), Vec::new())),
    }
}

/// Ground truth (ignore rows dropped) and tracks, as `cargo xtask eval` reads them.
fn pair(gt: Source, pred: Source) -> PyResult<EvaluationPair> {
    let (gt_rows, gt_name, mut notes) = rows(gt, "gt")?;
    let (pred_rows, pred_name, pred_notes) = rows(pred, "pred")?;
    notes.extend(pred_notes);
    let mut pair =
        evaluation_pair_of_rows((gt_rows, &gt_name), (pred_rows, &pred_name)).or_raise()?;
    notes.append(&mut pair.notes);
    pair.notes = notes;
    Ok(pair)
}

/// Frames in which either side has a row (py-motmetrics' `num_frames`).
fn frames(gt: &TrackSet, pred: &TrackSet) -> usize {
    let of = |s: &TrackSet| -> BTreeSet<u32> { s.by_frame().into_keys().collect() };
    of(gt).union(&of(pred)).count()
}

/// Every metric by name.
fn names(r: &EvalReport, n_frames: usize, iou: bool) -> Vec<(&'static str, f64)> {
    let (c, i, h, s) = (&r.clear, &r.identity, &r.hota, &r.success);
    let n = |v: usize| v as f64;
    let mut out = vec![
        // py-motmetrics (its motchallenge_metrics and the counts they are made of).
        ("num_frames", n(n_frames)),
        ("num_objects", n(c.true_positives + c.false_negatives)),
        ("num_predictions", n(c.true_positives + c.false_positives)),
        ("num_unique_objects", n(c.n_gt_tracks)),
        ("num_detections", n(c.true_positives)),
        ("num_matches", n(c.true_positives - c.id_switches)),
        ("num_switches", n(c.id_switches)),
        ("num_false_positives", n(c.false_positives)),
        ("num_misses", n(c.false_negatives)),
        ("mota", c.mota),
        ("precision", c.precision),
        ("recall", c.recall),
        ("idtp", n(i.idtp)),
        ("idfp", n(i.idfp)),
        ("idfn", n(i.idfn)),
        ("idp", i.idp),
        ("idr", i.idr),
        ("idf1", i.idf1),
        // TrackEval.
        ("HOTA", h.hota),
        ("DetA", h.det_a),
        ("AssA", h.ass_a),
        ("LocA", h.loc_a),
        ("DetRe", h.det_re),
        ("DetPr", h.det_pr),
        ("AssRe", h.ass_re),
        ("AssPr", h.ass_pr),
        ("MOTA", c.mota),
        ("MOTP", c.motp),
        ("MODA", c.moda),
        ("CLR_Re", c.recall),
        ("CLR_Pr", c.precision),
        ("CLR_TP", n(c.true_positives)),
        ("CLR_FN", n(c.false_negatives)),
        ("CLR_FP", n(c.false_positives)),
        ("IDSW", n(c.id_switches)),
        ("MT", n(c.mostly_tracked)),
        ("PT", n(c.partially_tracked)),
        ("ML", n(c.mostly_lost)),
        ("Frag", n(c.fragmentations)),
        ("IDF1", i.idf1),
        ("IDR", i.idr),
        ("IDP", i.idp),
        ("IDTP", n(i.idtp)),
        ("IDFN", n(i.idfn)),
        ("IDFP", n(i.idfp)),
        // Yoon et al. 2016.
        ("SR", s.success_rate),
        ("FAF", s.false_alarms_per_frame),
    ];
    if iou {
        // py-motmetrics' MOTP is the mean distance 1 − IoU of the matches (NaN without one).
        let motp = if c.true_positives == 0 {
            f64::NAN
        } else {
            1.0 - c.motp
        };
        out.push(("motp", motp));
    }
    out
}

/// Mean OSPA and GOSPA (p = 2) over the frames at cut-off `cutoff`, on box centres.
fn ospa_means(gt: &TrackSet, pred: &TrackSet, cutoff: f64) -> PyResult<[(&'static str, f64); 2]> {
    let cfg = OspaConfig { cutoff, order: 2.0 };
    let mean = |v: Vec<f64>| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let ospa = eval_metrics::ospa_over_time(gt, pred, &cfg).or_raise()?;
    let gospa = eval_metrics::gospa_over_time(gt, pred, &cfg).or_raise()?;
    Ok([
        ("OSPA", mean(ospa.iter().map(|(_, o)| o.distance).collect())),
        (
            "GOSPA",
            mean(gospa.iter().map(|(_, g)| g.distance).collect()),
        ),
    ])
}

/// Scores `pred` against `gt`: MOTChallenge files or arrays (K, 6..10) frame, id, left, top,
/// width, height[, conf, x, y, z] (ground-truth rows of conf 0 are ignored). Boxes match at
/// IoU >= `iou`, or centres within `distance`. Returns a dict: CLEAR MOT and identity
/// metrics under py-motmetrics' names, the same and HOTA under TrackEval's, SR and FAF, the
/// mean OSPA and GOSPA with `ospa_cutoff` (or `distance`), and `notes`. CLEAR's matching is
/// TrackEval's (see the stub for where py-motmetrics' switch count can differ).
#[pyfunction]
#[pyo3(signature = (gt, pred, iou=0.5, distance=None, ospa_cutoff=None))]
pub fn evaluate<'py>(
    py: Python<'py>,
    gt: &Bound<'py, PyAny>,
    pred: &Bound<'py, PyAny>,
    iou: f64,
    distance: Option<f64>,
    ospa_cutoff: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let (gt, pred) = (source(gt, "gt")?, source(pred, "pred")?);
    let matching = match distance {
        Some(d) => MatchConfig::within_distance(d),
        None => MatchConfig::iou(iou),
    };
    let cutoff = ospa_cutoff.or(distance);
    let (values, notes) = py.detach(|| -> PyResult<_> {
        let EvaluationPair { gt, pred, notes } = pair(gt, pred)?;
        let report = eval_metrics::evaluate(&gt, &pred, &EvalConfig { matching }).or_raise()?;
        let mut values = names(&report, frames(&gt, &pred), distance.is_none());
        if let Some(c) = cutoff {
            values.extend(ospa_means(&gt, &pred, c)?);
        }
        Ok((values, notes))
    })?;
    let out = PyDict::new(py);
    for (k, v) in values {
        out.set_item(k, v)?;
    }
    out.set_item("notes", notes)?;
    Ok(out)
}
