//! Track correspondence between two cameras: which image tracks of camera a and camera b are
//! the same object. Candidate pairs are tracks that overlap in time; a hypothesis is a
//! one-to-one set of candidate pairs whose time-aligned points, pooled, must fit one
//! essential matrix. The search is greedy with verification:
//!
//! 1. candidates ranked by the number of time-aligned points; the search (steps 2–3) uses the
//!    `max_candidates` longest, the guided pass of step 5 all of them;
//! 2. seeds: every compatible pair among the first `seed_pool` candidates, fitted by least
//!    squares on a subsample and refitted on its inliers; a seed is valid when each of its two
//!    members keeps `accept_fraction` of its points as inliers; the best valid seed has the
//!    most inliers;
//! 3. growth: the compatible candidate with the largest inlier fraction under the current E
//!    (at least `screen_fraction`) is tried: E is refitted on the pooled points of the trial
//!    set (least squares, then polished), and the candidate joins if every member keeps
//!    `accept_fraction` of its points as inliers; a candidate that fails is not tried again;
//!    this runs from each of the `seed_trials` best seeds, and the grown set with the most
//!    inliers wins;
//! 4. the final pose: [`crate::estimate_relative_pose`] (RANSAC started from the growth's E)
//!    on all pooled points of the chosen pairs;
//! 5. a guided pass adds every compatible candidate (of all, not only the longest) that keeps
//!    `accept_fraction` under the refined E, and the pose is estimated again. In this pass
//!    two time-disjoint fragments of one track (MCMCDA broke it) may both join.
//!
//! Why the seed search can fail: the linear 8-point fit of two walkers' tracks is close to
//! degenerate (each walker's head and feet points lie on a vertical ruled surface), and for
//! some camera pairs every two-track seed's fit keeps almost no inliers. [`match_tracks_guided`]
//! skips the search when an approximate E is known (from the network: the pose composed
//! through other cameras) and runs step 5 alone from it.

use nalgebra::{Matrix3, Vector2};
use rand::Rng;
use serde::{Deserialize, Serialize};
use tracker_model::{Frame, ensure_in_range, ensure_positive};

use crate::error::{Result, invalid};
use crate::essential::{
    EssentialConfig, MIN_POINTS, TwoViewEstimate, estimate_relative_pose_from, fit_all_and_refit,
    polish_essential, sampson_distance,
};
use crate::refine::RefineConfig;

/// One camera's tracks as normalised feature points: per track, frames (increasing) and the
/// feature points at each frame (the same number and order in every frame and camera).
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureTrack {
    /// Frames, increasing.
    pub frames: Vec<Frame>,
    /// Feature points (normalised image coordinates) at each frame.
    pub points: Vec<Vec<Vector2<f64>>>,
}

/// Settings of [`match_tracks`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CorrespondenceConfig {
    /// Two tracks are a candidate pair when they share at least this many frames (default
    /// 10).
    pub min_overlap: usize,
    /// Candidates kept, longest overlap first (default 40).
    pub max_candidates: usize,
    /// Seeds are pairs among this many candidates with the most points (default 20).
    pub seed_pool: usize,
    /// A seed is polished only when its linear fit keeps this fraction of its points as
    /// inliers (default 0.3; decoys keep almost none).
    pub screen_fraction: f64,
    /// The refinement used to polish hypotheses.
    pub refine: RefineConfig,
    /// Growth is run from this many best seeds; the largest consensus wins (default 2).
    pub seed_trials: usize,
    /// Points per candidate in a seed fit, evenly subsampled (default 100).
    pub seed_points: usize,
    /// A member of a hypothesis must keep this fraction of its points as inliers (default
    /// 0.8).
    pub accept_fraction: f64,
    /// The fewest pooled inliers for the camera pair to count as matched (default 40).
    pub min_inliers: usize,
    /// Inlier threshold on the Sampson distance, pixels (default 2).
    pub threshold_px: f64,
    /// The essential-matrix estimation (its `threshold` is replaced by `threshold_px` over the
    /// focal length).
    pub essential: EssentialConfig,
}

impl Default for CorrespondenceConfig {
    fn default() -> Self {
        Self {
            min_overlap: 10,
            max_candidates: 40,
            seed_pool: 20,
            screen_fraction: 0.3,
            refine: RefineConfig {
                max_iterations: 10,
                ..RefineConfig::default()
            },
            seed_trials: 2,
            seed_points: 100,
            accept_fraction: 0.8,
            min_inliers: 40,
            threshold_px: 2.0,
            essential: EssentialConfig::default(),
        }
    }
}

impl CorrespondenceConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        if self.min_overlap < 2 {
            return Err(invalid(
                "min_overlap",
                format!("{}; at least 2", self.min_overlap),
            ));
        }
        if self.max_candidates == 0
            || self.seed_pool < 2
            || self.seed_points < 4
            || self.seed_trials == 0
        {
            return Err(invalid(
                "max_candidates / seed_pool / seed_points / seed_trials",
                "need ≥ 1, ≥ 2, ≥ 4 and ≥ 1".into(),
            ));
        }
        ensure_in_range(self.accept_fraction, 0.0, 1.0, "accept_fraction")?;
        ensure_in_range(self.screen_fraction, 0.0, 1.0, "screen_fraction")?;
        self.refine.check()?;
        ensure_positive(self.threshold_px, "threshold_px")?;
        self.essential.check()
    }
}

/// A chosen pair of tracks with its score under the final essential matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackMatch {
    /// Index of the track in camera a's list.
    pub track_a: usize,
    /// Index of the track in camera b's list.
    pub track_b: usize,
    /// Time-aligned correspondences the pair contributes.
    pub n_points: usize,
    /// Fraction of them that are inliers.
    pub inlier_fraction: f64,
    /// RMS Sampson distance of its inliers, pixels.
    pub rms_sampson_px: f64,
}

/// The result for one camera pair.
#[derive(Debug, Clone)]
pub struct PairMatching {
    /// The chosen track pairs, in the order they joined.
    pub matches: Vec<TrackMatch>,
    /// The relative pose (b relative to a) from the pooled points.
    pub estimate: TwoViewEstimate,
    /// Pooled normalised points in camera a.
    pub x_a: Vec<Vector2<f64>>,
    /// Pooled normalised points in camera b.
    pub x_b: Vec<Vector2<f64>>,
    /// For each pooled point: (index into `matches`, frame, feature index).
    pub origin: Vec<(usize, Frame, usize)>,
}

#[derive(Debug, Clone)]
struct Candidate {
    a: usize,
    b: usize,
    x_a: Vec<Vector2<f64>>,
    x_b: Vec<Vector2<f64>>,
    origin: Vec<(Frame, usize)>,
}

fn aligned(ta: &FeatureTrack, tb: &FeatureTrack) -> Candidate {
    let (mut i, mut j) = (0, 0);
    let mut c = Candidate {
        a: 0,
        b: 0,
        x_a: Vec::new(),
        x_b: Vec::new(),
        origin: Vec::new(),
    };
    while i < ta.frames.len() && j < tb.frames.len() {
        match ta.frames[i].cmp(&tb.frames[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                for (k, (pa, pb)) in ta.points[i].iter().zip(&tb.points[j]).enumerate() {
                    c.x_a.push(*pa);
                    c.x_b.push(*pb);
                    c.origin.push((ta.frames[i], k));
                }
                i += 1;
                j += 1;
            }
        }
    }
    c
}

fn frame_overlap(c: &Candidate) -> usize {
    let mut n = 0;
    let mut last = None;
    for (f, _) in &c.origin {
        if last != Some(*f) {
            n += 1;
            last = Some(*f);
        }
    }
    n
}

fn inlier_fraction(e: &Matrix3<f64>, c: &Candidate, threshold: f64) -> f64 {
    let n = c
        .x_a
        .iter()
        .zip(&c.x_b)
        .filter(|(a, b)| sampson_distance(e, a, b) <= threshold)
        .count();
    n as f64 / c.x_a.len().max(1) as f64
}

fn subsample(c: &Candidate, n: usize) -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    let len = c.x_a.len();
    if len <= n {
        return (c.x_a.clone(), c.x_b.clone());
    }
    // Whole frames, evenly spaced: every feature of a chosen frame is kept, so a subsample
    // never loses one of the heights (top points alone are coplanar, a degenerate set).
    let starts: Vec<usize> = (0..len)
        .filter(|&i| i == 0 || c.origin[i].0 != c.origin[i - 1].0)
        .collect();
    let per_frame = len.div_ceil(starts.len().max(1));
    let n_frames = (n / per_frame.max(1)).max(1).min(starts.len());
    let mut xa = Vec::with_capacity(n);
    let mut xb = Vec::with_capacity(n);
    for k in 0..n_frames {
        let s = starts[k * starts.len() / n_frames];
        let mut i = s;
        while i < len && c.origin[i].0 == c.origin[s].0 {
            xa.push(c.x_a[i]);
            xb.push(c.x_b[i]);
            i += 1;
        }
    }
    (xa, xb)
}

fn pooled_sub(
    cands: &[Candidate],
    members: &[usize],
    n: usize,
) -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    let mut xa = Vec::new();
    let mut xb = Vec::new();
    for &m in members {
        let (a, b) = subsample(&cands[m], n);
        xa.extend(a);
        xb.extend(b);
    }
    (xa, xb)
}

fn pooled(cands: &[Candidate], members: &[usize]) -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    let mut xa = Vec::new();
    let mut xb = Vec::new();
    for &m in members {
        xa.extend_from_slice(&cands[m].x_a);
        xb.extend_from_slice(&cands[m].x_b);
    }
    (xa, xb)
}

/// Finds the track pairs between camera a (`tracks_a`) and camera b (`tracks_b`) and the
/// relative pose they imply; `pixel_scale` (the focal length) turns `threshold_px` into
/// normalised units. `None` when no hypothesis passes verification.
pub fn match_tracks<R: Rng + ?Sized>(
    tracks_a: &[FeatureTrack],
    tracks_b: &[FeatureTrack],
    pixel_scale: f64,
    config: &CorrespondenceConfig,
    rng: &mut R,
) -> Result<Option<PairMatching>> {
    config.check()?;
    ensure_positive(pixel_scale, "pixel_scale")?;
    let threshold = config.threshold_px / pixel_scale;
    // 1. Candidates: all of them for the final guided pass, the longest for the search.
    let all = candidates(tracks_a, tracks_b, config.min_overlap);
    let cands = &all[..all.len().min(config.max_candidates)];
    if cands.len() < 2 {
        return Ok(None);
    }
    let seeds = seed_pairs(cands, threshold, config);
    if seeds.is_empty() {
        return Ok(None);
    }
    let Some((_, members, e)) = best_growth(cands, &seeds, threshold, config) else {
        return Ok(None);
    };
    finish(&all, members, &e, pixel_scale, threshold, config, rng)
}

/// Step 2 of [`match_tracks`], the seeds: pairs among the `seed_pool` longest candidates (no
/// camera's track twice), each fitted by least squares on all its (subsampled) points and
/// refitted on the inliers, screened by the share of points the linear fit holds, polished by
/// LM and accepted when both tracks keep `accept_fraction` of their points within the
/// threshold of the Sampson distance (Hartley & Zisserman 2004). Sorted by inliers, most
/// first (ties: the lower pair). Minimal samples of two tracks are close to degenerate (each
/// walker's points lie near a vertical ruled surface); a fit on all points is not, and the
/// tracks of a true pair carry few outliers.
fn seed_pairs(
    cands: &[Candidate],
    threshold: f64,
    config: &CorrespondenceConfig,
) -> Vec<(usize, [usize; 2])> {
    let pool = config.seed_pool.min(cands.len());
    let mut seeds: Vec<(usize, [usize; 2])> = Vec::new();
    for p in 0..pool {
        for q in p + 1..pool {
            let (cp, cq) = (&cands[p], &cands[q]);
            if cp.a == cq.a || cp.b == cq.b {
                continue;
            }
            let (mut xa, mut xb) = subsample(cp, config.seed_points);
            let (qa, qb) = subsample(cq, config.seed_points);
            xa.extend(qa);
            xb.extend(qb);
            let Ok((e, n_in)) =
                fit_all_and_refit(&xa, &xb, threshold, config.essential.local_refits)
            else {
                continue;
            };
            // Decoys fit nothing; a true pair's linear fit holds a good share of its points
            // and non-linear polishing recovers the rest.
            if n_in as f64 / (xa.len() as f64) < config.screen_fraction {
                continue;
            }
            let Ok((e, n_in)) = polish_essential(&xa, &xb, &e, threshold, 3, &config.refine) else {
                continue;
            };
            let in_p = inlier_fraction(&e, cp, threshold);
            let in_q = inlier_fraction(&e, cq, threshold);
            if in_p < config.accept_fraction || in_q < config.accept_fraction {
                continue;
            }
            seeds.push((n_in, [p, q]));
        }
    }
    seeds.sort_by(|p, q| q.0.cmp(&p.0).then(p.1.cmp(&q.1)));
    seeds
}

/// Step 3 of [`match_tracks`]: growth from each of the `seed_trials` best seeds; the grown
/// hypothesis with the most inliers over its members wins (ties: the earlier seed), as a
/// seed of two tracks can fit a wrong E that nothing else joins. (score, members, E), or
/// `None` when no seed grows.
fn best_growth(
    cands: &[Candidate],
    seeds: &[(usize, [usize; 2])],
    threshold: f64,
    config: &CorrespondenceConfig,
) -> Option<(usize, Vec<usize>, Matrix3<f64>)> {
    let mut best: Option<(usize, Vec<usize>, Matrix3<f64>)> = None;
    for &(_, seed) in seeds.iter().take(config.seed_trials) {
        let Ok((members, e)) = grow(cands, seed, threshold, config) else {
            continue;
        };
        let score: usize = members
            .iter()
            .map(|&m| {
                let c = &cands[m];
                c.x_a
                    .iter()
                    .zip(&c.x_b)
                    .filter(|(a, b)| sampson_distance(&e, a, b) <= threshold)
                    .count()
            })
            .sum();
        if best.as_ref().is_none_or(|(s, _, _)| score > *s) {
            best = Some((score, members, e));
        }
    }
    best
}

/// Guided track correspondence: the relative pose of the two cameras is already known
/// approximately (`essential_guess`, e.g. composed through the network,
/// E = \[t\]× R of `pose_b ∘ pose_a⁻¹`, Hartley & Zisserman 2004, §9.6), so no seed search is needed.
/// Every candidate (all of them, not only the `max_candidates` longest) that keeps
/// `accept_fraction` of its points within the Sampson threshold of the guess joins, best
/// first and compatible with those already in (one-to-one, except that time-disjoint
/// fragments of a track may both join); the pose is then estimated from the pair's own
/// pooled points (RANSAC started from the guess, cheirality, LM), one more guided pass is
/// made under that estimate, and the pose estimated again. `None` when fewer than
/// `min_inliers` pooled inliers remain.
pub fn match_tracks_guided<R: Rng + ?Sized>(
    tracks_a: &[FeatureTrack],
    tracks_b: &[FeatureTrack],
    essential_guess: &Matrix3<f64>,
    pixel_scale: f64,
    config: &CorrespondenceConfig,
    rng: &mut R,
) -> Result<Option<PairMatching>> {
    config.check()?;
    ensure_positive(pixel_scale, "pixel_scale")?;
    if !essential_guess.iter().all(|v| v.is_finite()) || essential_guess.norm() == 0.0 {
        return Err(invalid("essential_guess", "not finite or zero".into()));
    }
    let threshold = config.threshold_px / pixel_scale;
    let all = candidates(tracks_a, tracks_b, config.min_overlap);
    finish(
        &all,
        Vec::new(),
        essential_guess,
        pixel_scale,
        threshold,
        config,
        rng,
    )
}

/// Candidates (track pairs sharing ≥ `min_overlap` frames), most points first.
fn candidates(
    tracks_a: &[FeatureTrack],
    tracks_b: &[FeatureTrack],
    min_overlap: usize,
) -> Vec<Candidate> {
    let mut cands = Vec::new();
    for (a, ta) in tracks_a.iter().enumerate() {
        for (b, tb) in tracks_b.iter().enumerate() {
            let mut c = aligned(ta, tb);
            if frame_overlap(&c) >= min_overlap && c.x_a.len() >= MIN_POINTS {
                (c.a, c.b) = (a, b);
                cands.push(c);
            }
        }
    }
    cands.sort_by(|p, q| {
        q.x_a
            .len()
            .cmp(&p.x_a.len())
            .then((p.a, p.b).cmp(&(q.a, q.b)))
    });
    cands
}

/// Whether two candidates share no frame (`origin` is sorted by frame).
fn time_disjoint(p: &Candidate, q: &Candidate) -> bool {
    let (mut i, mut j) = (0, 0);
    while i < p.origin.len() && j < q.origin.len() {
        match p.origin[i].0.cmp(&q.origin[j].0) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => return false,
        }
    }
    true
}

/// Whether candidate `k` may join `members` in a guided pass: at every frame each track is
/// matched to at most one track of the other camera. Two fragments of one object's track
/// (MCMCDA broke it, or the object left and came back) may both pair with the other
/// camera's unbroken track, since they never claim the same frame.
fn compatible_guided(cands: &[Candidate], members: &[usize], k: usize) -> bool {
    let c = &cands[k];
    members.iter().all(|&m| {
        let d = &cands[m];
        m != k
            && ((d.a != c.a && d.b != c.b) || (!(d.a == c.a && d.b == c.b) && time_disjoint(d, c)))
    })
}

/// Adds, best first, every candidate compatible with `members` that keeps
/// `accept_fraction` of its points under `e`. Returns whether any joined.
fn guided_pass(
    cands: &[Candidate],
    members: &mut Vec<usize>,
    e: &Matrix3<f64>,
    threshold: f64,
    config: &CorrespondenceConfig,
) -> bool {
    let mut order: Vec<(f64, usize)> = (0..cands.len())
        .filter(|k| !members.contains(k))
        .map(|k| (inlier_fraction(e, &cands[k], threshold), k))
        .filter(|(f, _)| *f >= config.accept_fraction)
        .collect();
    order.sort_by(|p, q| q.0.total_cmp(&p.0).then(p.1.cmp(&q.1)));
    let before = members.len();
    for (_, k) in order {
        if compatible_guided(cands, members, k) {
            members.push(k);
        }
    }
    members.len() > before
}

/// Steps 4 and 5 of the module doc (and the whole of a guided match, where `members` starts
/// empty and `e` comes from elsewhere): the pose from the chosen pairs' pooled points, a
/// guided pass over all candidates under it, the pose again.
fn finish<R: Rng + ?Sized>(
    all: &[Candidate],
    mut members: Vec<usize>,
    e: &Matrix3<f64>,
    pixel_scale: f64,
    threshold: f64,
    config: &CorrespondenceConfig,
    rng: &mut R,
) -> Result<Option<PairMatching>> {
    let essential = EssentialConfig {
        threshold,
        ..config.essential
    };
    let mut estimate: Option<TwoViewEstimate> = None;
    // Two rounds: a pose on the members, a guided pass under it (every candidate, so pairs
    // outside the `max_candidates` longest and MCMCDA fragments can join too).
    for _ in 0..2 {
        if let Some(est) = &estimate {
            if !guided_pass(all, &mut members, &est.essential, threshold, config) {
                break;
            }
        } else if members.is_empty() {
            guided_pass(all, &mut members, e, threshold, config);
        }
        if members.is_empty() {
            return Ok(None);
        }
        let guess = estimate.as_ref().map_or(*e, |est| est.essential);
        let (xa, xb) = pooled(all, &members);
        match estimate_relative_pose_from(&xa, &xb, Some(&guess), &essential, rng) {
            Ok(est) => estimate = Some(est),
            Err(_) => return Ok(None),
        }
    }
    let Some(estimate) = estimate else {
        return Ok(None);
    };
    if estimate.n_inliers < config.min_inliers {
        return Ok(None);
    }
    let (x_a, x_b) = pooled(all, &members);
    let mut origin = Vec::with_capacity(x_a.len());
    let mut matches = Vec::with_capacity(members.len());
    let mut offset = 0;
    for (mi, &m) in members.iter().enumerate() {
        let c = &all[m];
        let n = c.x_a.len();
        let flags = &estimate.inliers[offset..offset + n];
        let n_in = flags.iter().filter(|&&f| f).count();
        let ss: f64 = (0..n)
            .filter(|&i| flags[i])
            .map(|i| sampson_distance(&estimate.essential, &c.x_a[i], &c.x_b[i]).powi(2))
            .sum();
        matches.push(TrackMatch {
            track_a: c.a,
            track_b: c.b,
            n_points: n,
            inlier_fraction: n_in as f64 / n as f64,
            rms_sampson_px: (ss / n_in.max(1) as f64).sqrt() * pixel_scale,
        });
        origin.extend(c.origin.iter().map(|&(f, k)| (mi, f, k)));
        offset += n;
    }
    Ok(Some(PairMatching {
        matches,
        estimate,
        x_a,
        x_b,
        origin,
    }))
}

/// Greedy growth with verification from a seed of two candidates (step 3 of the module doc).
fn grow(
    cands: &[Candidate],
    seed: [usize; 2],
    threshold: f64,
    config: &CorrespondenceConfig,
) -> Result<(Vec<usize>, Matrix3<f64>)> {
    let mut members: Vec<usize> = seed.to_vec();
    let (xa, xb) = pooled(cands, &members);
    let e0 = fit_all_and_refit(&xa, &xb, threshold, config.essential.local_refits)?.0;
    let mut e = polish_essential(&xa, &xb, &e0, threshold, 3, &config.refine)?.0;
    let mut rejected = vec![false; cands.len()];
    loop {
        let compatible = |k: usize| {
            !members.contains(&k)
                && !rejected[k]
                && members
                    .iter()
                    .all(|&m| cands[m].a != cands[k].a && cands[m].b != cands[k].b)
        };
        let next = (0..cands.len())
            .filter(|&k| compatible(k))
            .map(|k| (inlier_fraction(&e, &cands[k], threshold), k))
            .max_by(|p, q| p.0.total_cmp(&q.0).then(q.1.cmp(&p.1)));
        let Some((frac, k)) = next else { break };
        if frac < config.screen_fraction {
            break;
        }
        // Verification: E refitted on every (subsampled) point of the trial set, linear then
        // polished; every member must keep `accept_fraction` of its points as inliers.
        let mut trial = members.clone();
        trial.push(k);
        let (xa, xb) = pooled_sub(cands, &trial, config.seed_points);
        let verified = fit_all_and_refit(&xa, &xb, threshold, config.essential.local_refits)
            .and_then(|(e_ls, _)| polish_essential(&xa, &xb, &e_ls, threshold, 2, &config.refine))
            .map(|r| r.0)
            .ok()
            .filter(|e_new| {
                trial.iter().all(|&m| {
                    inlier_fraction(e_new, &cands[m], threshold) >= config.accept_fraction
                })
            });
        match verified {
            Some(e_new) => {
                members = trial;
                e = e_new;
            }
            None => rejected[k] = true,
        }
    }
    Ok((members, e))
}
