//! # gdt-bridge
//!
//! Recovers the missing trajectory between two disconnected track segments (seed 003): the
//! goal-directed state equation of Srinivasan, Eden, Willsky & Brown (2006) conditions a linear
//! Gauss-Markov motion model on reaching a noisy goal (the next segment's first observation) at
//! a known time, and its forward prediction fills the gap with positions and covariances.
//!
//! * [`GoalDirected`]: the general form (time-varying A_t, Q_t, goal y_T = H x_T + v), giving
//!   each step's transition, drift offset and reduced noise, and the conditional initial state;
//! * [`recover_gdt`]: gap recovery from segments A and B with a constant-velocity model, and
//!   [`recover_gdt_goal_state`], whose goal is B's full state from a backward filter;
//! * baselines [`linear`], [`natural_cubic_spline`], [`lsq_bspline`] and [`recover_baseline`];
//! * segment linking ([`link_segments`]): gated goal-directed likelihood costs and an optimal
//!   one-to-one assignment;
//! * the seed's evaluation protocol: [`gaps_from_mask`] turns masked crossings into gaps.
//!
//! The seed's special forms (eqs. 11-18: invertible H, pseudo-inverse) are
//! [`GoalDirected::seed_form`]; tests show where they equal the general form.
//!
//! ```
//! use gdt_bridge::{GdtConfig, Observation, recover_gdt};
//! use tracker_model::Vec2;
//! let seg = |f0: u32, n: u32| (f0..f0 + n).map(|f| Observation { frame: f, position: Vec2::new(2.0 * f as f64, 1.0) }).collect::<Vec<_>>();
//! let gap = recover_gdt(&seg(0, 10), &seg(20, 10), &GdtConfig::default()).unwrap();
//! assert_eq!(gap.frames, (10..20).collect::<Vec<_>>());
//! assert!((gap.positions[5].x - 30.0).abs() < 1.0);
//! ```

mod baselines;
mod error;
mod gap;
mod goal;
mod link;
mod protocol;

#[cfg(test)]
mod tests;

pub use baselines::{BSplineConfig, linear, lsq_bspline, natural_cubic_spline};
pub use error::{Error, Result};
pub use gap::{
    Baseline, GdtConfig, Observation, RecoveredGap, recover_baseline, recover_gdt,
    recover_gdt_goal_state,
};
pub use goal::{Goal, GoalDirected, GoalStep, Moments};
pub use link::{Link, LinkConfig, link_costs, link_segments};
pub use protocol::{GapCase, gaps_from_mask};
