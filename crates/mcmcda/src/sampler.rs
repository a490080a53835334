//! Multi-scan MCMCDA (Oh, Russell & Sastry 2009 Algorithm 3): a Metropolis-Hastings chain over
//! partitions with the eight moves, the MAP estimate (best sample seen), an optional running MMSE
//! functional, and independent chains in parallel.

use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::config::Move;
use crate::error::{Result, ensure_chains, ensure_samples};
use crate::partition::{Partition, TrackState};
use crate::problem::MeasId;
use crate::proposal::{End, FirstStep, ln_count};
use crate::track_filter::Node;

/// How often each move was proposed and accepted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MoveStats {
    /// Proposals per move, in [`Move::ALL`] order.
    pub proposed: [u64; 8],
    /// Accepted proposals per move (a proposal that leaves ω unchanged counts as accepted).
    pub accepted: [u64; 8],
}

impl MoveStats {
    /// Total proposals.
    pub fn total_proposed(&self) -> u64 {
        self.proposed.iter().sum()
    }

    /// Overall acceptance rate.
    pub fn acceptance_rate(&self) -> f64 {
        self.accepted.iter().sum::<u64>() as f64 / self.total_proposed().max(1) as f64
    }

    fn merge(&mut self, other: &Self) {
        for i in 0..8 {
            self.proposed[i] += other.proposed[i];
            self.accepted[i] += other.accepted[i];
        }
    }
}

/// The outcome of a proposal.
enum Outcome {
    Accepted,
    Rejected,
}

/// What an upper bound of the log Metropolis-Hastings ratio settled
/// ([`Chain::draw_against_bound`]).
enum Bounded {
    /// ln u ≥ the bound: rejected whatever the exact ratio.
    Rejected,
    /// The exact ratio decides, with ln u if it was drawn already.
    Undecided { log_u: Option<f64> },
}

#[cfg(test)]
thread_local! {
    /// Tests switch off the rejection against a bound, to compare with the exact ratio.
    pub(crate) static BOUNDED_REJECTION: std::cell::Cell<bool> = const { std::cell::Cell::new(true) };
    /// How often each move type (in [`Move::ALL`] order) was rejected against its bound
    /// (tests check that every bounded move exercises the case).
    pub(crate) static BOUNDED_REJECTIONS: std::cell::Cell<[u64; 8]> = const { std::cell::Cell::new([0; 8]) };
    /// Whether the current step was rejected against its bound.
    static BOUNDED_THIS_STEP: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Tests: a bound of the log ratio must hold for the exact ratio.
#[cfg(test)]
fn check_bound(bound: f64, exact: f64) {
    assert!(
        exact.is_nan() || exact <= bound + 1e-9,
        "the bound {bound} is below the log ratio {exact}"
    );
}

/// One Markov chain: its current partition, generator, MAP and statistics.
pub struct Chain<'a, R> {
    state: Partition<'a>,
    rng: R,
    log_posterior: f64,
    best: Vec<Vec<MeasId>>,
    best_log_posterior: f64,
    stats: MoveStats,
    candidates: Vec<MeasId>,
    grown: Vec<MeasId>,
    from: Vec<MeasId>,
    /// The nodes a single-track move overwrote (restored if it is rejected).
    saved_nodes: Vec<Node>,
    /// Tests force acceptance to check that every move's reverse restores ω.
    #[cfg(test)]
    pub(crate) force_accept: bool,
    /// Tests read the forward proposal probability of the last proposal.
    #[cfg(test)]
    pub(crate) last_log_q: Option<f64>,
}

impl<'a, R: Rng> Chain<'a, R> {
    /// A chain starting from `initial` (e.g. the greedy nearest-neighbour partition, or
    /// [`Partition::empty`]).
    pub fn new(initial: Partition<'a>, rng: R) -> Self {
        let log_posterior = initial.log_posterior();
        Self {
            best: initial.canonical(),
            best_log_posterior: log_posterior,
            state: initial,
            rng,
            log_posterior,
            stats: MoveStats::default(),
            candidates: Vec::new(),
            grown: Vec::new(),
            from: Vec::new(),
            saved_nodes: Vec::new(),
            #[cfg(test)]
            force_accept: false,
            #[cfg(test)]
            last_log_q: None,
        }
    }

    /// The current partition.
    pub fn state(&self) -> &Partition<'a> {
        &self.state
    }

    /// The best partition seen (canonical form) and its log posterior.
    pub fn map(&self) -> (&[Vec<MeasId>], f64) {
        (&self.best, self.best_log_posterior)
    }

    /// Proposal statistics so far.
    pub fn stats(&self) -> &MoveStats {
        &self.stats
    }

    /// Runs `n` steps of Algorithm 3.
    pub fn run(&mut self, n: u64) {
        for _ in 0..n {
            self.step();
        }
    }

    /// Runs `n` steps and returns the running mean of `f` over the n samples (the MMSE
    /// estimate of eq. 11 for any functional of ω with a fixed length).
    pub fn run_mmse(&mut self, n: u64, mut f: impl FnMut(&Partition<'a>) -> Vec<f64>) -> Vec<f64> {
        let mut mean: Vec<f64> = Vec::new();
        for i in 1..=n {
            self.step();
            let value = f(&self.state);
            if mean.is_empty() {
                mean = vec![0.0; value.len()];
            }
            let w = 1.0 / i as f64;
            for (m, v) in mean.iter_mut().zip(value) {
                *m += w * (v - *m);
            }
        }
        mean
    }

    /// One Metropolis-Hastings step; returns the move proposed and whether it was accepted.
    pub fn step(&mut self) -> (Move, bool) {
        let k = self.state.n_tracks();
        let m = self.draw_move(k);
        (m, self.step_with(m))
    }

    /// One step with the move type fixed (if `m` is not allowed with K tracks, nothing
    /// happens); returns whether the proposal was accepted.
    pub(crate) fn step_with(&mut self, m: Move) -> bool {
        if !m.allowed_with(self.state.n_tracks()) {
            return false;
        }
        #[cfg(test)]
        BOUNDED_THIS_STEP.with(|b| b.set(false));
        let outcome = match m {
            Move::Birth => self.birth(),
            Move::Death => self.death(),
            Move::Split => self.split(),
            Move::Merge => self.merge(),
            Move::Extension | Move::Reduction | Move::Update => self.single_track(m),
            Move::Switch => self.switch(),
        };
        self.stats.proposed[m.index()] += 1;
        #[cfg(test)]
        if BOUNDED_THIS_STEP.with(std::cell::Cell::get) {
            BOUNDED_REJECTIONS.with(|n| {
                let mut counts = n.get();
                counts[m.index()] += 1;
                n.set(counts);
            });
        }
        let accepted = matches!(outcome, Outcome::Accepted);
        if accepted {
            self.stats.accepted[m.index()] += 1;
            if self.log_posterior > self.best_log_posterior {
                self.best_log_posterior = self.log_posterior;
                self.best = self.state.canonical();
            }
        }
        accepted
    }

    fn draw_move(&mut self, k: usize) -> Move {
        let u: f64 = self.rng.random();
        let mut acc = 0.0;
        for m in Move::ALL {
            acc += self.state.model.move_probability(m, k);
            if u < acc {
                return m;
            }
        }
        Move::Birth
    }

    /// Metropolis-Hastings acceptance of a change of the log posterior by `delta`.
    fn accept(&mut self, delta: f64, log_q_forward: f64, log_q_reverse: f64) -> bool {
        self.accept_drawn(delta, log_q_forward, log_q_reverse, None)
    }

    /// [`Self::accept`] with ln u already drawn (by [`Self::draw_against_bound`]) or not;
    /// u is drawn only when the log ratio is below 0.
    fn accept_drawn(
        &mut self,
        delta: f64,
        log_q_forward: f64,
        log_q_reverse: f64,
        log_u: Option<f64>,
    ) -> bool {
        let log_ratio = delta + log_q_reverse - log_q_forward;
        #[cfg(test)]
        {
            self.last_log_q = Some(log_q_forward);
        }
        #[cfg(test)]
        if self.force_accept {
            self.log_posterior += delta;
            return true;
        }
        if log_ratio.is_nan() {
            return false;
        }
        if log_ratio >= 0.0 || log_u.unwrap_or_else(|| self.rng.random::<f64>().ln()) < log_ratio {
            self.log_posterior += delta;
            true
        } else {
            false
        }
    }

    /// Settles what an upper `bound` of the log Metropolis-Hastings ratio can before the
    /// ratio itself is evaluated. Below 0 the ratio is negative too, so [`Self::accept`]
    /// would draw u: it is drawn now, and ln u ≥ bound rejects the move at once (the same
    /// decision, from the same draw, as the exact ratio would give). Otherwise nothing is
    /// drawn.
    fn draw_against_bound(&mut self, bound: f64) -> Bounded {
        #[cfg(test)]
        if self.force_accept || !BOUNDED_REJECTION.with(std::cell::Cell::get) {
            return Bounded::Undecided { log_u: None };
        }
        // A margin far above the rounding of sums of a few hundred terms.
        let bound = bound + 1e-6;
        if bound < 0.0 {
            let log_u = self.rng.random::<f64>().ln();
            if log_u >= bound {
                #[cfg(test)]
                {
                    BOUNDED_THIS_STEP.with(|b| b.set(true));
                    self.last_log_q = None;
                }
                return Bounded::Rejected;
            }
            return Bounded::Undecided { log_u: Some(log_u) };
        }
        Bounded::Undecided { log_u: None }
    }

    fn birth(&mut self) -> Outcome {
        let s = &self.state;
        let n_scans = s.n_scans();
        if n_scans < 2 {
            return Outcome::Rejected;
        }
        let t1 = s.lo + self.rng.random_range(0..n_scans - 1);
        let d1 = s.sample_gap(&mut self.rng);
        let n_births = s.birth_set_count(t1, d1);
        if n_births == 0 {
            return Outcome::Rejected;
        }
        let pick = self.rng.random_range(0..n_births);
        let Some(&y1) = s
            .problem
            .scan(t1)
            .iter()
            .filter(|&&m| s.is_free(m) && !s.successors(m, d1).is_empty())
            .nth(pick)
        else {
            return Outcome::Rejected;
        };
        self.candidates.clear();
        self.candidates.extend(
            s.successors(y1, d1)
                .iter()
                .copied()
                .filter(|&n| s.is_free(n)),
        );
        if self.candidates.is_empty() {
            return Outcome::Rejected;
        }
        let n_second = self.candidates.len();
        let y2 = self.candidates[self.rng.random_range(0..n_second)];
        // Room for a typical track's growth without reallocating.
        let mut track = Vec::with_capacity(16);
        track.extend([y1, y2]);
        let log_steps = s
            .grow(
                y2,
                End::Tail,
                FirstStep::MayStop,
                &mut track,
                &mut self.candidates,
                &mut self.rng,
            )
            .unwrap_or(f64::NEG_INFINITY);
        // q of this birth from the draws just made, instead of recounting every candidate
        // set: only the stop at the last measurement is evaluated.
        let log_grow = log_steps + s.log_stop_at(track[track.len() - 1], End::Tail);
        let log_q_forward = s.log_birth_probability_given(d1, n_births, n_second, log_grow);
        #[cfg(test)]
        assert_eq!(
            log_q_forward.to_bits(),
            s.log_birth_probability(&track).to_bits()
        );
        let k_new = s.n_tracks() + 1;
        let log_q_reverse = s.model.log_move_probability(Move::Death, k_new) - ln_count(k_new);
        self.state.insert(track, None);
        let delta = self.state.tracks[k_new - 1].weight;
        if self.accept(delta, log_q_forward, log_q_reverse) {
            Outcome::Accepted
        } else {
            self.state.remove(k_new - 1);
            Outcome::Rejected
        }
    }

    fn death(&mut self) -> Outcome {
        let k = self.state.n_tracks();
        let victim = self.rng.random_range(0..k);
        let log_q_forward = self.state.model.log_move_probability(Move::Death, k) - ln_count(k);
        let old = self.state.remove(victim);
        // The reverse birth's q is at most its value with both candidate counts at 1 and a
        // growth of probability 1: evaluated only if that can accept.
        let s = &self.state;
        let d1 = s.problem.scan_of(old.meas[1]) - s.problem.scan_of(old.meas[0]);
        let log_q_reverse_at_most = s.log_birth_probability_given(d1, 1, 1, 0.0);
        let bound = -old.weight + log_q_reverse_at_most - log_q_forward;
        if let Bounded::Undecided { log_u } = self.draw_against_bound(bound) {
            let log_q_reverse = self.state.log_birth_probability(&old.meas);
            #[cfg(test)]
            check_bound(bound, -old.weight + log_q_reverse - log_q_forward);
            if self.accept_drawn(-old.weight, log_q_forward, log_q_reverse, log_u) {
                return Outcome::Accepted;
            }
        }
        self.state.reinsert(old);
        Outcome::Rejected
    }

    fn split(&mut self) -> Outcome {
        let s = &self.state;
        let k = s.n_tracks();
        let n_split = s.split_count();
        if n_split == 0 {
            return Outcome::Rejected;
        }
        let mut pick = self.rng.random_range(0..n_split);
        let Some((victim, cut)) = s.tracks.iter().enumerate().find_map(|(i, t)| {
            let n = t.meas.len().saturating_sub(3);
            if pick < n {
                Some((i, pick + 2))
            } else {
                pick -= n;
                None
            }
        }) else {
            return Outcome::Rejected;
        };
        let log_q_forward = s.model.log_move_probability(Move::Split, k) - ln_count(n_split);
        let mut old = self.state.remove(victim);
        let head = old.meas[..cut].to_vec();
        let tail = old.meas[cut..].to_vec();
        // The head keeps the old track's first `cut` nodes: when they are most of it, it
        // takes over the old buffer and only the nodes after the cut are saved (a long
        // track's prefix is not copied); otherwise the short prefix is copied.
        let keep = self.state.model.reusable_prefix(cut.min(old.nodes.len()));
        let handed_over = keep >= old.nodes.len() - keep;
        if handed_over {
            self.saved_nodes.clear();
            self.saved_nodes.extend_from_slice(&old.nodes[keep..]);
            let nodes = std::mem::take(&mut old.nodes);
            self.state.insert_into(head, nodes, keep);
        } else {
            self.state.insert(head, Some((&old.nodes, cut)));
        }
        self.state.insert(tail, None);
        let s = &self.state;
        let head_index = k - 1;
        // The reverse merge's q is at most ξ(merge) / (K + 1) (the head has ≥ 1 partner, the
        // tail): its partner count is taken only if that can accept.
        let log_q_reverse_at_most =
            s.model.log_move_probability(Move::Merge, k + 1) - ln_count(k + 1);
        let delta = s.tracks[k - 1].weight + s.tracks[k].weight - old.weight;
        let bound = delta + log_q_reverse_at_most - log_q_forward;
        if let Bounded::Undecided { log_u } = self.draw_against_bound(bound) {
            let log_q_reverse =
                log_q_reverse_at_most - ln_count(self.state.merge_partner_count(head_index));
            #[cfg(test)]
            check_bound(bound, delta + log_q_reverse - log_q_forward);
            if self.accept_drawn(delta, log_q_forward, log_q_reverse, log_u) {
                return Outcome::Accepted;
            }
        }
        // The new tracks go (last first), the old one comes back.
        self.state.remove(k);
        if !handed_over {
            self.state.remove(k - 1);
            self.state.reinsert(old);
            return Outcome::Rejected;
        }
        let mut nodes = self.state.remove(k - 1).nodes;
        nodes.truncate(keep);
        nodes.extend_from_slice(&self.saved_nodes);
        old.nodes = nodes;
        self.state.reinsert(old);
        Outcome::Rejected
    }

    fn merge(&mut self) -> Outcome {
        let s = &self.state;
        let k = s.n_tracks();
        let first = self.rng.random_range(0..k);
        let n_partners = s.merge_partner_count(first);
        if n_partners == 0 {
            return Outcome::Rejected;
        }
        let pick = self.rng.random_range(0..n_partners);
        let mut second = usize::MAX;
        let mut i = 0;
        s.for_each_merge_partner(first, |k2| {
            if i == pick {
                second = k2;
            }
            i += 1;
        });
        let log_q_forward =
            s.model.log_move_probability(Move::Merge, k) - ln_count(k) - ln_count(n_partners);
        let (mut a, b) = self.remove_pair(first, second);
        let mut joined = Vec::with_capacity(a.meas.len() + b.meas.len());
        joined.extend_from_slice(&a.meas);
        joined.extend_from_slice(&b.meas);
        // The joined track keeps all of a's nodes: it takes over a's buffer (no copy of a
        // long track), and a rejection cuts it back to them.
        let keep = self
            .state
            .model
            .reusable_prefix(a.meas.len().min(a.nodes.len()));
        let nodes = std::mem::take(&mut a.nodes);
        self.state.insert_into(joined, nodes, keep);
        let s = &self.state;
        let log_q_reverse =
            s.model.log_move_probability(Move::Split, k - 1) - ln_count(s.split_count());
        let delta = s.tracks[k - 2].weight - a.weight - b.weight;
        if self.accept(delta, log_q_forward, log_q_reverse) {
            return Outcome::Accepted;
        }
        // As `restore`: the joined track goes, a and b come back in that order.
        let mut nodes = self.state.remove(k - 2).nodes;
        nodes.truncate(keep);
        a.nodes = nodes;
        self.state.reinsert(a);
        self.state.reinsert(b);
        Outcome::Rejected
    }

    /// Extension, reduction or update of one track at its tail or (mirrored in time) its
    /// head; K is unchanged and q sums over every way of producing the new track.
    ///
    /// The new track is filtered first, and the two q, which dominate the move's cost, are
    /// evaluated only if the move can still be accepted: q(ω → ω') is at least the
    /// probability of the way the move just took, and q(ω' → ω) at most
    /// (ξ(extension) + ξ(reduction) + ξ(update)) / K, which bound the Metropolis-Hastings
    /// log ratio from above ([`Self::draw_against_bound`]).
    fn single_track(&mut self, m: Move) -> Outcome {
        let k = self.state.n_tracks();
        let victim = self.rng.random_range(0..k);
        let head = self.state.model.config.head_probability;
        let end = if self.rng.random_bool(head) {
            End::Head
        } else {
            End::Tail
        };
        let old = self.state.remove(victim);
        // Work in growth order: from the kept end outwards (a reused buffer).
        let mut from = std::mem::take(&mut self.from);
        from.clear();
        from.extend_from_slice(&old.meas);
        if end == End::Head {
            from.reverse();
        }
        self.grown.clear();
        // ln of the probability of the way taken, the stop apart: the end, the move, the
        // kept part, and the growth steps.
        let log_end = match end {
            End::Head => head.ln(),
            End::Tail => (-head).ln_1p(),
        };
        let log_way = log_end + self.state.model.log_move_probability(m, k);
        let proposed = self.grow_single_track(m, end, &from, log_way);
        let unchanged = self.grown == from;
        self.from = from;
        let Some(log_q_forward_at_least) = proposed else {
            self.state.reinsert(old);
            return Outcome::Rejected;
        };
        if unchanged {
            self.state.reinsert(old);
            return Outcome::Accepted;
        }
        let mut new = std::mem::take(&mut self.grown);
        if end == End::Head {
            new.reverse();
        }
        self.decide_single_track(k, old, new, log_q_forward_at_least)
    }

    /// The new track of [`Self::single_track`] in growth order, into `self.grown`, from the
    /// old one in growth order (`from`); returns ln of the probability of the way taken (a
    /// lower bound on q(ω → ω')), or `None` when move `m` cannot be made on this track.
    fn grow_single_track(
        &mut self,
        m: Move,
        end: End,
        from: &[MeasId],
        log_way: f64,
    ) -> Option<f64> {
        let len = from.len();
        let gamma = self.state.model.config.stop_probability;
        match m {
            Move::Extension => {
                self.grown.extend_from_slice(from);
                self.state
                    .grow(
                        from[len - 1],
                        end,
                        FirstStep::MayStop,
                        &mut self.grown,
                        &mut self.candidates,
                        &mut self.rng,
                    )
                    .map(|steps| log_way + steps + gamma.ln())
            }
            Move::Reduction if len >= 3 => {
                let r = self.rng.random_range(2..len);
                self.grown.extend_from_slice(&from[..r]);
                Some(log_way - ln_count(len - 2))
            }
            Move::Update => {
                let r = self.rng.random_range(1..=len);
                self.grown.extend_from_slice(&from[..r]);
                self.state
                    .grow(
                        from[r - 1],
                        end,
                        FirstStep::of_update(r),
                        &mut self.grown,
                        &mut self.candidates,
                        &mut self.rng,
                    )
                    .map(|steps| log_way - ln_count(len) + steps + gamma.ln())
            }
            _ => None,
        }
    }

    /// Filters the proposed track `new` (K = `k` with it) that would replace `old`, and
    /// accepts or rejects it: the Metropolis-Hastings ratio is first bounded with
    /// `log_q_forward_at_least`, and both q are computed only when the bound cannot decide.
    fn decide_single_track(
        &mut self,
        k: usize,
        mut old: TrackState,
        new: Vec<MeasId>,
        log_q_forward_at_least: f64,
    ) -> Outcome {
        let keep = old
            .meas
            .iter()
            .zip(&new)
            .take_while(|(a, b)| a == b)
            .count();
        let keep = self.state.model.reusable_prefix(keep.min(old.nodes.len()));
        // Most of the track is kept: the new track takes over the old one's filtered nodes
        // (no copy of the kept prefix, which is most of a long track), and the nodes it
        // overwrites are saved, so that a rejection puts the old track back exactly. Else
        // (a head move changes most of it) the short kept prefix is copied.
        let handed_over = keep >= old.nodes.len() - keep;
        let candidate = if handed_over {
            self.saved_nodes.clear();
            self.saved_nodes.extend_from_slice(&old.nodes[keep..]);
            let nodes = std::mem::take(&mut old.nodes);
            self.state.filtered(new, nodes, keep)
        } else {
            self.state.filtered_after(new, &old.nodes[..keep])
        };
        let delta = candidate.weight - old.weight;
        let model = self.state.model;
        let log_q_reverse_at_most = (model.move_probability(Move::Extension, k)
            + model.move_probability(Move::Reduction, k)
            + model.move_probability(Move::Update, k))
        .ln();
        // The −ln K of both q cancels in the bound.
        let bound = delta + log_q_reverse_at_most - log_q_forward_at_least;
        let rejected = match self.draw_against_bound(bound) {
            Bounded::Rejected => candidate,
            Bounded::Undecided { log_u } => {
                // Both q in the partition without the track.
                let log_q_forward =
                    self.state
                        .log_single_track_probability(k, &old.meas, &candidate.meas);
                let log_q_reverse =
                    self.state
                        .log_single_track_probability(k, &candidate.meas, &old.meas);
                #[cfg(test)]
                check_bound(bound, delta + log_q_reverse - log_q_forward);
                self.state.reinsert(candidate);
                if self.accept_drawn(delta, log_q_forward, log_q_reverse, log_u) {
                    return Outcome::Accepted;
                }
                self.state.remove(k - 1)
            }
        };
        if handed_over {
            let mut nodes = rejected.nodes;
            nodes.truncate(keep);
            nodes.extend_from_slice(&self.saved_nodes);
            old.nodes = nodes;
        }
        self.state.reinsert(old);
        // The rejected track's buffer holds the next proposal.
        self.grown = rejected.meas;
        Outcome::Rejected
    }

    fn switch(&mut self) -> Outcome {
        let s = &self.state;
        let k = s.n_tracks();
        let a = self.rng.random_range(0..k);
        let p = self.rng.random_range(0..s.tracks[a].meas.len() - 1);
        let n_partners = s.switch_partner_count(a, p);
        if n_partners == 0 {
            return Outcome::Rejected;
        }
        let pick = self.rng.random_range(0..n_partners);
        let (mut b, mut q) = (usize::MAX, 0);
        let mut i = 0;
        s.for_each_switch_partner(a, p, |k2, pos| {
            if i == pick {
                (b, q) = (k2, pos);
            }
            i += 1;
        });
        let log_q_forward =
            s.log_switch_probability_given(a, n_partners, b, s.switch_partner_count(b, q));
        let (ta, tb) = self.remove_pair(a, b);
        let mut new_a = Vec::with_capacity(p + tb.meas.len() - q);
        new_a.extend_from_slice(&ta.meas[..=p]);
        new_a.extend_from_slice(&tb.meas[q + 1..]);
        let mut new_b = Vec::with_capacity(q + ta.meas.len() - p);
        new_b.extend_from_slice(&tb.meas[..=q]);
        new_b.extend_from_slice(&ta.meas[p + 1..]);
        self.state.insert(new_a, Some((&ta.nodes, p + 1)));
        self.state.insert(new_b, Some((&tb.nodes, q + 1)));
        let s = &self.state;
        let delta = s.tracks[k - 2].weight + s.tracks[k - 1].weight - ta.weight - tb.weight;
        // The reverse switch's q is at most its value with one partner at each end: the
        // partners are counted only if that can accept.
        let log_q_reverse_at_most = s.log_switch_probability_given(k - 2, 1, k - 1, 1);
        let bound = delta + log_q_reverse_at_most - log_q_forward;
        if let Bounded::Undecided { log_u } = self.draw_against_bound(bound) {
            let log_q_reverse = self.state.log_switch_probability(k - 2, p, k - 1, q);
            #[cfg(test)]
            check_bound(bound, delta + log_q_reverse - log_q_forward);
            if self.accept_drawn(delta, log_q_forward, log_q_reverse, log_u) {
                return Outcome::Accepted;
            }
        }
        self.restore(2, [ta, tb]);
        Outcome::Rejected
    }

    /// Removes tracks `i` and `j` (i ≠ j), returned in that order.
    fn remove_pair(&mut self, i: usize, j: usize) -> (TrackState, TrackState) {
        // Remove the higher index first so the lower one does not move.
        if i > j {
            let a = self.state.remove(i);
            let b = self.state.remove(j);
            (a, b)
        } else {
            let b = self.state.remove(j);
            let a = self.state.remove(i);
            (a, b)
        }
    }

    /// Undoes a rejected move: removes the `n_new` tracks just inserted (the last ones) and
    /// puts `old` back.
    fn restore<const N: usize>(&mut self, n_new: usize, old: [TrackState; N]) {
        for _ in 0..n_new {
            let last = self.state.n_tracks() - 1;
            self.state.remove(last);
        }
        for t in old {
            self.state.reinsert(t);
        }
    }
}

/// The result of a multi-scan MCMCDA run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct McmcdaRun {
    /// The MAP partition (canonical form: tracks of measurement ids).
    pub tracks: Vec<Vec<MeasId>>,
    /// Its log posterior (up to a constant of Y).
    pub log_posterior: f64,
    /// Which chain found it.
    pub chain: usize,
    /// Proposal statistics summed over chains.
    pub stats: MoveStats,
}

/// Runs `n_chains` independent chains of `n_samples` steps each from `initial`, in parallel;
/// chain i draws from ChaCha8(seed) stream i, so the result does not depend on the thread
/// count. The MAP is the best over all chains (ties go to the lowest chain index). The chain
/// count must be in 1..=[`crate::MAX_CHAINS`] and the steps at most [`crate::MAX_SAMPLES`].
pub fn run_chains(
    initial: &Partition<'_>,
    n_chains: usize,
    n_samples: u64,
    seed: u64,
) -> Result<McmcdaRun> {
    ensure_chains(n_chains)?;
    ensure_samples(n_samples, "samples")?;
    let results: Vec<(Vec<Vec<MeasId>>, f64, MoveStats)> = (0..n_chains)
        .into_par_iter()
        .map(|i| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(i as u64);
            let mut chain = Chain::new(initial.clone(), rng);
            chain.run(n_samples);
            let (best, lp) = chain.map();
            (best.to_vec(), lp, *chain.stats())
        })
        .collect();
    let mut stats = MoveStats::default();
    let mut best = 0;
    for (i, r) in results.iter().enumerate() {
        stats.merge(&r.2);
        if r.1 > results[best].1 {
            best = i;
        }
    }
    let (tracks, log_posterior, _) = results.into_iter().nth(best).unwrap_or_default();
    Ok(McmcdaRun {
        tracks,
        log_posterior,
        chain: best,
        stats,
    })
}
