//! HOTA (Luiten et al., IJCV 2021) with the sub-metrics DetA, AssA, LocA, DetRe, DetPr, AssRe,
//! AssPr, following TrackEval's `hota.py`: a global alignment score from soft per-frame
//! matches, per-frame assignments maximising alignment × similarity, then detection and
//! association scores at each α ∈ {0.05, …, 0.95}, averaged.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::sequence::{NO_PAIR, Sequence};

/// The localisation thresholds α.
pub const ALPHAS: [f64; 19] = [
    0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40, 0.45, 0.50, 0.55, 0.60, 0.65, 0.70, 0.75, 0.80,
    0.85, 0.90, 0.95,
];

/// HOTA and its parts, each averaged over α; `per_alpha` keeps the curves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HotaMetrics {
    /// √(DetA · AssA), averaged over α.
    pub hota: f64,
    /// Detection accuracy TP / (TP + FN + FP).
    pub det_a: f64,
    /// Association accuracy.
    pub ass_a: f64,
    /// Mean similarity of the matched pairs.
    pub loc_a: f64,
    /// Detection recall TP / (TP + FN).
    pub det_re: f64,
    /// Detection precision TP / (TP + FP).
    pub det_pr: f64,
    /// Association recall.
    pub ass_re: f64,
    /// Association precision.
    pub ass_pr: f64,
    /// HOTA at each α of [`ALPHAS`].
    pub per_alpha: Vec<f64>,
}

/// Per-frame result of the second pass.
struct FrameMatches {
    /// (pair index, similarity) of the assigned pairs with positive similarity.
    pairs: Vec<(u32, f64)>,
}

/// Result of the first pass: detections per object and the global alignment of every pair.
struct Alignment {
    /// Detections of each truth object.
    gt_count: Vec<f64>,
    /// Detections of each estimated object.
    pred_count: Vec<f64>,
    /// Global alignment score of each (truth, estimate) pair of the sequence.
    score: Vec<f64>,
}

/// Matches counted at each α: true positives, summed similarity, and per-pair match counts.
struct AlphaCounts {
    tp: Vec<f64>,
    loc: Vec<f64>,
    pair_counts: Vec<[f64; ALPHAS.len()]>,
}

/// Computes HOTA over an aligned sequence. Frames are assigned in parallel; the reduction runs
/// in frame order, so the result does not depend on the thread count.
pub fn hota(seq: &Sequence) -> Result<HotaMetrics> {
    if seq.n_gt_dets == 0 || seq.n_pred_dets == 0 {
        // TrackEval: nothing can match; every score but LocA is 0 and LocA is 1.
        return Ok(HotaMetrics {
            hota: 0.0,
            det_a: 0.0,
            ass_a: 0.0,
            loc_a: 1.0,
            det_re: 0.0,
            det_pr: 0.0,
            ass_re: 0.0,
            ass_pr: 0.0,
            per_alpha: vec![0.0; ALPHAS.len()],
        });
    }
    let alignment = align(seq);
    let matches = match_frames(seq, &alignment.score)?;
    let counts = count_per_alpha(seq, &matches);
    Ok(scores(seq, &alignment, &counts))
}

/// Pass 1: potential matches, soft-counted per frame, and object sizes, giving each pair's
/// global alignment score.
fn align(seq: &Sequence) -> Alignment {
    let mut gt_count = vec![0.0f64; seq.gt_ids.len()];
    let mut pred_count = vec![0.0f64; seq.pred_ids.len()];
    let mut potential = vec![0.0f64; seq.pairs.len()];
    let mut row_sums = Vec::new();
    let mut col_sums = Vec::new();
    for f in &seq.frames {
        let (ng, np) = (f.gt.len(), f.pred.len());
        row_sums.clear();
        row_sums.extend((0..ng).map(|i| f.sim[i * np..(i + 1) * np].iter().sum::<f64>()));
        col_sums.clear();
        col_sums.extend((0..np).map(|j| (0..ng).map(|i| f.sim(i, j)).sum::<f64>()));
        for (k, (&s, &pair)) in f.sim.iter().zip(&f.pair).enumerate() {
            if pair != NO_PAIR {
                potential[pair as usize] += s / (row_sums[k / np] + col_sums[k % np] - s);
            }
        }
        f.gt.iter().for_each(|&g| gt_count[g] += 1.0);
        f.pred.iter().for_each(|&h| pred_count[h] += 1.0);
    }
    let score = seq
        .pairs
        .iter()
        .zip(&potential)
        .map(|(&(g, h), &p)| p / (gt_count[g] + pred_count[h] - p))
        .collect();
    Alignment {
        gt_count,
        pred_count,
        score,
    }
}

/// Pass 2: per-frame assignment maximising alignment × similarity (frames in parallel,
/// collected in frame order).
fn match_frames(seq: &Sequence, alignment: &[f64]) -> Result<Vec<FrameMatches>> {
    seq.frames
        .par_iter()
        .map(|f| {
            let np = f.pred.len();
            let score: Vec<f64> = f
                .sim
                .iter()
                .zip(&f.pair)
                .map(|(&s, &pair)| {
                    if pair == NO_PAIR {
                        0.0
                    } else {
                        alignment[pair as usize] * s
                    }
                })
                .collect();
            let pairs = tracker_model::assignment::maximise(f.gt.len(), np, &score)?
                .into_iter()
                .map(|(i, j)| (f.pair[i * np + j], f.sim(i, j)))
                .filter(|&(pair, _)| pair != NO_PAIR)
                .collect();
            Ok(FrameMatches { pairs })
        })
        .collect()
}

/// Reduces the matches per α, in frame order: TP counts, localisation sums and per-pair match
/// counts.
fn count_per_alpha(seq: &Sequence, matches: &[FrameMatches]) -> AlphaCounts {
    let n_alpha = ALPHAS.len();
    let mut tp = vec![0.0f64; n_alpha];
    let mut loc = vec![0.0f64; n_alpha];
    let mut pair_counts = vec![[0.0f64; ALPHAS.len()]; seq.pairs.len()];
    for fm in matches {
        for &(pair, s) in &fm.pairs {
            let counts = &mut pair_counts[pair as usize];
            for (a, alpha) in ALPHAS.iter().enumerate() {
                if s >= alpha - f64::EPSILON {
                    tp[a] += 1.0;
                    loc[a] += s;
                    counts[a] += 1.0;
                }
            }
        }
    }
    AlphaCounts {
        tp,
        loc,
        pair_counts,
    }
}

/// The detection, association and localisation scores at each α, and their means over α.
fn scores(seq: &Sequence, alignment: &Alignment, counts: &AlphaCounts) -> HotaMetrics {
    let n_gt = seq.n_gt_dets as f64;
    let n_pred = seq.n_pred_dets as f64;
    let (gt_count, pred_count) = (&alignment.gt_count, &alignment.pred_count);
    let n_alpha = ALPHAS.len();
    let mut out = HotaMetrics {
        hota: 0.0,
        det_a: 0.0,
        ass_a: 0.0,
        loc_a: 0.0,
        det_re: 0.0,
        det_pr: 0.0,
        ass_re: 0.0,
        ass_pr: 0.0,
        per_alpha: Vec::with_capacity(n_alpha),
    };
    for a in 0..n_alpha {
        let tp_a = counts.tp[a];
        let (fn_a, fp_a) = (n_gt - tp_a, n_pred - tp_a);
        let (mut ass_a, mut ass_re, mut ass_pr) = (0.0, 0.0, 0.0);
        for (&(g, h), pair_counts) in seq.pairs.iter().zip(&counts.pair_counts) {
            let m = pair_counts[a];
            if m > 0.0 {
                let (ng, nh) = (gt_count[g], pred_count[h]);
                ass_a += m * m / (ng + nh - m);
                ass_re += m * m / ng;
                ass_pr += m * m / nh;
            }
        }
        let tp_div = tp_a.max(1.0);
        let (ass_a, ass_re, ass_pr) = (ass_a / tp_div, ass_re / tp_div, ass_pr / tp_div);
        let det_a = tp_a / (tp_a + fn_a + fp_a).max(1.0);
        let h = (det_a * ass_a).sqrt();
        out.per_alpha.push(h);
        out.hota += h;
        out.det_a += det_a;
        out.ass_a += ass_a;
        out.ass_re += ass_re;
        out.ass_pr += ass_pr;
        out.det_re += tp_a / (tp_a + fn_a).max(1.0);
        out.det_pr += tp_a / (tp_a + fp_a).max(1.0);
        out.loc_a += counts.loc[a].max(1e-10) / tp_a.max(1e-10);
    }
    let k = n_alpha as f64;
    for v in [
        &mut out.hota,
        &mut out.det_a,
        &mut out.ass_a,
        &mut out.loc_a,
        &mut out.det_re,
        &mut out.det_pr,
        &mut out.ass_re,
        &mut out.ass_pr,
    ] {
        *v /= k;
    }
    out
}
