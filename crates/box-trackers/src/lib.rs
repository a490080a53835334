//! The box trackers people run on detection files, behind tracker-model's one
//! [`Tracker`](tracker_model::Tracker) interface:
//! - [`SortConfig`] → SORT (Bewley et al. 2016);
//! - [`ByteTrackConfig`] → ByteTrack (Zhang et al. 2022);
//! - [`OcSortConfig`] → OC-SORT (Cao et al. 2023).
//!
//! With their defaults they equal roboflow `trackers` 2.6.1 (Apache-2.0) on the same files:
//! the same rows, ids up to renaming (`docs/comparisons/roboflow_trackers.py`, checked by this
//! crate's tests against its recorded output). Each config's documentation says where that
//! reference departs from its paper and which setting gives the paper's variant.
//!
//! Like the reference, a step outputs the detections given to confirmed tracks, at the
//! detections' boxes. Frames are stepped in increasing order; a gap costs at most the
//! frames it takes every track to die.
//!
//! ```
//! use box_trackers::ByteTrackConfig;
//! use tracker_model::{BoundingBox, Detection, Tracker};
//!
//! let mut tracker = ByteTrackConfig::default().build()?;
//! for frame in 1..=5 {
//!     let walker = BoundingBox::new(10.0 + 4.0 * f64::from(frame), 20.0, 30.0, 80.0)?;
//!     let clutter = BoundingBox::new(300.0, 40.0 * f64::from(frame), 20.0, 20.0)?;
//!     let detections = [
//!         Detection::boxed(2 * u64::from(frame), frame, walker).with_score(0.9),
//!         Detection::boxed(2 * u64::from(frame) + 1, frame, clutter).with_score(0.3),
//!     ];
//!     tracker.step(frame, &detections)?;
//! }
//! let tracks = tracker.finish()?;
//! assert_eq!(tracks.len(), 1); // the walker, confirmed at its second box
//! assert_eq!(tracks.tracks()[0].len(), 4);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod associate;
mod bytetrack;
mod config;
mod error;
mod kalman;
mod ocsort;
mod sort;
mod tracker;

#[cfg(test)]
mod tests;

pub use associate::{Matching, Matrix, assign, assign_iou, assign_overlapping, iou};
pub use bytetrack::{ByteTrack, ByteTrackTracker};
pub use config::{
    ByteTrackConfig, MAX_COAST_FRAMES, MAX_CONSECUTIVE_FRAMES, MAX_DELTA_T, MAX_FRAME_RATE,
    MAX_LOST_TRACK_BUFFER, OcSortConfig, SortConfig,
};
pub use error::{Error, Result};
pub use kalman::{Corners, StateLayout};
pub use ocsort::{OcSort, OcSortTracker};
pub use sort::{Sort, SortTracker};
pub use tracker::{Assigned, Association, BoxDetection, BoxTracker, IdSource};
