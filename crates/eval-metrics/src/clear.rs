//! CLEAR MOT metrics (Bernardin & Stiefelhagen 2008) with the MOTChallenge conventions of
//! TrackEval's `clear.py`: a pair may match only if its similarity reaches the threshold; a
//! truth object keeps the estimate it was matched to in the previous frame when that pair is
//! still valid (a bonus of 1000 in the assignment score); an identity switch is a matched truth
//! whose estimate differs from the last one it was matched to, in any earlier frame; a frame
//! with no truth or no estimates neither matches nor breaks a run (TrackEval skips it).

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::sequence::{FrameData, Sequence};

/// The CLEAR MOT counts and scores.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClearMetrics {
    /// 1 − (FN + FP + IDSW) / #truth detections (denominator at least 1, as in TrackEval).
    pub mota: f64,
    /// Mean similarity of the matched pairs (mean IoU for boxes), TrackEval's MOTP; the original
    /// paper's MOTP is a mean distance instead.
    pub motp: f64,
    /// 1 − (FN + FP) / #truth detections.
    pub moda: f64,
    /// TP / (TP + FN).
    pub recall: f64,
    /// TP / (TP + FP).
    pub precision: f64,
    /// Matched pairs.
    pub true_positives: usize,
    /// Unmatched estimates.
    pub false_positives: usize,
    /// Unmatched truth detections.
    pub false_negatives: usize,
    /// Identity switches.
    pub id_switches: usize,
    /// Fragmentations: times a truth track is picked up again after being lost (a frame with
    /// no truth or no estimates does not lose it, as in TrackEval).
    pub fragmentations: usize,
    /// Truth tracks matched in more than 80 % of their frames.
    pub mostly_tracked: usize,
    /// Truth tracks matched in 20 % to 80 % of their frames.
    pub partially_tracked: usize,
    /// Truth tracks matched in less than 20 % of their frames.
    pub mostly_lost: usize,
    /// Number of truth tracks.
    pub n_gt_tracks: usize,
}

/// Computes CLEAR MOT over an aligned sequence with match threshold `threshold`.
pub fn clear_mot(seq: &Sequence, threshold: f64) -> Result<ClearMetrics> {
    let n_gt = seq.gt_ids.len();
    let eps = f64::EPSILON;
    // Estimate last matched to each truth object, in any frame / in the previous frame.
    let mut last_match: Vec<Option<usize>> = vec![None; n_gt];
    let mut prev_frame_match: Vec<Option<usize>> = vec![None; n_gt];
    let mut matched_frames = vec![0usize; n_gt];
    let mut present_frames = vec![0usize; n_gt];
    let mut segments = vec![0usize; n_gt];
    let (mut tp, mut fp, mut fn_, mut idsw) = (0usize, 0usize, 0usize, 0usize);
    let mut sim_sum = 0.0;
    let mut scores = Vec::new();
    let mut current: Vec<Option<usize>> = vec![None; n_gt];
    for f in &seq.frames {
        let (ng, np) = (f.gt.len(), f.pred.len());
        // As TrackEval's clear.py: a frame without truth or without estimates (and an empty
        // frame, which the sequence skips) leaves the previous frame's matches in place, so a
        // run of matches continues across it (no fragmentation, the same continuation bonus).
        if ng == 0 || np == 0 {
            fp += np;
            fn_ += ng;
            for &g in &f.gt {
                present_frames[g] += 1;
            }
            continue;
        }
        assignment_scores(f, &prev_frame_match, threshold, &mut scores);
        current.iter_mut().for_each(|m| *m = None);
        let mut n_matched = 0;
        for (i, j) in tracker_model::assignment::maximise(ng, np, &scores)? {
            if scores[i * np + j] <= eps {
                continue;
            }
            let (g, h) = (f.gt[i], f.pred[j]);
            n_matched += 1;
            sim_sum += f.sim(i, j);
            if last_match[g].is_some_and(|prev| prev != h) {
                idsw += 1;
            }
            last_match[g] = Some(h);
            matched_frames[g] += 1;
            if prev_frame_match[g].is_none() {
                segments[g] += 1;
            }
            current[g] = Some(h);
        }
        for &g in &f.gt {
            present_frames[g] += 1;
        }
        std::mem::swap(&mut prev_frame_match, &mut current);
        tp += n_matched;
        fn_ += ng - n_matched;
        fp += np - n_matched;
    }
    let (mt, pt, ml) = coverage_classes(&present_frames, &matched_frames);
    let n_gt_dets = (tp + fn_) as f64;
    let denom = n_gt_dets.max(1.0);
    Ok(ClearMetrics {
        mota: (tp as f64 - fp as f64 - idsw as f64) / denom,
        motp: sim_sum / (tp as f64).max(1.0),
        moda: (tp as f64 - fp as f64) / denom,
        recall: tp as f64 / denom,
        precision: tp as f64 / ((tp + fp) as f64).max(1.0),
        true_positives: tp,
        false_positives: fp,
        false_negatives: fn_,
        id_switches: idsw,
        fragmentations: segments.iter().map(|&s| s.saturating_sub(1)).sum(),
        mostly_tracked: mt,
        partially_tracked: pt,
        mostly_lost: ml,
        n_gt_tracks: n_gt,
    })
}

/// The assignment scores of one frame, row-major: the similarity where it reaches the
/// threshold (0 elsewhere), plus 1000 for a pair that was matched in the previous frame.
fn assignment_scores(
    f: &FrameData,
    prev_frame_match: &[Option<usize>],
    threshold: f64,
    scores: &mut Vec<f64>,
) {
    scores.clear();
    for (i, &g) in f.gt.iter().enumerate() {
        for (j, &h) in f.pred.iter().enumerate() {
            let s = f.sim(i, j);
            let kept = prev_frame_match[g] == Some(h);
            scores.push(if s < threshold - f64::EPSILON {
                0.0
            } else {
                s + if kept { 1000.0 } else { 0.0 }
            });
        }
    }
}

/// Mostly tracked (matched in more than 80 % of its frames), partially tracked and mostly lost
/// (less than 20 %) truth tracks; tracks never present are not counted.
fn coverage_classes(present_frames: &[usize], matched_frames: &[usize]) -> (usize, usize, usize) {
    let (mut mt, mut pt, mut ml) = (0, 0, 0);
    for (&present, &matched) in present_frames.iter().zip(matched_frames) {
        if present == 0 {
            continue;
        }
        let ratio = matched as f64 / present as f64;
        if ratio > 0.8 {
            mt += 1;
        } else if ratio >= 0.2 {
            pt += 1;
        } else {
            ml += 1;
        }
    }
    (mt, pt, ml)
}
