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
/// Scans are consecutive frames starting at [`Problem::first_frame`]; a scan may be empty.
/// Measurements can be added to any scan already present (late measurements), and their
/// neighbourhood entries are added on both sides, so nothing is recomputed.
#[derive(Debug, Clone)]
pub struct Problem {
    first_frame: Frame,
    max_gap: usize,
    radius_per_scan: f64,
    positions: Vec<Vec2>,
    scan_of: Vec<u32>,
    /// Members of each scan, by scan index (frame − first_frame).
    scans: Vec<Vec<MeasId>>,
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
            scans: Vec::new(),
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

    /// Appends the scan at `frame` (after any empty scans needed to reach it). Returns the ids
    /// given to `points`, in order.
    pub fn push_scan(&mut self, frame: Frame, points: &[Vec2]) -> Result<Vec<MeasId>> {
        let next = self.first_frame + self.scans.len() as Frame;
        if frame < next {
            return Err(if self.scans.is_empty() {
                Error::FrameBeforeFirst {
                    frame,
                    first: self.first_frame,
                }
            } else {
                Error::FramesOutOfOrder {
                    frame,
                    last: next - 1,
                }
            });
        }
        while self.first_frame + (self.scans.len() as Frame) <= frame {
            self.scans.push(Vec::new());
        }
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
            .filter(|s| *s < self.scans.len())
            .ok_or(Error::FrameNotHeld {
                frame,
                first: self.first_frame,
                end: self.first_frame + self.scans.len() as Frame,
            })?;
        let id = MeasId::try_from(self.positions.len()).map_err(|_| Error::TooManyMeasurements)?;
        self.positions.push(position);
        self.scan_of.push(scan as u32);
        let d_bar = self.max_gap;
        self.forward.extend((0..d_bar).map(|_| Vec::new()));
        self.backward.extend((0..d_bar).map(|_| Vec::new()));
        for d in 1..=d_bar {
            if let Some(later) = self.scans.get(scan + d) {
                for &other in later {
                    if self.within(id, other, d) {
                        self.forward[id as usize * d_bar + d - 1].push(other);
                        self.backward[other as usize * d_bar + d - 1].push(id);
                    }
                }
            }
            if let Some(earlier) = scan.checked_sub(d).map(|s| &self.scans[s]) {
                for &other in earlier {
                    if self.within(id, other, d) {
                        self.backward[id as usize * d_bar + d - 1].push(other);
                        self.forward[other as usize * d_bar + d - 1].push(id);
                    }
                }
            }
        }
        self.scans[scan].push(id);
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
        self.scans.len()
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
        match self.scans.len() {
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

    /// The measurements of scan index `s`.
    pub fn scan(&self, s: usize) -> &[MeasId] {
        &self.scans[s]
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
