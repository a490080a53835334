//! Identity metrics IDF1, IDP, IDR (Ristani et al., ECCV-W 2016).
//!
//! The definition pairs truth and estimated trajectories one-to-one (or with dummies) to
//! minimise IDFN + IDFP. Pairing truth g with estimate h costs (n_g − m_gh) + (n_h − m_gh),
//! where m_gh counts the frames in which they match; leaving both unpaired costs n_g + n_h. So
//! the total is Σ n_g + Σ n_h − 2 Σ_pairs m_gh, and the optimum is the maximum-weight matching
//! of the m_gh, which is what we solve (TrackEval solves the equivalent square problem with
//! dummy rows and columns; `tests` checks the two against brute force).

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::sequence::{NO_PAIR, Sequence};

/// IDF1 and its parts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IdentityMetrics {
    /// 2 IDTP / (2 IDTP + IDFP + IDFN).
    pub idf1: f64,
    /// IDTP / (IDTP + IDFP).
    pub idp: f64,
    /// IDTP / (IDTP + IDFN).
    pub idr: f64,
    /// Detections matched under the global identity assignment.
    pub idtp: usize,
    /// Estimated detections not so matched.
    pub idfp: usize,
    /// Truth detections not so matched.
    pub idfn: usize,
    /// The identity assignment: (truth track index, estimated track index) in
    /// [`Sequence::gt_ids`] / [`Sequence::pred_ids`] order, pairs with at least one match only.
    pub pairs: Vec<(usize, usize)>,
}

/// Frames in which each pair of [`Sequence::pairs`] matches at `threshold`.
fn match_counts(seq: &Sequence, threshold: f64) -> Vec<usize> {
    let mut counts = vec![0usize; seq.pairs.len()];
    for f in &seq.frames {
        for (&s, &pair) in f.sim.iter().zip(&f.pair) {
            if pair != NO_PAIR && s >= threshold - f64::EPSILON {
                counts[pair as usize] += 1;
            }
        }
    }
    counts
}

/// Computes IDF1, IDP and IDR with match threshold `threshold`.
pub fn identity(seq: &Sequence, threshold: f64) -> Result<IdentityMetrics> {
    let counts = match_counts(seq, threshold);
    let matching = || seq.pairs.iter().zip(&counts).filter(|(_, c)| **c > 0);
    // Only trajectories that match something can be paired usefully; compress to those.
    let mut rows: Vec<usize> = matching().map(|(k, _)| k.0).collect();
    let mut cols: Vec<usize> = matching().map(|(k, _)| k.1).collect();
    rows.sort_unstable();
    rows.dedup();
    cols.sort_unstable();
    cols.dedup();
    let mut weights = vec![0.0; rows.len() * cols.len()];
    for (&(g, h), &c) in matching() {
        let (Ok(r), Ok(c_idx)) = (rows.binary_search(&g), cols.binary_search(&h)) else {
            continue;
        };
        weights[r * cols.len() + c_idx] = c as f64;
    }
    let mut idtp = 0usize;
    let mut pairs = Vec::new();
    for (r, c) in tracker_model::assignment::maximise(rows.len(), cols.len(), &weights)? {
        let w = weights[r * cols.len() + c];
        if w > 0.0 {
            idtp += w as usize;
            pairs.push((rows[r], cols[c]));
        }
    }
    pairs.sort_unstable();
    let idfn = seq.n_gt_dets - idtp;
    let idfp = seq.n_pred_dets - idtp;
    let tp = idtp as f64;
    Ok(IdentityMetrics {
        idf1: tp / (tp + 0.5 * idfp as f64 + 0.5 * idfn as f64).max(1.0),
        idp: tp / (tp + idfp as f64).max(1.0),
        idr: tp / (tp + idfn as f64).max(1.0),
        idtp,
        idfp,
        idfn,
        pairs,
    })
}
