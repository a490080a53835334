//! The proposal distribution of multi-scan MCMCDA (Oh, Russell & Sastry 2009 §IV-B): how tracks
//! grow, and the exact probability q(ω → ω') of every move, evaluated from the partition alone.
//!
//! Probabilities are evaluated by functions separate from the sampling code, so the two can
//! be checked against each other (the tests compare proposal frequencies with these q, and
//! the chain with the enumerated posterior, which only holds if they agree). Where two move types can produce the same ω'
//! (an update that regrows the old tail and then some is also an extension), q sums over
//! every way, as the Metropolis-Hastings ratio requires.

use rand::{Rng, RngExt};

use crate::config::Move;
use crate::partition::{FREE, OUTSIDE, Partition};
use crate::problem::MeasId;

/// A running log Σ exp(x_i) (−∞ terms ignored), so that the terms need no buffer.
#[derive(Default)]
struct LogSumExp {
    /// The largest term so far (None before the first finite one).
    max: Option<f64>,
    /// Σ exp(x_i − max).
    sum: f64,
}

impl LogSumExp {
    fn add(&mut self, x: f64) {
        if x == f64::NEG_INFINITY {
            return;
        }
        match self.max {
            Some(m) if x <= m => self.sum += (x - m).exp(),
            Some(m) => {
                self.sum = self.sum * (m - x).exp() + 1.0;
                self.max = Some(x);
            }
            None => {
                self.max = Some(x);
                self.sum = 1.0;
            }
        }
    }

    fn value(&self) -> f64 {
        self.max.map_or(f64::NEG_INFINITY, |m| m + self.sum.ln())
    }
}

/// A track's measurements in growth order: as stored (tail moves) or reversed (head moves),
/// without copying.
#[derive(Clone, Copy)]
struct Ordered<'a> {
    meas: &'a [MeasId],
    reversed: bool,
}

impl<'a> Ordered<'a> {
    fn new(meas: &'a [MeasId], reversed: bool) -> Self {
        Self { meas, reversed }
    }

    fn len(&self) -> usize {
        self.meas.len()
    }

    /// The measurement at growth position `i` (0-based).
    fn get(&self, i: usize) -> MeasId {
        if self.reversed {
            self.meas[self.meas.len() - 1 - i]
        } else {
            self.meas[i]
        }
    }
}

/// ln n, tabulated for the small counts that candidate sets have (the same values as
/// `(n as f64).ln()`, which is used beyond the table).
pub(crate) fn ln_count(n: usize) -> f64 {
    static TABLE: std::sync::LazyLock<[f64; 256]> =
        std::sync::LazyLock::new(|| std::array::from_fn(|n| (n as f64).ln()));
    TABLE.get(n).copied().unwrap_or_else(|| (n as f64).ln())
}

#[cfg(test)]
thread_local! {
    /// Tests switch off the early stop of the suffix sums, to compare with the full loop.
    pub(crate) static EARLY_STOP: std::cell::Cell<bool> = const { std::cell::Cell::new(true) };
    /// How often the suffix sums stopped early (tests check that the case is exercised).
    pub(crate) static EARLY_STOPS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

#[inline]
fn early_stop_allowed() -> bool {
    #[cfg(test)]
    {
        EARLY_STOP.with(std::cell::Cell::get)
    }
    #[cfg(not(test))]
    {
        true
    }
}

/// Which end of a track a move grows or cuts: the paper's moves act on the tail; the head
/// variants are their mirror images in time (see [`crate::McmcdaConfig::head_probability`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum End {
    Tail,
    Head,
}

/// Whether growth may stop before its first step. A track needs two measurements, so growth
/// that starts from a single kept measurement must add one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FirstStep {
    /// Growth may stop at once (with probability γ), leaving the track as it is.
    MayStop,
    /// The first step always draws a measurement; if none is free the move is rejected.
    Mandatory,
}

impl FirstStep {
    /// The first step of an update that keeps the first `kept` measurements in growth order.
    pub(crate) fn of_update(kept: usize) -> Self {
        if kept == 1 {
            FirstStep::Mandatory
        } else {
            FirstStep::MayStop
        }
    }
}

impl Partition<'_> {
    /// The measurements next to `m` at gap `d` in the direction of `end`.
    #[inline]
    fn neighbours(&self, m: MeasId, d: usize, end: End) -> &[MeasId] {
        match end {
            End::Tail => self.successors(m, d),
            End::Head => self.predecessors(m, d),
        }
    }

    /// Draws d ~ ζ.
    pub(crate) fn sample_gap<R: Rng + ?Sized>(&self, rng: &mut R) -> usize {
        let u: f64 = rng.random();
        let cdf = &self.model.zeta_cdf;
        cdf.iter().position(|c| u < *c).unwrap_or(cdf.len() - 1) + 1
    }

    /// |L(y_m, t_m, d) ∩ Free| within the window (or its mirror image towards the head).
    pub(crate) fn free_neighbour_count(&self, m: MeasId, d: usize, end: End) -> usize {
        self.neighbours(m, d, end)
            .iter()
            .filter(|&&n| self.is_free(n))
            .count()
    }

    /// log of the probability that growth stops at `m`: γ, or "go on" and then find the drawn
    /// gap's candidate set empty, γ + (1 − γ) Σ_{d: C(d) = ∅} ζ(d).
    pub(crate) fn log_stop_at(&self, m: MeasId, end: End) -> f64 {
        // All d̄ lists of m in one look-up; gaps beyond `reach` leave the window, where the
        // candidate set is empty (what `successors` and `predecessors` return there). The
        // masses are added in increasing d, as a filtered sum over 1..=d̄ would.
        let t = self.problem.scan_of(m);
        let (lists, reach) = match end {
            End::Tail => (self.problem.forward_lists(m), self.hi.saturating_sub(t)),
            End::Head => (self.problem.backward_lists(m), t.saturating_sub(self.lo)),
        };
        let mut empty_mass = 0.0;
        for (d, (list, z)) in (1..).zip(lists.iter().zip(&self.model.zeta)) {
            if d > reach || !list.iter().any(|&n| self.is_free(n)) {
                empty_mass += z;
            }
        }
        let gamma = self.model.config.stop_probability;
        (gamma + (1.0 - gamma) * empty_mass).ln()
    }

    /// Grows a track from `start`, appending to `out`: repeat { stop with probability γ
    /// (unless this is a mandatory first step); draw d ~ ζ; C = L(y, t, d) ∩ Free; stop if
    /// C is empty; append a uniform member of C }. Towards the head, "after" reads "before"
    /// and `out` receives measurements in growth order (backwards in time). Returns `None` if
    /// a mandatory step found C empty (the move is rejected), else the log probability of the
    /// steps taken, Σ (go on) + ln ζ(d) − ln |C|, summed as
    /// [`Partition::log_grow_probability`] sums them (to the bit): that probability is this
    /// plus the stop term [`Partition::log_stop_at`] of the last measurement.
    pub(crate) fn grow<R: Rng + ?Sized>(
        &self,
        start: MeasId,
        end: End,
        first: FirstStep,
        out: &mut Vec<MeasId>,
        candidates: &mut Vec<MeasId>,
        rng: &mut R,
    ) -> Option<f64> {
        let gamma = self.model.config.stop_probability;
        let mut mandatory = first == FirstStep::Mandatory;
        let mut y = start;
        let mut log_steps = 0.0;
        loop {
            if !mandatory && rng.random_bool(gamma) {
                return Some(log_steps);
            }
            let d = self.sample_gap(rng);
            candidates.clear();
            candidates.extend(
                self.neighbours(y, d, end)
                    .iter()
                    .copied()
                    .filter(|&n| self.is_free(n)),
            );
            if candidates.is_empty() {
                return (!mandatory).then_some(log_steps);
            }
            y = candidates[rng.random_range(0..candidates.len())];
            out.push(y);
            if !mandatory {
                log_steps += self.model.log_go_on;
            }
            log_steps += self.model.log_zeta[d - 1] - ln_count(candidates.len());
            mandatory = false;
        }
    }

    /// log P(growing from `start` towards `end` yields exactly `tail`, in growth order), in
    /// this partition (whose free set must be the one growth ran with).
    pub(crate) fn log_grow_probability(
        &self,
        start: MeasId,
        end: End,
        tail: &[MeasId],
        first: FirstStep,
    ) -> f64 {
        let mandatory_first = first == FirstStep::Mandatory;
        if tail.is_empty() && mandatory_first {
            return f64::NEG_INFINITY;
        }
        let mut lp = 0.0;
        let mut y = start;
        for (i, &next) in tail.iter().enumerate() {
            if i > 0 || !mandatory_first {
                lp += self.model.log_go_on;
            }
            let step = self.log_grow_step(y, next, end);
            if step == f64::NEG_INFINITY {
                return f64::NEG_INFINITY;
            }
            lp += step;
            y = next;
        }
        lp + self.log_stop_at(y, end)
    }

    /// The birth set L^B(t, d): free measurements of scan t with a non-empty L(y, t, d).
    pub(crate) fn birth_set_count(&self, t: usize, d: usize) -> usize {
        self.problem
            .scan(t)
            .iter()
            .filter(|&&m| self.is_free(m) && !self.successors(m, d).is_empty())
            .count()
    }

    /// log q of proposing `track` by a birth from this partition (which must not hold it):
    /// ξ_K(birth) · 1/(T − 1) · ζ(d₁) / |L^B(t₁, d₁)| · 1/|C₂| · P(grow the rest).
    pub(crate) fn log_birth_probability(&self, track: &[MeasId]) -> f64 {
        let (t1, t2) = (
            self.problem.scan_of(track[0]),
            self.problem.scan_of(track[1]),
        );
        let d1 = t2 - t1;
        let n_births = self.birth_set_count(t1, d1);
        let n_second = self.free_neighbour_count(track[0], d1, End::Tail);
        if n_births == 0 || n_second == 0 {
            return f64::NEG_INFINITY;
        }
        let log_grow =
            self.log_grow_probability(track[1], End::Tail, &track[2..], FirstStep::MayStop);
        self.log_birth_probability_given(d1, n_births, n_second, log_grow)
    }

    /// [`Self::log_birth_probability`] of a track whose first gap is `d1`, from the counts
    /// |L^B(t₁, d₁)| and |C₂| and the log probability of growing the rest: the birth move
    /// passes what its draws found, so both give the same bits.
    pub(crate) fn log_birth_probability_given(
        &self,
        d1: usize,
        n_births: usize,
        n_second: usize,
        log_grow: f64,
    ) -> f64 {
        self.model
            .log_move_probability(Move::Birth, self.n_tracks())
            - ln_count(self.n_scans() - 1)
            + self.model.log_zeta[d1 - 1]
            - ln_count(n_births)
            - ln_count(n_second)
            + log_grow
    }

    /// |S(ω)|: the split points (k, i) with |τ_k| ≥ 4 and both parts keeping ≥ 2.
    pub(crate) fn split_count(&self) -> usize {
        self.tracks
            .iter()
            .map(|t| t.meas.len().saturating_sub(3))
            .sum()
    }

    /// Calls `f(k2)` for each track k2 ≠ k1 whose first measurement can follow k1's last.
    pub(crate) fn for_each_merge_partner(&self, k1: usize, mut f: impl FnMut(usize)) {
        let Some(&last) = self.tracks[k1].meas.last() else {
            return;
        };
        for d in 1..=self.problem.max_gap() {
            for &m in self.successors(last, d) {
                let k2 = self.owner_of(m);
                if k2 != FREE && k2 != OUTSIDE && k2 as usize != k1 && self.slot_of(m) == 0 {
                    f(k2 as usize);
                }
            }
        }
    }

    pub(crate) fn merge_partner_count(&self, k1: usize) -> usize {
        let mut n = 0;
        self.for_each_merge_partner(k1, |_| n += 1);
        n
    }

    /// Calls `f(k2, q)` for each switch partner of (τ_k1, position p): positions q of other
    /// tracks with τ_k1(p+1) ∈ L(τ_k2(q), ·) and τ_k2(q+1) ∈ L(τ_k1(p), ·), gaps in 1..=d̄.
    pub(crate) fn for_each_switch_partner(
        &self,
        k1: usize,
        p: usize,
        mut f: impl FnMut(usize, usize),
    ) {
        let track = &self.tracks[k1].meas;
        let (y_p, s1) = (track[p], track[p + 1]);
        let t_p = self.problem.scan_of(y_p);
        let t_s1 = self.problem.scan_of(s1);
        let d_bar = self.problem.max_gap();
        let lists = self.problem.backward_lists(s1);
        for d in 1..=d_bar.min(t_s1) {
            for &y in lists.get(d) {
                let k2 = self.owner_of(y);
                if k2 == FREE || k2 == OUTSIDE || k2 as usize == k1 {
                    continue;
                }
                let other = &self.tracks[k2 as usize].meas;
                let q = self.slot_of(y) as usize;
                let Some(&s2) = other.get(q + 1) else {
                    continue;
                };
                let t_s2 = self.problem.scan_of(s2);
                if t_s2 > t_p && t_s2 - t_p <= d_bar && self.problem.within(y_p, s2, t_s2 - t_p) {
                    f(k2 as usize, q);
                }
            }
        }
    }

    pub(crate) fn switch_partner_count(&self, k1: usize, p: usize) -> usize {
        let mut n = 0;
        self.for_each_switch_partner(k1, p, |_, _| n += 1);
        n
    }

    /// log q of a switch of (τ_a, p) with (τ_b, q) in this partition: the pair can be drawn
    /// from either end (track, position, then partner).
    pub(crate) fn log_switch_probability(&self, a: usize, p: usize, b: usize, q: usize) -> f64 {
        let (n_a, n_b) = (
            self.switch_partner_count(a, p),
            self.switch_partner_count(b, q),
        );
        self.log_switch_probability_given(a, n_a, b, n_b)
    }

    /// [`Self::log_switch_probability`] with the partner counts of the two ends given.
    pub(crate) fn log_switch_probability_given(
        &self,
        a: usize,
        n_a: usize,
        b: usize,
        n_b: usize,
    ) -> f64 {
        let k = self.n_tracks() as f64;
        let end = |t: usize, n: usize| 1.0 / ((self.tracks[t].meas.len() - 1) as f64 * n as f64);
        self.model
            .log_move_probability(Move::Switch, self.n_tracks())
            - k.ln()
            + (end(a, n_a) + end(b, n_b)).ln()
    }

    /// log q(τ → τ') for the moves that change one track and keep K (extension, reduction,
    /// update, at either end), summed over every way of producing τ'. Evaluated in the
    /// partition *without* the track (its measurements free): growth beyond the kept part
    /// only looks at scans the kept part does not occupy, where that free set is exactly the
    /// one each move grew with. `k` is K in ω.
    pub(crate) fn log_single_track_probability(
        &self,
        k: usize,
        from: &[MeasId],
        to: &[MeasId],
    ) -> f64 {
        let head = self.model.config.head_probability;
        let mut sum = LogSumExp::default();
        if head < 1.0 {
            let (from, to) = (Ordered::new(from, false), Ordered::new(to, false));
            self.one_end_terms(k, from, to, End::Tail, (-head).ln_1p(), &mut sum);
        }
        if head > 0.0 {
            let (from, to) = (Ordered::new(from, true), Ordered::new(to, true));
            self.one_end_terms(k, from, to, End::Head, head.ln(), &mut sum);
        }
        sum.value() - ln_count(k)
    }

    /// Adds to `sum` the log-probability terms (each plus `offset`) of producing `to` from
    /// `from` at one end, given that end was chosen and the track drawn; both sequences are
    /// in growth order from the kept end.
    ///
    /// Every term is a growth probability of a suffix of `to` (from `to[r − 1]` on), and a
    /// growth probability is a sum of per-step terms (go on, ζ(d)/|C|) plus the stop at the
    /// last measurement, each step depending only on its own edge and the free set. So the
    /// steps are evaluated once, from the far end, and the terms read off the running suffix
    /// sum: O(|τ'|) per proposal instead of O(|τ'|²), which dominated long tracks (the same
    /// value as [`Partition::log_grow_probability`] of each suffix, summed in another order).
    fn one_end_terms(
        &self,
        k: usize,
        from: Ordered<'_>,
        to: Ordered<'_>,
        end: End,
        offset: f64,
        sum: &mut LogSumExp,
    ) {
        let log_xi = |m| self.model.log_move_probability(m, k);
        let (n_from, n_to) = (from.len(), to.len());
        let common = (0..n_from.min(n_to))
            .take_while(|&i| from.get(i) == to.get(i))
            .count();
        let extension = n_to > n_from && common == n_from;
        if from.len() >= 3 && n_to >= 2 && n_to < n_from && common == n_to {
            sum.add(offset + log_xi(Move::Reduction) - ln_count(n_from - 2));
        }
        if common == 0 {
            // Neither an update (it keeps at least one measurement) nor an extension.
            return;
        }
        let stop = self.log_stop_at(to.get(n_to - 1), end);
        let log_update = offset + log_xi(Move::Update) - ln_count(n_from);
        let log_extension = offset + log_xi(Move::Extension);
        let go_on = self.model.log_go_on;
        // acc = Σ_{j ≥ r} (go on + step j), the edges to[j − 1] → to[j]; r runs down from
        // |τ'|. Update from r keeps to[..r] (r ≤ common); its first step is mandatory (no
        // go-on factor, and an empty tail impossible) when r = 1. Extension grows from
        // r = common = |τ|.
        let mut acc = 0.0;
        for r in (1..=n_to).rev() {
            if r < n_to {
                acc += go_on + self.log_grow_step(to.get(r - 1), to.get(r), end);
            }
            if extension && r == common {
                sum.add(log_extension + acc + stop);
            }
            if r <= common.min(n_from) {
                let grow = match r {
                    1 if n_to < 2 => f64::NEG_INFINITY,
                    1 => acc - go_on + stop,
                    _ => acc + stop,
                };
                sum.add(log_update + grow);
            }
            // The terms still to come are updates from r' < r. Each edge multiplies a term by
            // at most max ζ(d) (go on ≤ 1, a candidate set holds at least the measurement
            // taken), and the term of r' = 1 lacks one go-on factor, so every one of them is
            // at most `bound`. Once that is below e⁻³⁸ < 2⁻⁵⁴ of the largest term so far,
            // adding any of them leaves the sum's bits unchanged (the sum is ≥ 1 in units of
            // its largest term, whose half ulp is ≥ 2⁻⁵³): stopping returns exactly what the
            // whole loop would, in O(|changed part| + about 40 edges) on a long track instead
            // of O(|τ'|).
            if r <= common && r > 1 && early_stop_allowed() {
                let bound = log_update + acc + stop + self.model.max_log_zeta;
                if bound == f64::NEG_INFINITY || sum.max.is_some_and(|m| bound < m - 38.0) {
                    #[cfg(test)]
                    EARLY_STOPS.with(|n| n.set(n.get() + 1));
                    break;
                }
            }
        }
    }

    /// log of one growth step `y → next` towards `end` (ζ(d)/|C(d)|, the go-on factor
    /// apart), −∞ if growth cannot make it in this partition.
    fn log_grow_step(&self, y: MeasId, next: MeasId, end: End) -> f64 {
        let (t, t_next) = (self.problem.scan_of(y), self.problem.scan_of(next));
        let (earlier, later) = match end {
            End::Tail => (t, t_next),
            End::Head => (t_next, t),
        };
        if later <= earlier
            || later - earlier > self.problem.max_gap()
            || !self.is_free(next)
            || (end == End::Head && earlier < self.lo)
        {
            return f64::NEG_INFINITY;
        }
        let d = later - earlier;
        if !self.problem.within(y, next, d) {
            return f64::NEG_INFINITY;
        }
        self.model.log_zeta[d - 1] - ln_count(self.free_neighbour_count(y, d, end))
    }
}
