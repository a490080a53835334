//! The metrics of the papers this workspace reproduces: MAE and MMAE of recovered gap
//! trajectories (Oh & Jung 2015, Table 1), success rate and false alarms per frame (Yoon,
//! Hwang, Choi & Yoon 2016, Table 1), distance error over time (Huynh & Vu 2006), mean
//! position error per track (the audio-video fusion of Kushwaha et al. 2008, reviewed by Oh
//! 2012), and the association precision, recall and F1 of MCMCDA (Oh, Russell & Sastry 2009).

use std::collections::{HashMap, HashSet};

use serde::{Deserialize, Serialize};
use tracker_model::{Frame, Origin, Scan, Track, TrackSet, Vec2};

use crate::error::{Error, Result};
use crate::identity;
use crate::sequence::Sequence;
use crate::similarity::MatchConfig;

/// Mean absolute error of a recovered trajectory against the truth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Mae {
    /// Mean |x̂ − x|.
    pub x: f64,
    /// Mean |ŷ − y|.
    pub y: f64,
    /// "Total" as the mean Euclidean error per point.
    pub euclidean: f64,
    /// "Total" as the mean of the two axes' MAE.
    pub axis_mean: f64,
    /// Number of points.
    pub n_points: usize,
}

/// MAE of `estimate` against `truth`, point by point.
pub fn mae(truth: &[Vec2], estimate: &[Vec2]) -> Result<Mae> {
    if truth.len() != estimate.len() {
        return Err(Error::LengthMismatch {
            what: "MAE estimates (one per truth point)",
            expected: truth.len(),
            got: estimate.len(),
        });
    }
    if truth.is_empty() {
        return Err(Error::Model(tracker_model::Error::Empty {
            what: "trajectory for MAE",
        }));
    }
    let n = truth.len() as f64;
    let (mut sx, mut sy, mut se) = (0.0, 0.0, 0.0);
    for (t, e) in truth.iter().zip(estimate) {
        let d = e - t;
        if !(d.x.is_finite() && d.y.is_finite()) {
            return Err(Error::Model(tracker_model::Error::NonFinite {
                what: "MAE input",
            }));
        }
        sx += d.x.abs();
        sy += d.y.abs();
        se += d.norm();
    }
    Ok(Mae {
        x: sx / n,
        y: sy / n,
        euclidean: se / n,
        axis_mean: (sx + sy) / (2.0 * n),
        n_points: truth.len(),
    })
}

/// MMAE: the mean over segments of each segment's MAE (every segment weighs the same, however
/// long its gap).
pub fn mmae(segments: &[Mae]) -> Result<Mae> {
    if segments.is_empty() {
        return Err(Error::Model(tracker_model::Error::Empty {
            what: "segments for MMAE",
        }));
    }
    let k = segments.len() as f64;
    let mean = |f: fn(&Mae) -> f64| segments.iter().map(f).sum::<f64>() / k;
    Ok(Mae {
        x: mean(|m| m.x),
        y: mean(|m| m.y),
        euclidean: mean(|m| m.euclidean),
        axis_mean: mean(|m| m.axis_mean),
        n_points: segments.iter().map(|m| m.n_points).sum(),
    })
}

/// Success rate and false alarms per frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SuccessRate {
    /// Share of truth objects matched by an estimate (one-to-one per frame).
    pub success_rate: f64,
    /// Unmatched estimates per frame.
    pub false_alarms_per_frame: f64,
    /// Truth objects (object-frames).
    pub n_gt: usize,
    /// Matched truth objects.
    pub n_matched: usize,
    /// Unmatched estimates.
    pub n_false: usize,
    /// Frames in the sequence: from the first to the last frame of either set.
    pub n_frames: usize,
}

/// SR and FAF: per frame, the one-to-one matching that maximises the total similarity among
/// pairs reaching the threshold (Yoon et al. 2016 use IoU ≥ 0.5).
pub fn success_rate(gt: &TrackSet, pred: &TrackSet, config: &MatchConfig) -> Result<SuccessRate> {
    config.check()?;
    success_rate_of(
        &Sequence::new(gt, pred, config.similarity)?,
        config.threshold,
    )
}

/// SR and FAF over an already aligned sequence.
pub(crate) fn success_rate_of(seq: &Sequence, threshold: f64) -> Result<SuccessRate> {
    let mut n_matched = 0;
    let mut weights = Vec::new();
    for f in &seq.frames {
        weights.clear();
        weights.extend(f.sim.iter().map(|&s| {
            if s >= threshold - f64::EPSILON {
                s
            } else {
                0.0
            }
        }));
        n_matched += tracker_model::assignment::maximise(f.gt.len(), f.pred.len(), &weights)?
            .into_iter()
            .filter(|&(i, j)| weights[i * f.pred.len() + j] > 0.0)
            .count();
    }
    let n_frames = match (seq.frames.first(), seq.frames.last()) {
        (Some(a), Some(b)) => (b.frame - a.frame + 1) as usize,
        _ => 0,
    };
    Ok(SuccessRate {
        success_rate: n_matched as f64 / (seq.n_gt_dets as f64).max(1.0),
        false_alarms_per_frame: (seq.n_pred_dets - n_matched) as f64 / (n_frames as f64).max(1.0),
        n_gt: seq.n_gt_dets,
        n_matched,
        n_false: seq.n_pred_dets - n_matched,
        n_frames,
    })
}

/// Distance between a true and an estimated trajectory at every frame both have.
pub fn distance_error_series(truth: &Track, estimate: &Track) -> Vec<(Frame, f64)> {
    truth
        .points()
        .iter()
        .filter_map(|t| {
            estimate.at(t.frame).map(|e| {
                (
                    t.frame,
                    (t.location.position() - e.location.position()).norm(),
                )
            })
        })
        .collect()
}

/// Mean position error of one truth track under the identity assignment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrackError {
    /// The truth track.
    pub gt_id: tracker_model::TrackId,
    /// The estimated track assigned to it.
    pub pred_id: tracker_model::TrackId,
    /// Mean distance over the frames both exist.
    pub mean_error: f64,
    /// Frames compared.
    pub n_frames: usize,
}

/// Pairs each truth track with an estimated track by the IDF1 assignment at `max_distance` and
/// reports the mean distance over their common frames (the audio-video fusion experiment of
/// Kushwaha et al. 2008 as reviewed by Oh 2012).
pub fn mean_error_per_track(
    gt: &TrackSet,
    pred: &TrackSet,
    max_distance: f64,
) -> Result<Vec<TrackError>> {
    let config = MatchConfig::within_distance(max_distance);
    config.check()?;
    let seq = Sequence::new(gt, pred, config.similarity)?;
    let ids = identity::identity(&seq, config.threshold)?;
    let mut out = Vec::with_capacity(ids.pairs.len());
    for (g, h) in ids.pairs {
        let (gt_track, pred_track) = (&gt.tracks()[g], &pred.tracks()[h]);
        let errors = distance_error_series(gt_track, pred_track);
        if errors.is_empty() {
            continue;
        }
        out.push(TrackError {
            gt_id: gt_track.id(),
            pred_id: pred_track.id(),
            mean_error: errors.iter().map(|e| e.1).sum::<f64>() / errors.len() as f64,
            n_frames: errors.len(),
        });
    }
    Ok(out)
}

/// Association precision, recall and F1 over measurement-to-measurement links.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AssociationScores {
    /// Correct estimated links / estimated links.
    pub precision: f64,
    /// Correct estimated links / true links.
    pub recall: f64,
    /// Harmonic mean of the two.
    pub f1: f64,
    /// Links between consecutive detections of the same true target.
    pub n_true_links: usize,
    /// Links between consecutive measurements of the same estimated track.
    pub n_estimated_links: usize,
    /// Estimated links that are true links.
    pub n_correct_links: usize,
}

/// A measurement's address: (scan index, index within the scan).
type MeasurementRef = (usize, usize);

/// Links between consecutive members of each group, groups given as (label, member) pairs in
/// scan order.
fn chain_links<L: std::hash::Hash + Eq>(
    members: impl Iterator<Item = (L, MeasurementRef)>,
) -> HashSet<(MeasurementRef, MeasurementRef)> {
    let mut last: HashMap<L, MeasurementRef> = HashMap::new();
    let mut links = HashSet::new();
    for (label, m) in members {
        if let Some(prev) = last.insert(label, m) {
            links.insert((prev, m));
        }
    }
    links
}

/// Scores a data association against the true origins recorded in simulated `scans`.
///
/// `labels[s][i]` is the track the tracker gave measurement `i` of scan `s` (`None`: false
/// alarm). A link joins two measurements that are consecutive members of one track; the true
/// links join consecutive detections of one target. Precision and recall count links, as in
/// the MCMCDA paper's association F1 (TAC 2009, §V).
pub fn association_scores<Z>(
    scans: &[Scan<Z>],
    labels: &[Vec<Option<u64>>],
) -> Result<AssociationScores> {
    if scans.len() != labels.len() {
        return Err(Error::LengthMismatch {
            what: "label lists (one per scan)",
            expected: scans.len(),
            got: labels.len(),
        });
    }
    for (index, (scan, l)) in scans.iter().zip(labels).enumerate() {
        if scan.measurements.len() != l.len() {
            return Err(Error::ScanLabelsMismatch {
                scan: index,
                n_measurements: scan.measurements.len(),
                n_labels: l.len(),
            });
        }
    }
    let truth = chain_links(scans.iter().enumerate().flat_map(|(s, scan)| {
        scan.measurements
            .iter()
            .enumerate()
            .filter_map(move |(i, m)| match m.origin {
                Origin::Target(id) => Some((id, (s, i))),
                Origin::Clutter | Origin::Unknown => None,
            })
    }));
    let estimated = chain_links(labels.iter().enumerate().flat_map(|(s, l)| {
        l.iter()
            .enumerate()
            .filter_map(move |(i, label)| label.map(|k| (k, (s, i))))
    }));
    let correct = estimated.intersection(&truth).count();
    let precision = correct as f64 / (estimated.len() as f64).max(1.0);
    let recall = correct as f64 / (truth.len() as f64).max(1.0);
    let f1 = if precision + recall > 0.0 {
        2.0 * precision * recall / (precision + recall)
    } else {
        0.0
    };
    Ok(AssociationScores {
        precision,
        recall,
        f1,
        n_true_links: truth.len(),
        n_estimated_links: estimated.len(),
        n_correct_links: correct,
    })
}
