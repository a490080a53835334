//! `cargo xtask eval --gt GT.txt --pred PRED.txt`: scores a tracker's MOTChallenge output
//! against MOTChallenge ground truth with every sequence-level metric of eval-metrics.

use std::path::Path;

use anyhow::{Context, Result};
use eval_metrics::{EvalConfig, EvalReport, MatchConfig, evaluate};
use scenarios::mot::parse_evaluation_pair;
use scenarios::{Table, fmt_num};
use tracker_model::TrackSet;

use crate::report::to_markdown;
use crate::{Outcome, read_file};

/// Reads ground truth and tracker output (see `parse_evaluation_pair` for the conventions).
fn load(gt: &Path, pred: &Path) -> Result<(TrackSet, TrackSet)> {
    parse_evaluation_pair(
        (&read_file(gt)?, &gt.display().to_string()),
        (&read_file(pred)?, &pred.display().to_string()),
    )
}

/// The report as (metric, value) rows, in the order the table shows them.
fn rows(r: &EvalReport) -> Vec<(&'static str, String)> {
    let c = &r.clear;
    let h = &r.hota;
    let i = &r.identity;
    let count = |v: usize| v.to_string();
    vec![
        ("HOTA", fmt_num(h.hota)),
        ("DetA", fmt_num(h.det_a)),
        ("AssA", fmt_num(h.ass_a)),
        ("LocA", fmt_num(h.loc_a)),
        ("DetRe", fmt_num(h.det_re)),
        ("DetPr", fmt_num(h.det_pr)),
        ("AssRe", fmt_num(h.ass_re)),
        ("AssPr", fmt_num(h.ass_pr)),
        ("MOTA", fmt_num(c.mota)),
        ("MOTP (mean IoU of matches)", fmt_num(c.motp)),
        ("MODA", fmt_num(c.moda)),
        ("Recall", fmt_num(c.recall)),
        ("Precision", fmt_num(c.precision)),
        ("TP", count(c.true_positives)),
        ("FP", count(c.false_positives)),
        ("FN", count(c.false_negatives)),
        ("IDSW", count(c.id_switches)),
        ("Frag", count(c.fragmentations)),
        ("MT", count(c.mostly_tracked)),
        ("PT", count(c.partially_tracked)),
        ("ML", count(c.mostly_lost)),
        ("IDF1", fmt_num(i.idf1)),
        ("IDP", fmt_num(i.idp)),
        ("IDR", fmt_num(i.idr)),
        ("IDTP", count(i.idtp)),
        ("IDFP", count(i.idfp)),
        ("IDFN", count(i.idfn)),
        ("SR", fmt_num(r.success.success_rate)),
        ("FAF", fmt_num(r.success.false_alarms_per_frame)),
    ]
}

/// Runs the evaluation and prints a table or JSON.
#[expect(
    clippy::print_stdout,
    reason = "the evaluation is printed on the terminal"
)]
pub fn run(gt: &Path, pred: &Path, iou: f64, json: bool) -> Outcome {
    let (gt_set, pred_set) = load(gt, pred)?;
    let config = EvalConfig {
        matching: MatchConfig::iou(iou),
    };
    let report = evaluate(&gt_set, &pred_set, &config).context("evaluation failed")?;
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        let mut table = Table::new(
            &format!(
                "{} against {} (IoU ≥ {iou}; {} truth tracks, {} estimated tracks)",
                pred.display(),
                gt.display(),
                gt_set.len(),
                pred_set.len()
            ),
            &["metric", "value"],
        );
        for (name, value) in rows(&report) {
            table.row(vec![name.to_string(), value]);
        }
        println!("{}", to_markdown(&table));
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
