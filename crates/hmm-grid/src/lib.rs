//! # hmm-grid
//!
//! Ground-target tracking with a discrete hidden Markov model λ = (π, A, B) on a map (Huynh &
//! Vu, "Ground mobile target tracking by hidden Markov model", 2006; Rabiner 1989):
//!
//! * [`Hmm`], checked at construction (finite, non-negative, rows summing to 1; errors name
//!   the row), with transitions stored dense or as CSR ([`Transitions`]), chosen by fill;
//!   every algorithm costs O(T · nnz(A));
//! * [`forward`] (scaled, with the log-likelihood), [`backward`], [`posterior`] marginals,
//!   [`expected_transitions`], [`viterbi`] in log space, [`posterior_decode`], and
//!   [`forward_log`] as an independent log-space formulation;
//! * [`baum_welch`] over several sequences with a tolerance, an iteration cap, frozen
//!   components ([`Freeze`]), [`PseudoCounts`] and the log-likelihood history; the E-step runs
//!   in parallel and reduces in sequence order, so results do not depend on the thread count;
//! * maps ([`StateSpace`]): free cells of a [`CellGrid`] with obstacles or the crossroads of a
//!   road graph, transitions from a [`SpeedDistribution`], and an emission matrix from a
//!   [`SensorModel`] whose accuracy falls with distance; [`Hmm::sample`] simulates a target.
//!
//! ```
//! use hmm_grid::{Hmm, Transitions, viterbi};
//! let a = Transitions::from_dense(2, vec![0.9, 0.1, 0.2, 0.8]).unwrap();
//! let hmm = Hmm::new(vec![0.5, 0.5], a, vec![0.8, 0.2, 0.3, 0.7], 2).unwrap();
//! let (path, log_p) = viterbi(&hmm, &[0, 0, 1, 1]).unwrap();
//! assert_eq!(path, vec![0, 0, 1, 1]);
//! assert!(log_p < 0.0);
//! ```

mod error;
mod inference;
mod learn;
mod map;
mod model;

#[cfg(test)]
mod tests;

pub use error::{Error, Result};
pub use inference::{
    Forward, Posterior, backward, expected_transitions, forward, forward_log, posterior,
    posterior_decode, viterbi,
};
pub use learn::{BaumWelchConfig, FitReport, Freeze, PseudoCounts, baum_welch};
pub use map::{CellGrid, SensorModel, SpeedDistribution, StateSpace};
pub use model::{Hmm, ROW_SUM_TOLERANCE, SPARSE_FILL, Transitions};
