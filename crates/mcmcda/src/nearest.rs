//! Nearest-neighbour baselines on the same model: the greedy multi-scan nearest-neighbour filter
//! (NNF) that initialises MCMCDA in Oh, Russell & Sastry 2009 §V, and global nearest neighbour
//! (GNN) with optimal assignment and M-of-N confirmation.
//!
//! Both run one Kalman filter per track, scan by scan. A measurement can continue a track
//! only if the pair is allowed in Ω (gap ≤ d̄ scans, inside the neighbourhood radius) and its
//! innovation passes the χ² gate; the cost of a pair is its negative log predictive density.
//! Unused measurements start tentative tracks. Every output track therefore is a feasible
//! MCMCDA track.

use std::ops::RangeInclusive;

use serde::{Deserialize, Serialize};
use tracker_model::{GATE_CHI2_2D, ensure_positive};

use crate::config::Model;
use crate::error::{Result, invalid_parameter};
use crate::partition::{Partition, check_window};
use crate::problem::{MeasId, Problem};
use crate::track_filter::Node;

/// How measurements are given to tracks within one scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Assignment {
    /// Repeatedly take the cheapest remaining (track, measurement) pair.
    Greedy,
    /// Minimum total cost (Hungarian-type solver from the `lsap` crate).
    Optimal,
}

/// Settings of the nearest-neighbour trackers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NearestNeighbourConfig {
    /// Assignment within a scan.
    pub assignment: Assignment,
    /// χ² gate on the innovation's squared Mahalanobis distance (2 degrees of freedom).
    pub gate: f64,
    /// M of M-of-N confirmation: a track is kept if it has ≥ M detections among the first
    /// N scans of its life.
    pub confirm_hits: u32,
    /// N of M-of-N confirmation.
    pub confirm_window: u32,
}

impl NearestNeighbourConfig {
    /// The greedy multi-scan NNF that initialises MCMCDA: every track that reaches two
    /// measurements is kept (2 of d̄ + 1 scans, which is all a track can wait anyway).
    pub fn greedy_init(model: &Model) -> Self {
        Self {
            assignment: Assignment::Greedy,
            gate: GATE_CHI2_2D,
            confirm_hits: 2,
            confirm_window: model.max_gap() + 1,
        }
    }

    /// Checks the gate (finite, > 0) and the confirmation rule (2 ≤ M ≤ N). Every function
    /// that takes the configuration calls this first.
    pub fn check(&self) -> Result<()> {
        ensure_positive(self.gate, "gate")?;
        if self.confirm_hits < 2 || self.confirm_window < self.confirm_hits {
            return Err(invalid_parameter(
                "confirm_hits",
                format!(
                    "confirmation {} of {} needs 2 ≤ M ≤ N (confirm_hits ≤ confirm_window)",
                    self.confirm_hits, self.confirm_window
                ),
            ));
        }
        Ok(())
    }
}

impl Default for NearestNeighbourConfig {
    /// GNN with a 99.9 % gate and 2-of-3 confirmation.
    fn default() -> Self {
        Self {
            assignment: Assignment::Optimal,
            gate: GATE_CHI2_2D,
            confirm_hits: 2,
            confirm_window: 3,
        }
    }
}

struct Live {
    meas: Vec<MeasId>,
    /// The filtered state, from the second measurement on (the two-point start needs it).
    node: Option<Node>,
    first_scan: usize,
}

impl Live {
    fn last(&self) -> MeasId {
        self.meas[self.meas.len() - 1]
    }
}

/// Runs a nearest-neighbour tracker over the scans `window` of `problem` and returns the
/// confirmed tracks (measurement ids, scan-ordered), each feasible in MCMCDA's Ω.
pub fn nearest_neighbour_tracks(
    model: &Model,
    problem: &Problem,
    window: RangeInclusive<usize>,
    config: &NearestNeighbourConfig,
) -> Result<Vec<Vec<MeasId>>> {
    config.check()?;
    let (lo, hi) = check_window(problem, &window)?;
    let d_bar = problem.max_gap();
    let mut live: Vec<Live> = Vec::new();
    let mut done: Vec<Vec<MeasId>> = Vec::new();
    let mut pairs: Vec<(f64, usize, usize, Node)> = Vec::new();
    for t in lo..=hi {
        let scan = problem.scan(t);
        pairs.clear();
        for (k, track) in live.iter().enumerate() {
            let last = track.last();
            let gap = t - problem.scan_of(last);
            for (j, &m) in scan.iter().enumerate() {
                if !problem.within(last, m, gap) {
                    continue;
                }
                let node = match track.node {
                    Some(node) => node,
                    None => model.first_node(problem, &[last, m]),
                };
                let (next, maha) = model.step(&node, problem.position(m), gap);
                if maha <= config.gate {
                    let cost = node.cum_log_likelihood() - next.cum_log_likelihood();
                    pairs.push((cost, k, j, next));
                }
            }
        }
        let chosen = match config.assignment {
            Assignment::Greedy => greedy(&mut pairs, live.len(), scan.len()),
            Assignment::Optimal => optimal(&pairs, live.len(), scan.len())?,
        };
        let mut used = vec![false; scan.len()];
        for &p in &chosen {
            let (_, k, j, next) = pairs[p];
            used[j] = true;
            live[k].meas.push(scan[j]);
            live[k].node = Some(next);
        }
        for (j, &m) in scan.iter().enumerate() {
            if !used[j] {
                live.push(Live {
                    meas: vec![m],
                    node: None,
                    first_scan: t,
                });
            }
        }
        // Retire tracks that can no longer grow (next gap would exceed d̄) or failed M-of-N.
        let mut kept = Vec::with_capacity(live.len());
        for track in live.drain(..) {
            let age = (t - track.first_scan + 1) as u32;
            let failed =
                age >= config.confirm_window && (track.meas.len() as u32) < config.confirm_hits;
            let stale = t + 1 - problem.scan_of(track.last()) > d_bar;
            if failed {
                continue;
            }
            if stale || t == hi {
                if track.meas.len() as u32 >= config.confirm_hits {
                    done.push(track.meas);
                }
            } else {
                kept.push(track);
            }
        }
        live = kept;
    }
    done.sort_unstable();
    Ok(done)
}

/// Cheapest pairs first, each track and measurement used once.
fn greedy(pairs: &mut [(f64, usize, usize, Node)], n_tracks: usize, n_meas: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..pairs.len()).collect();
    order.sort_by(|&a, &b| pairs[a].0.total_cmp(&pairs[b].0));
    let mut track_used = vec![false; n_tracks];
    let mut meas_used = vec![false; n_meas];
    let mut out = Vec::new();
    for p in order {
        let (_, k, j, _) = pairs[p];
        if !track_used[k] && !meas_used[j] {
            track_used[k] = true;
            meas_used[j] = true;
            out.push(p);
        }
    }
    out
}

/// Minimum-cost assignment over the gated pairs (tracker-model's solver).
fn optimal(
    pairs: &[(f64, usize, usize, Node)],
    n_tracks: usize,
    n_meas: usize,
) -> Result<Vec<usize>> {
    if pairs.is_empty() {
        return Ok(Vec::new());
    }
    // Pairs outside the gate cost more than any set of gated pairs together.
    let forbidden = 1.0 + pairs.iter().map(|p| p.0.abs()).sum::<f64>() * 2.0;
    let mut costs = vec![forbidden; n_tracks * n_meas];
    let mut index = vec![usize::MAX; n_tracks * n_meas];
    for (p, &(c, k, j, _)) in pairs.iter().enumerate() {
        costs[k * n_meas + j] = c;
        index[k * n_meas + j] = p;
    }
    Ok(
        tracker_model::assignment::minimise(n_tracks, n_meas, &costs)?
            .into_iter()
            .map(|(k, j)| index[k * n_meas + j])
            .filter(|&p| p != usize::MAX)
            .collect(),
    )
}

/// The greedy NNF partition of the window, ready to start a chain.
pub fn greedy_initial_partition<'a>(
    model: &'a Model,
    problem: &'a Problem,
    window: RangeInclusive<usize>,
) -> Result<Partition<'a>> {
    let tracks = nearest_neighbour_tracks(
        model,
        problem,
        window.clone(),
        &NearestNeighbourConfig::greedy_init(model),
    )?;
    Partition::from_tracks(model, problem, window, &tracks)
}
