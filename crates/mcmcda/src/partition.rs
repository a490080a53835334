//! A partition ω of the measurements of a window of scans into false alarms and tracks, with
//! each track's cached Kalman nodes and posterior term, so that the log posterior changes by
//! the terms of the tracks a move touches and nothing else.

use std::ops::RangeInclusive;

use crate::config::Model;
use crate::error::{Error, Result};
use crate::problem::{MeasId, Problem};
use crate::track_filter::Node;

/// `owner` value of a measurement in the window that no track holds (a false alarm).
pub(crate) const FREE: u32 = u32::MAX;
/// `owner` value of a measurement outside the window.
pub(crate) const OUTSIDE: u32 = u32::MAX - 1;

/// One track: its measurements in scan order, filtered nodes, and its posterior term.
#[derive(Debug, Clone)]
pub(crate) struct TrackState {
    pub(crate) meas: Vec<MeasId>,
    pub(crate) nodes: Vec<Node>,
    pub(crate) weight: f64,
}

/// A feasible partition of the measurements in a window of scans (the chain's state ω).
#[derive(Debug, Clone)]
pub struct Partition<'a> {
    pub(crate) model: &'a Model,
    pub(crate) problem: &'a Problem,
    pub(crate) lo: usize,
    pub(crate) hi: usize,
    pub(crate) tracks: Vec<TrackState>,
    /// The smallest id of a measurement in the window: `owner` and `slot` start there.
    id_base: MeasId,
    /// Track index holding each measurement from `id_base` to the window's last id, or
    /// FREE / OUTSIDE (ids outside that span are OUTSIDE too), so that the maps grow with
    /// the window and not with the problem.
    owner: Vec<u32>,
    /// Position of each held measurement inside its track, indexed like `owner`.
    slot: Vec<u32>,
    /// Σ_t n_t log λ_f over the window: the log posterior of "everything is clutter".
    baseline: f64,
}

impl<'a> Partition<'a> {
    /// The partition of the scans `window` (indices into `problem`) with every measurement a
    /// false alarm.
    pub fn empty(
        model: &'a Model,
        problem: &'a Problem,
        window: RangeInclusive<usize>,
    ) -> Result<Self> {
        if !problem.has_neighbourhoods() {
            return Err(Error::NoNeighbourhoods);
        }
        let (lo, hi) = check_window(problem, &window)?;
        let span = problem.id_span(lo..=hi).unwrap_or(0..0);
        let mut owner = vec![OUTSIDE; span.len()];
        let mut n_in = 0usize;
        for (_, scan) in problem.nonempty_scans(lo..=hi) {
            for &m in scan {
                owner[(m - span.start) as usize] = FREE;
                n_in += 1;
            }
        }
        Ok(Self {
            model,
            problem,
            lo,
            hi,
            tracks: Vec::new(),
            id_base: span.start,
            slot: vec![0; span.len()],
            owner,
            baseline: n_in as f64 * model.log_clutter_density,
        })
    }

    /// The partition of `window` with the given tracks (each a list of measurement ids); every
    /// constraint of Ω is checked: measurements inside the window and in at most one track,
    /// at least two per track, one per scan, gaps of at most d̄ scans and consecutive
    /// measurements within the neighbourhood radius.
    pub fn from_tracks(
        model: &'a Model,
        problem: &'a Problem,
        window: RangeInclusive<usize>,
        tracks: &[Vec<MeasId>],
    ) -> Result<Self> {
        let mut partition = Self::empty(model, problem, window)?;
        for (k, track) in tracks.iter().enumerate() {
            partition.check_track(k, track)?;
            partition.insert(track.clone(), None);
        }
        Ok(partition)
    }

    /// Why `track` (number `k` in the caller's list) cannot be added to this partition, if
    /// it cannot.
    fn check_track(&self, k: usize, track: &[MeasId]) -> Result<()> {
        if track.len() < 2 {
            return Err(Error::TrackTooShort {
                track: k,
                len: track.len(),
            });
        }
        for &id in track {
            if !self.problem.contains(id) && !self.problem.is_forgotten(id) {
                return Err(Error::UnknownMeasurement { track: k, id });
            }
            match self.owner_of(id) {
                OUTSIDE => return Err(Error::MeasurementOutsideWindow { track: k, id }),
                FREE => {}
                _ => return Err(Error::MeasurementTaken { track: k, id }),
            }
        }
        for pair in track.windows(2) {
            let (first, second) = (pair[0], pair[1]);
            let (ta, tb) = (self.problem.scan_of(first), self.problem.scan_of(second));
            if tb <= ta {
                return Err(Error::ScansNotIncreasing {
                    track: k,
                    first,
                    second,
                });
            }
            let gap = tb - ta;
            let max_gap = self.problem.max_gap();
            if gap > max_gap {
                return Err(Error::GapTooLong {
                    track: k,
                    first,
                    second,
                    gap,
                    max_gap,
                });
            }
            if !self.problem.within(first, second, gap) {
                return Err(Error::TooFarApart {
                    track: k,
                    first,
                    second,
                    gap,
                });
            }
        }
        Ok(())
    }

    /// Number of tracks K.
    pub fn n_tracks(&self) -> usize {
        self.tracks.len()
    }

    /// Number of scans in the window.
    pub fn n_scans(&self) -> usize {
        self.hi - self.lo + 1
    }

    /// The window's scan indices.
    pub fn window(&self) -> RangeInclusive<usize> {
        self.lo..=self.hi
    }

    /// The tracks' measurement lists, in the partition's current order.
    pub fn tracks(&self) -> impl Iterator<Item = &[MeasId]> {
        self.tracks.iter().map(|t| t.meas.as_slice())
    }

    /// The partition in a canonical form (tracks sorted by their first measurement's id), for
    /// comparing partitions.
    pub fn canonical(&self) -> Vec<Vec<MeasId>> {
        let mut out: Vec<Vec<MeasId>> = self.tracks().map(<[MeasId]>::to_vec).collect();
        out.sort_unstable();
        out
    }

    /// The track holding measurement `m`, if any.
    pub fn track_of(&self, m: MeasId) -> Option<usize> {
        match self.owner_of(m) {
            FREE | OUTSIDE => None,
            k => Some(k as usize),
        }
    }

    /// Where `m` sits in `owner` and `slot`, if in their span.
    #[inline]
    fn index(&self, m: MeasId) -> Option<usize> {
        m.checked_sub(self.id_base)
            .map(|i| i as usize)
            .filter(|&i| i < self.owner.len())
    }

    /// The track index holding `m`, or FREE (a false alarm in the window) or OUTSIDE.
    #[inline]
    pub(crate) fn owner_of(&self, m: MeasId) -> u32 {
        self.index(m).map_or(OUTSIDE, |i| self.owner[i])
    }

    /// Position of `m` inside the track holding it (meaningful when [`Self::owner_of`] is a
    /// track).
    #[inline]
    pub(crate) fn slot_of(&self, m: MeasId) -> u32 {
        self.index(m).map_or(0, |i| self.slot[i])
    }

    /// Sets the owner (and slot) of `m`, a measurement of the window.
    #[inline]
    fn set_owner(&mut self, m: MeasId, k: u32, slot: Option<u32>) {
        let i = (m - self.id_base) as usize;
        self.owner[i] = k;
        if let Some(s) = slot {
            self.slot[i] = s;
        }
    }

    /// log P(ω | Y) up to a constant that depends on Y only (Oh, Russell & Sastry 2009 eq. 9).
    pub fn log_posterior(&self) -> f64 {
        self.baseline + self.tracks.iter().map(|t| t.weight).sum::<f64>()
    }

    /// Whether `m` is a false alarm in the window.
    #[inline]
    pub(crate) fn is_free(&self, m: MeasId) -> bool {
        self.owner_of(m) == FREE
    }

    /// Adds a track (assumed feasible), filtering it from the first `keep` nodes of `prefix`.
    pub(crate) fn insert(&mut self, meas: Vec<MeasId>, prefix: Option<(&[Node], usize)>) {
        let prefix = prefix.map_or(&[][..], |(old, keep)| &old[..keep.min(old.len())]);
        let track = self.filtered_after(meas, prefix);
        self.reinsert(track);
    }

    /// [`Self::filtered`] from a copy of `prefix`, the nodes of the track's first
    /// measurements.
    pub(crate) fn filtered_after(&self, meas: Vec<MeasId>, prefix: &[Node]) -> TrackState {
        let mut nodes = Vec::with_capacity(meas.len());
        nodes.extend_from_slice(prefix);
        self.filtered(meas, nodes, prefix.len())
    }

    /// Adds a track (assumed feasible) whose first `keep` nodes are already in `nodes` (the
    /// rest is dropped and filtered anew): a move that keeps a prefix hands over the old
    /// track's buffer instead of copying it.
    pub(crate) fn insert_into(&mut self, meas: Vec<MeasId>, nodes: Vec<Node>, keep: usize) {
        let track = self.filtered(meas, nodes, keep);
        self.reinsert(track);
    }

    /// A track (assumed feasible) filtered from the first `keep` nodes in `nodes` and
    /// weighed in this window, without adding it: its measurements stay as they are.
    pub(crate) fn filtered(
        &self,
        meas: Vec<MeasId>,
        mut nodes: Vec<Node>,
        keep: usize,
    ) -> TrackState {
        let keep = keep.min(nodes.len());
        self.model
            .filter_track(self.problem, &meas, &mut nodes, keep);
        let weight = nodes.last().map_or(0.0, |last| {
            self.model.track_weight(self.problem, &meas, last, self.hi)
        });
        TrackState {
            meas,
            nodes,
            weight,
        }
    }

    /// Adds back a track removed earlier, with its cached nodes.
    pub(crate) fn reinsert(&mut self, track: TrackState) {
        let k = self.tracks.len() as u32;
        for (i, &m) in track.meas.iter().enumerate() {
            self.set_owner(m, k, Some(i as u32));
        }
        self.tracks.push(track);
    }

    /// Removes track `k`; its measurements become false alarms. The last track takes index k.
    pub(crate) fn remove(&mut self, k: usize) -> TrackState {
        let removed = self.tracks.swap_remove(k);
        for &m in &removed.meas {
            self.set_owner(m, FREE, None);
        }
        if let Some(moved) = self.tracks.get(k) {
            for &m in &moved.meas {
                // Disjoint fields: `tracks` read, `owner` written.
                self.owner[(m - self.id_base) as usize] = k as u32;
            }
        }
        removed
    }

    /// The measurements a track may hold after `m`: L(y_m, t_m, d) restricted to the window.
    #[inline]
    pub(crate) fn successors(&self, m: MeasId, d: usize) -> &[MeasId] {
        if self.problem.scan_of(m) + d > self.hi {
            &[]
        } else {
            self.problem.forward(m, d)
        }
    }

    /// The measurements a track may hold before `m`: those y' of scan t_m − d with
    /// y_m ∈ L(y', t_m − d, d), restricted to the window.
    #[inline]
    pub(crate) fn predecessors(&self, m: MeasId, d: usize) -> &[MeasId] {
        if self.problem.scan_of(m) < self.lo + d {
            &[]
        } else {
            self.problem.backward(m, d)
        }
    }

    /// Checks every invariant of the partition and its caches (for tests and debugging):
    /// Ω's constraints, the owner and slot maps, and each cached weight against a fresh
    /// filter.
    pub fn check_invariants(&self) -> Result<()> {
        let mut fresh = Self::empty(self.model, self.problem, self.window())?;
        for (k, t) in self.tracks.iter().enumerate() {
            fresh.check_track(k, &t.meas)?;
            fresh.insert(t.meas.clone(), None);
            let w = fresh.tracks[k].weight;
            if (w - t.weight).abs() > 1e-9 * w.abs().max(1.0) {
                return Err(Error::StaleWeight {
                    track: k,
                    cached: t.weight,
                    fresh: w,
                });
            }
            for (i, &m) in t.meas.iter().enumerate() {
                if self.owner_of(m) != k as u32 || self.slot_of(m) != i as u32 {
                    return Err(Error::OwnerMapWrong { id: m });
                }
            }
        }
        if fresh.id_base != self.id_base || fresh.owner.len() != self.owner.len() {
            return Err(Error::OwnerMapWrong { id: self.id_base });
        }
        if let Some(stale) = (0..self.owner.len()).find(|&i| fresh.owner[i] != self.owner[i]) {
            return Err(Error::OwnerMapWrong {
                id: self.id_base + stale as MeasId,
            });
        }
        Ok(())
    }
}

/// The window's first and last scan indices, if it is a non-empty range of the problem's
/// scans.
pub(crate) fn check_window(
    problem: &Problem,
    window: &RangeInclusive<usize>,
) -> Result<(usize, usize)> {
    let (lo, hi) = (*window.start(), *window.end());
    if lo > hi || hi >= problem.n_scans() {
        return Err(Error::WindowOutOfRange {
            start: lo,
            end: hi,
            n_scans: problem.n_scans(),
        });
    }
    if lo < problem.first_kept_scan() {
        return Err(Error::ScanForgotten {
            scan: lo,
            first_kept: problem.first_kept_scan(),
        });
    }
    Ok((lo, hi))
}
