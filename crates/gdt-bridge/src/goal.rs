//! The goal-directed state equation (Srinivasan, Eden, Willsky & Brown, Neural Computation
//! 18(10), 2006) in its general form: a linear Gauss-Markov model x_t = A_t x_{t−1} + w_t,
//! w_t ~ N(0, Q_t), t = 1..T, conditioned on a noisy goal y_T = H x_T + v, v ~ N(0, Π).
//!
//! With Φ(T, t) = A_T ⋯ A_{t+1} (Φ(T, T) = I) and P_t = Σ_{s=t}^{T} Φ(T, s) Q_s Φ(T, s)ᵀ, the
//! conditioned process is again linear-Gaussian:
//!
//! * K_t = Q_t Φ(T, t)ᵀ Hᵀ (H P_t Hᵀ + Π)⁻¹,
//! * x_t = A_t x_{t−1} + u_t + ε_t with drift u_t = K_t (y_T − H Φ(T, t−1) x_{t−1}) and
//!   ε_t ~ N(0, Q_t − K_t H Φ(T, t) Q_t),
//! * x_0 | goal ~ N(m_0 + K_0 (y_T − H Φ(T, 0) m_0), P_0 − K_0 H Φ(T, 0) P_0) with
//!   K_0 = P_0 Φ(T, 0)ᵀ Hᵀ (H Φ(T, 0) P_0 Φ(T, 0)ᵀ Hᵀ + H P_1 Hᵀ + Π)⁻¹.
//!
//! This is exact Gaussian conditioning, so predicting forward through the conditioned model
//! gives the same moments as a Rauch-Tung-Striebel smoother of the free model with the goal as
//! a terminal measurement (see `tests`).

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};
use tracker_model::{
    CholeskyFactor, Gaussian, check_finite_matrix, check_positive_semidefinite, cholesky_checked,
};

use crate::error::{Error, Result};

/// The goal: a measurement y_T = H x_T + v of the final state, v ~ N(0, Π).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Goal<const N: usize, const M: usize> {
    /// H.
    pub observation: SMatrix<f64, M, N>,
    /// y_T.
    pub value: SVector<f64, M>,
    /// Π (symmetric positive definite).
    pub covariance: SMatrix<f64, M, M>,
}

/// One step of the conditioned process: x_t = `transition` x_{t−1} + `offset` + ε_t,
/// ε_t ~ N(0, `covariance`). Here `transition` = A_t − K_t H Φ(T, t−1) and `offset` = K_t y_T,
/// so the drift is u_t = `offset` − K_t H Φ(T, t−1) x_{t−1}.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GoalStep<const N: usize> {
    /// A_t − K_t H Φ(T, t−1).
    pub transition: SMatrix<f64, N, N>,
    /// K_t y_T.
    pub offset: SVector<f64, N>,
    /// Cov ε_t = Q_t − K_t H Φ(T, t) Q_t (positive semi-definite; singular at t = T when the
    /// goal pins the state exactly).
    pub covariance: SMatrix<f64, N, N>,
}

/// Mean and covariance of a state (the covariance may be singular, unlike [`Gaussian`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Moments<const N: usize> {
    /// Mean.
    pub mean: SVector<f64, N>,
    /// Covariance (symmetric positive semi-definite).
    pub covariance: SMatrix<f64, N, N>,
}

/// The goal-conditioned model: its initial state and one step per time 1..T.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GoalDirected<const N: usize> {
    /// x_0 | goal.
    pub initial: Moments<N>,
    /// Steps t = 1..T.
    pub steps: Vec<GoalStep<N>>,
}

impl<const N: usize> GoalDirected<N> {
    /// Builds the conditioned model from A_1..A_T, Q_1..Q_T, the goal and the prior of x_0.
    pub fn new<const M: usize>(
        transitions: &[SMatrix<f64, N, N>],
        process_noise: &[SMatrix<f64, N, N>],
        goal: &Goal<N, M>,
        prior: &Gaussian<N>,
    ) -> Result<Self> {
        check_model(transitions, process_noise, goal)?;
        let horizon = transitions.len();
        let (phi, acc) = propagators(transitions, process_noise);
        let h = &goal.observation;
        let steps = (1..=horizon)
            .map(|t| {
                let q = &process_noise[t - 1];
                let s = h * acc[t] * h.transpose() + goal.covariance;
                let chol = CholeskyFactor::new(&symmetric(&s), "goal innovation covariance")?;
                // K_t = Q_t Φ(T,t)ᵀ Hᵀ S⁻¹ = (S⁻¹ H Φ(T,t) Q_t)ᵀ.
                let h_phi = h * phi[t];
                let gain = chol.solve(&(h_phi * q)).transpose();
                Ok(GoalStep {
                    transition: transitions[t - 1] - gain * h * phi[t - 1],
                    offset: gain * goal.value,
                    covariance: symmetric(&(q - gain * h_phi * q)),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let p0 = prior.covariance();
        let h_phi0 = h * phi[0];
        let s0 = h_phi0 * p0 * h_phi0.transpose() + h * acc[1] * h.transpose() + goal.covariance;
        let chol0 = CholeskyFactor::new(&symmetric(&s0), "goal innovation covariance")?;
        let gain0 = chol0.solve(&(h_phi0 * p0)).transpose();
        let initial = Moments {
            mean: prior.mean() + gain0 * (goal.value - h_phi0 * prior.mean()),
            covariance: symmetric(&(p0 - gain0 * h_phi0 * p0)),
        };
        Ok(Self { initial, steps })
    }

    /// The special forms of Oh & Jung (2015) (eqs. 11-15 for an invertible H, 16-18 with the
    /// pseudo-inverse H⁺ = (HᵀH)⁻¹Hᵀ when only HᵀH is invertible): the goal becomes a target on
    /// the state, μ = H⁺ y_T with covariance H⁺ Π H⁺ᵀ, and with the backward transitions
    /// φ(t, T) = Φ(T, t)⁻¹ (every A_t must be invertible),
    /// Π(t, T) = φ(t, T) (H⁺ Π H⁺ᵀ + P_t) φ(t, T)ᵀ, u_t = Q_t Π(t, T)⁻¹ φ(t, T) (μ − Φ(T, t−1) x_{t−1}),
    /// ε_t = Q_t − Q_t Π(t, T)⁻¹ Q_t, cov(x_0 | y) = (P_0⁻¹ + Π(0, T)⁻¹)⁻¹ and
    /// E[x_0 | y] = cov(x_0 | y) (P_0⁻¹ m_0 + Π(0, T)⁻¹ φ(0, T) μ).
    ///
    /// With an invertible H this is exactly [`GoalDirected::new`]; with the pseudo-inverse it is
    /// exact only when Π is a multiple of the identity (ordinary least squares is then the
    /// generalised one); otherwise it is Oh & Jung's approximation.
    pub fn pseudo_inverse_form<const M: usize>(
        transitions: &[SMatrix<f64, N, N>],
        process_noise: &[SMatrix<f64, N, N>],
        goal: &Goal<N, M>,
        prior: &Gaussian<N>,
    ) -> Result<Self> {
        check_model(transitions, process_noise, goal)?;
        let horizon = transitions.len();
        let h = &goal.observation;
        let hth_inv = (h.transpose() * h)
            .try_inverse()
            .ok_or(Error::GoalUnderdetermined)?;
        let h_pinv = hth_inv * h.transpose();
        let target = h_pinv * goal.value;
        let target_cov = symmetric(&(h_pinv * goal.covariance * h_pinv.transpose()));
        let (phi, acc) = propagators(transitions, process_noise);
        // Π(t, T) and φ(t, T); P_0 of the sum is P_1 (no noise enters before step 1).
        let backward = |t: usize| -> Result<(CholeskyFactor<N>, SMatrix<f64, N, N>)> {
            let back = phi[t]
                .try_inverse()
                .ok_or(Error::SingularTransition { step: t })?;
            let p = acc[t.max(1)];
            let pi = symmetric(&(back * (target_cov + p) * back.transpose()));
            Ok((CholeskyFactor::new(&pi, "Π(t, T)")?, back))
        };
        let steps = (1..=horizon)
            .map(|t| {
                let q = &process_noise[t - 1];
                let (pi, back) = backward(t)?;
                let gain = q * pi.solve(&back);
                Ok(GoalStep {
                    transition: transitions[t - 1] - gain * phi[t - 1],
                    offset: gain * target,
                    covariance: symmetric(&(q - q * pi.solve(&q.transpose()))),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let (pi0, back0) = backward(0)?;
        let p0_inv =
            cholesky_checked(prior.covariance(), "prior covariance")?
                .solve(&SMatrix::<f64, N, N>::identity());
        let pi0_inv = pi0.solve(&SMatrix::<f64, N, N>::identity());
        let cov0 = CholeskyFactor::new(
            &symmetric(&(p0_inv + pi0_inv)),
            "conditional initial covariance",
        )?
        .solve(&SMatrix::<f64, N, N>::identity());
        let mean0 = cov0 * (p0_inv * prior.mean() + pi0_inv * back0 * target);
        Ok(Self {
            initial: Moments {
                mean: mean0,
                covariance: symmetric(&cov0),
            },
            steps,
        })
    }

    /// The marginal moments of x_0..x_T under the conditioned model (forward prediction).
    pub fn predict(&self) -> Vec<Moments<N>> {
        let mut out = Vec::with_capacity(self.steps.len() + 1);
        out.push(self.initial.clone());
        for step in &self.steps {
            let prev = out.last().unwrap_or(&self.initial);
            let mean = step.transition * prev.mean + step.offset;
            let covariance = symmetric(
                &(step.transition * prev.covariance * step.transition.transpose()
                    + step.covariance),
            );
            out.push(Moments { mean, covariance });
        }
        out
    }
}

/// Checks the model and goal once for both forms: T ≥ 1 steps with as many noise matrices,
/// finite transitions, positive semi-definite process noise (each distinct matrix once: a
/// time-invariant model repeats the same ones), and a finite goal with positive-definite Π.
fn check_model<const N: usize, const M: usize>(
    transitions: &[SMatrix<f64, N, N>],
    process_noise: &[SMatrix<f64, N, N>],
    goal: &Goal<N, M>,
) -> Result<()> {
    let horizon = transitions.len();
    if horizon == 0 || process_noise.len() != horizon {
        return Err(Error::HorizonMismatch {
            transitions: horizon,
            process_noise: process_noise.len(),
        });
    }
    for (t, (a, q)) in transitions.iter().zip(process_noise).enumerate() {
        // A time-invariant model repeats the same matrices; check each distinct one once.
        if t > 0 && *a == transitions[t - 1] && *q == process_noise[t - 1] {
            continue;
        }
        check_finite_matrix(a, "transition matrix")?;
        check_positive_semidefinite(q, "process noise").map_err(|source| Error::ProcessNoise {
            step: t + 1,
            source,
        })?;
    }
    check_finite_matrix(&goal.observation, "goal observation matrix")?;
    check_finite_matrix(&goal.value, "goal value")?;
    cholesky_checked(&goal.covariance, "goal covariance")?;
    Ok(())
}

/// Φ(T, t) for t = 0..T (built backwards: Φ(T, T) = I, Φ(T, t−1) = Φ(T, t) A_t) and the
/// accumulated noise P_t = Σ_{s=t}^{T} Φ(T, s) Q_s Φ(T, s)ᵀ for t = 1..T (with P_{T+1} = 0).
fn propagators<const N: usize>(
    transitions: &[SMatrix<f64, N, N>],
    process_noise: &[SMatrix<f64, N, N>],
) -> (Vec<SMatrix<f64, N, N>>, Vec<SMatrix<f64, N, N>>) {
    let horizon = transitions.len();
    let mut phi = vec![SMatrix::<f64, N, N>::identity(); horizon + 1];
    for t in (1..=horizon).rev() {
        phi[t - 1] = phi[t] * transitions[t - 1];
    }
    let mut acc = vec![SMatrix::<f64, N, N>::zeros(); horizon + 2];
    for t in (1..=horizon).rev() {
        acc[t] = acc[t + 1] + phi[t] * process_noise[t - 1] * phi[t].transpose();
    }
    (phi, acc)
}

fn symmetric<const N: usize>(m: &SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
    (m + m.transpose()) * 0.5
}
