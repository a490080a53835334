//! The per-frame view that CLEAR MOT, identity and HOTA metrics share: for every frame, which
//! truth and estimated objects are present and the similarity of every pair. Computed once.

use std::collections::BTreeMap;

use tracker_model::{Frame, Location, TrackId, TrackPoint, TrackSet};

use crate::error::{Error, Result};
use crate::similarity::Similarity;

/// One frame: dense indices of the objects present and their similarity matrix.
#[derive(Debug, Clone)]
pub struct FrameData {
    /// The frame number.
    pub frame: Frame,
    /// Dense indices (into [`Sequence::gt_ids`]) of the truth objects present.
    pub gt: Vec<usize>,
    /// Dense indices (into [`Sequence::pred_ids`]) of the estimates present.
    pub pred: Vec<usize>,
    /// Row-major `gt.len() × pred.len()` similarities.
    pub sim: Vec<f64>,
}

impl FrameData {
    /// Similarity of the `i`-th truth and `j`-th estimate of this frame.
    pub fn sim(&self, i: usize, j: usize) -> f64 {
        self.sim[i * self.pred.len() + j]
    }
}

/// Truth and estimates aligned frame by frame.
#[derive(Debug, Clone)]
pub struct Sequence {
    /// Truth track ids; position = dense index.
    pub gt_ids: Vec<TrackId>,
    /// Estimated track ids; position = dense index.
    pub pred_ids: Vec<TrackId>,
    /// Frames in increasing order: every frame where truth or an estimate exists.
    pub frames: Vec<FrameData>,
    /// Number of truth detections (object-frames).
    pub n_gt_dets: usize,
    /// Number of estimated detections.
    pub n_pred_dets: usize,
}

impl Sequence {
    /// Aligns `gt` and `pred` and computes every similarity.
    pub fn new(gt: &TrackSet, pred: &TrackSet, similarity: Similarity) -> Result<Self> {
        if similarity == Similarity::Iou {
            for (set, side) in [(gt, "truth"), (pred, "estimate")] {
                let has_point = set
                    .tracks()
                    .iter()
                    .flat_map(|t| t.points())
                    .any(|p| !matches!(p.location, Location::Box(_)));
                if has_point {
                    return Err(Error::Incompatible(format!(
                        "IoU similarity needs boxes, but the {side} tracks contain points; use a distance similarity"
                    )));
                }
            }
        }
        let gt_ids: Vec<TrackId> = gt.tracks().iter().map(|t| t.id()).collect();
        let pred_ids: Vec<TrackId> = pred.tracks().iter().map(|t| t.id()).collect();
        // Frame → (truth points, estimate points), each with its dense index.
        let mut by_frame: BTreeMap<Frame, (Vec<(usize, TrackPoint)>, Vec<(usize, TrackPoint)>)> =
            BTreeMap::new();
        for (idx, t) in gt.tracks().iter().enumerate() {
            for p in t.points() {
                by_frame.entry(p.frame).or_default().0.push((idx, *p));
            }
        }
        for (idx, t) in pred.tracks().iter().enumerate() {
            for p in t.points() {
                by_frame.entry(p.frame).or_default().1.push((idx, *p));
            }
        }
        let mut frames = Vec::with_capacity(by_frame.len());
        for (frame, (g, h)) in by_frame {
            let mut sim = Vec::with_capacity(g.len() * h.len());
            for (_, gp) in &g {
                for (_, hp) in &h {
                    sim.push(similarity.between(&gp.location, &hp.location)?);
                }
            }
            frames.push(FrameData {
                frame,
                gt: g.iter().map(|(i, _)| *i).collect(),
                pred: h.iter().map(|(i, _)| *i).collect(),
                sim,
            });
        }
        Ok(Self {
            n_gt_dets: gt.n_points(),
            n_pred_dets: pred.n_points(),
            gt_ids,
            pred_ids,
            frames,
        })
    }
}
