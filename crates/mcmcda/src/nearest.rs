//! Nearest-neighbour baselines on the same model: the greedy multi-scan nearest-neighbour filter
//! (NNF) that initialises MCMCDA in Oh, Russell & Sastry 2009 §V, and global nearest neighbour
//! (GNN) with optimal assignment, a non-assignment cost from the clutter density, M-of-N
//! confirmation and deletion after a gap.
//!
//! Both run one Kalman filter per track, scan by scan. A measurement can continue a track
//! only if the pair is allowed in Ω (gap ≤ d̄ scans, inside the neighbourhood radius) and its
//! innovation passes the χ² gate. Unused measurements start tentative tracks. Every output
//! track therefore is a feasible MCMCDA track.
//!
//! GNN's costs ([`AssignmentCost::LogLikelihoodRatio`]) are the track-score increments of
//! Blackman 2004 (IEEE AES Magazine 19(1), §"track score"), the log-likelihood-ratio form of
//! GNN that JPDA's hypothesis weights also use (Bar-Shalom, Willett & Tian 2011, §6): within
//! one scan, a joint assignment of measurements z_j to tracks k has likelihood
//!
//!   Π_(k,j) assigned p_d N(z_j; ẑ_k, S_k) · Π_k unassigned (1 − p_d) · Π_j unassigned λ,
//!
//! where λ = (λ_f + λ_b) is the density of measurements that continue no track (clutter or
//! a newborn; per unit volume per scan). Dividing by the "nothing assigned" hypothesis, the
//! best joint assignment minimises Σ c_kj over the assigned pairs with
//!
//!   c_kj = −ln [ p_d N(z_j; ẑ_k, S_k) / ((1 − p_d) λ) ],
//!
//! and leaving a track unassigned costs 0. With detection scores s
//! ([`crate::Problem::push_scan_scored`]) the measurement's likelihood under "target" and
//! under "clutter or newborn" carries the score densities f₁(s) and f₀(s) (Lerro &
//! Bar-Shalom 1993, amplitude information), so c_kj loses ln f₁(s_j)/f₀(s_j). A pair with c_kj ≥ 0 is never worth taking, so
//! this is also a gate: d² < 2 ln[p_d / ((1 − p_d) λ 2π √|S|)]. The old forced assignment
//! ([`AssignmentCost::Forced`], as many gated pairs as possible, cost −ln N) is kept for the
//! NNF that starts the chain, as in the paper.

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

/// What a (track, measurement) pair costs and what leaving a track without a measurement
/// costs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AssignmentCost {
    /// Pairs cost −ln N(z; ẑ, S) and as many gated pairs as possible are assigned (no
    /// non-assignment option): the greedy NNF of Oh, Russell & Sastry 2009 §V.
    Forced,
    /// Pairs cost −ln[p_d N(z; ẑ, S) / ((1 − p_d) λ)] with λ the density of clutter plus
    /// births; a track may stay unassigned at cost 0 (Blackman 2004's track-score
    /// increments; see the module documentation).
    LogLikelihoodRatio,
}

/// Settings of the nearest-neighbour trackers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NearestNeighbourConfig {
    /// Assignment within a scan.
    pub assignment: Assignment,
    /// Costs, and whether a track may go without a measurement it could take.
    pub cost: AssignmentCost,
    /// χ² gate on the innovation's squared Mahalanobis distance (2 degrees of freedom).
    pub gate: f64,
    /// M of M-of-N confirmation: a track is kept if it has ≥ M detections among the first
    /// N scans of its life.
    pub confirm_hits: u32,
    /// N of M-of-N confirmation.
    pub confirm_window: u32,
    /// Deletion: the largest gap, in scans, between consecutive measurements of a track
    /// (1 = no missed scan); a track whose next measurement would come later ends. At most
    /// d̄ (larger values act as d̄); unset = d̄.
    pub max_gap: Option<u32>,
}

impl NearestNeighbourConfig {
    /// The greedy multi-scan NNF that initialises MCMCDA: every track that reaches two
    /// measurements is kept (2 of d̄ + 1 scans, which is all a track can wait anyway).
    pub fn greedy_init(model: &Model) -> Self {
        Self {
            assignment: Assignment::Greedy,
            cost: AssignmentCost::Forced,
            gate: GATE_CHI2_2D,
            confirm_hits: 2,
            confirm_window: model.max_gap() + 1,
            max_gap: None,
        }
    }

    /// Checks the gate (finite, > 0), the confirmation rule (2 ≤ M ≤ N) and the deletion
    /// gap (≥ 1). Every function that takes the configuration calls this first.
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
        if self.max_gap == Some(0) {
            return Err(invalid_parameter(
                "max_gap",
                "0; consecutive measurements of a track are at least 1 scan apart".into(),
            ));
        }
        Ok(())
    }
}

impl Default for NearestNeighbourConfig {
    /// GNN with the log-likelihood-ratio costs, a 99.9 % gate, 2-of-3 confirmation and
    /// deletion after d̄ missed scans.
    fn default() -> Self {
        Self {
            assignment: Assignment::Optimal,
            cost: AssignmentCost::LogLikelihoodRatio,
            gate: GATE_CHI2_2D,
            confirm_hits: 2,
            confirm_window: 3,
            max_gap: None,
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
/// confirmed tracks (measurement ids, scan-ordered), each feasible in MCMCDA's Ω. Only the
/// non-empty scans are visited: time does not grow with gaps in the frame numbers.
pub fn nearest_neighbour_tracks(
    model: &Model,
    problem: &Problem,
    window: RangeInclusive<usize>,
    config: &NearestNeighbourConfig,
) -> Result<Vec<Vec<MeasId>>> {
    config.check()?;
    let (lo, hi) = check_window(problem, &window)?;
    let max_gap = config
        .max_gap
        .map_or(problem.max_gap(), |g| (g as usize).min(problem.max_gap()));
    let log_ratio = log_ratio(model, config);
    let mut live: Vec<Live> = Vec::new();
    let mut done: Vec<Vec<MeasId>> = Vec::new();
    let mut pairs: Vec<Pair> = Vec::new();
    for (t, scan) in problem.nonempty_scans(lo..=hi) {
        live = retire(live, t, problem, max_gap, config, &mut done);
        pairs.clear();
        let gating = Gating {
            model,
            problem,
            log_ratio,
            config,
        };
        gating.pairs(&live, t, scan, &mut pairs);
        let chosen = match (config.assignment, config.cost) {
            (Assignment::Greedy, _) => greedy(&mut pairs, live.len(), scan.len()),
            (Assignment::Optimal, AssignmentCost::Forced) => {
                optimal(&pairs, live.len(), scan.len(), false)?
            }
            (Assignment::Optimal, AssignmentCost::LogLikelihoodRatio) => {
                optimal(&pairs, live.len(), scan.len(), true)?
            }
        };
        extend(&mut live, &pairs, &chosen, t, scan);
    }
    // The window's end: every confirmed track still alive is finished.
    done.extend(
        live.into_iter()
            .filter(|t| confirmed(t, config))
            .map(|t| t.meas),
    );
    done.sort_unstable();
    Ok(done)
}

/// A gated (track, measurement) pair: (cost, track index, measurement index in the scan,
/// the track's filtered state after the measurement).
type Pair = (f64, usize, usize, Node);

/// ln[p_d / ((1 − p_d) λ)], λ = (λ_f + λ_b) / V: the constant part of −c_kj (Blackman
/// 2004's track-score increment, module docs); 0 for the forced assignment.
fn log_ratio(model: &Model, config: &NearestNeighbourConfig) -> f64 {
    let cfg = model.config();
    match config.cost {
        AssignmentCost::Forced => 0.0,
        AssignmentCost::LogLikelihoodRatio => {
            let density = (cfg.clutter_per_scan + cfg.births_per_scan) / cfg.volume;
            cfg.p_detect.ln() - (-cfg.p_detect).ln_1p() - density.ln()
        }
    }
}

/// Whether a track has its M (`confirm_hits`) measurements.
fn confirmed(track: &Live, config: &NearestNeighbourConfig) -> bool {
    track.meas.len() as u32 >= config.confirm_hits
}

/// Before scan `t`: ends the tracks that can no longer grow (the gap would exceed the
/// deletion gap; the confirmed ones go to `done`) and drops those that failed M-of-N (their
/// first N scans are over). Returns the tracks kept, in order.
fn retire(
    live: Vec<Live>,
    t: usize,
    problem: &Problem,
    max_gap: usize,
    config: &NearestNeighbourConfig,
    done: &mut Vec<Vec<MeasId>>,
) -> Vec<Live> {
    let mut kept = Vec::with_capacity(live.len());
    for track in live {
        let failed = (t - track.first_scan) as u64 >= u64::from(config.confirm_window)
            && !confirmed(&track, config);
        if failed {
            continue;
        }
        if t - problem.scan_of(track.last()) > max_gap {
            if confirmed(&track, config) {
                done.push(track.meas);
            }
        } else {
            kept.push(track);
        }
    }
    kept
}

/// What gating a scan against the live tracks needs.
struct Gating<'a> {
    model: &'a Model,
    problem: &'a Problem,
    log_ratio: f64,
    config: &'a NearestNeighbourConfig,
}

impl Gating<'_> {
    /// The gated pairs of scan `t` (into `pairs`, by track then measurement): allowed in Ω,
    /// inside the χ² gate, and (log-likelihood-ratio costs) of negative cost.
    fn pairs(&self, live: &[Live], t: usize, scan: &[MeasId], pairs: &mut Vec<Pair>) {
        let (model, problem, config) = (self.model, self.problem, self.config);
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
                    // −ln N(z; ẑ, S), then the log-likelihood ratio's constant and the
                    // score's ratio ln f₁(s)/f₀(s) (Lerro & Bar-Shalom 1993; 0 without
                    // scores). The forced NNF keeps its pure kinematic cost.
                    let score = match config.cost {
                        AssignmentCost::Forced => 0.0,
                        AssignmentCost::LogLikelihoodRatio => problem.log_score_ratio(m),
                    };
                    let cost = node.cum_log_likelihood()
                        - next.cum_log_likelihood()
                        - self.log_ratio
                        - score;
                    if config.cost == AssignmentCost::Forced || cost < 0.0 {
                        pairs.push((cost, k, j, next));
                    }
                }
            }
        }
    }
}

/// Applies the chosen pairs (each track takes its measurement and filtered state) and starts
/// a tentative track at scan `t` on every measurement left unused.
fn extend(live: &mut Vec<Live>, pairs: &[Pair], chosen: &[usize], t: usize, scan: &[MeasId]) {
    let mut used = vec![false; scan.len()];
    for &p in chosen {
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

/// Minimum-cost assignment over the gated pairs (tracker-model's solver). With `may_miss`,
/// every track also has its own "no measurement" column of cost 0, so a pair is taken only
/// if it lowers the total (the pairs' costs are then relative to leaving both unassigned);
/// without it, as many pairs as possible are assigned.
fn optimal(
    pairs: &[(f64, usize, usize, Node)],
    n_tracks: usize,
    n_meas: usize,
    may_miss: bool,
) -> Result<Vec<usize>> {
    if pairs.is_empty() {
        return Ok(Vec::new());
    }
    // Pairs outside the gate cost more than any set of gated pairs together.
    let forbidden = 1.0 + pairs.iter().map(|p| p.0.abs()).sum::<f64>() * 2.0;
    let n_cols = if may_miss { n_meas + n_tracks } else { n_meas };
    let mut costs = vec![forbidden; n_tracks * n_cols];
    let mut index = vec![usize::MAX; n_tracks * n_cols];
    for (p, &(c, k, j, _)) in pairs.iter().enumerate() {
        costs[k * n_cols + j] = c;
        index[k * n_cols + j] = p;
    }
    if may_miss {
        for k in 0..n_tracks {
            costs[k * n_cols + n_meas + k] = 0.0;
        }
    }
    Ok(
        tracker_model::assignment::minimise(n_tracks, n_cols, &costs)?
            .into_iter()
            .map(|(k, j)| index[k * n_cols + j])
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
