//! # mot
//!
//! Multi-object tracking on detection files, the trackers people run on a MOTChallenge
//! `det.txt`:
//!
//! * [`text`]: MOTChallenge text as the tools read it (headers skipped with a note, empty
//!   files and zero-area boxes typed errors).
//! * [`track`]: each tracker's configuration, checked once and fitted to the file
//!   ([`track::fit_model`]: p_d, clutter and birth rates, R and q from a first GNN pass;
//!   [`track::fit_scores`]: the detection-score likelihood ratio); offline MCMCDA with
//!   tracklet linking, online MCMCDA, GNN (smoothed or online with coasting) and SMC-PHD with
//!   label-based track management ([`track::track_detections`]); output boxes fitted to each
//!   track's detections ([`track::smooth_boxes`]).
//! * [`frames`]: the PHD fused with image local detectors on a folder of frames.
//! * [`video`]: detections from a folder of frames by background subtraction, and tracks
//!   drawn back on the frames.
//! * [`driver`]: any tracker of tracker-model's one interface ([`tracker_model::Tracker`],
//!   [`tracker_model::BatchTracker`]) on detections, with [`track::FileTracker`] the file
//!   trackers above behind the same interface.
//! * [`walkers`]: seeded, realistic pedestrian detection files with their ground truth.
//!
//! Tracking a MOTChallenge detection file with offline MCMCDA:
//!
//! ```
//! use mot::track::{TrackConfig, TrackerKind, track_detections};
//!
//! let text = include_str!("../../../fixtures/mot/walkers-dets.txt");
//! let detections = mot::text::parse_detections(text, "walkers-dets.txt")?;
//! let tracks = track_detections(TrackerKind::Mcmcda, &detections, &TrackConfig::default(), 7)?;
//! print!("{}", tracker_model::format_mot(&tracks.to_mot_rows(1.0)));
//! assert!(tracks.len() >= 5);
//! # Ok::<(), mot::Error>(())
//! ```
//!
//! Library code here reads no file and touches neither the clock nor the terminal, except
//! [`frames`] and [`video`], which read the frame folder they are given through
//! sensors-video's `FrameFolder` (and [`video::write_overlay`], which writes the frames it
//! draws). Errors are the one typed [`Error`].

pub mod driver;
mod error;
pub mod frames;
pub mod text;
pub mod track;
pub mod video;
pub mod walkers;

pub use error::{Error, Result};
