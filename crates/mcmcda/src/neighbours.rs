//! One direction's neighbourhood lists L(y, t, d), d = 1..=d̄ (Oh, Russell & Sastry 2009
//! eq. 27), of every measurement slot of a [`crate::Problem`].
//!
//! A slot's d̄ lists lie back to back in one vector, in increasing d, with their end offsets
//! in a flat table: two allocations per measurement instead of one per list. With d̄ = 24 (a
//! 25 fps detection file) the one-vector-per-list layout made 48 small vectors per detection,
//! and growing and freeing them was half the time of a one-sample online run.

use crate::problem::{MeasId, shrink};

/// The lists of every slot, in one direction.
#[derive(Debug, Clone)]
pub(crate) struct NeighbourLists {
    max_gap: usize,
    /// Each slot's lists, concatenated in increasing d.
    ids: Vec<Vec<MeasId>>,
    /// `ends[slot·d̄ + d − 1]`: where list d of `slot` ends in `ids[slot]` (list 1 starts at 0,
    /// list d at the end of list d − 1).
    ends: Vec<u32>,
}

/// The d̄ lists of one slot.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Lists<'a> {
    ids: &'a [MeasId],
    ends: &'a [u32],
}

impl<'a> Lists<'a> {
    /// List d, d ∈ 1..=d̄.
    #[inline]
    pub(crate) fn get(self, d: usize) -> &'a [MeasId] {
        let start = if d == 1 { 0 } else { self.ends[d - 2] as usize };
        &self.ids[start..self.ends[d - 1] as usize]
    }

    /// Lists 1..=d̄ in order.
    #[inline]
    pub(crate) fn iter(self) -> impl Iterator<Item = &'a [MeasId]> {
        let ids = self.ids;
        std::iter::once(0)
            .chain(self.ends.iter().copied())
            .zip(self.ends.iter().copied())
            .map(move |(start, end)| &ids[start as usize..end as usize])
    }
}

impl NeighbourLists {
    pub(crate) fn new(max_gap: usize) -> Self {
        Self {
            max_gap,
            ids: Vec::new(),
            ends: Vec::new(),
        }
    }

    /// A new slot at the end, every list empty.
    pub(crate) fn push_slot(&mut self) {
        self.ids.push(Vec::new());
        self.ends.extend(std::iter::repeat_n(0, self.max_gap));
    }

    /// The lists of `slot`.
    #[inline]
    pub(crate) fn lists(&self, slot: usize) -> Lists<'_> {
        Lists {
            ids: &self.ids[slot],
            ends: &self.ends[slot * self.max_gap..(slot + 1) * self.max_gap],
        }
    }

    /// Appends `id` to list d of `slot`. Appending to the last non-empty list (the usual case:
    /// scans arrive in order) moves nothing; an earlier list shifts the later ones by one.
    pub(crate) fn push(&mut self, slot: usize, d: usize, id: MeasId) {
        self.extend(slot, d, &[id]);
    }

    /// Appends `new` to list d of `slot`.
    pub(crate) fn extend(&mut self, slot: usize, d: usize, new: &[MeasId]) {
        if new.is_empty() {
            return;
        }
        let ends = &mut self.ends[slot * self.max_gap..(slot + 1) * self.max_gap];
        let at = ends[d - 1] as usize;
        let list = &mut self.ids[slot];
        if at == list.len() {
            list.extend_from_slice(new);
        } else {
            list.splice(at..at, new.iter().copied());
        }
        // A slot's lists hold at most the ids of d̄ scans: far below u32::MAX, like the ids.
        let added = new.len() as u32;
        for end in &mut ends[d - 1..] {
            *end += added;
        }
    }

    /// Empties lists d..=d̄ of `slot` (1 ≤ d; d > d̄ leaves the slot as it is).
    pub(crate) fn clear_from(&mut self, slot: usize, d: usize) {
        if d > self.max_gap {
            return;
        }
        let ends = &mut self.ends[slot * self.max_gap..(slot + 1) * self.max_gap];
        let start = if d == 1 { 0 } else { ends[d - 2] };
        ends[d - 1..].fill(start);
        let list = &mut self.ids[slot];
        list.truncate(start as usize);
        if start == 0 {
            *list = Vec::new();
        }
    }

    /// Drops the first `n` slots (the later ones move to the front).
    pub(crate) fn drain_front(&mut self, n: usize) {
        self.ids.drain(..n);
        self.ends.drain(..n * self.max_gap);
    }

    /// Capacity back to what the kept slots need.
    pub(crate) fn shrink(&mut self) {
        shrink(&mut self.ends);
        shrink(&mut self.ids);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against one vector per list, for pushes in and out of order and clearing.
    #[test]
    fn lists_match_one_vector_per_list() {
        let d_bar = 4;
        let mut lists = NeighbourLists::new(d_bar);
        let mut want: Vec<Vec<Vec<MeasId>>> = Vec::new();
        for _ in 0..3 {
            lists.push_slot();
            want.push(vec![Vec::new(); d_bar]);
        }
        let pushes = [
            (0, 1, 5),
            (0, 3, 7),
            (0, 2, 6),
            (0, 3, 8),
            (1, 4, 9),
            (0, 1, 10),
        ];
        for (slot, d, id) in pushes {
            lists.push(slot, d, id);
            want[slot][d - 1].push(id);
        }
        lists.extend(2, 2, &[1, 2, 3]);
        want[2][1].extend([1, 2, 3]);
        let check = |lists: &NeighbourLists, want: &[Vec<Vec<MeasId>>]| {
            for (slot, w) in want.iter().enumerate() {
                let got = lists.lists(slot);
                for d in 1..=d_bar {
                    assert_eq!(got.get(d), w[d - 1].as_slice(), "slot {slot}, d {d}");
                }
                let all: Vec<&[MeasId]> = got.iter().collect();
                let w: Vec<&[MeasId]> = w.iter().map(Vec::as_slice).collect();
                assert_eq!(all, w, "slot {slot}");
            }
        };
        check(&lists, &want);
        lists.clear_from(0, 3);
        want[0][2].clear();
        want[0][3].clear();
        lists.clear_from(1, 5);
        check(&lists, &want);
        lists.clear_from(2, 1);
        want[2].iter_mut().for_each(Vec::clear);
        check(&lists, &want);
        lists.drain_front(1);
        want.remove(0);
        check(&lists, &want);
    }
}
