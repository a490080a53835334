//! SORT (Bewley, Ge, Ott, Ramos & Upcroft 2016): a Kalman filter per box, predicted boxes
//! matched to detections by the maximum-IoU assignment, tracks started from unmatched
//! detections and deleted after `max_misses` frames without a match.

use crate::associate::assign_iou;
use crate::config::{Checked, SortConfig};
use crate::error::Result;
use crate::kalman::{BoxFilter, Corners};
use crate::tracker::{Association, BoxDetection, BoxTracker, IdSource, coasting_of};

/// SORT behind tracker-model's interface.
pub type SortTracker = BoxTracker<Sort>;

#[derive(Debug, Clone, PartialEq)]
struct SortTrack {
    filter: BoxFilter,
    number: Option<u64>,
    /// Frames since the last match.
    misses: u32,
    /// Matches, the first detection included (SORT's maturity counts them all, consecutive
    /// or not).
    hits: u32,
}

/// SORT's association.
#[derive(Debug, Clone, PartialEq)]
pub struct Sort {
    config: SortConfig,
    checked: Checked,
    tracks: Vec<SortTrack>,
}

impl SortConfig {
    /// Checks the settings and builds the tracker.
    pub fn build(&self) -> Result<SortTracker> {
        Ok(BoxTracker::new(Sort {
            config: *self,
            checked: self.checked()?,
            tracks: Vec::new(),
        })
        .coasting(self.coast_frames))
    }
}

impl Sort {
    /// The settings.
    pub fn config(&self) -> &SortConfig {
        &self.config
    }

    /// The live tracks' predicted or updated boxes, confirmed or not.
    pub fn boxes(&self) -> Vec<Corners> {
        let layout = self.checked.noise.layout;
        self.tracks
            .iter()
            .map(|t| t.filter.corners(layout))
            .collect()
    }
}

impl Association for Sort {
    fn has_tracks(&self) -> bool {
        !self.tracks.is_empty()
    }

    fn associate(
        &mut self,
        detections: &[BoxDetection],
        ids: &mut IdSource,
    ) -> Result<Vec<(usize, u64)>> {
        let noise = &self.checked.noise;
        for t in &mut self.tracks {
            t.filter.predict(noise);
            t.misses += 1;
        }
        let boxes: Vec<Corners> = detections.iter().map(|d| d.corners).collect();
        let matching = assign_iou(&self.boxes(), &boxes, self.config.minimum_iou_threshold)?;
        let mut out = Vec::with_capacity(matching.matched.len());
        for &(row, col) in &matching.matched {
            let track = &mut self.tracks[row];
            track
                .filter
                .update(noise, &noise.layout.measure(&boxes[col]))?;
            track.misses = 0;
            track.hits += 1;
            // Numbers go to tracks as they mature, in the order of the matches.
            if track.hits >= self.config.minimum_consecutive_frames {
                let number = *track.number.get_or_insert_with(|| ids.allocate());
                out.push((col, number));
            }
        }
        for &col in &matching.unmatched_cols {
            if detections[col].score >= self.config.track_activation_threshold {
                self.tracks.push(SortTrack {
                    filter: BoxFilter::new(noise, &boxes[col]),
                    number: None,
                    misses: 0,
                    hits: 1,
                });
            }
        }
        let (max_misses, min_hits) = (
            self.checked.max_misses,
            self.config.minimum_consecutive_frames,
        );
        self.tracks
            .retain(|t| t.misses <= max_misses && (t.hits >= min_hits || t.misses == 0));
        Ok(out)
    }
    fn coasting(&self, max: u32) -> Vec<(u64, Corners)> {
        let tracks = self.tracks.iter().map(|t| (t.number, t.misses, &t.filter));
        coasting_of(tracks, self.checked.noise.layout, max)
    }
}
