//! Distributed multi-target tracking and identity management (DMTIM; Oh, Hwang & Sastry,
//! JGCD 31(1) 2008, after Hwang, Roy, Balakrishnan & Tomlin, CDC 2004).
//!
//! N sensors with circular ranges ([`SensorSpec`]) each track their own measurements with
//! online MCMCDA ([`mcmcda::OnlineTracker`]) and keep an identity belief matrix
//! ([`identity_mgmt::BeliefMatrix`]: all identities the sensor knows × its tracks). The run
//! has two phases:
//!
//! 1. [`track_all`]: each sensor's tracker, and where tracks come within
//!    `interaction_distance_m` of each other, a mixing matrix from MCMC samples of the window
//!    ([`mcmcda::OnlineTracker::sample_joins`] → [`identity_mgmt::Continuation::from_samples`])
//!    when they separate. Beliefs do not feed back into tracking, so this runs once and
//!    every identity variant replays it.
//! 2. [`manage_identities`]: per frame, mixing; hand-over of tracks that end near the edge of
//!    a range to the neighbours they head for; new tracks adopt a hand-over or a neighbour's
//!    matched track, or are announced new targets, or are unknown (uniform); local
//!    information (a transponder read, possibly wrong) rescaled by Sinkhorn; the query-based
//!    exchange: each sensor asks its neighbours (overlapping ranges) for their track
//!    estimates and belief columns (never raw measurements), matches tracks of one target by
//!    optimal assignment under a Mahalanobis gate and fuses the columns by a selectable
//!    criterion. Bytes exchanged are counted against what sending the raw measurements of
//!    the same queries would cost.
//!
//! Baselines: [`centralised`] observations (one tracker over all measurements) through the
//! same two phases, and [`IdentityMode::NearestTrack`] (identities follow the nearest track
//! estimate, no MCMC labels, no mixing).
//!
//! The truth is used only to generate observations ([`observe`]), to announce a target's
//! identity when it first appears (the papers' premise), to de-duplicate the centralised
//! scan, and to score.
//!
//! An aircraft's identity, announced to the radar where it appears, carried on to the next:
//!
//! ```
//! use dmtim::{DmtimConfig, SensorSpec, TruthTarget, manage_identities, observe, track_all};
//! use identity_mgmt::IdentityId;
//! use rand::SeedableRng;
//! use tracker_model::{ConstantVelocity2, Vec2};
//!
//! // Radars 30 m apart with 20 m ranges; aircraft 7 appears to the first, flies into the second.
//! let radar = |x: f64| SensorSpec { name: format!("x{x}"), centre: [x, 0.0], range_m: 20.0 };
//! let mut config = DmtimConfig { sensors: vec![radar(0.0), radar(30.0)], ..Default::default() };
//! config.mcmcda.measurement_noise = nalgebra::Matrix2::identity() * 0.09; // σ = 0.3 m
//! config.mcmcda.motion = ConstantVelocity2::mcmcda(1.0, 0.01)?; // metres and frames
//! let flight = [Vec2::new(-15.0, 0.0), Vec2::new(45.0, 0.0)];
//! let truth = [TruthTarget::along(IdentityId(7), 0, &flight, 1.0)?]; // 1 m a frame
//! let obs = observe(&truth, &config, 60, &mut rand_chacha::ChaCha8Rng::seed_from_u64(1))?;
//! let run = manage_identities(&track_all(&obs, &config, 1)?, &obs, &truth, &config)?;
//! assert_eq!(run.final_beliefs[1].argmax()[0].identity, Some(IdentityId(7)));
//! # Ok::<(), dmtim::Error>(())
//! ```

mod config;
mod error;
mod identity;
mod scene;
mod tracking;

#[cfg(test)]
mod tests;

pub use config::{
    DmtimConfig, IdentityMode, LocalInfoConfig, ReadUpdate, SensingConfig, SensorSpec,
};
pub use error::{Error, Result};
pub use identity::{
    BYTES_PER_MEASUREMENT, BYTES_PER_NUMBER, Event, EventKind, IdentityRun, ReadRule, Snapshot,
    manage_identities,
};
pub use scene::{Observations, Read, SensorScan, TruthTarget, centralised, observe, seven_radars};
pub use tracking::{Mixing, SensorFrame, track_all, track_sensor};
