//! OC-SORT (Cao, Pang, Weng, Khirodkar & Kitani 2023): SORT made observation-centric.
//! - **ORU** (§3.2): a track found again after a gap is rolled back to where it was lost and
//!   re-updated along a straight virtual trajectory from its last observation to the new
//!   one, so the filter's error over the gap does not carry on.
//! - **OCM** (§3.3, eq. 3's cost): the assignment weighs, beside the IoU, how well the
//!   direction from a track's observation Δt frames back to a detection agrees with the
//!   track's own direction, scaled by the detection's score.
//! - **OCR** (§3.4): tracks left unmatched are matched once more by their last observation.

use std::f64::consts::PI;

use crate::associate::{Matching, Matrix, assign};
use crate::config::{Checked, OcSortConfig};
use crate::error::Result;
use crate::kalman::{BoxFilter, Corners, Noise, StateLayout};
use crate::tracker::{Association, BoxDetection, BoxTracker, IdSource, coasting_of};

/// OC-SORT behind tracker-model's interface.
pub type OcSortTracker = BoxTracker<OcSort>;

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct OcSortTrack {
    pub(crate) filter: BoxFilter,
    pub(crate) number: Option<u64>,
    pub(crate) misses: u32,
    /// Consecutive matches (the first detection not counted, as in the reference).
    pub(crate) streak: u32,
    /// Predictions so far: the clock observations are kept by.
    pub(crate) age: u64,
    pub(crate) last_observation: Corners,
    /// The observations of the last Δt + 1 ages, oldest first.
    pub(crate) observations: Vec<(u64, Corners)>,
    /// The unit direction (dy, dx) from the observation Δt back to the latest one.
    pub(crate) velocity: Option<[f64; 2]>,
    /// The filter as it was when the track was first missed (ORU rolls back to it).
    pub(crate) frozen: Option<BoxFilter>,
    pub(crate) observed: bool,
}

/// The unit vector (dy, dx) from the centre of `from` to the centre of `to`.
fn direction(from: &Corners, to: &Corners) -> [f64; 2] {
    let (cx1, cy1) = ((from[0] + from[2]) / 2.0, (from[1] + from[3]) / 2.0);
    let (cx2, cy2) = ((to[0] + to[2]) / 2.0, (to[1] + to[3]) / 2.0);
    let (dy, dx) = (cy2 - cy1, cx2 - cx1);
    let norm = (dy * dy + dx * dx).sqrt() + 1e-6;
    [dy / norm, dx / norm]
}

impl OcSortTrack {
    pub(crate) fn new(noise: &Noise, b: &Corners) -> Self {
        Self {
            filter: BoxFilter::new(noise, b),
            number: None,
            misses: 0,
            streak: 0,
            age: 0,
            last_observation: *b,
            observations: Vec::new(),
            velocity: None,
            frozen: None,
            observed: true,
        }
    }

    pub(crate) fn predict(&mut self, noise: &Noise) {
        if self.observed && self.misses > 0 {
            self.frozen = Some(self.filter.clone());
            self.observed = false;
        }
        self.filter.predict(noise);
        if self.misses > 0 {
            self.streak = 0;
        }
        self.misses += 1;
        self.age += 1;
    }

    /// The observation Δt ages back, else the nearest of fewer ages back, else the latest.
    pub(crate) fn k_previous(&self, delta_t: u32) -> Option<&Corners> {
        let at = |age: u64| self.observations.iter().find(|(a, _)| *a == age);
        (1..=u64::from(delta_t))
            .rev()
            .find_map(|dt| self.age.checked_sub(dt).and_then(at))
            .or(self.observations.last())
            .map(|(_, b)| b)
    }

    pub(crate) fn update(&mut self, noise: &Noise, b: &Corners, delta_t: u32) -> Result<()> {
        if let Some(previous) = self.k_previous(delta_t) {
            self.velocity = Some(direction(previous, b));
        }
        if !self.observed
            && let Some(frozen) = self.frozen.take()
        {
            self.filter = frozen;
            self.re_update(noise, b)?;
        }
        self.filter.update(noise, &noise.layout.measure(b))?;
        self.observed = true;
        self.misses = 0;
        self.streak += 1;
        self.last_observation = *b;
        match self.observations.last_mut() {
            Some(last) if last.0 == self.age => last.1 = *b,
            _ => self.observations.push((self.age, *b)),
        }
        let cutoff = self.age.saturating_sub(u64::from(delta_t));
        self.observations.retain(|(a, _)| *a >= cutoff);
        Ok(())
    }

    /// ORU: from the frozen filter, one update per frame of the gap with the virtual
    /// observations on the line from the last observation to `b` (the last of them is `b`
    /// itself; the caller's real update follows, as in the reference).
    fn re_update(&mut self, noise: &Noise, b: &Corners) -> Result<()> {
        let gap = self.misses;
        // The line runs through the corners, or through centre, width and height (the
        // reference's w = √(s r), h = √(s / r) of the measurements).
        let centre_size = |z: [f64; 4]| {
            let w = (z[2] * z[3]).sqrt();
            let h = if z[3] != 0.0 {
                (z[2] / z[3]).sqrt()
            } else {
                0.0
            };
            [z[0], z[1], w, h]
        };
        let (from, to) = match noise.layout {
            StateLayout::Corners => (self.last_observation, *b),
            StateLayout::CentreAreaAspect => (
                centre_size(noise.layout.measure(&self.last_observation)),
                centre_size(noise.layout.measure(b)),
            ),
        };
        let step: [f64; 4] = std::array::from_fn(|i| (to[i] - from[i]) / f64::from(gap));
        for i in 0..gap {
            let k = f64::from(i + 1);
            let v: [f64; 4] = std::array::from_fn(|j| from[j] + k * step[j]);
            let z = match noise.layout {
                StateLayout::Corners => v,
                StateLayout::CentreAreaAspect => [v[0], v[1], v[2] * v[3], v[2] / v[3]],
            };
            self.filter.update(noise, &z)?;
            if i + 1 < gap {
                self.filter.predict(noise);
            }
        }
        Ok(())
    }
}

/// OC-SORT's association.
#[derive(Debug, Clone, PartialEq)]
pub struct OcSort {
    config: OcSortConfig,
    checked: Checked,
    tracks: Vec<OcSortTrack>,
    /// Frames stepped with a track or a detection (the reference's `frame_count`): in the
    /// first `minimum_consecutive_frames` of them any match is output.
    frame_count: u64,
}

impl OcSortConfig {
    /// Checks the settings and builds the tracker.
    pub fn build(&self) -> Result<OcSortTracker> {
        Ok(BoxTracker::new(OcSort {
            config: *self,
            checked: self.checked()?,
            tracks: Vec::new(),
            frame_count: 0,
        })
        .coasting(self.coast_frames))
    }
}

/// The direction-consistency score of every track with every box (OCM): (π/2 − |Δθ|)/π of
/// the angle between the track's direction and the direction from its observation Δt back to
/// the box, 0 for a track with no direction yet, times the box's score; rounded to f32 as in
/// the reference.
pub(crate) fn direction_scores(
    tracks: &[OcSortTrack],
    boxes: &[&BoxDetection],
    delta_t: u32,
) -> Matrix {
    let mut values = Vec::with_capacity(tracks.len() * boxes.len());
    for t in tracks {
        let from = t.k_previous(delta_t).unwrap_or(&t.last_observation);
        let (inertia, mask) = t.velocity.map_or(([0.0, 0.0], 0.0), |v| (v, 1.0));
        values.extend(boxes.iter().map(|d| {
            let [dy, dx] = direction(from, &d.corners);
            let cos = (inertia[1] * dx + inertia[0] * dy).clamp(-1.0, 1.0);
            let cost = (mask * ((PI / 2.0 - cos.acos().abs()) / PI)) as f32;
            (f64::from(cost) * d.score) as f32
        }));
    }
    Matrix {
        n_rows: tracks.len(),
        n_cols: boxes.len(),
        values,
    }
}

impl OcSort {
    /// The settings.
    pub fn config(&self) -> &OcSortConfig {
        &self.config
    }

    /// The track's number if it is output now: any match in the first frames, else a track
    /// with enough consecutive matches; numbered when first output.
    fn output_number(&mut self, track: usize, ids: &mut IdSource) -> Option<u64> {
        let min = self.config.minimum_consecutive_frames;
        let t = &mut self.tracks[track];
        let output = if self.frame_count <= u64::from(min) {
            t.misses == 0
        } else {
            t.streak >= min
        };
        output.then(|| *t.number.get_or_insert_with(|| ids.allocate()))
    }

    fn match_and_update(
        &mut self,
        pairs: impl IntoIterator<Item = (usize, usize)>,
        high: &[&BoxDetection],
        high_index: &[usize],
        ids: &mut IdSource,
        out: &mut Vec<(usize, u64)>,
    ) -> Result<()> {
        for (track, col) in pairs {
            let delta_t = self.config.delta_t;
            self.tracks[track].update(&self.checked.noise, &high[col].corners, delta_t)?;
            if let Some(number) = self.output_number(track, ids) {
                out.push((high_index[col], number));
            }
        }
        Ok(())
    }

    /// The first association: IoU of the predictions plus λ times the direction term, gated
    /// on the IoU alone.
    fn first_matching(&self, high: &[&BoxDetection]) -> Result<Matching> {
        let layout = self.checked.noise.layout;
        let predicted: Vec<Corners> = self
            .tracks
            .iter()
            .map(|t| t.filter.corners(layout))
            .collect();
        let boxes: Vec<Corners> = high.iter().map(|d| d.corners).collect();
        let iou = Matrix::iou(&predicted, &boxes);
        let weight = self.config.direction_consistency_weight;
        if weight == 0.0 {
            return assign(&iou, &iou, self.config.minimum_iou_threshold);
        }
        let mut score = direction_scores(&self.tracks, high, self.config.delta_t);
        let weight = weight as f32;
        for (s, i) in score.values.iter_mut().zip(&iou.values) {
            *s = i + weight * *s;
        }
        assign(&score, &iou, self.config.minimum_iou_threshold)
    }
}

impl Association for OcSort {
    fn has_tracks(&self) -> bool {
        !self.tracks.is_empty()
    }

    fn associate(
        &mut self,
        detections: &[BoxDetection],
        ids: &mut IdSource,
    ) -> Result<Vec<(usize, u64)>> {
        if self.tracks.is_empty() && detections.is_empty() {
            return Ok(Vec::new());
        }
        let high_index: Vec<usize> = (0..detections.len())
            .filter(|&i| detections[i].score >= self.config.high_conf_det_threshold)
            .collect();
        let high: Vec<&BoxDetection> = high_index.iter().map(|&i| &detections[i]).collect();
        for t in &mut self.tracks {
            t.predict(&self.checked.noise);
        }
        let first = self.first_matching(&high)?;
        let mut out = Vec::new();
        self.match_and_update(first.matched, &high, &high_index, ids, &mut out)?;
        let mut unmatched = first.unmatched_cols;
        if !unmatched.is_empty() && !first.unmatched_rows.is_empty() {
            // OCR: the tracks left, by their last observations.
            let last: Vec<Corners> = first
                .unmatched_rows
                .iter()
                .map(|&t| self.tracks[t].last_observation)
                .collect();
            let boxes: Vec<Corners> = unmatched.iter().map(|&c| high[c].corners).collect();
            let iou = Matrix::iou(&last, &boxes);
            let ocr = assign(&iou, &iou, self.config.minimum_iou_threshold)?;
            let pairs = ocr
                .matched
                .iter()
                .map(|&(r, c)| (first.unmatched_rows[r], unmatched[c]));
            let pairs: Vec<_> = pairs.collect();
            self.match_and_update(pairs, &high, &high_index, ids, &mut out)?;
            unmatched = ocr.unmatched_cols.iter().map(|&c| unmatched[c]).collect();
        }
        for &c in &unmatched {
            let track = OcSortTrack::new(&self.checked.noise, &high[c].corners);
            self.tracks.push(track);
        }
        let max_misses = self.checked.max_misses;
        self.tracks.retain(|t| t.misses <= max_misses);
        self.frame_count += 1;
        Ok(out)
    }
    fn coasting(&self, max: u32) -> Vec<(u64, Corners)> {
        let tracks = self.tracks.iter().map(|t| (t.number, t.misses, &t.filter));
        coasting_of(tracks, self.checked.noise.layout, max)
    }
}
