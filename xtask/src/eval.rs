//! `cargo xtask eval --gt GT.txt --pred PRED.txt`: scores a tracker's MOTChallenge output
//! against MOTChallenge ground truth with every sequence-level metric of eval-metrics.

use std::path::Path;

use anyhow::{Context, Result};
use eval_metrics::{EvalConfig, EvalReport, MatchConfig, evaluate};
use mot::text::{EvaluationPair, load_evaluation_pair};
use scenarios::{Table, fmt_num};

use crate::report::to_markdown;
use crate::{Outcome, read_file};

/// Reads ground truth and tracker output (see `mot::text` for the conventions: empty
/// ground truth is an error, empty predictions and skipped headers come with notes).
fn load_with_notes(gt: &Path, pred: &Path) -> Result<EvaluationPair> {
    Ok(load_evaluation_pair(
        (&read_file(gt)?, &gt.display().to_string()),
        (&read_file(pred)?, &pred.display().to_string()),
    )?)
}

/// [`load_with_notes`] without the notes.
#[cfg(test)]
fn load(gt: &Path, pred: &Path) -> Result<(tracker_model::TrackSet, tracker_model::TrackSet)> {
    load_with_notes(gt, pred).map(|p| (p.gt, p.pred))
}

/// The metrics of the table, in order.
const NAMES: [&str; 29] = [
    "HOTA",
    "DetA",
    "AssA",
    "LocA",
    "DetRe",
    "DetPr",
    "AssRe",
    "AssPr",
    "MOTA",
    "MOTP (mean IoU of matches)",
    "MODA",
    "Recall",
    "Precision",
    "TP",
    "FP",
    "FN",
    "IDSW",
    "Frag",
    "MT",
    "PT",
    "ML",
    "IDF1",
    "IDP",
    "IDR",
    "IDTP",
    "IDFP",
    "IDFN",
    "SR",
    "FAF",
];

/// The report's values in the order of [`NAMES`].
fn values(r: &EvalReport) -> [f64; 29] {
    let (c, h, i) = (&r.clear, &r.hota, &r.identity);
    let count = |v: usize| v as f64;
    [
        h.hota,
        h.det_a,
        h.ass_a,
        h.loc_a,
        h.det_re,
        h.det_pr,
        h.ass_re,
        h.ass_pr,
        c.mota,
        c.motp,
        c.moda,
        c.recall,
        c.precision,
        count(c.true_positives),
        count(c.false_positives),
        count(c.false_negatives),
        count(c.id_switches),
        count(c.fragmentations),
        count(c.mostly_tracked),
        count(c.partially_tracked),
        count(c.mostly_lost),
        i.idf1,
        i.idp,
        i.idr,
        count(i.idtp),
        count(i.idfp),
        count(i.idfn),
        r.success.success_rate,
        r.success.false_alarms_per_frame,
    ]
}

/// The report as (metric, value) rows, in the order the table shows them.
fn rows(r: &EvalReport) -> Vec<(&'static str, f64)> {
    NAMES.into_iter().zip(values(r)).collect()
}

/// The short name a metric goes by in `--require`: its first word ("MOTP (mean IoU…)" → MOTP).
fn short_name(name: &str) -> &str {
    name.split_whitespace().next().unwrap_or(name)
}

/// One `--require` threshold: metric, comparison, bound.
#[derive(Debug, Clone, PartialEq)]
struct Requirement {
    metric: String,
    op: &'static str,
    bound: f64,
}

impl Requirement {
    fn holds(&self, value: f64) -> bool {
        match self.op {
            ">=" => value >= self.bound,
            ">" => value > self.bound,
            "<=" => value <= self.bound,
            _ => value < self.bound,
        }
    }
}

/// Parses "MOTA>=0.9, IDF1>=0.8"; metric names are matched without regard to case.
fn parse_requirements(text: &str) -> Result<Vec<Requirement>> {
    let known: Vec<&str> = NAMES.iter().map(|n| short_name(n)).collect();
    text.split(',')
        .map(str::trim)
        .filter(|part| !part.is_empty())
        .map(|part| {
            let (at, op) = [">=", "<=", ">", "<"]
                .iter()
                .find_map(|op| part.find(op).map(|at| (at, *op)))
                .with_context(|| format!("requirement \"{part}\" has no >=, >, <= or <"))?;
            let name = part[..at].trim();
            let metric = known
                .iter()
                .find(|k| k.eq_ignore_ascii_case(name))
                .with_context(|| {
                    format!(
                        "requirement \"{part}\": unknown metric \"{name}\"; known: {}",
                        known.join(", ")
                    )
                })?;
            let value = part[at + op.len()..].trim();
            let bound: f64 = value
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .with_context(|| {
                    format!("requirement \"{part}\": \"{value}\" is not a finite number")
                })?;
            Ok(Requirement {
                metric: metric.to_string(),
                op,
                bound,
            })
        })
        .collect()
}

/// Runs the evaluation and prints a table or JSON on stdout; with `require`, false when a
/// threshold fails. Notes and requirement verdicts go to stderr, so `--json` output parses
/// whatever else is asked.
#[expect(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "the evaluation is printed on the terminal, notes on stderr"
)]
pub fn run(
    gt: &Path,
    pred: &Path,
    matching: Matching,
    json: bool,
    require: Option<&str>,
) -> Outcome {
    let evaluation = evaluate_files(gt, pred, matching, json, require)?;
    for note in &evaluation.notes {
        eprintln!("note: {note}");
    }
    println!("{}", evaluation.printed);
    for verdict in &evaluation.verdicts {
        eprintln!("{verdict}");
    }
    Ok(evaluation.all_hold)
}

/// What [`run`] prints: the result (stdout) and the notes and verdicts (stderr).
struct Evaluation {
    notes: Vec<String>,
    printed: String,
    verdicts: Vec<String>,
    all_hold: bool,
}

/// What the two files hold and how their objects match.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Matching {
    /// MOTChallenge boxes, matched at IoU ≥ the threshold.
    Boxes {
        /// The IoU threshold.
        iou: f64,
    },
    /// Point CSVs (`time_s,id,x,y`; a track file's `track_id` serves as the id), matched
    /// within the distance; OSPA and GOSPA with that cut-off (p = 2) are added.
    Points {
        /// The distance threshold and OSPA cut-off.
        distance: f64,
    },
}

/// The two files as track sets, with any notes on reading them.
fn load_sets(gt: &Path, pred: &Path, matching: Matching) -> Result<EvaluationPair> {
    match matching {
        Matching::Boxes { .. } => load_with_notes(gt, pred),
        Matching::Points { .. } => {
            let (gt_set, pred_set) =
                air_traffic::point_track_sets(&read_file(gt)?, &read_file(pred)?)
                    .with_context(|| format!("reading {} and {}", gt.display(), pred.display()))?;
            Ok(EvaluationPair {
                gt: gt_set,
                pred: pred_set,
                notes: Vec::new(),
            })
        }
    }
}

/// Mean OSPA and GOSPA over the frames, for point matching.
fn ospa_rows(
    gt: &tracker_model::TrackSet,
    pred: &tracker_model::TrackSet,
    matching: Matching,
) -> Result<Vec<(String, f64)>> {
    let Matching::Points { distance } = matching else {
        return Ok(Vec::new());
    };
    let cfg = eval_metrics::OspaConfig {
        cutoff: distance,
        order: 2.0,
    };
    let mean = |v: Vec<f64>| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let ospa = eval_metrics::ospa_over_time(gt, pred, &cfg)?;
    let gospa = eval_metrics::gospa_over_time(gt, pred, &cfg)?;
    Ok(vec![
        (
            format!("OSPA (c = {distance}, p = 2, mean over frames)"),
            mean(ospa.iter().map(|(_, o)| o.distance).collect()),
        ),
        (
            format!("GOSPA (c = {distance}, p = 2, mean over frames)"),
            mean(gospa.iter().map(|(_, g)| g.distance).collect()),
        ),
    ])
}

fn evaluate_files(
    gt: &Path,
    pred: &Path,
    matching: Matching,
    json: bool,
    require: Option<&str>,
) -> Result<Evaluation> {
    let requirements = require
        .map(parse_requirements)
        .transpose()?
        .unwrap_or_default();
    let EvaluationPair {
        gt: gt_set,
        pred: pred_set,
        notes,
    } = load_sets(gt, pred, matching)?;
    let (config, rule) = match matching {
        Matching::Boxes { iou } => (MatchConfig::iou(iou), format!("IoU ≥ {iou}")),
        Matching::Points { distance } => (
            MatchConfig::within_distance(distance),
            format!("distance ≤ {distance}"),
        ),
    };
    let config = EvalConfig { matching: config };
    let report = evaluate(&gt_set, &pred_set, &config).context("evaluation failed")?;
    let values = rows(&report);
    let extra = ospa_rows(&gt_set, &pred_set, matching)?;
    let printed = if json {
        let mut value = serde_json::to_value(&report)?;
        if let (Some(map), false) = (value.as_object_mut(), extra.is_empty()) {
            map.insert("ospa_mean".into(), extra[0].1.into());
            map.insert("gospa_mean".into(), extra[1].1.into());
        }
        serde_json::to_string_pretty(&value)?
    } else {
        let mut table = Table::new(
            &format!(
                "{} against {} ({rule}; {} truth tracks, {} estimated tracks)",
                pred.display(),
                gt.display(),
                gt_set.len(),
                pred_set.len()
            ),
            &["metric", "value"],
        );
        for (name, value) in &values {
            table.row(vec![name.to_string(), fmt_num(*value)]);
        }
        for (name, value) in &extra {
            table.row(vec![name.clone(), fmt_num(*value)]);
        }
        to_markdown(&table)
    };
    let mut all_hold = true;
    let mut verdicts = Vec::with_capacity(requirements.len());
    for req in &requirements {
        let value = values
            .iter()
            .find(|(n, _)| short_name(n) == req.metric)
            .map_or(f64::NAN, |(_, v)| *v);
        let holds = req.holds(value);
        all_hold &= holds;
        let verdict = if holds { "holds" } else { "FAILS" };
        verdicts.push(format!(
            "requirement {}{}{}: {verdict} ({} = {})",
            req.metric,
            req.op,
            req.bound,
            req.metric,
            fmt_num(value)
        ));
    }
    Ok(Evaluation {
        notes,
        printed,
        verdicts,
        all_hold,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Point files: a track file scored against truth 1 m off everywhere (distance 10): every
    /// truth point matched (MOTA 1), OSPA 1 (p = 2, one pair 1 m apart per frame), and a
    /// frame's missing estimate costs a miss and the cut-off.
    #[test]
    fn point_files_score_by_distance_with_ospa() {
        let dir = std::env::temp_dir().join(format!("xtask-eval-points-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (gt, pred) = (dir.join("truth.csv"), dir.join("tracks.csv"));
        std::fs::write(&gt, "time_s,id,x,y\n0,1,0,0\n10,1,100,0\n20,1,200,0\n").unwrap();
        std::fs::write(
            &pred,
            "time_s,track_id,x,y,vx,vy,hit\n0,5,0,1,10,0,1\n10,5,100,1,10,0,1\n20,5,200,1,10,0,1\n",
        )
        .unwrap();
        let matching = Matching::Points { distance: 10.0 };
        let run = evaluate_files(&gt, &pred, matching, true, Some("MOTA>=1")).unwrap();
        let parsed: serde_json::Value = serde_json::from_str(&run.printed).unwrap();
        assert!(run.all_hold, "{}", run.printed);
        assert_eq!(parsed["ospa_mean"].as_f64(), Some(1.0));
        std::fs::write(&pred, "time_s,track_id,x,y\n0,5,0,1\n20,5,200,1\n").unwrap();
        let run = evaluate_files(&gt, &pred, matching, true, None).unwrap();
        let parsed: serde_json::Value = serde_json::from_str(&run.printed).unwrap();
        // Frames 0 and 2 cost 1 m, frame 1 the cut-off 10: mean (1 + 10 + 1) / 3.
        assert_eq!(parsed["ospa_mean"].as_f64(), Some(4.0));
        assert!((parsed["clear"]["mota"].as_f64().unwrap() - 2.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn json_stays_parseable_with_requirements() {
        let dir = std::env::temp_dir().join(format!("xtask-eval-json-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let gt = dir.join("gt.txt");
        std::fs::write(&gt, "1,1,0,0,10,10,1,-1,-1,-1\n2,1,1,0,10,10,1,-1,-1,-1\n").unwrap();
        let run = evaluate_files(
            &gt,
            &gt,
            Matching::Boxes { iou: 0.5 },
            true,
            Some("MOTA>=0.9,IDF1<0.5"),
        )
        .unwrap();
        let parsed: serde_json::Value = serde_json::from_str(&run.printed).unwrap();
        assert!(parsed.is_object(), "{}", run.printed);
        assert_eq!(run.verdicts.len(), 2, "{:?}", run.verdicts);
        assert!(run.verdicts[0].contains("holds") && run.verdicts[1].contains("FAILS"));
        assert!(!run.all_hold);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn malformed_files_name_the_file_and_line() {
        let dir = std::env::temp_dir().join(format!("xtask-eval-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let gt = dir.join("gt.txt");
        let bad = dir.join("bad.txt");
        std::fs::write(&gt, "1,1,0,0,10,10,1,-1,-1,-1\n").unwrap();
        std::fs::write(&bad, "1,1,0,0,10,10\n\n2,1,0,0,ten,10\n").unwrap();
        let err = format!("{:#}", load(&gt, &bad).unwrap_err());
        assert!(
            err.contains("bad.txt") && err.contains("line 3") && err.contains("width"),
            "{err}"
        );
        let missing = format!("{:#}", load(&dir.join("nope.txt"), &gt).unwrap_err());
        assert!(missing.contains("nope.txt"), "{missing}");
        // A valid pair evaluates, and ignored ground truth (confidence 0) is dropped.
        std::fs::write(&bad, "1,1,0,0,10,10,1\n1,2,50,0,10,10,0\n").unwrap();
        let (g, _) = load(&bad, &gt).unwrap();
        assert_eq!(g.n_points(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn empty_files_get_an_error_or_a_note() {
        let dir = std::env::temp_dir().join(format!("xtask-eval-empty-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (gt, empty) = (dir.join("gt.txt"), dir.join("empty.txt"));
        std::fs::write(&gt, "1,1,0,0,10,10,1,-1,-1,-1\n").unwrap();
        std::fs::write(&empty, "").unwrap();
        // Empty ground truth: an error (it used to score MOTA −90 against nothing).
        let err = format!(
            "{:#}",
            run(&empty, &gt, Matching::Boxes { iou: 0.5 }, true, None).unwrap_err()
        );
        assert!(
            err.contains("empty.txt") && err.contains("no ground truth"),
            "{err}"
        );
        // Empty predictions: scored, all missed, with a note.
        let pair = load_with_notes(&gt, &empty).unwrap();
        assert!(pair.notes[0].contains("no tracks"), "{:?}", pair.notes);
        let report = evaluate(&pair.gt, &pair.pred, &EvalConfig::default()).unwrap();
        assert_eq!(report.clear.false_negatives, 1);
        assert!(report.clear.mota.abs() < 1e-12, "{}", report.clear.mota);
        // A zero-area box is an error at parse time (it used to count as FP 1, FN 1).
        std::fs::write(&empty, "1,1,0,0,0,10\n").unwrap();
        let err = format!(
            "{:#}",
            run(&gt, &empty, Matching::Boxes { iou: 0.5 }, true, None).unwrap_err()
        );
        assert!(err.contains("zero area") && err.contains("line 1"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn requirements_parse_and_compare() {
        let reqs = parse_requirements("mota>=0.9, IDF1 > 0.8,FP<3,").unwrap();
        assert_eq!(
            reqs,
            vec![
                Requirement {
                    metric: "MOTA".into(),
                    op: ">=",
                    bound: 0.9
                },
                Requirement {
                    metric: "IDF1".into(),
                    op: ">",
                    bound: 0.8
                },
                Requirement {
                    metric: "FP".into(),
                    op: "<",
                    bound: 3.0
                },
            ]
        );
        assert!(reqs[0].holds(0.9) && !reqs[0].holds(0.899));
        assert!(!reqs[1].holds(0.8) && reqs[1].holds(0.81));
        assert!(reqs[2].holds(2.0) && !reqs[2].holds(3.0));
        assert!(!reqs[0].holds(f64::NAN));
        for bad in ["MOTA=0.9", "MOTX>=1", "MOTA>=high", "MOTA>=inf"] {
            let err = format!("{:#}", parse_requirements(bad).unwrap_err());
            assert!(err.contains(bad), "{err}");
        }
    }
}
