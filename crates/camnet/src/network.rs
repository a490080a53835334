//! The camera network: pairwise relative poses from track correspondence, the maximum
//! spanning tree of the view graph weighted by inliers, relative scales from points seen by
//! three cameras, and every pose in camera 0's frame up to one global scale.
//!
//! Scale: camera 0's first tree edge has |t| = 1. An edge (p → c) takes its scale from an
//! already-scaled edge (q, p) at p: the same image point of camera p (track, frame, feature)
//! is triangulated in both pairs, and the scale ratio is the median over such points of the
//! ratio of their distances from camera p's centre.

use std::collections::{BTreeMap, HashMap};

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tracker_model::Frame;

use crate::correspondence::{CorrespondenceConfig, FeatureTrack, PairMatching, match_tracks};
use crate::error::{Error, Result};
use crate::geometry::{Intrinsics, Pose, triangulate};
use crate::tracks::{Features, ImageTrack};

/// One camera: its intrinsics and its image tracks.
#[derive(Debug, Clone)]
pub struct CameraTracks {
    /// K.
    pub intrinsics: Intrinsics,
    /// The camera's image tracks.
    pub tracks: Vec<ImageTrack>,
}

/// Settings of [`localise`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NetworkConfig {
    /// Which blob points become correspondences (default top and bottom).
    pub features: Features,
    /// Track correspondence and pose per camera pair.
    pub correspondence: CorrespondenceConfig,
    /// A scale transfer needs at least this many points seen by the three cameras (default
    /// 5).
    pub min_scale_points: usize,
}

impl Default for NetworkConfig {
    fn default() -> Self {
        Self {
            features: Features::TopBottom,
            correspondence: CorrespondenceConfig::default(),
            min_scale_points: 5,
        }
    }
}

/// One camera pair (a < b).
#[derive(Debug, Clone)]
pub struct PairResult {
    /// Camera a.
    pub a: usize,
    /// Camera b.
    pub b: usize,
    /// The matching and the pose of b relative to a, if any hypothesis passed.
    pub matching: Option<PairMatching>,
}

/// The localised network.
#[derive(Debug, Clone)]
pub struct Network {
    /// Every camera pair, in order (0,1), (0,2), …, (1,2), …
    pub pairs: Vec<PairResult>,
    /// Tree edges (parent, child) in the order they were placed.
    pub tree: Vec<(usize, usize)>,
    /// Each camera's pose `camera_from_camera0` up to the global scale; `None` when it is not
    /// connected or its scale could not be transferred.
    pub poses: Vec<Option<Pose>>,
    /// For each tree edge, how many three-camera points set its scale (0 for the first edge).
    pub scale_points: Vec<usize>,
}

/// The pairwise result for cameras a and b, if any.
impl Network {
    /// The pair (a, b) with a < b.
    pub fn pair(&self, a: usize, b: usize) -> Option<&PairResult> {
        self.pairs.iter().find(|p| p.a == a && p.b == b)
    }
}

/// Triangulated points keyed by one camera's (track, frame, feature).
type PointsByKey = HashMap<(usize, Frame, usize), Vector3<f64>>;

/// Points of one pair keyed by camera `cam`'s (track, frame, feature), in `cam`'s frame, with
/// the pose of the other camera relative to `cam` (unit translation).
fn points_at(pair: &PairResult, m: &PairMatching, cam: usize) -> (Pose, PointsByKey) {
    let pose_b_from_a = m.estimate.pose;
    let mut out = HashMap::new();
    for (i, &(mi, frame, k)) in m.origin.iter().enumerate() {
        if !m.estimate.inliers[i] {
            continue;
        }
        let Some(x_a) = triangulate(&pose_b_from_a, &m.x_a[i], &m.x_b[i]) else {
            continue;
        };
        let x_b = pose_b_from_a.apply(&x_a);
        if x_a.z <= 0.0 || x_b.z <= 0.0 {
            continue;
        }
        let tm = &m.matches[mi];
        if cam == pair.a {
            out.insert((tm.track_a, frame, k), x_a);
        } else {
            out.insert((tm.track_b, frame, k), x_b);
        }
    }
    let rel = if cam == pair.a {
        pose_b_from_a
    } else {
        pose_b_from_a.inverse()
    };
    (rel, out)
}

/// Localises the cameras: track correspondence and relative pose for every pair (in parallel;
/// pair k draws from ChaCha8(seed) stream k, so the result does not depend on the thread
/// count), the maximum spanning tree by inliers, scale transfer, poses in camera 0's frame.
pub fn localise(cameras: &[CameraTracks], config: &NetworkConfig, seed: u64) -> Result<Network> {
    config.correspondence.check()?;
    for (index, c) in cameras.iter().enumerate() {
        c.intrinsics.check().map_err(|e| Error::BadCamera {
            index,
            reason: e.to_string(),
        })?;
    }
    let n = cameras.len();
    let features: Vec<Vec<FeatureTrack>> = cameras
        .iter()
        .map(|c| {
            c.tracks
                .iter()
                .map(|t| FeatureTrack {
                    frames: t.frames.clone(),
                    points: t.normalised(&c.intrinsics, config.features),
                })
                .collect()
        })
        .collect();
    let pair_ids: Vec<(usize, usize)> = (0..n)
        .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
        .collect();
    let pairs = pair_ids
        .par_iter()
        .enumerate()
        .map(|(k, &(a, b))| -> Result<PairResult> {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(k as u64);
            let scale =
                0.5 * (cameras[a].intrinsics.mean_focal() + cameras[b].intrinsics.mean_focal());
            let matching = match_tracks(
                &features[a],
                &features[b],
                scale,
                &config.correspondence,
                &mut rng,
            )?;
            Ok(PairResult { a, b, matching })
        })
        .collect::<Result<Vec<_>>>()?;
    // Maximum spanning tree (Prim from camera 0, ties to the lower pair index).
    let weight = |p: &PairResult| p.matching.as_ref().map_or(0, |m| m.estimate.n_inliers);
    let mut placed = vec![false; n];
    let mut tree = Vec::new();
    if n > 0 {
        placed[0] = true;
    }
    loop {
        let best = pairs
            .iter()
            .filter(|p| weight(p) > 0 && placed[p.a] != placed[p.b])
            .max_by(|p, q| weight(p).cmp(&weight(q)).then((q.a, q.b).cmp(&(p.a, p.b))));
        let Some(p) = best else { break };
        let (parent, child) = if placed[p.a] { (p.a, p.b) } else { (p.b, p.a) };
        placed[child] = true;
        tree.push((parent, child));
    }
    // Scales and poses along the tree, in placement order.
    let mut poses: Vec<Option<Pose>> = vec![None; n];
    if n > 0 {
        poses[0] = Some(Pose::identity());
    }
    // Scaled edges: (p, c) → scale of the pair's unit translation.
    let mut scaled: BTreeMap<(usize, usize), f64> = BTreeMap::new();
    let mut scale_points = Vec::with_capacity(tree.len());
    let pair_of = |x: usize, y: usize| {
        let (a, b) = (x.min(y), x.max(y));
        pairs.iter().find(|p| p.a == a && p.b == b)
    };
    for &(p, c) in &tree {
        let Some(parent_pose) = poses[p] else {
            scale_points.push(0);
            continue;
        };
        let Some(pair) = pair_of(p, c) else { continue };
        let Some(m) = pair.matching.as_ref() else {
            continue;
        };
        let (rel, here) = points_at(pair, m, p);
        // Reference: the scaled edge at p with the most shared points.
        let mut best: Option<(usize, f64)> = None;
        for (&(x, y), &s_ref) in &scaled {
            let q = if x == p {
                y
            } else if y == p {
                x
            } else {
                continue;
            };
            let Some(rp) = pair_of(p, q) else { continue };
            let Some(rm) = rp.matching.as_ref() else {
                continue;
            };
            let (_, there) = points_at(rp, rm, p);
            let mut ratios: Vec<f64> = here
                .iter()
                .filter_map(|(key, x_here)| {
                    there.get(key).map(|x_there| x_there.norm() / x_here.norm())
                })
                .filter(|r| r.is_finite() && *r > 0.0)
                .collect();
            // At least one ratio, whatever `min_scale_points` says (0 would mean "any").
            if ratios.is_empty() || ratios.len() < config.min_scale_points {
                continue;
            }
            ratios.sort_by(f64::total_cmp);
            let median = ratios[ratios.len() / 2];
            if best.is_none_or(|(n, _)| ratios.len() > n) {
                best = Some((ratios.len(), s_ref * median));
            }
        }
        let scale = match best {
            Some((npts, s)) => {
                scale_points.push(npts);
                s
            }
            None if scaled.is_empty() => {
                scale_points.push(0);
                1.0
            }
            None => {
                scale_points.push(0);
                continue;
            }
        };
        scaled.insert((p, c), scale);
        let edge = Pose {
            rotation: rel.rotation,
            translation: rel.translation * scale,
        };
        poses[c] = Some(edge.compose(&parent_pose));
    }
    Ok(Network {
        pairs,
        tree,
        poses,
        scale_points,
    })
}
