//! The measurements Y of a data-association problem and the neighbourhood structure
//! L(y, t, d) = { y' ∈ Y_{t+d} : ‖y − y'‖ ≤ d·v̄·T_s } (Oh, Russell & Sastry 2009 eq. 27),
//! computed once as measurements arrive and kept in both directions.

use std::ops::RangeInclusive;

use tracker_model::{Frame, Scan, Vec2};

use crate::config::Model;
use crate::error::{Error, Result};

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
#[derive(Debug, Clone)]
pub struct Problem {
    first_frame: Frame,
    max_gap: usize,
    radius_per_scan: f64,
    positions: Vec<Vec2>,
    scan_of: Vec<u32>,
    /// Number of scans, empty ones included (frame − first_frame of the last scan, plus 1).
    n_scans: usize,
    /// Indices of the non-empty scans, increasing.
    held: Vec<u32>,
    /// Members of each non-empty scan, in the order of `held`.
    members: Vec<Vec<MeasId>>,
    /// forward[m·d̄ + d − 1] = L(y_m, t_m, d); backward likewise for scan t_m − d.
    forward: Vec<Vec<MeasId>>,
    backward: Vec<Vec<MeasId>>,
}

impl Problem {
    /// An empty problem whose first scan is `first_frame`, with the neighbourhood radius and
    /// depth of `model`.
    pub fn empty(model: &Model, first_frame: Frame) -> Self {
        Self {
            first_frame,
            max_gap: model.max_gap() as usize,
            radius_per_scan: model.radius_per_scan,
            positions: Vec::new(),
            scan_of: Vec::new(),
            n_scans: 0,
            held: Vec::new(),
            members: Vec::new(),
            forward: Vec::new(),
            backward: Vec::new(),
        }
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
            .map(|p| self.add_measurement(frame, *p))
            .collect()
    }

    /// Adds one measurement to the existing scan at `frame` (a late measurement joins its own
    /// scan) and links it into the neighbourhoods.
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
        let id = MeasId::try_from(self.positions.len()).map_err(|_| Error::TooManyMeasurements)?;
        self.positions.push(position);
        self.scan_of.push(scan as u32);
        let d_bar = self.max_gap;
        self.forward.extend((0..d_bar).map(|_| Vec::new()));
        self.backward.extend((0..d_bar).map(|_| Vec::new()));
        for d in 1..=d_bar {
            let later: Vec<MeasId> = self
                .scan(scan + d)
                .iter()
                .copied()
                .filter(|&other| self.within(id, other, d))
                .collect();
            for other in later {
                self.forward[id as usize * d_bar + d - 1].push(other);
                self.backward[other as usize * d_bar + d - 1].push(id);
            }
            let earlier: Vec<MeasId> = scan
                .checked_sub(d)
                .map_or(&[][..], |s| self.scan(s))
                .iter()
                .copied()
                .filter(|&other| self.within(id, other, d))
                .collect();
            for other in earlier {
                self.backward[id as usize * d_bar + d - 1].push(other);
                self.forward[other as usize * d_bar + d - 1].push(id);
            }
        }
        let at = self.held.partition_point(|&s| (s as usize) < scan);
        if self.held.get(at) == Some(&(scan as u32)) {
            self.members[at].push(id);
        } else {
            self.held.insert(at, scan as u32);
            self.members.insert(at, vec![id]);
        }
        Ok(id)
    }

    /// Whether `a` and `b` can be consecutive measurements of one track `d` scans apart.
    pub fn within(&self, a: MeasId, b: MeasId, d: usize) -> bool {
        let r = d as f64 * self.radius_per_scan;
        (self.positions[a as usize] - self.positions[b as usize]).norm_squared() <= r * r
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

    /// Number of measurements.
    pub fn n_measurements(&self) -> usize {
        self.positions.len()
    }

    /// d̄.
    pub fn max_gap(&self) -> usize {
        self.max_gap
    }

    /// The measurements of scan index `s` (empty for an empty scan or one past the end).
    pub fn scan(&self, s: usize) -> &[MeasId] {
        match u32::try_from(s).map(|s| self.held.binary_search(&s)) {
            Ok(Ok(i)) => &self.members[i],
            _ => &[],
        }
    }

    /// The non-empty scans among the indices `window`, in increasing order, with their
    /// measurements: what a loop over scans visits when empty scans have nothing to do.
    pub fn nonempty_scans(
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

    /// Whether `m` is a measurement of this problem.
    pub fn contains(&self, m: MeasId) -> bool {
        (m as usize) < self.positions.len()
    }

    /// Position of a measurement.
    pub fn position(&self, m: MeasId) -> Vec2 {
        self.positions[m as usize]
    }

    /// Scan index of a measurement.
    pub fn scan_of(&self, m: MeasId) -> usize {
        self.scan_of[m as usize] as usize
    }

    /// L(y_m, t_m, d), d ∈ 1..=d̄.
    pub fn forward(&self, m: MeasId, d: usize) -> &[MeasId] {
        &self.forward[m as usize * self.max_gap + d - 1]
    }

    /// The measurements y' of scan t_m − d with y_m ∈ L(y', t_m − d, d).
    pub fn backward(&self, m: MeasId, d: usize) -> &[MeasId] {
        &self.backward[m as usize * self.max_gap + d - 1]
    }
}
