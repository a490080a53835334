//! Phase one: every sensor tracks its own measurements with online MCMCDA and, where tracks
//! come close, draws MCMC samples to build the mixing matrix of their identities (Oh, Hwang
//! & Sastry 2008). Nothing here depends on beliefs, so the identity layer (any fusion
//! criterion, or none) replays these records.

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

/// Runs one sensor's tracker over its scans.
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
    let mut origin_of: std::collections::HashMap<MeasId, Option<usize>> =
        std::collections::HashMap::new();
    let mut out = Vec::with_capacity(scans.len());
    let d_int = config.interaction_distance_m;
    for (frame, scan) in scans.iter().enumerate() {
        let frame_id = tracker_model::Frame::try_from(frame).map_err(|_| {
            crate::error::invalid("frames", format!("frame {frame} does not fit a Frame"))
        })?;
        let ids = tracker.push_scan(frame_id, &scan.points).map_err(err)?;
        let est = ids.estimates;
        // The ids of this scan's points: the last ones added, in order.
        let n_total = tracker.problem().n_measurements();
        let first = n_total - scan.points.len();
        for (k, o) in scan.origins.iter().enumerate() {
            origin_of.insert((first + k) as MeasId, *o);
        }
        let map = tracker.map_tracks();
        let track_of_label = |l: u64| map.iter().find(|(m, _)| *m == l).map(|(_, t)| t);
        let origins: Vec<Option<usize>> = est
            .iter()
            .map(|(l, _)| {
                let t = track_of_label(*l)?;
                let m = t.last()?;
                if tracker.problem().scan_of(*m) != frame {
                    return None;
                }
                origin_of.get(m).copied().flatten()
            })
            .collect();
        let read_tracks: Vec<Option<u64>> = scan
            .reads
            .iter()
            .map(|r| {
                let m = (first + r.point) as MeasId;
                est.iter()
                    .map(|(l, _)| *l)
                    .find(|&l| track_of_label(l).is_some_and(|t| t.contains(&m)))
            })
            .collect();
        // Clusters of estimates closer than the interaction distance (single linkage).
        let n = est.len();
        let mut group: Vec<usize> = (0..n).collect();
        fn root(g: &mut [usize], mut i: usize) -> usize {
            while g[i] != i {
                g[i] = g[g[i]];
                i = g[i];
            }
            i
        }
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
        // Open or grow interactions; the pre piece of a track is its last measurement
        // before this scan.
        for c in &clusters {
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
                    && let Some(m) = last_before(&tracker, l, frame)
                {
                    merged.labels.push(l);
                    merged.pre.push(m);
                }
            }
            open.push(merged);
        }
        // Close interactions whose tracks have separated.
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
            let labels: Vec<u64> = alive.iter().map(|&i| o.labels[i]).collect();
            let pre: Vec<MeasId> = alive.iter().map(|&i| o.pre[i]).collect();
            let post: Option<Vec<MeasId>> = labels
                .iter()
                .map(|&l| last_before(&tracker, l, usize::MAX))
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
                        .map_err(err)?;
                    let (m, _) = Continuation::from_samples(n_pieces, &samples, &config.mixing)
                        .map_err(|source| Error::Identity { sensor, source })?;
                    (m, false)
                }
                _ => (uniform(n_pieces), true),
            };
            mixings.push(Mixing {
                labels,
                continuation,
                uniform_fallback,
            });
        }
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
