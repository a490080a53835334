//! The Kalman filter over a sequence with missing measurements, and the Rauch-Tung-Striebel
//! smoother.

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::gaussian::{CholeskyFactor, Gaussian, symmetrise};
use crate::models::{ObservationModel, TransitionModel};

/// One time step of a filter run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FilterStep<const N: usize> {
    /// The prediction before this step's measurement (for step 0, the prior).
    pub predicted: Gaussian<N>,
    /// The estimate after this step's measurement (equal to `predicted` when it is missing).
    pub filtered: Gaussian<N>,
    /// log N(z; H x⁻, S) of this step's measurement, `None` when it is missing.
    pub log_likelihood: Option<f64>,
    /// The squared Mahalanobis distance of the innovation, `None` when missing.
    pub innovation_mahalanobis_sq: Option<f64>,
}

/// The result of [`filter`]: every step's prediction and estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FilterRun<const N: usize> {
    /// One entry per input time step.
    pub steps: Vec<FilterStep<N>>,
}

impl<const N: usize> FilterRun<N> {
    /// Sum of the measurement log-likelihoods (log p(z_{1:T}) under the model).
    pub fn log_likelihood(&self) -> f64 {
        self.steps.iter().filter_map(|s| s.log_likelihood).sum()
    }

    /// The filtered estimates.
    pub fn filtered(&self) -> impl Iterator<Item = &Gaussian<N>> {
        self.steps.iter().map(|s| &s.filtered)
    }
}

/// Filters `measurements`, one per sampling period, `None` where the measurement is missing.
///
/// `prior` is the state distribution at the first step before its measurement; later steps
/// predict one sampling period each.
///
/// ```
/// use nalgebra::Vector2;
/// use tracker_model::{ConstantVelocity2, Gaussian, filter, position_measurement, smooth};
/// let motion = ConstantVelocity2::mcmcda(1.0, 0.1).unwrap();
/// let sensor = position_measurement(1.0).unwrap();
/// let prior = Gaussian::new(nalgebra::Vector4::zeros(), nalgebra::Matrix4::identity() * 100.0).unwrap();
/// let zs = [Some(Vector2::new(0.0, 0.0)), None, Some(Vector2::new(2.0, 1.0))];
/// let run = filter(&motion, &sensor, &prior, &zs).unwrap();
/// let smoothed = smooth(&motion, &run).unwrap();
/// assert_eq!(smoothed.len(), 3);
/// ```
pub fn filter<T, O, const N: usize, const M: usize>(
    transition: &T,
    observation: &O,
    prior: &Gaussian<N>,
    measurements: &[Option<SVector<f64, M>>],
) -> Result<FilterRun<N>>
where
    T: TransitionModel<N> + ?Sized,
    O: ObservationModel<N, M> + ?Sized,
{
    let mut steps: Vec<FilterStep<N>> = Vec::with_capacity(measurements.len());
    for z in measurements {
        let predicted = match steps.last() {
            None => prior.clone(),
            Some(previous) => transition.predict(&previous.filtered),
        };
        let step = match z {
            Some(z) => {
                let updated = observation.update(&predicted, z)?;
                FilterStep {
                    predicted,
                    filtered: updated.state,
                    log_likelihood: Some(updated.innovation.log_likelihood),
                    innovation_mahalanobis_sq: Some(updated.innovation.mahalanobis_sq),
                }
            }
            None => FilterStep {
                filtered: predicted.clone(),
                predicted,
                log_likelihood: None,
                innovation_mahalanobis_sq: None,
            },
        };
        steps.push(step);
    }
    Ok(FilterRun { steps })
}

/// Rauch-Tung-Striebel smoothing of a filter run made with the same `transition`:
/// C_k = P_k Fᵀ (P⁻_{k+1})⁻¹, x^s_k = x_k + C_k (x^s_{k+1} − x⁻_{k+1}),
/// P^s_k = P_k + C_k (P^s_{k+1} − P⁻_{k+1}) C_kᵀ.
///
/// Each step is [`TransitionModel::smooth_step`]: the Cholesky route of [`rts_step`] unless
/// the model has a faster one with the same result.
pub fn smooth<T, const N: usize>(transition: &T, run: &FilterRun<N>) -> Result<Vec<Gaussian<N>>>
where
    T: TransitionModel<N> + ?Sized,
{
    let Some(last) = run.steps.last() else {
        return Err(Error::Empty { what: "filter run" });
    };
    let f = transition.transition_matrix(1);
    let mut out = Vec::with_capacity(run.steps.len());
    out.push(last.filtered.clone());
    // Built from the last step backwards, then put in time order.
    for k in (0..run.steps.len() - 1).rev() {
        let next = out.last().unwrap_or(&last.filtered);
        let step = transition.smooth_step(
            &f,
            &run.steps[k].filtered,
            &run.steps[k + 1].predicted,
            next,
        )?;
        out.push(step);
    }
    out.reverse();
    Ok(out)
}

/// One RTS step by the general route: the Cholesky factor of P⁻_{k+1} gives the gain
/// Cᵀ = (P⁻_{k+1})⁻¹ F P_k (using the symmetry of both covariances), then
/// x^s_k = x_k + C (x^s_{k+1} − x⁻_{k+1}) and P^s_k = P_k + C (P^s_{k+1} − P⁻_{k+1}) Cᵀ.
/// `f` is the one-period transition matrix.
pub fn rts_step<const N: usize>(
    f: &SMatrix<f64, N, N>,
    filtered: &Gaussian<N>,
    next_predicted: &Gaussian<N>,
    next_smoothed: &Gaussian<N>,
) -> Result<Gaussian<N>> {
    let chol = CholeskyFactor::new(next_predicted.covariance(), "predicted covariance")?;
    let gain = chol.solve(&(f * filtered.covariance())).transpose();
    let mean = filtered.mean() + gain * (next_smoothed.mean() - next_predicted.mean());
    let cov = symmetrise(
        &(filtered.covariance()
            + gain * (next_smoothed.covariance() - next_predicted.covariance()) * gain.transpose()),
    );
    Ok(Gaussian::from_parts(mean, cov))
}
