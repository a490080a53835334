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
//! Tracking your detector's boxes frame by frame with the SMC-PHD filter alone:
//!
//! ```
//! use phd_filter::{PhdConfig, PhdTracker, SmcPhd};
//! use tracker_model::BoundingBox;
//!
//! let mut tracker = PhdTracker::global_only(SmcPhd::new(PhdConfig::default(), 7)?);
//! for frame in 0..8 {
//!     // This frame's detections (left, top, width, height): two people walking apart.
//!     let dx = 3.0 * f64::from(frame);
//!     let person_1 = BoundingBox::new(100.0 - dx, 200.0, 40.0, 100.0)?;
//!     let person_2 = BoundingBox::new(400.0 + dx, 180.0, 45.0, 110.0)?;
//!     tracker.step(frame, &[person_1, person_2])?;
//! }
//! let tracks = tracker.tracks()?;
//! // One track per person, each followed to the last frame.
//! assert!(tracks.len() == 2 && tracks.tracks().iter().all(|t| t.last_frame() == Some(7)));
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
