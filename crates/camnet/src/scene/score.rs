//! A localised network scored against a simulated scene's truth, as Meingast, Oh & Sastry
//! (ICCV 2007) measure it: the pairwise rotation and translation-direction errors, the camera
//! positions after a similarity alignment, and the track correspondences that are right.

use std::collections::BTreeMap;

use nalgebra::Vector3;

use crate::error::{Error, Result, invalid};
use crate::geometry::{Pose, angle_between_deg, rotation_error_deg, umeyama};
use crate::network::{Network, PoseRoute};
use crate::scene::TrackedCameras;
use crate::tracks::ImageTrack;

/// The person most of a track's blobs come from (`None` if false blobs dominate; a tie goes to
/// the lower label), from the blobs' labels per scan (see
/// [`Detections`](crate::scene::Detections)); a blob outside `labels` counts as false.
pub fn majority(track: &ImageTrack, labels: &[Vec<Option<usize>>]) -> Option<usize> {
    let mut count: BTreeMap<Option<usize>, usize> = BTreeMap::new();
    for &(s, k) in &track.sources {
        let label = labels.get(s).and_then(|l| l.get(k)).copied().flatten();
        *count.entry(label).or_default() += 1;
    }
    count
        .into_iter()
        .max_by_key(|&(l, c)| (c, std::cmp::Reverse(l)))
        .and_then(|(l, _)| l)
}

/// The number of frames two image tracks share.
pub fn overlap(a: &ImageTrack, b: &ImageTrack) -> usize {
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < a.frames.len() && j < b.frames.len() {
        match a.frames[i].cmp(&b.frames[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                n += 1;
                i += 1;
                j += 1;
            }
        }
    }
    n
}

/// One camera pair scored against the truth.
#[derive(Debug, Clone, PartialEq)]
pub struct PairScore {
    /// Camera a.
    pub a: usize,
    /// Camera b.
    pub b: usize,
    /// True track pairs available: tracks of the same person sharing enough frames.
    pub shared_tracks: usize,
    /// (rotation error °, translation-direction error °) when the pair has a pose.
    pub error_deg: Option<(f64, f64)>,
    /// Where the pose came from.
    pub route: Option<PoseRoute>,
}

/// The pairwise scores of one scene: every pair's errors, and the correspondence counts
/// behind precision (`correct / chosen`) and recall (`correct / true_pairs`).
#[derive(Debug, Clone, PartialEq)]
pub struct PairTally {
    /// Every pair of the network, in its order.
    pub pairs: Vec<PairScore>,
    /// Track pairs the matching chose, over all camera pairs.
    pub chosen: usize,
    /// Those whose two tracks follow the same person.
    pub correct: usize,
    /// True track pairs available, over all camera pairs.
    pub true_pairs: usize,
}

/// Scores every camera pair of the network against the truth (`cams`, the true
/// `camera_from_world` poses, and the tracks' labels): shared true track pairs (the same
/// person, at least `min_overlap` frames in common), the matched track pairs that are right,
/// and the pose's rotation and translation-direction errors. The network, the tracks and the
/// labels must all be of the same cameras.
pub fn score_pairs(
    net: &Network,
    tracked: &TrackedCameras,
    cams: &[Pose],
    min_overlap: usize,
) -> Result<PairTally> {
    check_cameras(net, tracked, cams)?;
    let (inputs, labels) = (&tracked.cameras, &tracked.labels);
    let mut pairs = Vec::new();
    let (mut chosen, mut correct, mut true_pairs) = (0, 0, 0);
    for pr in &net.pairs {
        let (a, b) = (pr.a, pr.b);
        let mut shared = 0;
        for (i, ta) in inputs[a].tracks.iter().enumerate() {
            for (j, tb) in inputs[b].tracks.iter().enumerate() {
                if labels[a][i].is_some()
                    && labels[a][i] == labels[b][j]
                    && overlap(ta, tb) >= min_overlap
                {
                    shared += 1;
                }
            }
        }
        true_pairs += shared;
        let truth = cams[b].compose(&cams[a].inverse());
        if let Some(m) = &pr.matching {
            chosen += m.matches.len();
            correct += m
                .matches
                .iter()
                .filter(|t| {
                    labels[a][t.track_a].is_some() && labels[a][t.track_a] == labels[b][t.track_b]
                })
                .count();
        }
        let error_deg = pr.pose.map(|q| {
            (
                rotation_error_deg(&q.rotation, &truth.rotation),
                angle_between_deg(&q.translation, &truth.translation),
            )
        });
        pairs.push(PairScore {
            a,
            b,
            shared_tracks: shared,
            error_deg,
            route: pr.route,
        });
    }
    Ok(PairTally {
        pairs,
        chosen,
        correct,
        true_pairs,
    })
}

/// Checks that the network, the tracks, their labels and the true poses are of the same
/// cameras, so that scoring cannot index out of range.
fn check_cameras(net: &Network, tracked: &TrackedCameras, cams: &[Pose]) -> Result<()> {
    let n = cams.len();
    let mismatch = |index: usize, reason: String| Err(Error::BadCamera { index, reason });
    if net.poses.len() != n || tracked.cameras.len() != n || tracked.labels.len() != n {
        return Err(invalid(
            "cams",
            format!(
                "{n} true poses, but {} placed, {} tracked and {} labelled cameras",
                net.poses.len(),
                tracked.cameras.len(),
                tracked.labels.len()
            ),
        ));
    }
    for (c, (input, labels)) in tracked.cameras.iter().zip(&tracked.labels).enumerate() {
        if input.tracks.len() != labels.len() {
            let (t, l) = (input.tracks.len(), labels.len());
            return mismatch(c, format!("{t} tracks but {l} track labels"));
        }
    }
    for pr in &net.pairs {
        if pr.a >= n || pr.b >= n {
            return mismatch(
                pr.a.max(pr.b),
                format!("a pair of a network of {n} cameras"),
            );
        }
        let matched = pr.matching.iter().flat_map(|m| &m.matches);
        for t in matched {
            if t.track_a >= tracked.labels[pr.a].len() || t.track_b >= tracked.labels[pr.b].len() {
                return mismatch(
                    pr.a,
                    format!("a track match outside pair {}–{}", pr.a, pr.b),
                );
            }
        }
    }
    Ok(())
}

/// The placed cameras after a similarity alignment to the truth.
#[derive(Debug, Clone, PartialEq)]
pub struct Alignment {
    /// The cameras the network placed.
    pub placed: Vec<usize>,
    /// Their position errors after the joint refinement, % of the scene size (empty when
    /// fewer than three cameras are placed).
    pub position_error_pct: Vec<f64>,
    /// The same before the joint refinement (equal to the above when it did not run).
    pub position_error_pct_tree: Vec<f64>,
    /// Aligned centre and optical axis per camera, `None` for a camera not placed.
    pub est_cams: Vec<Option<(Vector3<f64>, Vector3<f64>)>>,
}

/// Similarity (Umeyama) alignment of the placed cameras' centres (camera 0's frame) to the
/// true centres of `cams`, after and before the joint refinement: the camera position errors,
/// as % of the largest distance between cameras.
pub fn align_cameras(net: &Network, cams: &[Pose]) -> Result<Alignment> {
    if net.poses.len() != cams.len() {
        let (n, m) = (cams.len(), net.poses.len());
        return Err(invalid(
            "cams",
            format!("{n} true poses but a network of {m} cameras"),
        ));
    }
    let placed: Vec<usize> = (0..cams.len())
        .filter(|&c| net.poses[c].is_some())
        .collect();
    let true_centres: Vec<Vector3<f64>> = cams.iter().map(Pose::centre).collect();
    let scene = true_centres
        .iter()
        .flat_map(|a| true_centres.iter().map(move |b| (a - b).norm()))
        .fold(0.0, f64::max);
    let mut position_error_pct = Vec::new();
    let mut position_error_pct_tree = Vec::new();
    let mut est_cams = vec![None; cams.len()];
    if placed.len() >= 3 {
        let to: Vec<Vector3<f64>> = placed.iter().map(|&c| true_centres[c]).collect();
        let before = net.bundle.as_ref().map_or(&net.poses, |b| &b.poses_before);
        for (poses, errors, draw) in [
            (&net.poses, &mut position_error_pct, true),
            (before, &mut position_error_pct_tree, false),
        ] {
            let from: Vec<Vector3<f64>> = placed
                .iter()
                .filter_map(|&c| poses[c].map(|q| q.centre()))
                .collect();
            if from.len() != placed.len() {
                continue;
            }
            let sim = umeyama(&from, &to)?;
            for (&c, f) in placed.iter().zip(&from) {
                let centre = sim.apply(f);
                errors.push(100.0 * (centre - true_centres[c]).norm() / scene);
                if draw && let Some(q) = poses[c] {
                    let axis = sim.rotation * (q.rotation.inverse() * Vector3::z());
                    est_cams[c] = Some((centre, axis));
                }
            }
        }
    }
    Ok(Alignment {
        placed,
        position_error_pct,
        position_error_pct_tree,
        est_cams,
    })
}
