//! # av-fusion
//!
//! Audio-video fusion tracked by MCMCDA: the multi-sensor system of Kushwaha, Oh, Amundson,
//! Koutsoukos & Ledeczi (MFI 2008), as reviewed by Oh (2012, "Data Association and Its Applications to Intelligent
//! Systems: A Review", §V). Audio nodes report
//! beamforms (energy over 36 beams) and video nodes detection functions (foreground pixels
//! over 160 angles); a fusion node buffers them, fuses them on a grid at a fixed rate and
//! tracks the grid's peaks with online MCMCDA (Kushwaha et al. 2008, §§3-4); choices and
//! numbers in `docs/av-fusion.md`.
//!
//! * [`SensorNode`] (kind, believed pose, profile layout, clock offset, weight, profile
//!   exponent, optional [`LobeEqualisation`] that lifts a profile's weaker lobes) and
//!   [`Report`] (values at a time stamp of the node's own clock; [`Report::from_beamform`]);
//! * [`FusionNode`]: a [`SensorBuffer`] per sensor (circular, kept in time order so late
//!   reports take their place), and [`SchedulerConfig`]: ticks at a fixed rate, each taking
//!   every sensor's report nearest in time within a staleness limit; a sensor with none is
//!   left out of the tick, not zero-filled ([`FusionNode::snapshot`]);
//! * [`fuse_snapshot`]: each profile projected with tracker-model's
//!   [`BearingProfile::project`](tracker_model::BearingProfile::project), fused by
//!   [`FusionRule::WeightedSum`] (each grid scaled to max 1 or sum 1, [`SumScaling`]) or [`FusionRule::Product`] (with a configurable floor so that
//!   one sensor that sees nothing does not zero the grid), peaks by non-maximum suppression
//!   with covariances from the peak's second moments ([`PeakMeasurement`]), optionally one at
//!   a time by explaining away ([`PeakExtraction::explain_away_deg`]);
//! * [`AvPipeline`] / [`track_reports`]: the peak lists through
//!   [`mcmcda::OnlineTracker`] into a [`tracker_model::TrackSet`] whose frames are the ticks,
//!   optionally with each peak's contrast as a detection score ([`PeakScores`]);
//! * [`scene`]: Table 1's road (Kushwaha et al. 2008) with simulated acoustic nodes and
//!   cameras, the six approaches (audio, video, audio+video × weighted sum, floored product)
//!   and each one scored on a simulated run against the truth;
//! * [`tuning`]: the searches on tuning seeds behind the road scene's settings and peak-score
//!   tables, their lines sent to the caller's [`tuning::Log`].
//!
//! One tick of the fusion node on your nodes' reports: three microphone arrays with 8 beams each
//! (beam i points i × 45° from +x) report their beam energies at 0 s, and the floored product
//! of their projections peaks where their loudest beams cross:
//!
//! ```
//! use av_fusion::*;
//! use tracker_model::{Region2, SensorPose, Vec2};
//!
//! let at = |x, y| SensorPose { position: Vec2::new(x, y), heading_rad: 0.0 };
//! let sensors = [at(0.0, 0.0), at(20.0, 0.0), at(10.0, 20.0)].map(|p| SensorNode::audio("mic", p, 8));
//! let mut node = FusionNode::new(sensors.to_vec(), SchedulerConfig::default())?;
//! let report = |sensor, v: [f64; 8]| Report { sensor, local_time_s: 0.0, values: v.into() };
//! node.receive(report(0, [0.2, 1.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0]))?; // loudest towards 45°
//! node.receive(report(1, [0.0, 0.0, 0.2, 1.0, 0.2, 0.0, 0.0, 0.0]))?; // towards 135°
//! node.receive(report(2, [0.0, 0.0, 0.0, 0.0, 0.0, 0.2, 1.0, 0.2]))?; // towards 270°
//! let fusion = FusionConfig { region: Region2::square(20.0)?, cell_size_m: 0.5, max_range_m: None,
//!     min_range_m: 0.5, range_fade: None, rule: FusionRule::Product { floor: 0.05 },
//!     modalities: Modalities::Both, peaks: PeakExtraction::default() };
//! let fused = fuse_snapshot(&sensors, &node.snapshot(0), &fusion)?;
//! assert!((fused.peaks[0].position - Vec2::new(10.0, 10.0)).norm() < 0.5); // within a cell
//! # Ok::<(), av_fusion::Error>(())
//! ```
//!
//! The whole chain, [`track_reports`]: three full-circle nodes around a target that moves along
//! x at 10 m/s, fused at 10 Hz by the floored product and tracked:
//!
//! ```
//! use av_fusion::{
//!     AvConfig, FusionConfig, FusionRule, Modalities, PeakExtraction, Report, SchedulerConfig,
//!     SensorNode, TrackerConfig, track_reports,
//! };
//! use mcmcda::{McmcdaConfig, OnlineConfig};
//! use nalgebra::Matrix2;
//! use tracker_model::{ConstantVelocity2, Region2, SensorPose, Vec2, wrap_angle_rad};
//!
//! let poses = [(5.0, 0.0), (30.0, 0.0), (17.5, 20.0)];
//! let sensors: Vec<SensorNode> = poses
//!     .iter()
//!     .enumerate()
//!     .map(|(i, &(x, y))| {
//!         let pose = SensorPose { position: Vec2::new(x, y), heading_rad: 0.0 };
//!         SensorNode::audio(format!("a{i}"), pose, 72)
//!     })
//!     .collect();
//! // Each node reports a bump of energy towards the target (5° wide) every 0.1 s.
//! let target = |t: f64| Vec2::new(2.0 + 10.0 * t, 10.0);
//! let mut reports = Vec::new();
//! for k in 0..30 {
//!     let t = 0.1 * f64::from(k);
//!     for (i, s) in sensors.iter().enumerate() {
//!         let d = target(t) - s.pose.position;
//!         let bearing = d.y.atan2(d.x);
//!         let values = (0..72)
//!             .map(|b| {
//!                 let off = wrap_angle_rad(f64::from(b) * 5f64.to_radians() - bearing);
//!                 (-0.5 * (off / 5f64.to_radians()).powi(2)).exp()
//!             })
//!             .collect();
//!         reports.push(Report { sensor: i, local_time_s: t, values });
//!     }
//! }
//! let config = AvConfig {
//!     scheduler: SchedulerConfig { rate_hz: 10.0, ..SchedulerConfig::default() },
//!     fusion: FusionConfig {
//!         region: Region2::new(Vec2::new(0.0, 0.0), Vec2::new(35.0, 20.0))?,
//!         cell_size_m: 0.5,
//!         max_range_m: None,
//!         min_range_m: 0.5,
//!         range_fade: None,
//!         rule: FusionRule::Product { floor: 0.05 },
//!         modalities: Modalities::Both,
//!         peaks: PeakExtraction::default(),
//!     },
//!     tracker: TrackerConfig {
//!         mcmcda: McmcdaConfig {
//!             volume: 700.0,
//!             births_per_scan: 0.05,
//!             clutter_per_scan: 0.5,
//!             p_disappear: 0.01,
//!             motion: ConstantVelocity2::mcmcda(0.1, 1.0)?,
//!             measurement_noise: Matrix2::identity() * 0.1,
//!             max_speed: 20.0,
//!             ..McmcdaConfig::default()
//!         },
//!         online: OnlineConfig { window: 8, samples_per_scan: 200, ..OnlineConfig::default() },
//!         seed: 1,
//!         peak_scores: None,
//!     },
//! };
//! let run = track_reports(sensors, reports, 30, &config)?;
//! assert_eq!(run.tracks.len(), 1);
//! let track = &run.tracks.tracks()[0];
//! for p in track.points() {
//!     let truth = target(run.clock.time_s(p.frame));
//!     assert!((p.location.position() - truth).norm() < 0.5); // within one cell
//! }
//! # Ok::<(), av_fusion::Error>(())
//! ```
//!
//! Invariants: the fusion node never reads the truth; a sensor absent from a tick is left out,
//! never zero-filled; projections run in parallel but combine in sensor order, and the sampler
//! draws from its own seeded generator, so output is identical at any thread count; bad input
//! (unknown sensor, wrong profile length, NaN or negative values) is an [`Error`].

mod buffer;
mod error;
mod fusion;
mod node;
pub mod scene;
mod tracker;
pub mod tuning;

#[cfg(test)]
mod tests;

pub use buffer::{
    Arrival, Buffered, FusionNode, SchedulerConfig, Selected, SensorBuffer, Snapshot,
};
pub use error::{Error, Result};
pub use fusion::{
    FusedScan, FusionConfig, FusionRule, Modalities, PeakExtraction, PeakMeasurement, RangeFade,
    SumScaling, extract_peaks, fuse_grids, fuse_snapshot,
};
pub use node::{LobeEqualisation, ProfileShape, Report, SensorKind, SensorNode};
pub use tracker::{AvConfig, AvPipeline, AvRun, PeakScores, TrackerConfig, track_reports};
