//! The per-frame view that CLEAR MOT, identity and HOTA metrics share: for every frame, which
//! truth and estimated objects are present and the similarity of every pair. Computed once.

use std::collections::HashMap;

use rayon::prelude::*;
use tracker_model::{Frame, Location, TrackId, TrackPoint, TrackSet};

use crate::error::{Error, Result, Side};
use crate::similarity::Similarity;

/// Marks a frame entry whose similarity is 0 (the pair is not in [`Sequence::pairs`]).
pub const NO_PAIR: u32 = u32::MAX;

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
    /// For each entry of `sim`, the index of its (truth, estimate) pair in
    /// [`Sequence::pairs`], or [`NO_PAIR`] where the similarity is 0.
    pub pair: Vec<u32>,
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
    /// Every (truth, estimate) pair with positive similarity in some frame, numbered in order
    /// of first appearance; metrics accumulate per pair in plain vectors indexed this way.
    pub pairs: Vec<(usize, usize)>,
    /// Number of truth detections (object-frames).
    pub n_gt_dets: usize,
    /// Number of estimated detections.
    pub n_pred_dets: usize,
}

/// (frame, side: 0 truth / 1 estimate, dense track index, point). A reference keeps the
/// entries small, which makes sorting them cheap.
type Entry<'a> = (Frame, u8, usize, &'a TrackPoint);

fn entries<'a>(set: &'a TrackSet, side: u8, out: &mut Vec<Entry<'a>>) {
    for (idx, t) in set.tracks().iter().enumerate() {
        out.extend(t.points().iter().map(|p| (p.frame, side, idx, p)));
    }
}

/// Groups entries by frame, frames ascending, truth before estimates and tracks in index order
/// within a frame. Frame numbers are usually dense, so a bucket per frame avoids sorting; a
/// sparse numbering (huge gaps) falls back to a sort.
fn group_by_frame(mut all: Vec<Entry<'_>>) -> Vec<Vec<Entry<'_>>> {
    let Some(first) = all.iter().map(|e| e.0).min() else {
        return Vec::new();
    };
    let last = all.iter().map(|e| e.0).max().unwrap_or(first);
    let span = (last - first) as usize + 1;
    if span > 4 * all.len() + 1024 {
        all.sort_unstable_by_key(|e| (e.0, e.1, e.2));
        return all.chunk_by(|a, b| a.0 == b.0).map(<[_]>::to_vec).collect();
    }
    // `entries` pushes truth before estimates and tracks in index order, so pushing into
    // buckets in input order already gives the order within each frame.
    let mut buckets: Vec<Vec<Entry<'_>>> = vec![Vec::new(); span];
    for e in all {
        buckets[(e.0 - first) as usize].push(e);
    }
    buckets.retain(|b| !b.is_empty());
    buckets
}

impl Sequence {
    /// Aligns `gt` and `pred` and computes every similarity (frames in parallel).
    pub fn new(gt: &TrackSet, pred: &TrackSet, similarity: Similarity) -> Result<Self> {
        if similarity == Similarity::Iou {
            for (set, side) in [(gt, Side::Truth), (pred, Side::Estimate)] {
                let has_point = set
                    .tracks()
                    .iter()
                    .flat_map(|t| t.points())
                    .any(|p| !matches!(p.location, Location::Box(_)));
                if has_point {
                    return Err(Error::IouNeedsBoxes { side });
                }
            }
        }
        let mut all = Vec::with_capacity(gt.n_points() + pred.n_points());
        entries(gt, 0, &mut all);
        entries(pred, 1, &mut all);
        let groups = group_by_frame(all);
        let mut frames = groups
            .par_iter()
            .map(|group| {
                let group = group.as_slice();
                let split = group.partition_point(|e| e.1 == 0);
                let (g, h) = group.split_at(split);
                let sim = similarity.matrix(
                    &g.iter().map(|e| e.3.location).collect::<Vec<_>>(),
                    &h.iter().map(|e| e.3.location).collect::<Vec<_>>(),
                )?;
                Ok(FrameData {
                    frame: group[0].0,
                    gt: g.iter().map(|e| e.2).collect(),
                    pred: h.iter().map(|e| e.2).collect(),
                    pair: Vec::new(),
                    sim,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        // Number the pairs sequentially, in frame order, so the numbering is deterministic.
        let mut index: HashMap<(usize, usize), u32> = HashMap::new();
        let mut pairs = Vec::new();
        for f in &mut frames {
            let np = f.pred.len();
            f.pair = f
                .sim
                .iter()
                .enumerate()
                .map(|(k, &s)| {
                    if s <= 0.0 {
                        return NO_PAIR;
                    }
                    let key = (f.gt[k / np], f.pred[k % np]);
                    *index.entry(key).or_insert_with(|| {
                        pairs.push(key);
                        (pairs.len() - 1) as u32
                    })
                })
                .collect();
        }
        Ok(Self {
            n_gt_dets: gt.n_points(),
            n_pred_dets: pred.n_points(),
            gt_ids: gt.tracks().iter().map(|t| t.id()).collect(),
            pred_ids: pred.tracks().iter().map(|t| t.id()).collect(),
            frames,
            pairs,
        })
    }
}
