//! # phd-filter
//!
//! Probability hypothesis density filters for boxes, and the fusion of a global detector with
//! online local detectors of Yoon, Hwang, Choi & Yoon (2016):
//!
//! * [`SmcPhd`]: the SMC-PHD filter (Vo, Singh & Doucet 2005) with measurement-driven birth and
//!   grouping extraction (Ristic et al. 2012), persistent identities, rayon-parallel and
//!   reproducible for a seed whatever the thread count;
//! * [`GmPhd`]: the Gaussian-mixture PHD filter (Vo & Ma 2006) with pruning, merging, capping;
//! * [`fuse`], [`updated_confidence`], [`DetectorBank`]: eqs. 1-2 and 9-10 of Yoon et al.;
//! * [`PhdTracker`]: their loop (local detections, fusion, filter, detector management), or
//!   the filter alone on the global detections ([`PhdTracker::global_only`]);
//! * [`scene`]: simulated pedestrian scenes with a global detector that misses and fires
//!   falsely, and local detectors behind [`tracker_model::LocalDetector`] that see only the
//!   people inside their search window (never the truth's identities), with their own miss
//!   rate, box noise, occlusion, drift to a neighbour, and clutter templates.
//!
//! Configurations are checked when a filter or tracker is built ([`PhdConfig::check`],
//! [`GmConfig::check`], [`FusionConfig::check`]) and trusted afterwards.
//!
//! Two people standing apart, detected in every frame, become two tracks:
//!
//! ```
//! use phd_filter::{PhdConfig, PhdTracker, SmcPhd};
//! use tracker_model::BoundingBox;
//!
//! // Each frame's detections as [left, top, width, height] in pixels: one person walks right,
//! // the other left.
//! let frames: Vec<Vec<[f64; 4]>> = (0..8)
//!     .map(|t| {
//!         let dx = 2.0 * f64::from(t);
//!         vec![[100.0 + dx, 200.0, 40.0, 100.0], [400.0 - dx, 180.0, 45.0, 110.0]]
//!     })
//!     .collect();
//! let mut tracker = PhdTracker::global_only(SmcPhd::new(PhdConfig::default(), 7)?);
//! for (frame, detections) in (0..).zip(&frames) {
//!     let boxes = detections
//!         .iter()
//!         .map(|&[left, top, width, height]| BoundingBox::new(left, top, width, height))
//!         .collect::<Result<Vec<_>, _>>()?;
//!     tracker.step(frame, &boxes)?;
//! }
//! let tracks = tracker.tracks()?;
//! assert_eq!(tracks.len(), 2);
//! # Ok::<(), phd_filter::Error>(())
//! ```

mod config;
mod error;
mod fusion;
mod gm;
pub mod scene;
mod smc;
mod tracker;

#[cfg(test)]
mod tests;

pub use config::{
    BoxMeasurement, BoxState, Motion, PhdConfig, StateMatrix, measurement_from_box, state_box,
};
pub use error::{Error, Result};
pub use fusion::{
    DetectorBank, FusionConfig, MAX_CONFIDENCE, ManagedDetector, Source, fuse, updated_confidence,
};
pub use gm::{Component, GmConfig, GmPhd};
pub use smc::{Estimate, Particle, PhdStep, SmcPhd};
pub use tracker::{FrameOutput, NoLocalDetectors, PhdFilter, PhdTracker};
