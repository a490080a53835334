//! The interacting multiple model filter (Blom & Bar-Shalom 1988, "The interacting multiple
//! model algorithm for systems with Markovian switching coefficients", IEEE TAC 33(8)): one
//! Gaussian per motion mode, mixed before each prediction through a Markov chain on the modes,
//! and mode probabilities updated by each mode's measurement likelihood.

use nalgebra::SVector;

use crate::error::{Error, Result};
use crate::gaussian::{Gaussian, symmetrise};
use crate::models::Innovation;
use crate::nonlinear::{GaussianFilter, MeasurementModel, MotionModel};

/// The most modes an IMM accepts; published IMMs use two to a dozen.
pub const MAX_IMM_MODES: usize = 32;

/// How far a row of the switching matrix may sum from one.
const ROW_SUM_TOLERANCE: f64 = 1e-9;

/// A motion mode of an IMM.
pub type Mode<const N: usize> = Box<dyn MotionModel<N> + Send + Sync>;

/// An IMM over modes sharing one N-component state, all run through one [`GaussianFilter`].
pub struct Imm<const N: usize> {
    modes: Vec<Mode<N>>,
    /// π_ij = P(mode j at this scan | mode i at the last), row-major.
    switching: Vec<f64>,
    filter: GaussianFilter,
    /// The mode probabilities a new target starts with (uniform unless set).
    start_probabilities: Vec<f64>,
}

/// The IMM's belief: one Gaussian per mode and the mode probabilities (after a prediction,
/// the predicted probabilities c̄).
#[derive(Debug, Clone, PartialEq)]
pub struct ImmState<const N: usize> {
    modes: Vec<Gaussian<N>>,
    probabilities: Vec<f64>,
}

/// The result of an IMM measurement update.
#[derive(Debug, Clone, PartialEq)]
pub struct ImmUpdated<const N: usize, const M: usize> {
    /// The posterior belief.
    pub state: ImmState<N>,
    /// log p(z | past) = log Σ_j c̄_j Λ_j.
    pub log_likelihood: f64,
    /// Each mode's innovation, in mode order.
    pub innovations: Vec<Innovation<M>>,
}

impl<const N: usize> ImmState<N> {
    /// Each mode's Gaussian, in mode order.
    pub fn modes(&self) -> &[Gaussian<N>] {
        &self.modes
    }

    /// The mode probabilities, summing to one.
    pub fn probabilities(&self) -> &[f64] {
        &self.probabilities
    }

    /// The moment-matched single Gaussian, Σ μ_j N(x_j, P_j) collapsed: the IMM's output
    /// estimate (Blom & Bar-Shalom's combination step).
    pub fn combined(&self) -> Gaussian<N> {
        let mean = self
            .modes
            .iter()
            .zip(&self.probabilities)
            .fold(SVector::<f64, N>::zeros(), |acc, (g, w)| {
                acc + g.mean() * *w
            });
        Gaussian::from_parts(
            mean,
            symmetrise(&spread(&self.modes, &self.probabilities, &mean)),
        )
    }
}

/// Σ w_i (P_i + (x_i − x̄)(x_i − x̄)ᵀ).
fn spread<const N: usize>(
    modes: &[Gaussian<N>],
    weights: &[f64],
    mean: &SVector<f64, N>,
) -> nalgebra::SMatrix<f64, N, N> {
    modes
        .iter()
        .zip(weights)
        .fold(nalgebra::SMatrix::zeros(), |acc, (g, w)| {
            let d = g.mean() - mean;
            acc + (g.covariance() + d * d.transpose()) * *w
        })
}

fn check_probabilities(p: &[f64], what: &'static str) -> Result<()> {
    if p.iter().any(|v| !v.is_finite() || *v < 0.0) {
        return Err(Error::InvalidParameter {
            name: what,
            reason: format!("{p:?} must be finite and non-negative"),
        });
    }
    let sum: f64 = p.iter().sum();
    if (sum - 1.0).abs() > ROW_SUM_TOLERANCE {
        return Err(Error::InvalidParameter {
            name: what,
            reason: format!("{p:?} sums to {sum}, not 1"),
        });
    }
    Ok(())
}

impl<const N: usize> Imm<N> {
    /// An IMM over `modes` (1 to [`MAX_IMM_MODES`]) with the row-stochastic switching matrix
    /// `switching[i][j]` = P(mode j next | mode i now).
    pub fn new(
        modes: Vec<Mode<N>>,
        switching: &[Vec<f64>],
        filter: GaussianFilter,
    ) -> Result<Self> {
        let r = modes.len();
        if r == 0 || r > MAX_IMM_MODES {
            return Err(Error::InvalidParameter {
                name: "modes",
                reason: format!("{r} modes; an IMM takes 1 to {MAX_IMM_MODES}"),
            });
        }
        if switching.len() != r || switching.iter().any(|row| row.len() != r) {
            return Err(Error::ShapeMismatch(format!(
                "the switching matrix must be {r} × {r}, one row and column per mode"
            )));
        }
        for row in switching {
            check_probabilities(row, "switching matrix row")?;
        }
        Ok(Self {
            start_probabilities: vec![1.0 / r as f64; r],
            modes,
            switching: switching.concat(),
            filter,
        })
    }

    /// The same IMM with the mode probabilities a new target starts with (see
    /// [`StateEstimator::start`](crate::StateEstimator::start)).
    pub fn with_start_probabilities(mut self, probabilities: &[f64]) -> Result<Self> {
        if probabilities.len() != self.modes.len() {
            return Err(Error::ShapeMismatch(format!(
                "{} start probabilities for {} modes",
                probabilities.len(),
                self.modes.len()
            )));
        }
        check_probabilities(probabilities, "start probabilities")?;
        self.start_probabilities = probabilities.to_vec();
        Ok(self)
    }

    /// The filter every mode runs.
    pub fn filter(&self) -> GaussianFilter {
        self.filter
    }

    /// The mode probabilities a new target starts with.
    pub fn start_probabilities(&self) -> &[f64] {
        &self.start_probabilities
    }

    /// The number of modes.
    pub fn mode_count(&self) -> usize {
        self.modes.len()
    }

    /// Every mode starting at `prior`, with these mode probabilities.
    pub fn start(&self, prior: Gaussian<N>, probabilities: &[f64]) -> Result<ImmState<N>> {
        self.start_from_modes(vec![prior; self.modes.len()], probabilities)
    }

    /// A belief given mode by mode (a checkpoint restored, say), checked against this IMM.
    pub fn start_from_modes(
        &self,
        modes: Vec<Gaussian<N>>,
        probabilities: &[f64],
    ) -> Result<ImmState<N>> {
        if modes.len() != self.modes.len() || probabilities.len() != self.modes.len() {
            return Err(Error::ShapeMismatch(format!(
                "{} Gaussians and {} probabilities for {} modes",
                modes.len(),
                probabilities.len(),
                self.modes.len()
            )));
        }
        check_probabilities(probabilities, "mode probabilities")?;
        Ok(ImmState {
            modes,
            probabilities: probabilities.to_vec(),
        })
    }

    fn check_state(&self, state: &ImmState<N>) -> Result<()> {
        if state.modes.len() == self.modes.len() {
            Ok(())
        } else {
            Err(Error::ShapeMismatch(format!(
                "a belief over {} modes given to an IMM of {}",
                state.modes.len(),
                self.modes.len()
            )))
        }
    }

    /// Mixing and prediction Δ seconds ahead: c̄_j = Σ_i π_ij μ_i, μ_{i|j} = π_ij μ_i / c̄_j,
    /// each mode j predicted from Σ_i μ_{i|j} N(x_i, P_i) collapsed (Blom & Bar-Shalom 1988,
    /// eqs. 8-10). A mode no one can switch into (c̄_j = 0) keeps its own state.
    pub fn predict(&self, state: &ImmState<N>, dt_s: f64) -> Result<ImmState<N>> {
        self.check_state(state)?;
        let r = self.modes.len();
        let mut predicted = Vec::with_capacity(r);
        let mut c_bar = vec![0.0; r];
        let mut weights = vec![0.0; r];
        for (j, (mode, c)) in self.modes.iter().zip(&mut c_bar).enumerate() {
            for (i, w) in weights.iter_mut().enumerate() {
                *w = self.switching[i * r + j] * state.probabilities[i];
            }
            *c = weights.iter().sum();
            let mixed = if *c > 0.0 {
                weights.iter_mut().for_each(|w| *w /= *c);
                let mean = state
                    .modes
                    .iter()
                    .zip(&weights)
                    .fold(SVector::<f64, N>::zeros(), |acc, (g, w)| {
                        acc + g.mean() * *w
                    });
                let cov = symmetrise(&spread(&state.modes, &weights, &mean));
                Gaussian::from_parts(mean, cov)
            } else {
                state.modes[j].clone()
            };
            predicted.push(self.filter.predict(mode.as_ref(), &mixed, dt_s)?);
        }
        Ok(ImmState {
            modes: predicted,
            probabilities: c_bar,
        })
    }

    /// Each mode's update with z, and μ_j ∝ c̄_j Λ_j (eq. 12), in log space so that a
    /// measurement far from every mode does not underflow.
    pub fn update<O, const M: usize>(
        &self,
        sensor: &O,
        predicted: &ImmState<N>,
        z: &SVector<f64, M>,
    ) -> Result<ImmUpdated<N, M>>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        self.check_state(predicted)?;
        let mut modes = Vec::with_capacity(self.modes.len());
        let mut innovations = Vec::with_capacity(self.modes.len());
        let mut log_weights = Vec::with_capacity(self.modes.len());
        for (g, c) in predicted.modes.iter().zip(&predicted.probabilities) {
            let updated = self.filter.update(sensor, g, z)?;
            log_weights.push(c.ln() + updated.innovation.log_likelihood);
            modes.push(updated.state);
            innovations.push(updated.innovation);
        }
        let top = log_weights
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let total: f64 = log_weights.iter().map(|w| (w - top).exp()).sum();
        let probabilities = log_weights
            .iter()
            .map(|w| (w - top).exp() / total)
            .collect();
        Ok(ImmUpdated {
            state: ImmState {
                modes,
                probabilities,
            },
            log_likelihood: top + total.ln(),
            innovations,
        })
    }
}
