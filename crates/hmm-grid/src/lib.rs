//! # hmm-grid
//!
//! Ground-target tracking with a discrete hidden Markov model λ = (π, A, B) on a map (Huynh &
//! Vu, "Ground mobile target tracking by hidden Markov model", 2006; Rabiner 1989):
//!
//! * [`Hmm`], checked at construction (finite, non-negative, rows summing to 1; errors name
//!   the row), with the transition matrix [`Transitions`] stored dense or as CSR with a CSC
//!   index ([`StorageChoice`]: chosen by fill, or forced); every algorithm costs O(T · nnz(A));
//! * [`forward`] (scaled, with the log-likelihood), [`backward`], [`posterior`] marginals,
//!   [`expected_transitions`], [`viterbi`] in log space, [`posterior_decode`], and
//!   [`forward_log`] as an independent log-space formulation;
//! * [`baum_welch`] ([`BaumWelchConfig`] checked into a [`BaumWelch`] trainer) over several
//!   sequences with a tolerance, an iteration cap, frozen components ([`Freeze`]),
//!   [`PseudoCounts`] and the log-likelihood history; the E-step runs in parallel and reduces
//!   in sequence order, so results do not depend on the thread count;
//! * maps ([`StateSpace`]): free cells of a [`CellGrid`] with obstacles or the crossroads of a
//!   road graph, transitions from a [`SpeedDistribution`], and an emission matrix from a
//!   [`SensorModel`] whose accuracy falls with distance; [`Hmm::sample`] simulates a target
//!   and [`StateSpace::path_to_track`] turns a decoded path into a `Track`.
//!
//! Decoding the most probable path of a target on three road segments (0, 1, 2) in a row,
//! moving at most one segment per step, seen by a sensor that names the right segment 80 % of
//! the time:
//!
//! ```
//! use hmm_grid::{Hmm, StorageChoice, Transitions, viterbi};
//!
//! // A by rows: a_ij = P(segment j next | segment i now).
//! let a = [[0.6, 0.4, 0.0], [0.2, 0.6, 0.2], [0.0, 0.4, 0.6]];
//! // B by rows: b_i(m) = P(the sensor reports segment m | the target is on segment i).
//! let b = [[0.8, 0.1, 0.1], [0.1, 0.8, 0.1], [0.1, 0.1, 0.8]];
//! let a = Transitions::from_row_major(3, a.concat(), StorageChoice::Auto)?;
//! let hmm = Hmm::new(vec![1.0, 0.0, 0.0], a, b.concat(), 3)?;
//!
//! // The sensor's reports. The target cannot jump from segment 0 to 2 in one step, so the
//! // most probable path reads the first 2 as a misreport of segment 1.
//! let reports = [0, 2, 2, 2, 1, 1];
//! let (path, _log_p) = viterbi(&hmm, &reports)?;
//! assert_eq!(path, vec![0, 1, 2, 2, 1, 1]);
//! # Ok::<(), hmm_grid::Error>(())
//! ```
//!
//! [`posterior`] gives P(segment i at step t | all reports) for the same model and reports.

mod error;
mod inference;
mod learn;
mod map;
mod model;
mod transitions;

#[cfg(test)]
mod tests;

pub use error::{Error, Result};
pub use inference::{
    Forward, Posterior, backward, expected_transitions, forward, forward_log, posterior,
    posterior_decode, viterbi,
};
pub use learn::{BaumWelch, BaumWelchConfig, FitReport, Freeze, PseudoCounts, baum_welch};
pub use map::{CellGrid, SensorModel, SpeedDistribution, StateSpace};
pub use model::Hmm;
pub use transitions::{ROW_SUM_TOLERANCE, SPARSE_FILL, StorageChoice, Transitions};
