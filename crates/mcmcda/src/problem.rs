//! The measurements Y of a data-association problem and the neighbourhood structure
//! L(y, t, d) = { y' ∈ Y_{t+d} : ‖y − y'‖ ≤ d·v̄·T_s } (Oh, Russell & Sastry 2009 eq. 27),
//! computed once as measurements arrive and kept in both directions (or not at all, for a
//! problem [`Problem::without_neighbourhoods`], which serves the nearest-neighbour baseline).

use std::ops::RangeInclusive;

use tracker_model::{Frame, Scan, Vec2};

use crate::config::Model;
use crate::error::{Error, Result};
use crate::neighbours::{Lists, NeighbourLists};

/// A measurement's index in a [`Problem`], in arrival order.
pub type MeasId = u32;

/// Measurements by scan with their forward and backward neighbourhoods.
///
/// Scans are consecutive frames starting at [`Problem::first_frame`]: scan index s is frame
/// `first_frame + s`, and a scan may be empty. Only the scans that hold measurements are
/// stored (with their indices), so memory and time do not grow with gaps in the frame
/// numbers: a frame four billion frames ahead costs no more than the next one. Empty scans
/// still count everywhere the posterior and the proposal count scans (Oh, Russell & Sastry
/// 2009 eq. 9 has a term for every scan a track spans, detected or not).
/// Measurements can be added to any scan already present (late measurements), and their
/// neighbourhood entries are added on both sides, so nothing is recomputed.
///
/// A long-running (online) problem can drop its oldest scans with `Problem::forget_before`,
/// so that storage is proportional to the scans kept, not to the run's length. Measurement
/// ids and scan indices stay what they were: ids keep counting from 0 in arrival order and
/// scan index s is still frame `first_frame + s`. A forgotten measurement is no longer
/// [`contains`](Problem::contains)ed; asking its position, scan or neighbours panics with a
/// message that says so (as indexing a slice out of range does), never answers with another
/// measurement's data.
#[derive(Debug, Clone)]
pub struct Problem {
    first_frame: Frame,
    max_gap: usize,
    radius_per_scan: f64,
    /// Id of `positions[0]`: the ids below it are forgotten.
    id_base: MeasId,
    /// The first scan kept: scans before it are forgotten, and so are the measurements of
    /// those scans whose ids lie at or above `id_base` (late arrivals), which keep a slot
    /// with empty neighbourhoods until the ids before them are dropped.
    scan_base: usize,
    /// Indexed by id − `id_base`, like `scan_of`, `forward` and `backward`.
    positions: Vec<Vec2>,
    /// ln f₁(s)/f₀(s) of each measurement's detection score s (0 when none was given):
    /// indexed like `positions`.
    log_score_ratios: Vec<f64>,
    scan_of: Vec<u32>,
    /// Number of scans, empty ones included (frame − first_frame of the last scan, plus 1).
    n_scans: usize,
    /// Indices of the non-empty scans, increasing.
    held: Vec<u32>,
    /// Members of each non-empty scan, in the order of `held`.
    members: Vec<Vec<MeasId>>,
    /// List d of slot m: L(y_m, t_m, d); backward likewise for scan t_m − d.
    forward: NeighbourLists,
    backward: NeighbourLists,
    /// Reused by [`Self::add_measurement`] (holds nothing between calls).
    scratch: Vec<MeasId>,
    /// Whether the neighbourhoods are kept ([`Self::without_neighbourhoods`]: not).
    linked: bool,
}

impl Problem {
    /// An empty problem whose first scan is `first_frame`, with the neighbourhood radius and
    /// depth of `model`.
    pub fn empty(model: &Model, first_frame: Frame) -> Self {
        Self {
            first_frame,
            max_gap: model.max_gap() as usize,
            radius_per_scan: model.radius_per_scan,
            id_base: 0,
            scan_base: 0,
            positions: Vec::new(),
            log_score_ratios: Vec::new(),
            scan_of: Vec::new(),
            n_scans: 0,
            held: Vec::new(),
            members: Vec::new(),
            forward: NeighbourLists::new(model.max_gap() as usize),
            backward: NeighbourLists::new(model.max_gap() as usize),
            scratch: Vec::new(),
            linked: true,
        }
    }

    /// [`Self::empty`] for a problem that keeps the measurements by scan but not their
    /// neighbourhoods: what the nearest-neighbour baseline ([`crate::nearest_neighbour_tracks`])
    /// reads, without the cost of the lists (each holds the measurements of the d̄ scans on
    /// either side within reach of the measurement: at a 25 fps detection file's d̄ = 24
    /// nearly every detection of 48 frames). `Self::forward` and `Self::backward` are
    /// empty, and a [`crate::chain::Partition`] of it (MCMCDA's chain, the greedy start) and
    /// [`crate::reference::enumerate_partitions`] fail with [`Error::NoNeighbourhoods`].
    pub fn without_neighbourhoods(model: &Model, first_frame: Frame) -> Self {
        Self {
            linked: false,
            ..Self::empty(model, first_frame)
        }
    }

    /// Whether the neighbourhoods are kept (false for [`Self::without_neighbourhoods`]).
    pub(crate) fn has_neighbourhoods(&self) -> bool {
        self.linked
    }

    /// A problem holding `scans`, whose frames must be strictly increasing; frames missing
    /// between them become empty scans.
    pub fn from_scans(model: &Model, scans: &[Scan]) -> Result<Self> {
        let first = scans.first().map_or(0, |s| s.frame);
        let mut problem = Self::empty(model, first);
        for scan in scans {
            let points: Vec<Vec2> = scan.measurements.iter().map(|m| m.value).collect();
            problem.push_scan(scan.frame, &points)?;
        }
        Ok(problem)
    }

    /// Appends the scan at `frame` (frames skipped before it become empty scans, which cost
    /// nothing to store). Returns the ids given to `points`, in order.
    pub fn push_scan(&mut self, frame: Frame, points: &[Vec2]) -> Result<Vec<MeasId>> {
        self.push_scored(frame, points, None)
    }

    /// [`Self::push_scan`] with each measurement's score likelihood ratio: `log_score_ratios[i]`
    /// = ln f₁(sᵢ)/f₀(sᵢ), the log density of point i's detection score sᵢ under "detected
    /// target" over "false alarm" (Lerro & Bar-Shalom 1993, IEEE AES 29(2): the amplitude
    /// likelihood ratio). A track's term of the log posterior then gains the ratio of every
    /// measurement it holds (Oh, Russell & Sastry 2009 eq. 9 with each p_d N(·)/λ_f multiplied
    /// by f₁(s)/f₀(s)), and GNN's pair costs lose it. All zeros is [`Self::push_scan`].
    pub fn push_scan_scored(
        &mut self,
        frame: Frame,
        points: &[Vec2],
        log_score_ratios: &[f64],
    ) -> Result<Vec<MeasId>> {
        self.push_scored(frame, points, Some(log_score_ratios))
    }

    /// [`Self::push_scan_scored`], with all ratios 0 when `log_score_ratios` is `None` (no
    /// vector of zeros allocated per scan).
    pub(crate) fn push_scored(
        &mut self,
        frame: Frame,
        points: &[Vec2],
        log_score_ratios: Option<&[f64]>,
    ) -> Result<Vec<MeasId>> {
        let ratio = |i: usize| log_score_ratios.map_or(0.0, |r| r[i]);
        if let Some(r) = log_score_ratios
            && r.len() != points.len()
        {
            return Err(Error::ScoreCount {
                points: points.len(),
                scores: r.len(),
            });
        }
        if log_score_ratios.is_some_and(|r| r.iter().any(|r| !r.is_finite())) {
            return Err(Error::Model(tracker_model::Error::NonFinite {
                what: "log score ratio",
            }));
        }
        let next = u64::from(self.first_frame) + self.n_scans as u64;
        if u64::from(frame) < next {
            return Err(if self.n_scans == 0 {
                Error::FrameBeforeFirst {
                    frame,
                    first: self.first_frame,
                }
            } else {
                Error::FramesOutOfOrder {
                    frame,
                    last: (next - 1) as Frame,
                }
            });
        }
        self.n_scans = (frame - self.first_frame) as usize + 1;
        points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let id = self.add_measurement(frame, *p)?;
                let slot = self.slot(id);
                self.log_score_ratios[slot] = ratio(i);
                Ok(id)
            })
            .collect()
    }

    /// Adds one measurement to the existing scan at `frame` (a late measurement joins its own
    /// scan) and links it into the neighbourhoods. A frame whose scan was forgotten
    /// (`Self::forget_before`) is refused with [`Error::ScanForgotten`].
    pub fn add_measurement(&mut self, frame: Frame, position: Vec2) -> Result<MeasId> {
        if !(position.x.is_finite() && position.y.is_finite()) {
            return Err(Error::Model(tracker_model::Error::NonFinite {
                what: "measurement position",
            }));
        }
        let scan = frame
            .checked_sub(self.first_frame)
            .map(|s| s as usize)
            .filter(|s| *s < self.n_scans)
            .ok_or(Error::FrameNotHeld {
                frame,
                first: self.first_frame,
                end: u64::from(self.first_frame) + self.n_scans as u64,
            })?;
        if scan < self.scan_base {
            return Err(Error::ScanForgotten {
                scan,
                first_kept: self.scan_base,
            });
        }
        let id = MeasId::try_from(self.n_measurements()).map_err(|_| Error::TooManyMeasurements)?;
        let slot = self.positions.len();
        self.positions.push(position);
        self.log_score_ratios.push(0.0);
        self.scan_of.push(scan as u32);
        self.forward.push_slot();
        self.backward.push_slot();
        if self.linked {
            self.link(slot, scan, position);
        }
        // Where `scan` is (or goes) in `held`: the end of the earlier scans.
        let at = self.held.partition_point(|&s| (s as usize) < scan);
        if self.held.get(at) == Some(&(scan as u32)) {
            self.members[at].push(id);
        } else {
            self.held.insert(at, scan as u32);
            self.members.insert(at, vec![id]);
        }
        Ok(id)
    }

    /// Adds the measurement in `slot` (at `position` in scan `scan`, not yet among the scan's
    /// members) to the neighbourhoods, its own and those of the measurements within reach.
    fn link(&mut self, slot: usize, scan: usize, position: Vec2) {
        let id = self.id_base + slot as MeasId;
        let d_bar = self.max_gap;
        // One reused buffer for the neighbours found at each gap (no allocation per gap). Only
        // the held (non-empty) scans within d̄ of `scan` are visited, found by two binary
        // searches, instead of looking up each of the 2 d̄ scan indices: the lists are the
        // same, since each gap's list is filled from one scan only.
        let mut found = std::mem::take(&mut self.scratch);
        let later = self.held.partition_point(|&s| (s as usize) <= scan)
            ..self.held.partition_point(|&s| (s as usize) <= scan + d_bar);
        for i in later {
            let d = self.held[i] as usize - scan;
            self.neighbours_in(i, position, d, &mut found);
            self.forward.extend(slot, d, &found);
            for &other in &found {
                let other = self.slot(other);
                self.backward.push(other, d, id);
            }
        }
        let at = self.held.partition_point(|&s| (s as usize) < scan);
        let earlier =
            self.held
                .partition_point(|&s| (s as usize) < scan.saturating_sub(d_bar))..at;
        // Latest scan first, so that the new measurement's lists are appended in increasing
        // d (each list comes from one scan, so the order of the scans changes no list).
        for i in earlier.rev() {
            let d = scan - self.held[i] as usize;
            self.neighbours_in(i, position, d, &mut found);
            self.backward.extend(slot, d, &found);
            for &other in &found {
                let other = self.slot(other);
                self.forward.push(other, d, id);
            }
        }
        self.scratch = found;
    }

    /// Forgets every scan before scan index `scan` (clamped to [`Self::n_scans`]) and its
    /// measurements: their positions and neighbourhoods are dropped, the neighbourhoods of
    /// the measurements kept lose the entries that pointed at them, and storage shrinks to
    /// what the kept scans need. Ids, scan indices and frames keep their meaning; forgotten
    /// scans read as empty ([`Self::scan`], [`Self::nonempty_scans`]), forgotten ids are not
    /// [`Self::contains`]ed, windows must start at or after [`Self::first_kept_scan`]
    /// ([`crate::chain::Partition`] fails with [`Error::ScanForgotten`] otherwise) and
    /// measurements can no longer be added to forgotten scans. Forgetting is for good:
    /// asking for an earlier scan than already forgotten does nothing (tested by
    /// `tests::a_problem_forgets_old_scans_and_keeps_ids_and_scan_indices`).
    pub(crate) fn forget_before(&mut self, scan: usize) {
        let scan = scan.min(self.n_scans);
        if scan <= self.scan_base {
            return;
        }
        self.scan_base = scan;
        let cut = self.held.partition_point(|&s| (s as usize) < scan);
        let dropped: Vec<Vec<MeasId>> = self.members.drain(..cut).collect();
        self.held.drain(..cut);
        let new_base = self
            .members
            .iter()
            .flatten()
            .copied()
            .min()
            .map_or(self.n_measurements() as MeasId, |m| m);
        let d_bar = self.max_gap;
        // Late arrivals among the forgotten (ids above new_base): keep the slot, drop the rest.
        for &m in dropped.iter().flatten().filter(|&&m| m >= new_base) {
            let i = (m - self.id_base) as usize;
            self.forward.clear_from(i, 1);
            self.backward.clear_from(i, 1);
        }
        let n_drop = (new_base - self.id_base) as usize;
        self.positions.drain(..n_drop);
        self.log_score_ratios.drain(..n_drop);
        self.scan_of.drain(..n_drop);
        self.forward.drain_front(n_drop);
        self.backward.drain_front(n_drop);
        self.id_base = new_base;
        // Backward neighbourhoods reaching into the forgotten scans.
        let reach = self.members.len().min(
            self.held
                .partition_point(|&s| (s as usize) < scan.saturating_add(d_bar)),
        );
        for &m in self.members[..reach].iter().flatten() {
            let i = (m - self.id_base) as usize;
            // Scan t − d is forgotten for every d > t − scan.
            let t = self.scan_of[i] as usize;
            self.backward.clear_from(i, t + 1 - scan);
        }
        shrink(&mut self.positions);
        shrink(&mut self.log_score_ratios);
        shrink(&mut self.scan_of);
        self.forward.shrink();
        self.backward.shrink();
        shrink(&mut self.held);
        shrink(&mut self.members);
    }

    /// The first scan index not forgotten (0 unless `Self::forget_before` was called).
    pub(crate) fn first_kept_scan(&self) -> usize {
        self.scan_base
    }

    /// The scans kept, `first_kept_scan()..=n_scans() − 1`: the widest window a run can use
    /// after `Self::forget_before` (the same as [`Self::all_scans`] before). Fails with
    /// [`Error::EmptyProblem`] when no scan is kept.
    pub fn kept_scans(&self) -> Result<RangeInclusive<usize>> {
        match self.n_scans {
            n if n > self.scan_base => Ok(self.scan_base..=n - 1),
            _ => Err(Error::EmptyProblem),
        }
    }

    /// Number of measurements kept (not forgotten).
    pub fn n_kept_measurements(&self) -> usize {
        self.members.iter().map(Vec::len).sum()
    }

    /// Whether `m` was a measurement of this problem and has been forgotten.
    pub(crate) fn is_forgotten(&self, m: MeasId) -> bool {
        (m as usize) < self.n_measurements() && !self.contains(m)
    }

    /// Where `m` is stored; panics (with the reason) for an id not held.
    #[inline]
    #[track_caller]
    fn slot(&self, m: MeasId) -> usize {
        match m.checked_sub(self.id_base).map(|i| i as usize) {
            Some(i)
                if self
                    .scan_of
                    .get(i)
                    .is_some_and(|&s| s as usize >= self.scan_base) =>
            {
                i
            }
            _ => self.not_held(m),
        }
    }

    #[cold]
    #[track_caller]
    fn not_held(&self, m: MeasId) -> ! {
        if self.is_forgotten(m) {
            panic!(
                "measurement {m} was forgotten (scans before {} are dropped)",
                self.scan_base
            )
        }
        panic!(
            "measurement {m} does not exist (the problem has {})",
            self.n_measurements()
        )
    }

    /// Whether `a` and `b` can be consecutive measurements of one track `d` scans apart.
    pub(crate) fn within(&self, a: MeasId, b: MeasId, d: usize) -> bool {
        self.within_of(self.position(a), b, d)
    }

    /// Sets `found` to the measurements of the `i`-th held scan within reach of `position`
    /// `d` scans away.
    fn neighbours_in(&self, i: usize, position: Vec2, d: usize, found: &mut Vec<MeasId>) {
        found.clear();
        found.extend(
            self.members[i]
                .iter()
                .copied()
                .filter(|&other| self.within_of(position, other, d)),
        );
    }

    /// [`Self::within`] for a measurement at `position`.
    fn within_of(&self, position: Vec2, b: MeasId, d: usize) -> bool {
        let r = d as f64 * self.radius_per_scan;
        (position - self.position(b)).norm_squared() <= r * r
    }

    /// Frame of scan index 0.
    pub fn first_frame(&self) -> Frame {
        self.first_frame
    }

    /// Number of scans.
    pub fn n_scans(&self) -> usize {
        self.n_scans
    }

    /// Every scan index, `0..=n_scans() − 1`: the window of a whole-problem (batch) run.
    /// Fails with [`Error::EmptyProblem`] when the problem holds no scans.
    ///
    /// ```
    /// use mcmcda::{Error, McmcdaConfig, Problem};
    /// use tracker_model::Vec2;
    ///
    /// let model = McmcdaConfig::default().check()?;
    /// let mut problem = Problem::empty(&model, 10);
    /// assert_eq!(problem.all_scans(), Err(Error::EmptyProblem));
    /// problem.push_scan(12, &[Vec2::new(1.0, 2.0)])?;
    /// assert_eq!(problem.all_scans()?, 0..=2);
    /// # Ok::<(), mcmcda::Error>(())
    /// ```
    pub fn all_scans(&self) -> Result<RangeInclusive<usize>> {
        match self.n_scans {
            0 => Err(Error::EmptyProblem),
            n => Ok(0..=n - 1),
        }
    }

    /// Number of measurements given ids so far, forgotten ones included: the ids are
    /// `0..n_measurements()`, and the next measurement added gets id `n_measurements()`.
    pub fn n_measurements(&self) -> usize {
        self.id_base as usize + self.positions.len()
    }

    /// d̄.
    pub(crate) fn max_gap(&self) -> usize {
        self.max_gap
    }

    /// The measurements of scan index `s` (empty for an empty scan, a forgotten one or one
    /// past the end).
    pub fn scan(&self, s: usize) -> &[MeasId] {
        match u32::try_from(s).map(|s| self.held.binary_search(&s)) {
            Ok(Ok(i)) => &self.members[i],
            _ => &[],
        }
    }

    /// The non-empty scans among the indices `window`, in increasing order, with their
    /// measurements: what a loop over scans visits when empty scans have nothing to do.
    pub(crate) fn nonempty_scans(
        &self,
        window: RangeInclusive<usize>,
    ) -> impl Iterator<Item = (usize, &[MeasId])> + '_ {
        let (lo, hi) = (*window.start(), *window.end());
        let from = self.held.partition_point(|&s| (s as usize) < lo);
        self.held[from..]
            .iter()
            .zip(&self.members[from..])
            .map(|(&s, m)| (s as usize, m.as_slice()))
            .take_while(move |(s, _)| *s <= hi)
    }

    /// Whether `m` is a measurement of this problem (and not forgotten).
    pub fn contains(&self, m: MeasId) -> bool {
        m.checked_sub(self.id_base)
            .and_then(|i| self.scan_of.get(i as usize))
            .is_some_and(|&s| s as usize >= self.scan_base)
    }

    /// Position of a measurement.
    ///
    /// # Panics
    /// If `m` is not [`Self::contains`]ed: an unknown or forgotten id.
    #[track_caller]
    pub fn position(&self, m: MeasId) -> Vec2 {
        self.positions[self.slot(m)]
    }

    /// ln f₁(s)/f₀(s) of a measurement's detection score (0 when none was given; see
    /// [`Self::push_scan_scored`]).
    ///
    /// # Panics
    /// If `m` is not [`Self::contains`]ed: an unknown or forgotten id.
    #[track_caller]
    pub fn log_score_ratio(&self, m: MeasId) -> f64 {
        self.log_score_ratios[self.slot(m)]
    }

    /// Scan index of a measurement.
    ///
    /// # Panics
    /// If `m` is not [`Self::contains`]ed: an unknown or forgotten id.
    #[track_caller]
    pub fn scan_of(&self, m: MeasId) -> usize {
        self.scan_of[self.slot(m)] as usize
    }

    /// L(y_m, t_m, d), d ∈ 1..=d̄ (empty on a problem [`Self::without_neighbourhoods`]).
    ///
    /// # Panics
    /// If `m` is not [`Self::contains`]ed (an unknown or forgotten id), or d is not in 1..=d̄.
    #[track_caller]
    pub(crate) fn forward(&self, m: MeasId, d: usize) -> &[MeasId] {
        self.forward_lists(m).get(d)
    }

    /// The d̄ lists [`Self::forward`]`(m, d)`, d = 1..=d̄, read with `get(d)` (one look-up of
    /// `m` for every gap).
    ///
    /// # Panics
    /// If `m` is not [`Self::contains`]ed: an unknown or forgotten id.
    #[inline]
    #[track_caller]
    pub(crate) fn forward_lists(&self, m: MeasId) -> Lists<'_> {
        self.forward.lists(self.slot(m))
    }

    /// The d̄ lists [`Self::backward`]`(m, d)`, d = 1..=d̄, read with `get(d)`.
    ///
    /// # Panics
    /// If `m` is not [`Self::contains`]ed: an unknown or forgotten id.
    #[inline]
    #[track_caller]
    pub(crate) fn backward_lists(&self, m: MeasId) -> Lists<'_> {
        self.backward.lists(self.slot(m))
    }

    /// The measurements y' of scan t_m − d with y_m ∈ L(y', t_m − d, d) (none once scan
    /// t_m − d is forgotten, or on a problem [`Self::without_neighbourhoods`]).
    ///
    /// # Panics
    /// If `m` is not [`Self::contains`]ed (an unknown or forgotten id), or d is not in 1..=d̄.
    #[track_caller]
    pub(crate) fn backward(&self, m: MeasId, d: usize) -> &[MeasId] {
        self.backward_lists(m).get(d)
    }

    /// The range of ids of the measurements of the scans `window` (forgotten and other
    /// scans' ids may lie inside it: late measurements take later ids), or `None` when
    /// those scans hold no measurement. [`crate::chain::Partition`] sizes its maps by it.
    pub(crate) fn id_span(&self, window: RangeInclusive<usize>) -> Option<std::ops::Range<MeasId>> {
        let mut ids = self
            .nonempty_scans(window)
            .flat_map(|(_, m)| m.iter().copied());
        let first = ids.next()?;
        let (lo, hi) = ids.fold((first, first), |(lo, hi), m| (lo.min(m), hi.max(m)));
        Some(lo..hi + 1)
    }
}

/// Gives memory back after forgetting: capacity stays within a quarter of the length, so
/// a problem that streams holds what its kept scans need, not the most it ever held.
pub(crate) fn shrink<T>(v: &mut Vec<T>) {
    if v.capacity() > v.len() + v.len() / 4 + 8 {
        v.shrink_to_fit();
    }
}
