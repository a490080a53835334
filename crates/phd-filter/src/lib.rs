//! # phd-filter
//!
//! Probability hypothesis density filters for boxes, and seed 004's fusion of a global
//! detector with online local detectors:
//!
//! * [`SmcPhd`]: the SMC-PHD filter (Vo, Singh & Doucet 2005) with measurement-driven birth and
//!   grouping extraction (Ristic et al. 2012), persistent identities, rayon-parallel and
//!   reproducible for a seed whatever the thread count;
//! * [`GmPhd`]: the Gaussian-mixture PHD filter (Vo & Ma 2006) with pruning, merging, capping;
//! * [`fuse`], [`updated_confidence`], [`DetectorBank`]: eqs. 1-2 and 9-10 of the seed;
//! * [`PhdTracker`]: the seed's loop (local detections, fusion, filter, detector management);
//! * [`scene`]: simulated pedestrian scenes with a global detector that misses and fires
//!   falsely, and local detectors with their own failures, behind
//!   [`tracker_model::LocalDetector`].

mod config;
mod error;
mod fusion;
mod gm;
pub mod scene;
mod smc;
mod tracker;

#[cfg(test)]
mod tests;

pub use config::{BoxMeasurement, BoxState, Motion, PhdConfig, measurement_from_box, state_box};
pub use error::{Error, Result};
pub use fusion::{DetectorBank, FusionConfig, ManagedDetector, Source, fuse, updated_confidence};
pub use gm::{Component, GmConfig, GmPhd};
pub use smc::{Estimate, Particle, PhdStep, SmcPhd};
pub use tracker::{FrameOutput, NoLocalDetectors, PhdFilter, PhdTracker};
