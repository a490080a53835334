//! MOTChallenge files as text: the parsing and the conventions that `cargo xtask eval`,
//! `cargo xtask track` and the pipelines share. The caller reads the files.
//!
//! Conventions for input that would otherwise give silently wrong numbers:
//! - a header line (column names) is skipped, with a note;
//! - a box of zero width or height is an error (tracker-model's `Error::ZeroAreaBox`);
//! - empty detections are an error;
//! - empty ground truth (no row, or only confidence-0 rows) is an error: every metric divides
//!   by the number of truth objects;
//! - empty predictions are scored, with a note: every truth object is missed (MOTA, recall,
//!   IDF1 and HOTA are 0), which is what TrackEval reports for an empty tracker output.

use crate::error::{Error, Result};
use tracker_model::{MotRow, TrackSet, read_mot};

/// Rows of a MOTChallenge file and notes for the user (a skipped header).
pub fn read_rows(text: &str, file: &str) -> Result<(Vec<MotRow>, Vec<String>)> {
    let parsed = read_mot(text.as_bytes()).map_err(|error| Error::File {
        file: file.into(),
        error,
    })?;
    let notes = parsed
        .header
        .map(|(line, header)| format!("{file}: skipped the header on line {line}: {header}"))
        .into_iter()
        .collect();
    Ok((parsed.rows, notes))
}

/// Parses a MOTChallenge file; errors name `file` and the line.
pub fn parse_rows(text: &str, file: &str) -> Result<Vec<MotRow>> {
    read_rows(text, file).map(|(rows, _)| rows)
}

/// Detections and notes: like [`read_rows`], and an empty file is an error.
pub fn read_detections(text: &str, file: &str) -> Result<(Vec<MotRow>, Vec<String>)> {
    let (rows, notes) = read_rows(text, file)?;
    if rows.is_empty() {
        return Err(Error::NoDetections { what: file.into() });
    }
    Ok((rows, notes))
}

/// Parses MOTChallenge detections: like [`parse_rows`], and an empty file is an error.
pub fn parse_detections(text: &str, file: &str) -> Result<Vec<MotRow>> {
    read_detections(text, file).map(|(rows, _)| rows)
}

/// Ground truth and tracker output, ready to score, with notes for the user.
#[derive(Debug, Clone)]
pub struct EvaluationPair {
    /// Ground truth without its ignore (confidence 0) rows.
    pub gt: TrackSet,
    /// Tracker output.
    pub pred: TrackSet,
    /// Skipped headers, empty predictions.
    pub notes: Vec<String>,
}

/// Ground truth and tracker output as track sets. Ground-truth rows with confidence 0 are
/// "ignore" annotations in MOTChallenge and are dropped, as TrackEval does before matching
/// (its distractor-class handling is not applied). Empty ground truth is an error and empty
/// predictions get a note (see the module documentation).
pub fn load_evaluation_pair(
    (gt_text, gt_file): (&str, &str),
    (pred_text, pred_file): (&str, &str),
) -> Result<EvaluationPair> {
    let (gt_rows, mut notes) = read_rows(gt_text, gt_file)?;
    let (pred_rows, pred_notes) = read_rows(pred_text, pred_file)?;
    notes.extend(pred_notes);
    let mut pair = evaluation_pair_of_rows((gt_rows, gt_file), (pred_rows, pred_file))?;
    notes.append(&mut pair.notes);
    pair.notes = notes;
    Ok(pair)
}

/// [`load_evaluation_pair`] on rows already read (from arrays, say): the same conventions,
/// errors and notes naming `gt_file` and `pred_file`.
pub fn evaluation_pair_of_rows(
    (gt_rows, gt_file): (Vec<MotRow>, &str),
    (pred_rows, pred_file): (Vec<MotRow>, &str),
) -> Result<EvaluationPair> {
    let n_gt_rows = gt_rows.len();
    let gt_rows: Vec<MotRow> = gt_rows
        .into_iter()
        .filter(|r| r.confidence != 0.0)
        .collect();
    if gt_rows.is_empty() {
        let what = if n_gt_rows == 0 {
            "no rows".to_string()
        } else {
            format!("only ignore rows (confidence 0; {n_gt_rows} of them)")
        };
        return Err(Error::NoGroundTruth {
            file: gt_file.into(),
            what,
        });
    }
    let gt = TrackSet::from_mot_rows(&gt_rows).map_err(|error| Error::Rows {
        file: gt_file.into(),
        error,
    })?;
    let mut notes = Vec::new();
    if pred_rows.is_empty() {
        notes.push(format!(
            "{pred_file} holds no tracks: every truth object counts as missed (MOTA, recall, \
             IDF1 and HOTA are 0), as TrackEval scores an empty tracker output"
        ));
    }
    let pred = TrackSet::from_mot_rows(&pred_rows).map_err(|error| Error::Rows {
        file: pred_file.into(),
        error,
    })?;
    Ok(EvaluationPair { gt, pred, notes })
}

/// Tracks as the MOTChallenge text `cargo xtask track` writes: rows by frame, boxes rounded
/// to a thousandth of a pixel (smoothing leaves float noise in the last digits,
/// 28.359999999999978, and a thousandth of a pixel is far below any detector's precision).
pub fn format_tracks(set: &TrackSet) -> String {
    let mut boxes = set.to_mot_rows(0.0);
    for row in &mut boxes {
        for v in [
            &mut row.bbox.left,
            &mut row.bbox.top,
            &mut row.bbox.width,
            &mut row.bbox.height,
        ] {
            *v = (*v * 1e3).round() / 1e3;
        }
    }
    tracker_model::format_mot(&boxes)
}

/// [`load_evaluation_pair`] without the notes.
pub fn parse_evaluation_pair(gt: (&str, &str), pred: (&str, &str)) -> Result<(TrackSet, TrackSet)> {
    load_evaluation_pair(gt, pred).map(|pair| (pair.gt, pair.pred))
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROW: &str = "1,1,0,0,10,10,1,-1,-1,-1\n";

    #[test]
    fn empty_ground_truth_is_an_error() {
        for gt in ["", "\n\n", "1,1,0,0,10,10,0\n"] {
            let err = format!(
                "{:#}",
                load_evaluation_pair((gt, "gt.txt"), (ROW, "pred.txt")).unwrap_err()
            );
            assert!(
                err.contains("gt.txt") && err.contains("no ground truth"),
                "{err}"
            );
        }
    }

    #[test]
    fn empty_predictions_are_scored_with_a_note() {
        let pair = load_evaluation_pair((ROW, "gt.txt"), ("", "pred.txt")).unwrap();
        assert!(pair.pred.is_empty());
        assert_eq!(pair.notes.len(), 1);
        assert!(pair.notes[0].contains("pred.txt holds no tracks"));
        let pair = load_evaluation_pair((ROW, "gt.txt"), (ROW, "pred.txt")).unwrap();
        assert!(pair.notes.is_empty());
    }

    #[test]
    fn a_header_is_skipped_with_a_note() {
        let header = "frame,id,bb_left,bb_top,bb_width,bb_height,conf,x,y,z\n";
        let pair =
            load_evaluation_pair((&format!("{header}{ROW}"), "gt.txt"), (ROW, "pred.txt")).unwrap();
        assert_eq!(pair.gt.n_points(), 1);
        assert_eq!(
            pair.notes,
            vec![format!(
                "gt.txt: skipped the header on line 1: {}",
                header.trim()
            )]
        );
        let (rows, notes) = read_detections(&format!("{header}{ROW}"), "d.txt").unwrap();
        assert_eq!((rows.len(), notes.len()), (1, 1));
    }

    #[test]
    fn zero_area_boxes_are_rejected_with_the_file_and_line() {
        let err = format!(
            "{:#}",
            parse_detections("1,-1,0,0,10,10\n2,-1,5,5,0,0\n", "dets.txt").unwrap_err()
        );
        assert!(
            err.contains("dets.txt") && err.contains("line 2") && err.contains("zero area"),
            "{err}"
        );
    }
}
