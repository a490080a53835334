//! The camera network: pairwise relative poses from track correspondence, the maximum
//! spanning tree of the view graph weighted by inliers, relative scales from points seen by
//! three cameras, and every pose in camera 0's frame up to one global scale.
//!
//! Every pair of placed cameras then gets a relative pose, by one of three routes
//! ([`PoseRoute`]): *direct* (its own track correspondence found it), *guided* (the seed
//! search failed, but the pose composed through the network, pose_b ∘ pose_a⁻¹, gives an E
//! under which the pair's own track pairs are found by Sampson distance, and the pose is
//! estimated from those points alone, [`match_tracks_guided`]), or *composed* (no own
//! correspondences: the composed pose itself). After a guided pass the tree and scales are
//! computed once more, with the guided pairs as candidate edges.
//!
//! Scale: camera 0's first tree edge has |t| = 1. An edge (p → c) takes its scale from an
//! already-scaled edge (q, p) at p: the same image point of camera p (track, frame, feature)
//! is triangulated in both pairs, and the scale ratio is the median over such points of the
//! ratio of their distances from camera p's centre.

use std::collections::{BTreeMap, HashMap};

use nalgebra::{Vector2, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tracker_model::Frame;

use crate::bundle::{BundleObservation, bundle_adjust};
use crate::correspondence::{
    CorrespondenceConfig, FeatureTrack, PairMatching, match_tracks, match_tracks_guided,
};
use crate::error::{Error, Result};
use crate::geometry::{Intrinsics, Pose, project, triangulate};
use crate::refine::RefineConfig;
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
    /// Pairs the correspondence search left without a pose, whose two cameras are placed,
    /// are matched again guided by the composed pose (default true).
    pub guided: bool,
    /// Joint refinement of all placed cameras and the triangulated track points
    /// ([`bundle_adjust`]) after the tree; `None` (default) skips it.
    pub bundle: Option<RefineConfig>,
}

impl Default for NetworkConfig {
    fn default() -> Self {
        Self {
            features: Features::TopBottom,
            correspondence: CorrespondenceConfig::default(),
            min_scale_points: 5,
            guided: true,
            bundle: None,
        }
    }
}

/// Where a pair's relative pose came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseRoute {
    /// The pair's own track correspondence search ([`match_tracks`]).
    Direct,
    /// The pair's own points, found under the E of the pose composed through the network
    /// ([`match_tracks_guided`]).
    Guided,
    /// Composed through the network (pose_b ∘ pose_a⁻¹), no own correspondences.
    Composed,
}

/// One camera pair (a < b).
#[derive(Debug, Clone)]
pub struct PairResult {
    /// Camera a.
    pub a: usize,
    /// Camera b.
    pub b: usize,
    /// The matching and the pose of b relative to a from the pair's own points, if any
    /// (route direct or guided).
    pub matching: Option<PairMatching>,
    /// The route of `pose`.
    pub route: Option<PoseRoute>,
    /// The pose of b relative to a, unit translation: the matching's, or composed through
    /// the network when both cameras are placed and the pair has no matching.
    pub pose: Option<Pose>,
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
    /// The joint refinement, when configured and possible (the poses above are then its
    /// output).
    pub bundle: Option<BundleSummary>,
}

/// What the joint refinement did.
#[derive(Debug, Clone, PartialEq)]
pub struct BundleSummary {
    /// The poses before it (from the tree and the scale transfer).
    pub poses_before: Vec<Option<Pose>>,
    /// Track points triangulated from two or more placed cameras.
    pub points: usize,
    /// Their image observations.
    pub observations: usize,
    /// RMS reprojection error per coordinate before and after, normalised units.
    pub initial_rms: f64,
    /// See `initial_rms`.
    pub final_rms: f64,
    /// LM iterations.
    pub iterations: usize,
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
    let features = normalised_features(cameras, config);
    let mut pairs = direct_pairs(cameras, &features, config, seed)?;
    let (mut tree, mut poses, mut scale_points) = place(&pairs, n, config);
    // Guided pass: a pair without a matching whose cameras are both placed is matched under
    // the composed pose's E; its pose then comes from its own points.
    if config.guided {
        let guided = guided_pairs(cameras, &features, &pairs, &poses, config, seed)?;
        if !guided.is_empty() {
            for (k, m) in guided {
                pairs[k].route = Some(PoseRoute::Guided);
                pairs[k].pose = Some(m.estimate.pose);
                pairs[k].matching = Some(m);
            }
            (tree, poses, scale_points) = place(&pairs, n, config);
        }
    }
    let bundle = match &config.bundle {
        Some(refine) => refine_network(cameras, &features, &pairs, &mut poses, config, refine),
        None => None,
    };
    // Composed poses for the rest.
    for p in &mut pairs {
        if p.pose.is_none()
            && let (Some(pa), Some(pb)) = (poses[p.a], poses[p.b])
            && let Some(rel) = unit_relative(&pa, &pb)
        {
            p.route = Some(PoseRoute::Composed);
            p.pose = Some(rel);
        }
    }
    Ok(Network {
        pairs,
        tree,
        poses,
        scale_points,
        bundle,
    })
}

/// Each camera's tracks as feature tracks in normalised image coordinates (K⁻¹ applied to the
/// configured blob points).
fn normalised_features(cameras: &[CameraTracks], config: &NetworkConfig) -> Vec<Vec<FeatureTrack>> {
    cameras
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
        .collect()
}

/// The direct route for every pair (a < b, in order): its own track correspondence and
/// relative pose ([`match_tracks`], Meingast, Oh & Sastry 2007), in parallel; pair k draws
/// from ChaCha8(seed) stream k, so the result does not depend on the thread count.
fn direct_pairs(
    cameras: &[CameraTracks],
    features: &[Vec<FeatureTrack>],
    config: &NetworkConfig,
    seed: u64,
) -> Result<Vec<PairResult>> {
    let n = cameras.len();
    let pair_ids: Vec<(usize, usize)> = (0..n)
        .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
        .collect();
    pair_ids
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
            let (route, pose) = match &matching {
                Some(m) => (Some(PoseRoute::Direct), Some(m.estimate.pose)),
                None => (None, None),
            };
            Ok(PairResult {
                a,
                b,
                matching,
                route,
                pose,
            })
        })
        .collect::<Result<Vec<_>>>()
}

/// The guided route: every pair without a matching whose cameras are both placed, matched
/// under the E = \[t\]× R of the pose composed through the network (Hartley & Zisserman 2004,
/// §9.6; [`match_tracks_guided`]), in parallel; pair k draws from ChaCha8(seed) stream
/// (number of pairs + k). (pair index, matching) of those that found one.
fn guided_pairs(
    cameras: &[CameraTracks],
    features: &[Vec<FeatureTrack>],
    pairs: &[PairResult],
    poses: &[Option<Pose>],
    config: &NetworkConfig,
    seed: u64,
) -> Result<Vec<(usize, PairMatching)>> {
    let n_pairs = pairs.len() as u64;
    Ok(pairs
        .par_iter()
        .enumerate()
        .filter(|(_, p)| p.matching.is_none())
        .map(|(k, p)| -> Result<Option<(usize, PairMatching)>> {
            let (Some(pa), Some(pb)) = (poses[p.a], poses[p.b]) else {
                return Ok(None);
            };
            let Some(rel) = unit_relative(&pa, &pb) else {
                return Ok(None);
            };
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(n_pairs + k as u64);
            let scale =
                0.5 * (cameras[p.a].intrinsics.mean_focal() + cameras[p.b].intrinsics.mean_focal());
            Ok(match_tracks_guided(
                &features[p.a],
                &features[p.b],
                &rel.essential(),
                scale,
                &config.correspondence,
                &mut rng,
            )?
            .map(|m| (k, m)))
        })
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect())
}

/// The optional joint refinement ([`bundle_adjust`], Triggs et al. 2000) of every placed
/// camera and the tracks' points seen by two or more of them, with observations gated at
/// three times the correspondence threshold in the sharpest camera's normalised units. On
/// success the placed cameras take the refined poses and the summary is returned; `None`
/// when there is nothing to refine or the refinement fails (the tree's poses stay).
fn refine_network(
    cameras: &[CameraTracks],
    features: &[Vec<FeatureTrack>],
    pairs: &[PairResult],
    poses: &mut [Option<Pose>],
    config: &NetworkConfig,
    refine: &RefineConfig,
) -> Option<BundleSummary> {
    let gate = 3.0 * config.correspondence.threshold_px
        / cameras
            .iter()
            .map(|c| c.intrinsics.mean_focal())
            .fold(f64::INFINITY, f64::min);
    let (placed, points, obs) = network_points(features, pairs, poses, gate)?;
    let b = bundle_adjust(
        &placed.iter().filter_map(|&c| poses[c]).collect::<Vec<_>>(),
        &points,
        &obs,
        refine,
    )
    .ok()?;
    let poses_before = poses.to_vec();
    for (&c, pose) in placed.iter().zip(&b.poses) {
        poses[c] = Some(*pose);
    }
    Some(BundleSummary {
        poses_before,
        points: points.len(),
        observations: obs.len(),
        initial_rms: b.initial_rms,
        final_rms: b.final_rms,
        iterations: b.iterations,
    })
}

/// The pose of b relative to a (both `camera_from_camera0`) with unit translation; `None` for
/// coincident centres.
fn unit_relative(pose_a: &Pose, pose_b: &Pose) -> Option<Pose> {
    let rel = pose_b.compose(&pose_a.inverse());
    let t = rel.translation.try_normalize(1e-12)?;
    Some(Pose {
        rotation: rel.rotation,
        translation: t,
    })
}

/// The tree, poses and scale points of a [`Network`] from its pairs.
type Placement = (Vec<(usize, usize)>, Vec<Option<Pose>>, Vec<usize>);

/// Maximum spanning tree by inliers, scale transfer and poses in camera 0's frame.
fn place(pairs: &[PairResult], n: usize, config: &NetworkConfig) -> Placement {
    let tree = spanning_tree(pairs, n);
    // Scales and poses along the tree, in placement order.
    let mut poses: Vec<Option<Pose>> = vec![None; n];
    if n > 0 {
        poses[0] = Some(Pose::identity());
    }
    // Scaled edges: (p, c) → scale of the pair's unit translation.
    let mut scaled: BTreeMap<(usize, usize), f64> = BTreeMap::new();
    let mut scale_points = Vec::with_capacity(tree.len());
    for &(p, c) in &tree {
        let Some(parent_pose) = poses[p] else {
            scale_points.push(0);
            continue;
        };
        let Some(pair) = pair_of(pairs, p, c) else {
            continue;
        };
        let Some(m) = pair.matching.as_ref() else {
            continue;
        };
        let (rel, here) = points_at(pair, m, p);
        let scale = match transferred_scale(pairs, &scaled, p, &here, config) {
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
    (tree, poses, scale_points)
}

/// The maximum spanning tree of the view graph weighted by inlier count (Prim from camera 0,
/// ties to the lower pair index), as the camera network of Meingast, Oh & Sastry 2007 is
/// built: edges (parent, child) in the order the children are placed.
fn spanning_tree(pairs: &[PairResult], n: usize) -> Vec<(usize, usize)> {
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
    tree
}

/// The pair of cameras x and y, in either order.
fn pair_of(pairs: &[PairResult], x: usize, y: usize) -> Option<&PairResult> {
    let (a, b) = (x.min(y), x.max(y));
    pairs.iter().find(|p| p.a == a && p.b == b)
}

/// The scale of a new edge at camera `p` whose points (in p's frame, keyed by p's track,
/// frame and feature) are `here`: against the already-scaled edge at p with the most shared
/// points, that edge's scale times the median ratio of the shared points' distances from p's
/// centre (at least one ratio and `min_scale_points`). (shared points, scale), or `None`
/// when no scaled edge at p shares enough.
fn transferred_scale(
    pairs: &[PairResult],
    scaled: &BTreeMap<(usize, usize), f64>,
    p: usize,
    here: &PointsByKey,
    config: &NetworkConfig,
) -> Option<(usize, f64)> {
    // Reference: the scaled edge at p with the most shared points.
    let mut best: Option<(usize, f64)> = None;
    for (&(x, y), &s_ref) in scaled {
        let q = if x == p {
            y
        } else if y == p {
            x
        } else {
            continue;
        };
        let Some(rp) = pair_of(pairs, p, q) else {
            continue;
        };
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
    best
}

/// Placed cameras (camera 0 first), points and observations for the joint refinement.
type BundleInput = (Vec<usize>, Vec<Vector3<f64>>, Vec<BundleObservation>);

/// One observation of a bundle point: (bundle camera, normalised image point).
type Seen = (usize, Vector2<f64>);

fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

/// The bundle's points: tracks joined across cameras by the pairs' matches (union-find over
/// (camera, track)); one point per (object, frame, feature) seen by ≥ 2 placed cameras,
/// triangulated by multi-view DLT ([`triangulate_views`]). A camera with two tracks of one
/// object at one frame is left out of that point; an observation more than `gate`
/// (normalised) from its reprojection, or behind its camera, is dropped. `None` without
/// camera 0 or points.
fn network_points(
    features: &[Vec<FeatureTrack>],
    pairs: &[PairResult],
    poses: &[Option<Pose>],
    gate: f64,
) -> Option<BundleInput> {
    poses.first()?.as_ref()?;
    let placed: Vec<usize> = (0..poses.len()).filter(|&c| poses[c].is_some()).collect();
    let seen = observations_by_object(features, pairs, poses, &placed);
    let bundle_poses: Vec<Pose> = placed.iter().filter_map(|&c| poses[c]).collect();
    let mut points = Vec::new();
    let mut obs = Vec::new();
    for list in seen.values() {
        let mut here: Vec<(usize, Vector2<f64>)> = list
            .iter()
            .filter(|(c, _)| list.iter().filter(|(d, _)| d == c).count() == 1)
            .copied()
            .collect();
        if here.len() < 2 {
            continue;
        }
        let Some(x3) = triangulate_views(&bundle_poses, &here) else {
            continue;
        };
        here.retain(|(c, x)| {
            let y = bundle_poses[*c].apply(&x3);
            y.z > 0.0 && project(&y).is_some_and(|u| (u - x).norm() <= gate)
        });
        if here.len() < 2 || !x3.iter().all(|v| v.is_finite()) {
            continue;
        }
        let point = points.len();
        points.push(x3);
        obs.extend(
            here.iter()
                .map(|&(camera, x)| BundleObservation { camera, point, x }),
        );
    }
    if points.is_empty() {
        return None;
    }
    Some((placed, points, obs))
}

/// The observations of every (object, frame, feature) by the `placed` cameras, as (bundle
/// camera, image point) in camera order: an object is a class of (camera, track) joined by
/// the placed pairs' track matches (union-find with path halving, Tarjan & van Leeuwen 1984).
fn observations_by_object(
    features: &[Vec<FeatureTrack>],
    pairs: &[PairResult],
    poses: &[Option<Pose>],
    placed: &[usize],
) -> BTreeMap<(usize, Frame, usize), Vec<Seen>> {
    let mut slot = vec![usize::MAX; poses.len()];
    for (i, &c) in placed.iter().enumerate() {
        slot[c] = i;
    }
    let mut offset = Vec::with_capacity(features.len());
    let mut total = 0;
    for f in features {
        offset.push(total);
        total += f.len();
    }
    let mut parent: Vec<usize> = (0..total).collect();
    for p in pairs {
        let (Some(m), true) = (&p.matching, poses[p.a].is_some() && poses[p.b].is_some()) else {
            continue;
        };
        for t in &m.matches {
            let (x, y) = (
                find(&mut parent, offset[p.a] + t.track_a),
                find(&mut parent, offset[p.b] + t.track_b),
            );
            parent[x] = y;
        }
    }
    // (object, frame, feature) → observations (bundle camera, image point), and whether a
    // camera saw it twice.
    let mut seen: BTreeMap<(usize, Frame, usize), Vec<Seen>> = BTreeMap::new();
    for &c in placed {
        for (t, track) in features[c].iter().enumerate() {
            let object = find(&mut parent, offset[c] + t);
            for (frame, pts) in track.frames.iter().zip(&track.points) {
                for (k, x) in pts.iter().enumerate() {
                    seen.entry((object, *frame, k))
                        .or_default()
                        .push((slot[c], *x));
                }
            }
        }
    }
    seen
}

/// Multi-view linear (DLT) triangulation (Hartley & Zisserman 2004, §12.2) of one point seen
/// at `here` (bundle camera, normalised image point): the null vector of the stacked
/// x P₃ − P₁, y P₃ − P₂ rows, from the symmetric eigen-decomposition of AᵀA. `None` at
/// infinity (or when no eigenvalue compares).
fn triangulate_views(bundle_poses: &[Pose], here: &[Seen]) -> Option<Vector3<f64>> {
    let mut ata = nalgebra::Matrix4::<f64>::zeros();
    for (c, x) in here {
        let q = &bundle_poses[*c];
        let r = q.rotation.matrix();
        let row =
            |i: usize| nalgebra::RowVector4::new(r[(i, 0)], r[(i, 1)], r[(i, 2)], q.translation[i]);
        for a in [row(0) - row(2) * x.x, row(1) - row(2) * x.y] {
            ata += a.transpose() * a;
        }
    }
    let eig = ata.symmetric_eigen();
    let i = (0..4).min_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]))?;
    let h = eig.eigenvectors.column(i);
    if h[3].abs() < 1e-12 {
        return None;
    }
    Some(Vector3::new(h[0], h[1], h[2]) / h[3])
}
