//! # air-traffic
//!
//! Real aircraft for the trackers, and a radar to see them with:
//!
//! * [`read_collection`]: an ADS-B collection as the `traffic` package writes it (the
//!   quickstart sample of its wheel: 213 aircraft, 3 hours at 1 s over northern France, from
//!   OpenSky) into [`Trajectory`]s in a local east-north frame ([`EnuFrame`], WGS-84);
//! * [`StandinConfig`]: synthetic traffic of straight legs and coordinated turns, for
//!   machines without the real collection;
//! * [`RotatingRadar`]: a rotating 2-D radar's dwells over trajectories: range-bearing plots
//!   with their origins, detection probability and Poisson clutter, from the generator passed
//!   in; [`RotatingRadar::in_view`] and [`RotatingRadar::measurement_model`] are what a
//!   tracker (`mcmcda::PlotGnn`) needs of it;
//! * [`track_dwells`], [`truth_points`], [`truth_set`], [`track_set`] and [`score`]: a
//!   tracker over the dwells, and the truth and its tracks once per revolution with their
//!   position and velocity errors and the track breaks during turns;
//! * [`run_tracker`]: the compared trackers ([`RadarTracker`]: CV, coordinated turn by EKF
//!   or UKF, two IMMs) on one radar run;
//! * [`parse_plots`], [`track_plots`], [`format_tracks`], [`point_track_sets`]: users' own
//!   plot files (CSV: positions or range-bearing from sensors at known positions) tracked
//!   with `kf`, `ekf`, `ukf` or `imm`, and point tracks scored against point truth (what
//!   `cargo xtask track --plots` and `cargo xtask eval --distance` run).
//!
//! A stand-in, a radar and its plots:
//!
//! ```
//! use air_traffic::{RotatingRadar, StandinConfig};
//! use rand::SeedableRng;
//!
//! let traffic = StandinConfig {
//!     aircraft: 3, duration_s: 600.0, half_width_m: 50_000.0,
//!     speed_m_s: [150.0, 250.0], leg_s: [60.0, 180.0], turn_deg_s: [1.5, 3.0],
//!     turn_change_deg: [30.0, 90.0], life_s: [300.0, 600.0],
//! };
//! let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
//! let trajectories = traffic.generate(&mut rng)?;
//! let radar = RotatingRadar {
//!     position: [0.0, 0.0], period_s: 10.0, dwells: 12, min_range_m: 500.0,
//!     max_range_m: 100_000.0, sigma_range_m: 50.0, sigma_bearing_rad: 0.002,
//!     p_detect: 0.9, clutter_per_revolution: 5.0,
//! };
//! let dwells = radar.simulate(&trajectories, 0.0, 600.0, &mut rng)?;
//! assert_eq!(dwells.len(), 721); // every 10/12 s from 0 to 600 s
//! # Ok::<(), air_traffic::Error>(())
//! ```

mod adsb;
mod error;
mod geodesy;
mod plot_file;
mod radar;
mod standin;
mod trackers;
mod tracking;
mod trajectory;

#[cfg(test)]
mod tests;

pub use adsb::{MAX_REPORTS, ReadConfig, read_collection};
pub use error::{Error, Result};
pub use geodesy::EnuFrame;
pub use mcmcda::BirthPrior;
pub use plot_file::{
    MAX_PLOT_ROWS, PlotFilter, PlotRow, PlotTrackConfig, PlotValue, TrackRow, format_radar_run,
    format_tracks, parse_plots, point_track_sets, track_plots,
};
pub use radar::{MAX_DWELLS, MAX_DWELLS_PER_REVOLUTION, RadarDwell, RotatingRadar};
pub use standin::{MAX_STANDIN_AIRCRAFT, MAX_STANDIN_DURATION_S, StandinConfig};
pub use trackers::{MotionSettings, RadarScene, RadarTracker, TrackerOutcome, run_tracker};
pub use tracking::{
    KinematicScore, RadarRun, ScoreConfig, TruthPoint, score, track_dwells, track_set,
    truth_points, truth_set,
};
pub use trajectory::{Kinematics, Sample, Trajectory};
