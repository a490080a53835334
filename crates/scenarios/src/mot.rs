//! MOTChallenge files as text: the parsing and the conventions that `cargo xtask eval`,
//! `cargo xtask track` and the pipelines share. The caller reads the files.

use anyhow::{Context, Result, bail};
use tracker_model::{MotRow, TrackSet, parse_mot};

/// Parses a MOTChallenge file; errors name `file` and the line.
pub fn parse_rows(text: &str, file: &str) -> Result<Vec<MotRow>> {
    parse_mot(text.as_bytes()).with_context(|| format!("{file} is not a valid MOTChallenge file"))
}

/// Parses MOTChallenge detections: like [`parse_rows`], and an empty file is an error.
pub fn parse_detections(text: &str, file: &str) -> Result<Vec<MotRow>> {
    let rows = parse_rows(text, file)?;
    if rows.is_empty() {
        bail!("{file} holds no detections");
    }
    Ok(rows)
}

/// Ground truth and tracker output as track sets. Ground-truth rows with confidence 0 are
/// "ignore" annotations in MOTChallenge and are dropped, as TrackEval does before matching
/// (its distractor-class handling is not applied).
pub fn parse_evaluation_pair(
    (gt_text, gt_file): (&str, &str),
    (pred_text, pred_file): (&str, &str),
) -> Result<(TrackSet, TrackSet)> {
    let gt_rows: Vec<MotRow> = parse_rows(gt_text, gt_file)?
        .into_iter()
        .filter(|r| r.confidence != 0.0)
        .collect();
    let gt = TrackSet::from_mot_rows(&gt_rows).with_context(|| format!("in {gt_file}"))?;
    let pred = TrackSet::from_mot_rows(&parse_rows(pred_text, pred_file)?)
        .with_context(|| format!("in {pred_file}"))?;
    Ok((gt, pred))
}
