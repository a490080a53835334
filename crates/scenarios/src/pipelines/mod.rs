//! The pipelines a scenario file can name; `PIPELINES` in lib.rs registers them.

pub mod adsb_radar;
pub mod audio;
pub mod av_fusion;
pub mod camnet;
pub mod dmtim;
pub mod gdt;
pub mod hmm;
pub mod kalman;
pub mod mcmcda;
pub mod mot_box_trackers;
pub mod mot_eval;
pub mod mot_realistic;
pub mod mot_track;
pub mod phd;
pub mod phd_images;
pub mod simulator;
pub mod video;
