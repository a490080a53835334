//! One interface over the recursive estimators of a single target, so that a tracker runs
//! with any of them: the Kalman filter, the EKF or the UKF on one motion model
//! ([`SingleModel`]), or an [`Imm`] over several.

use nalgebra::SVector;

use crate::error::Result;
use crate::gaussian::Gaussian;
use crate::imm::{Imm, ImmState};
use crate::nonlinear::{GaussianFilter, MeasurementModel, MeasurementPrediction, MotionModel};

/// A measurement update's new belief and log p(z | past), the likelihood trackers score
/// associations with.
#[derive(Debug, Clone)]
pub struct Scored<B> {
    /// The posterior belief.
    pub belief: B,
    /// log p(z | the measurements before it).
    pub log_likelihood: f64,
}

/// A recursive estimator of one target's N-component state.
pub trait StateEstimator<const N: usize>: Send + Sync {
    /// What it carries between scans: a Gaussian, or one per mode with their probabilities.
    type Belief: Clone + Send + Sync + std::fmt::Debug;

    /// The belief of a new target whose state is `prior`.
    fn start(&self, prior: Gaussian<N>) -> Result<Self::Belief>;

    /// The belief Δ seconds on.
    fn predict(&self, belief: &Self::Belief, dt_s: f64) -> Result<Self::Belief>;

    /// The update with z seen by `sensor`.
    fn update<O, const M: usize>(
        &self,
        sensor: &O,
        predicted: &Self::Belief,
        z: &SVector<f64, M>,
    ) -> Result<Scored<Self::Belief>>
    where
        O: MeasurementModel<N, M> + ?Sized;

    /// The single Gaussian the belief reports.
    fn estimate(&self, belief: &Self::Belief) -> Gaussian<N>;

    /// N(ẑ, S) of the belief's estimate, for gating.
    fn predict_measurement<O, const M: usize>(
        &self,
        sensor: &O,
        predicted: &Self::Belief,
    ) -> Result<MeasurementPrediction<M>>
    where
        O: MeasurementModel<N, M> + ?Sized;
}

/// One motion model run through one [`GaussianFilter`]: the Kalman filter (`Extended` on
/// linear models), the EKF or the UKF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SingleModel<T> {
    /// The motion model.
    pub motion: T,
    /// How the Gaussian is carried through it.
    pub filter: GaussianFilter,
}

impl<T, const N: usize> StateEstimator<N> for SingleModel<T>
where
    T: MotionModel<N> + Send + Sync,
{
    type Belief = Gaussian<N>;

    fn start(&self, prior: Gaussian<N>) -> Result<Gaussian<N>> {
        Ok(prior)
    }

    fn predict(&self, belief: &Gaussian<N>, dt_s: f64) -> Result<Gaussian<N>> {
        self.filter.predict(&self.motion, belief, dt_s)
    }

    fn update<O, const M: usize>(
        &self,
        sensor: &O,
        predicted: &Gaussian<N>,
        z: &SVector<f64, M>,
    ) -> Result<Scored<Gaussian<N>>>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        let updated = self.filter.update(sensor, predicted, z)?;
        Ok(Scored {
            belief: updated.state,
            log_likelihood: updated.innovation.log_likelihood,
        })
    }

    fn estimate(&self, belief: &Gaussian<N>) -> Gaussian<N> {
        belief.clone()
    }

    fn predict_measurement<O, const M: usize>(
        &self,
        sensor: &O,
        predicted: &Gaussian<N>,
    ) -> Result<MeasurementPrediction<M>>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        self.filter.predict_measurement(sensor, predicted)
    }
}

impl<const N: usize> StateEstimator<N> for Imm<N> {
    type Belief = ImmState<N>;

    fn start(&self, prior: Gaussian<N>) -> Result<ImmState<N>> {
        Imm::start(self, prior, self.start_probabilities())
    }

    fn predict(&self, belief: &ImmState<N>, dt_s: f64) -> Result<ImmState<N>> {
        Imm::predict(self, belief, dt_s)
    }

    fn update<O, const M: usize>(
        &self,
        sensor: &O,
        predicted: &ImmState<N>,
        z: &SVector<f64, M>,
    ) -> Result<Scored<ImmState<N>>>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        let updated = Imm::update(self, sensor, predicted, z)?;
        Ok(Scored {
            belief: updated.state,
            log_likelihood: updated.log_likelihood,
        })
    }

    fn estimate(&self, belief: &ImmState<N>) -> Gaussian<N> {
        belief.combined()
    }

    /// Of the combined (moment-matched) prediction: one gate per target, not one per mode.
    fn predict_measurement<O, const M: usize>(
        &self,
        sensor: &O,
        predicted: &ImmState<N>,
    ) -> Result<MeasurementPrediction<M>>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        self.filter()
            .predict_measurement(sensor, &predicted.combined())
    }
}
