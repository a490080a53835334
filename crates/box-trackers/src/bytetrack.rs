//! ByteTrack (Zhang, Sun, Jiang, Yu, Weng, Yuan, Luo, Liu & Wang 2022, Algorithm 1): every
//! box is associated, high-score boxes first to all tracks, then low-score boxes to the
//! tracks the first stage left; tracks start only from unmatched high-score boxes.

use crate::associate::assign_iou;
use crate::config::{ByteTrackConfig, Checked};
use crate::error::Result;
use crate::kalman::{BoxFilter, Corners};
use crate::tracker::{Association, BoxDetection, BoxTracker, IdSource, coasting_of};

/// ByteTrack behind tracker-model's interface.
pub type ByteTrackTracker = BoxTracker<ByteTrack>;

#[derive(Debug, Clone, PartialEq)]
struct ByteTrackTrack {
    filter: BoxFilter,
    number: Option<u64>,
    misses: u32,
    /// Consecutive matches, the first detection included; a missed frame resets it at the
    /// next prediction.
    streak: u32,
}

/// ByteTrack's association.
#[derive(Debug, Clone, PartialEq)]
pub struct ByteTrack {
    config: ByteTrackConfig,
    checked: Checked,
    tracks: Vec<ByteTrackTrack>,
    /// The tracks' predicted boxes this frame, which both stages match against.
    predicted: Vec<Corners>,
}

impl ByteTrackConfig {
    /// Checks the settings and builds the tracker.
    pub fn build(&self) -> Result<ByteTrackTracker> {
        Ok(BoxTracker::new(ByteTrack {
            config: *self,
            checked: self.checked()?,
            tracks: Vec::new(),
            predicted: Vec::new(),
        })
        .coasting(self.coast_frames))
    }
}

impl ByteTrack {
    /// The settings.
    pub fn config(&self) -> &ByteTrackConfig {
        &self.config
    }

    /// Matches `rows` (track indices) by their predicted boxes to the detections `cols`, updates the matched tracks and returns the matching in local
    /// indices, with the confirmed tracks' (detection, number) pairs pushed to `out`.
    fn stage(
        &mut self,
        rows: &[usize],
        cols: &[usize],
        detections: &[BoxDetection],
        threshold: f64,
        ids: &mut IdSource,
        out: &mut Vec<(usize, u64)>,
    ) -> Result<crate::associate::Matching> {
        let row_boxes: Vec<Corners> = rows.iter().map(|&r| self.predicted[r]).collect();
        let col_boxes: Vec<Corners> = cols.iter().map(|&c| detections[c].corners).collect();
        let matching = assign_iou(&row_boxes, &col_boxes, threshold)?;
        let noise = &self.checked.noise;
        for &(r, c) in &matching.matched {
            let track = &mut self.tracks[rows[r]];
            track
                .filter
                .update(noise, &noise.layout.measure(&col_boxes[c]))?;
            track.misses = 0;
            track.streak += 1;
            if track.number.is_none() && track.streak >= self.config.minimum_consecutive_frames {
                track.number = Some(ids.allocate());
            }
            if let Some(number) = track.number {
                out.push((cols[c], number));
            }
        }
        Ok(matching)
    }
}

impl Association for ByteTrack {
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
            if t.misses > 0 {
                t.streak = 0;
            }
            t.misses += 1;
        }
        self.predicted.clear();
        self.predicted
            .extend(self.tracks.iter().map(|t| t.filter.corners(noise.layout)));
        let c = self.config;
        let (high, low): (Vec<usize>, Vec<usize>) = (0..detections.len())
            .filter(|&i| detections[i].score >= c.low_conf_det_threshold)
            .partition(|&i| detections[i].score >= c.high_conf_det_threshold);
        let mut out = Vec::new();
        let all: Vec<usize> = (0..self.tracks.len()).collect();
        let first = self.stage(
            &all,
            &high,
            detections,
            c.minimum_iou_threshold,
            ids,
            &mut out,
        )?;
        let second_threshold = c.second_iou_threshold.unwrap_or(c.minimum_iou_threshold);
        self.stage(
            &first.unmatched_rows,
            &low,
            detections,
            second_threshold,
            ids,
            &mut out,
        )?;
        for &h in &first.unmatched_cols {
            let d = &detections[high[h]];
            if d.score >= c.track_activation_threshold {
                self.tracks.push(ByteTrackTrack {
                    filter: BoxFilter::new(&self.checked.noise, &d.corners),
                    number: None,
                    misses: 0,
                    streak: 1,
                });
            }
        }
        let max_misses = self.checked.max_misses;
        self.tracks.retain(|t| {
            let mature = t.number.is_some() || t.streak >= c.minimum_consecutive_frames;
            t.misses <= max_misses && (mature || t.misses == 0)
        });
        Ok(out)
    }
    fn coasting(&self, max: u32) -> Vec<(u64, Corners)> {
        let tracks = self.tracks.iter().map(|t| (t.number, t.misses, &t.filter));
        coasting_of(tracks, self.checked.noise.layout, max)
    }
}
