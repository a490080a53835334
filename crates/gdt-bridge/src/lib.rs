//! # gdt-bridge
//!
//! Recovers the missing trajectory between two disconnected track segments (Oh & Jung 2015):
//! the goal-directed state equation of Srinivasan, Eden, Willsky & Brown (2006) conditions a
//! linear Gauss-Markov motion model on reaching a noisy goal (the next segment's first
//! observation) at a known time, and its forward prediction fills the gap with positions and
//! covariances.
//!
//! * [`GoalDirected`]: the general form (time-varying A_t, Q_t, goal y_T = H x_T + v), giving
//!   each step's transition, drift offset and reduced noise, and the conditional initial state;
//! * [`recover_gdt`]: gap recovery from segments A and B with a constant-velocity model, and
//!   [`recover_gdt_goal_state`], whose goal is B's full state from a backward filter;
//! * [`estimate_noise`]: the measurement variance and process noise by maximum likelihood over
//!   the observed frames of the segments, so GDT needs no oracle noise;
//! * baselines [`linear`], [`natural_cubic_spline`], [`lsq_bspline`] (explicit knots and
//!   weights, banded, O(n)), the GCV [`SmoothingSpline`], and [`recover_baseline`] with window
//!   fits whose size is cross-validated on the observations;
//! * segment linking ([`link_segments`]): gated goal-directed likelihood costs and an optimal
//!   one-to-one assignment;
//! * Oh & Jung's evaluation protocol: [`gaps_from_mask`] turns masked crossings into gaps;
//!   [`scene`] simulates their pedestrian scenes (walkers with detector noise) and cuts the
//!   observed gaps.
//!
//! Oh & Jung's special forms (their eqs. 11-18: invertible H, pseudo-inverse) are
//! [`GoalDirected::pseudo_inverse_form`]; tests show where they equal the general form.
//!
//! Settings are checked once: [`GdtConfig::check`] gives the [`GdtModel`] the recovery
//! functions take, [`LinkConfig::check`] the [`LinkModel`] of linking.
//!
//! Filling the gap between two segments of a walker's track, seen at frames 0-5 and 12-17 and
//! hidden in between:
//!
//! ```
//! use gdt_bridge::{GdtConfig, Observation, recover_gdt};
//! use tracker_model::Vec2;
//!
//! // (frame, x, y) in pixels.
//! let before = [(0, 10.0, 50.0), (1, 13.1, 50.9), (2, 15.9, 52.1), (3, 19.0, 53.0),
//!               (4, 22.1, 53.9), (5, 24.9, 55.0)];
//! let after = [(12, 46.0, 62.1), (13, 49.1, 62.9), (14, 52.0, 64.0), (15, 54.9, 65.1),
//!              (16, 58.0, 66.0), (17, 61.1, 66.9)];
//! let observed = |rows: &[(u32, f64, f64)]| -> Vec<Observation> {
//!     rows.iter().map(|&(frame, x, y)| Observation { frame, position: Vec2::new(x, y) }).collect()
//! };
//! let gap = recover_gdt(&observed(&before), &observed(&after), &GdtConfig::default().check()?)?;
//! assert_eq!(gap.frames, (6..12).collect::<Vec<_>>());
//! // About (3, 1) pixels per frame: at frame 9 the walker is near (37, 58).
//! assert!((gap.positions[3] - Vec2::new(37.0, 58.0)).norm() < 1.5);
//! # Ok::<(), gdt_bridge::Error>(())
//! ```
//!
//! Each recovered position comes with its covariance (`gap.covariances`).

mod baselines;
mod error;
mod gap;
mod goal;
mod link;
mod noise;
mod protocol;
pub mod scene;
mod search;

#[cfg(test)]
mod tests;

pub use baselines::{
    BSpline, BSplineConfig, GcvConfig, SmoothingSpline, gap_knots, linear, lsq_bspline,
    natural_cubic_spline,
};
pub use error::{Error, Result};
pub use gap::{
    Baseline, GdtConfig, GdtModel, MAX_GAP_FRAMES, Observation, RecoveredGap, WindowConfig,
    recover_baseline, recover_gdt, recover_gdt_goal_state, window_cv_errors,
};
pub use goal::{Goal, GoalDirected, GoalStep, Moments};
pub use link::{Link, LinkConfig, LinkModel, link_costs, link_segments};
pub use noise::{NoiseEstimate, NoiseSearch, estimate_noise, noise_log_likelihood};
pub use protocol::{GapCase, gaps_from_mask};
