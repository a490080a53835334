//! Phase one: every sensor tracks its own measurements with online MCMCDA and, where tracks
//! come close, draws MCMC samples to build the mixing matrix of their identities (Oh, Hwang
//! & Sastry 2008). Nothing here depends on beliefs, so the identity layer (any fusion
//! criterion, or none) replays these records.

use std::collections::HashMap;

use identity_mgmt::Continuation;
use mcmcda::{MeasId, Model, OnlineConfig, OnlineTracker};
use rayon::prelude::*;
use tracker_model::Vec2;

use crate::config::DmtimConfig;
use crate::error::{Error, Result};
use crate::scene::{Observations, SensorScan};

/// A mixing of the identities of some tracks after they interacted.
#[derive(Debug, Clone, PartialEq)]
pub struct Mixing {
    /// The tracks' labels (the matrix's rows and columns, in this order).
    pub labels: Vec<u64>,
    /// m_ij = P(the track labelled `labels[j]` now continues the one labelled `labels[i]`
    /// before the interaction).
    pub continuation: Continuation,
    /// True if a piece before the interaction had left the window, so the matrix is the
    /// uniform one (no information about who is who).
    pub uniform_fallback: bool,
}

/// One sensor's tracker output in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorFrame {
    /// Reported tracks: persistent label and position estimate.
    pub estimates: Vec<(u64, Vec2)>,
    /// Interactions that ended in this frame.
    pub mixings: Vec<Mixing>,
    /// Measurements received in this frame.
    pub n_measurements: usize,
    /// For each read of this frame's scan, the label of the reported track holding the
    /// measurement it came with (`None` if no reported track holds it).
    pub read_tracks: Vec<Option<u64>>,
    /// For scoring only: the true target behind each estimate (the origin of its measurement
    /// in this frame; `None` if clutter or if the track coasts through this frame, so a
    /// track is scored only in frames where it holds a measurement of a target).
    pub origins: Vec<Option<usize>>,
}

struct Open {
    labels: Vec<u64>,
    pre: Vec<MeasId>,
}

/// The last measurement of `label`'s MAP track before scan `before`, or its last one.
fn last_before(tracker: &OnlineTracker, label: u64, before: usize) -> Option<MeasId> {
    let (_, track) = tracker.map_tracks().iter().find(|(l, _)| *l == label)?;
    let p = tracker.problem();
    track
        .iter()
        .rev()
        .find(|&&m| p.scan_of(m) < before)
        .or(track.last())
        .copied()
}

/// Runs one sensor's tracker over its scans. Per frame: the scan goes to the tracker; each
/// estimate and each read is tied to the measurements it holds; estimates that came close
/// open (or grow) an interaction, and interactions whose tracks have separated are closed
/// with a mixing matrix (Oh, Hwang & Sastry 2008).
pub fn track_sensor(
    sensor: usize,
    model: Model,
    online: OnlineConfig,
    scans: &[SensorScan],
    config: &DmtimConfig,
    seed: u64,
) -> Result<Vec<SensorFrame>> {
    let err = |source| Error::Tracker { sensor, source };
    let mut tracker = OnlineTracker::new(model, 0, online, seed).map_err(err)?;
    let mut open: Vec<Open> = Vec::new();
    let mut origin_of: HashMap<MeasId, Option<usize>> = HashMap::new();
    let mut out = Vec::with_capacity(scans.len());
    for (frame, scan) in scans.iter().enumerate() {
        let frame_id = tracker_model::Frame::try_from(frame).map_err(|_| {
            crate::error::invalid("frames", format!("frame {frame} does not fit a Frame"))
        })?;
        let est = tracker
            .push_scan(frame_id, &scan.points)
            .map_err(err)?
            .estimates;
        // The ids of this scan's points: the last ones added, in order.
        let first = tracker.problem().n_measurements() - scan.points.len();
        for (k, o) in scan.origins.iter().enumerate() {
            origin_of.insert((first + k) as MeasId, *o);
        }
        let origins = estimate_origins(&tracker, &est, &origin_of, frame);
        let read_tracks = read_tracks(&tracker, &est, scan, first);
        let clusters = clusters(&est, config.interaction_distance_m);
        open_interactions(&mut open, &clusters, &tracker, frame);
        let mixings = close_interactions(&mut open, &clusters, &est, &mut tracker, config, sensor)?;
        out.push(SensorFrame {
            estimates: est,
            mixings,
            n_measurements: scan.points.len(),
            read_tracks,
            origins,
        });
    }
    Ok(out)
}

/// The measurements of `label`'s MAP track, if it has one.
fn track_of_label(tracker: &OnlineTracker, label: u64) -> Option<&[MeasId]> {
    let map = tracker.map_tracks();
    map.iter()
        .find(|(m, _)| *m == label)
        .map(|(_, t)| t.as_slice())
}

/// For scoring only: the true target behind each estimate, the origin of its track's
/// measurement in scan `frame` (`None` if it coasts through the scan or the measurement is
/// clutter).
fn estimate_origins(
    tracker: &OnlineTracker,
    est: &[(u64, Vec2)],
    origin_of: &HashMap<MeasId, Option<usize>>,
    frame: usize,
) -> Vec<Option<usize>> {
    est.iter()
        .map(|(l, _)| {
            let t = track_of_label(tracker, *l)?;
            let m = t.last()?;
            if tracker.problem().scan_of(*m) != frame {
                return None;
            }
            origin_of.get(m).copied().flatten()
        })
        .collect()
}

/// For each read of `scan` (whose first point has id `first`), the label of the reported
/// track holding the measurement it came with: a transponder reply arrives with its
/// target's radar plot, so the read is about whichever track took that plot.
fn read_tracks(
    tracker: &OnlineTracker,
    est: &[(u64, Vec2)],
    scan: &SensorScan,
    first: usize,
) -> Vec<Option<u64>> {
    scan.reads
        .iter()
        .map(|r| {
            let m = (first + r.point) as MeasId;
            est.iter()
                .map(|(l, _)| *l)
                .find(|&l| track_of_label(tracker, l).is_some_and(|t| t.contains(&m)))
        })
        .collect()
}

/// The root of `i` in the union-find forest `g`, halving the path on the way.
fn root(g: &mut [usize], mut i: usize) -> usize {
    while g[i] != i {
        g[i] = g[g[i]];
        i = g[i];
    }
    i
}

/// Groups of at least two estimates linked by chains of estimates closer than `d_int`
/// (single linkage): the tracks whose identities may swap (Oh, Hwang & Sastry 2008 mix
/// identities where tracks come close). Groups are in order of their first member, members
/// in estimate order.
pub(crate) fn clusters(est: &[(u64, Vec2)], d_int: f64) -> Vec<Vec<u64>> {
    let n = est.len();
    let mut group: Vec<usize> = (0..n).collect();
    for a in 0..n {
        for b in a + 1..n {
            if (est[a].1 - est[b].1).norm() < d_int {
                let (ra, rb) = (root(&mut group, a), root(&mut group, b));
                group[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    let mut clusters: Vec<Vec<u64>> = Vec::new();
    for r in 0..n {
        let members: Vec<u64> = (0..n)
            .filter(|&i| root(&mut group, i) == r)
            .map(|i| est[i].0)
            .collect();
        if members.len() >= 2 {
            clusters.push(members);
        }
    }
    clusters
}

/// Opens an interaction for each cluster, merging the open interactions it touches (a
/// track can only be in one). A track joining records its pre piece: its last measurement
/// before scan `frame`, where its identity was still its own.
fn open_interactions(
    open: &mut Vec<Open>,
    clusters: &[Vec<u64>],
    tracker: &OnlineTracker,
    frame: usize,
) {
    for c in clusters {
        let touching: Vec<usize> = (0..open.len())
            .filter(|&k| open[k].labels.iter().any(|l| c.contains(l)))
            .collect();
        let mut merged = Open {
            labels: Vec::new(),
            pre: Vec::new(),
        };
        for &k in touching.iter().rev() {
            let o = open.remove(k);
            merged.labels.extend(o.labels);
            merged.pre.extend(o.pre);
        }
        for &l in c {
            if !merged.labels.contains(&l)
                && let Some(m) = last_before(tracker, l, frame)
            {
                merged.labels.push(l);
                merged.pre.push(m);
            }
        }
        open.push(merged);
    }
}

/// Closes the open interactions none of whose clusters still holds two of its live tracks,
/// in order, and returns a mixing for each that kept at least two tracks.
fn close_interactions(
    open: &mut Vec<Open>,
    clusters: &[Vec<u64>],
    est: &[(u64, Vec2)],
    tracker: &mut OnlineTracker,
    config: &DmtimConfig,
    sensor: usize,
) -> Result<Vec<Mixing>> {
    let mut mixings = Vec::new();
    let mut k = 0;
    while k < open.len() {
        let alive: Vec<usize> = (0..open[k].labels.len())
            .filter(|&i| est.iter().any(|(l, _)| *l == open[k].labels[i]))
            .collect();
        let together = clusters.iter().any(|c| {
            alive
                .iter()
                .filter(|&&i| c.contains(&open[k].labels[i]))
                .count()
                >= 2
        });
        if together {
            k += 1;
            continue;
        }
        let o = open.remove(k);
        if alive.len() < 2 {
            continue;
        }
        mixings.push(mixing_of(&o, &alive, tracker, config, sensor)?);
    }
    Ok(mixings)
}

/// The mixing of the `alive` tracks of a closed interaction: m_ij is the fraction of MCMC
/// samples of the current window joining track i's pre piece to track j's latest
/// measurement (Oh, Hwang & Sastry 2008). If a pre piece has left the window the samples
/// cannot say, and the mixing is uniform.
fn mixing_of(
    o: &Open,
    alive: &[usize],
    tracker: &mut OnlineTracker,
    config: &DmtimConfig,
    sensor: usize,
) -> Result<Mixing> {
    let labels: Vec<u64> = alive.iter().map(|&i| o.labels[i]).collect();
    let pre: Vec<MeasId> = alive.iter().map(|&i| o.pre[i]).collect();
    let post: Option<Vec<MeasId>> = labels
        .iter()
        .map(|&l| last_before(tracker, l, usize::MAX))
        .collect();
    let in_window = tracker.window().is_some_and(|w| {
        pre.iter()
            .all(|&m| tracker.problem().scan_of(m) >= *w.start())
    });
    let n_pieces = labels.len();
    let (continuation, uniform_fallback) = match post {
        Some(post) if in_window => {
            let samples = tracker
                .sample_joins(&pre, &post, config.join_samples)
                .map_err(|source| Error::Tracker { sensor, source })?;
            let (m, _) = Continuation::from_samples(n_pieces, &samples, &config.mixing)
                .map_err(|source| Error::Identity { sensor, source })?;
            (m, false)
        }
        _ => (uniform(n_pieces), true),
    };
    Ok(Mixing {
        labels,
        continuation,
        uniform_fallback,
    })
}

fn uniform(n: usize) -> Continuation {
    let v = 1.0 / n as f64;
    Continuation::new(n, vec![v; n * n]).unwrap_or_else(|_| Continuation::identity(n))
}

/// Tracks every sensor, in parallel; sensor s's tracker is seeded with `seed + s`, so the
/// result does not depend on the thread count.
pub fn track_all(
    observations: &Observations,
    config: &DmtimConfig,
    seed: u64,
) -> Result<Vec<Vec<SensorFrame>>> {
    config.check()?;
    let models: Vec<Model> = config
        .sensors
        .iter()
        .enumerate()
        .map(|(s, spec)| {
            let mut c = config.mcmcda.clone();
            c.volume = std::f64::consts::PI * spec.range_m * spec.range_m;
            c.check()
                .map_err(|source| Error::Tracker { sensor: s, source })
        })
        .collect::<Result<_>>()?;
    observations
        .scans
        .par_iter()
        .zip(models)
        .enumerate()
        .map(|(s, (scans, model))| {
            track_sensor(
                s,
                model,
                config.online,
                scans,
                config,
                seed.wrapping_add(s as u64),
            )
        })
        .collect()
}
