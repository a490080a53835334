//! The three trackers' settings, with the reference's defaults, checked once when a tracker
//! is built. Every count has an upper bound.

use serde::{Deserialize, Serialize};
use tracker_model::{Error as ModelError, ensure_in_range, ensure_positive};

use crate::error::Result;
use crate::kalman::{Noise, StateLayout};

/// The largest `lost_track_buffer`: 3,000 frames at 30 fps (100 s).
pub const MAX_LOST_TRACK_BUFFER: u32 = 3_000;
/// The largest `frame_rate`, in frames per second.
pub const MAX_FRAME_RATE: f64 = 300.0;
/// The largest `minimum_consecutive_frames`.
pub const MAX_CONSECUTIVE_FRAMES: u32 = 1_000;
/// The largest OC-SORT `delta_t`.
pub const MAX_DELTA_T: u32 = 100;

fn invalid(name: &'static str, reason: String) -> ModelError {
    ModelError::InvalidParameter { name, reason }
}

/// The frames a confirmed track may go unmatched before it is deleted: `lost_track_buffer`
/// frames at 30 fps scaled to `frame_rate`, at least one for a positive buffer (the
/// reference's rule).
fn max_misses(lost_track_buffer: u32, frame_rate: f64) -> Result<u32> {
    let buffer = f64::from(lost_track_buffer);
    ensure_at_most(
        buffer,
        f64::from(MAX_LOST_TRACK_BUFFER),
        "lost_track_buffer",
        " frames",
    )?;
    ensure_positive(frame_rate, "frame_rate")?;
    ensure_at_most(
        frame_rate,
        MAX_FRAME_RATE,
        "frame_rate",
        " frames per second",
    )?;
    if lost_track_buffer == 0 {
        return Ok(0);
    }
    let scaled = (frame_rate / 30.0 * buffer).ceil();
    Ok((scaled as u32).max(1))
}

/// `value` at most `max` (every count and rate a user sets has a limit), `unit` after the
/// limit in the message.
fn ensure_at_most(value: f64, max: f64, name: &'static str, unit: &str) -> Result<()> {
    if value > max {
        return Err(invalid(name, format!("{value} is above the limit of {max}{unit}")).into());
    }
    Ok(())
}

fn ensure_threshold(value: f64, name: &'static str) -> Result<f64> {
    Ok(ensure_in_range(value, 0.0, 1.0, name)?)
}

/// The largest `coast_frames`.
pub const MAX_COAST_FRAMES: u32 = 1_000;

fn ensure_coast(value: u32) -> Result<()> {
    let max = f64::from(MAX_COAST_FRAMES);
    ensure_at_most(
        f64::from(value),
        max,
        "coast_frames",
        ": each is a box per track",
    )
}

fn ensure_consecutive(value: u32) -> Result<()> {
    let max = f64::from(MAX_CONSECUTIVE_FRAMES);
    ensure_at_most(f64::from(value), max, "minimum_consecutive_frames", "")
}

/// What every tracker's settings give once checked.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Checked {
    pub noise: Noise,
    pub max_misses: u32,
}

/// SORT (Bewley et al. 2016) as roboflow `trackers` 2.6.1 runs it.
///
/// Departures from the paper, each with the paper's value as a setting: the state is the
/// corners (the paper's centre, area and aspect is `state = "centre-area-aspect"`, with the
/// paper's noise), and a track lives 30 frames without a match (the paper deletes after one:
/// `lost_track_buffer = 1`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SortConfig {
    /// Frames at 30 fps a track lives without a match (scaled by `frame_rate`).
    pub lost_track_buffer: u32,
    /// The video's frame rate, frames per second.
    pub frame_rate: f64,
    /// The least score that starts a track.
    pub track_activation_threshold: f64,
    /// Matches (counting the first detection) before a track is output.
    pub minimum_consecutive_frames: u32,
    /// The least IoU of a match.
    pub minimum_iou_threshold: f64,
    /// Frames a confirmed track is output at its predicted box after a miss (0, the
    /// reference's way: only the detections given to tracks are output).
    pub coast_frames: u32,
    /// The Kalman state.
    pub state: StateLayout,
}

impl Default for SortConfig {
    fn default() -> Self {
        Self {
            lost_track_buffer: 30,
            frame_rate: 30.0,
            track_activation_threshold: 0.25,
            minimum_consecutive_frames: 3,
            minimum_iou_threshold: 0.3,
            coast_frames: 0,
            state: StateLayout::Corners,
        }
    }
}

impl SortConfig {
    pub(crate) fn checked(&self) -> Result<Checked> {
        ensure_threshold(
            self.track_activation_threshold,
            "track_activation_threshold",
        )?;
        ensure_threshold(self.minimum_iou_threshold, "minimum_iou_threshold")?;
        ensure_consecutive(self.minimum_consecutive_frames)?;
        ensure_coast(self.coast_frames)?;
        Ok(Checked {
            noise: paper_noise(self.state, 0.1, 0.01, 1.0),
            max_misses: max_misses(self.lost_track_buffer, self.frame_rate)?,
        })
    }
}

/// ByteTrack (Zhang et al. 2022) as roboflow `trackers` 2.6.1 runs it: high-score boxes are
/// matched to every track first, then the low-score boxes to the tracks left; only
/// high-score boxes above `track_activation_threshold` start tracks.
///
/// Departures from the paper: every box below `high_conf_det_threshold` enters the second
/// stage (the paper drops those below 0.1: `low_conf_det_threshold = 0.1`); both stages gate
/// at one IoU (the paper's second stage needs 0.5: `second_iou_threshold = 0.5`); the
/// paper's separate matching of unconfirmed tracks and its score-weighted IoU are not
/// offered.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ByteTrackConfig {
    /// Frames at 30 fps a track lives without a match (scaled by `frame_rate`).
    pub lost_track_buffer: u32,
    /// The video's frame rate, frames per second.
    pub frame_rate: f64,
    /// The least score that starts a track.
    pub track_activation_threshold: f64,
    /// Consecutive matches (counting the first detection) before a track is confirmed.
    pub minimum_consecutive_frames: u32,
    /// The least IoU of a match in the first stage (and the second, unless set apart).
    pub minimum_iou_threshold: f64,
    /// Boxes scoring at least this are high-score boxes.
    pub high_conf_det_threshold: f64,
    /// Boxes scoring below this are dropped (0 keeps every box).
    pub low_conf_det_threshold: f64,
    /// The least IoU of a second-stage match, when it differs from the first stage's.
    pub second_iou_threshold: Option<f64>,
    /// Frames a confirmed track is output at its predicted box after a miss (0, the
    /// reference's way: only the detections given to tracks are output).
    pub coast_frames: u32,
    /// The Kalman state.
    pub state: StateLayout,
}

impl Default for ByteTrackConfig {
    fn default() -> Self {
        Self {
            lost_track_buffer: 30,
            frame_rate: 30.0,
            track_activation_threshold: 0.7,
            minimum_consecutive_frames: 2,
            minimum_iou_threshold: 0.1,
            high_conf_det_threshold: 0.6,
            low_conf_det_threshold: 0.0,
            second_iou_threshold: None,
            coast_frames: 0,
            state: StateLayout::Corners,
        }
    }
}

impl ByteTrackConfig {
    pub(crate) fn checked(&self) -> Result<Checked> {
        ensure_threshold(
            self.track_activation_threshold,
            "track_activation_threshold",
        )?;
        ensure_threshold(self.minimum_iou_threshold, "minimum_iou_threshold")?;
        ensure_threshold(self.high_conf_det_threshold, "high_conf_det_threshold")?;
        ensure_threshold(self.low_conf_det_threshold, "low_conf_det_threshold")?;
        if let Some(t) = self.second_iou_threshold {
            ensure_threshold(t, "second_iou_threshold")?;
        }
        if self.low_conf_det_threshold > self.high_conf_det_threshold {
            return Err(invalid(
                "low_conf_det_threshold",
                format!(
                    "{} is above high_conf_det_threshold = {}: no box would be a low-score box",
                    self.low_conf_det_threshold, self.high_conf_det_threshold
                ),
            )
            .into());
        }
        ensure_consecutive(self.minimum_consecutive_frames)?;
        ensure_coast(self.coast_frames)?;
        // The reference scales its identity matrices the same way in either layout.
        let noise = Noise::diagonal(self.state, [0.01; 8], [0.1; 4], [1.0; 8]);
        Ok(Checked {
            noise,
            max_misses: max_misses(self.lost_track_buffer, self.frame_rate)?,
        })
    }
}

/// OC-SORT (Cao et al. 2023) as roboflow `trackers` 2.6.1 runs it: observation-centric
/// re-update after a gap (ORU), the direction term in the cost (OCM), and a second match of
/// the tracks left to their last observations (OCR). Boxes below `high_conf_det_threshold`
/// are not used (the paper's default, without its optional BYTE stage).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OcSortConfig {
    /// Frames at 30 fps a track lives without a match (scaled by `frame_rate`).
    pub lost_track_buffer: u32,
    /// The video's frame rate, frames per second.
    pub frame_rate: f64,
    /// Consecutive matches before a track is output (any match in the first frames).
    pub minimum_consecutive_frames: u32,
    /// The least IoU of a match.
    pub minimum_iou_threshold: f64,
    /// The weight λ of the direction term (paper eq. 3's OCM cost).
    pub direction_consistency_weight: f64,
    /// Boxes scoring at least this are used.
    pub high_conf_det_threshold: f64,
    /// Frames back to the observation the direction is measured from (paper's Δt).
    pub delta_t: u32,
    /// Frames a confirmed track is output at its predicted box after a miss (0, the
    /// reference's way: only the detections given to tracks are output).
    pub coast_frames: u32,
    /// The Kalman state.
    pub state: StateLayout,
}

impl Default for OcSortConfig {
    fn default() -> Self {
        Self {
            lost_track_buffer: 30,
            frame_rate: 30.0,
            minimum_consecutive_frames: 3,
            minimum_iou_threshold: 0.3,
            direction_consistency_weight: 0.2,
            high_conf_det_threshold: 0.6,
            delta_t: 3,
            coast_frames: 0,
            state: StateLayout::CentreAreaAspect,
        }
    }
}

impl OcSortConfig {
    pub(crate) fn checked(&self) -> Result<Checked> {
        ensure_threshold(self.minimum_iou_threshold, "minimum_iou_threshold")?;
        ensure_threshold(self.high_conf_det_threshold, "high_conf_det_threshold")?;
        ensure_in_range(
            self.direction_consistency_weight,
            0.0,
            10.0,
            "direction_consistency_weight",
        )?;
        ensure_consecutive(self.minimum_consecutive_frames)?;
        ensure_coast(self.coast_frames)?;
        if self.delta_t == 0 || self.delta_t > MAX_DELTA_T {
            return Err(invalid(
                "delta_t",
                format!("{} must be from 1 to {MAX_DELTA_T} frames", self.delta_t),
            )
            .into());
        }
        let noise = match self.state {
            StateLayout::CentreAreaAspect => paper_noise(self.state, 0.1, 0.01, 1.0),
            StateLayout::Corners => Noise::diagonal(
                self.state,
                [1.0, 1.0, 1.0, 1.0, 0.01, 0.01, 0.01, 0.01],
                [1.0; 4],
                [
                    10.0, 10.0, 10.0, 10.0, 10_000.0, 10_000.0, 10_000.0, 10_000.0,
                ],
            ),
        };
        Ok(Checked {
            noise,
            max_misses: max_misses(self.lost_track_buffer, self.frame_rate)?,
        })
    }
}

/// SORT's noise: in the centre layout the original SORT filter's (Bewley et al.'s code, which
/// OC-SORT keeps): R = diag(1, 1, 10, 10), P₀ = 10 · diag(1, 1, 1, 1, 1000, 1000, 1000),
/// Q = diag(1, 1, 1, 1, 0.01, 0.01, 0.0001); in the corner layout R = `r` I, Q = `q` I and
/// P₀ = `p0` I.
fn paper_noise(layout: StateLayout, r: f64, q: f64, p0: f64) -> Noise {
    match layout {
        StateLayout::Corners => Noise::diagonal(layout, [q; 8], [r; 4], [p0; 8]),
        StateLayout::CentreAreaAspect => {
            let slow = 0.01;
            Noise::diagonal(
                layout,
                // The area rate's variance is scaled twice, as the reference does (0.01 · 0.01
                // in f64, not the literal 1e-4).
                [1.0, 1.0, 1.0, 1.0, slow, slow, slow * slow, 0.0],
                [1.0, 1.0, 10.0, 10.0],
                [10.0, 10.0, 10.0, 10.0, 10_000.0, 10_000.0, 10_000.0, 0.0],
            )
        }
    }
}
