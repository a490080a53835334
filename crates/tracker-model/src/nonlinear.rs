//! Nonlinear motion and measurement models and the two Gaussian filters for them.
//!
//! * The extended Kalman filter linearises f and h at the estimate (Jazwinski 1970; the
//!   Joseph-form update of [`ObservationModel::update`](crate::ObservationModel::update)). On
//!   linear models it is the Kalman filter, to the bit.
//! * The unscented Kalman filter propagates 2n + 1 scaled sigma points (Julier 2002; Wan & van
//!   der Merwe 2000, "The unscented Kalman filter for nonlinear estimation", eqs. 15-17): the
//!   additive-noise form, with the update's sigma points drawn again from the predicted
//!   Gaussian, as filterpy 2.0 does.
//!
//! Time is in seconds, so scans may come at any interval; a model's cost does not depend on it.

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, ensure_in_range, ensure_non_negative};
use crate::gaussian::{CholeskyFactor, Gaussian, check_finite_matrix, symmetrise};
use crate::models::{Updated, innovation_from_residual, joseph_update};

/// x(t + Δ) = f(x(t), Δ) + w, w ~ N(0, Q(x(t), Δ)), for Δ ≥ 0 seconds.
pub trait MotionModel<const N: usize> {
    /// f(x, Δ), the noise-free state Δ seconds on; f(x, 0) = x.
    fn propagate(&self, x: &SVector<f64, N>, dt_s: f64) -> SVector<f64, N>;

    /// ∂f/∂x at x, the EKF's linearisation.
    fn jacobian(&self, x: &SVector<f64, N>, dt_s: f64) -> SMatrix<f64, N, N>;

    /// Q(x, Δ), the covariance of the noise accumulated over Δ seconds; the filters evaluate it
    /// at the prior mean.
    fn noise_covariance(&self, x: &SVector<f64, N>, dt_s: f64) -> SMatrix<f64, N, N>;
}

/// z = h(x) + v, v ~ N(0, R).
pub trait MeasurementModel<const N: usize, const M: usize> {
    /// h(x), the noise-free measurement.
    fn measure(&self, x: &SVector<f64, N>) -> SVector<f64, M>;

    /// ∂h/∂x at x, the EKF's linearisation.
    fn jacobian(&self, x: &SVector<f64, N>) -> SMatrix<f64, M, N>;

    /// R.
    fn noise(&self) -> SMatrix<f64, M, M>;

    /// z − ẑ; models with angles wrap them into (−π, π].
    fn residual(&self, z: &SVector<f64, M>, predicted: &SVector<f64, M>) -> SVector<f64, M> {
        z - predicted
    }

    /// Σ wᵢ zᵢ, the unscented transform's mean of measurements; models with angles take those
    /// as circular means, atan2(Σ wᵢ sin θᵢ, Σ wᵢ cos θᵢ).
    fn weighted_mean(&self, points: &[SVector<f64, M>], weights: &[f64]) -> SVector<f64, M> {
        points
            .iter()
            .zip(weights)
            .fold(SVector::zeros(), |acc, (p, w)| acc + p * *w)
    }
}

/// The scaled sigma points of Julier (2002) with Wan & van der Merwe's weights: λ = α²(n + κ)
/// − n; points x and x ± columns of √((n + λ) P); Wm₀ = λ / (n + λ), Wc₀ = Wm₀ + 1 − α² + β,
/// the others 1 / (2 (n + λ)).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawSigmaPoints", into = "RawSigmaPoints")]
pub struct SigmaPoints {
    alpha: f64,
    beta: f64,
    kappa: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSigmaPoints {
    alpha: f64,
    beta: f64,
    kappa: f64,
}

impl TryFrom<RawSigmaPoints> for SigmaPoints {
    type Error = Error;
    fn try_from(raw: RawSigmaPoints) -> Result<Self> {
        SigmaPoints::new(raw.alpha, raw.beta, raw.kappa)
    }
}

impl From<SigmaPoints> for RawSigmaPoints {
    fn from(s: SigmaPoints) -> Self {
        RawSigmaPoints {
            alpha: s.alpha,
            beta: s.beta,
            kappa: s.kappa,
        }
    }
}

/// The largest |κ| accepted: far beyond any published choice (κ = 0 or 3 − n).
pub const MAX_SIGMA_KAPPA: f64 = 1e3;

impl SigmaPoints {
    /// α ∈ (0, 1] spreads the points, β ≥ 0 carries prior knowledge of the distribution (2 is
    /// optimal for a Gaussian), κ is the secondary scaling; n + κ > 0 is checked where n is
    /// known.
    pub fn new(alpha: f64, beta: f64, kappa: f64) -> Result<Self> {
        ensure_in_range(alpha, f64::MIN_POSITIVE, 1.0, "alpha")?;
        ensure_non_negative(beta, "beta")?;
        ensure_in_range(kappa, -MAX_SIGMA_KAPPA, MAX_SIGMA_KAPPA, "kappa")?;
        Ok(Self { alpha, beta, kappa })
    }

    /// α = 1, β = 2, κ = 0: the points at √n standard deviations, with β's correction of the
    /// centre's covariance weight for a Gaussian prior.
    pub fn gaussian() -> Self {
        Self {
            alpha: 1.0,
            beta: 2.0,
            kappa: 0.0,
        }
    }

    /// n + λ and the weights (Wm, Wc) for an n-dimensional state.
    fn weights(&self, n: usize) -> Result<(f64, Vec<f64>, Vec<f64>)> {
        let n_f = n as f64;
        if n_f + self.kappa <= 0.0 {
            return Err(Error::InvalidParameter {
                name: "kappa",
                reason: format!(
                    "n + kappa must be positive; n = {n}, kappa = {}",
                    self.kappa
                ),
            });
        }
        let spread = self.alpha * self.alpha * (n_f + self.kappa);
        let lambda = spread - n_f;
        let other = 0.5 / spread;
        let mut wm = vec![other; 2 * n + 1];
        let mut wc = wm.clone();
        wm[0] = lambda / spread;
        wc[0] = wm[0] + (1.0 - self.alpha * self.alpha + self.beta);
        Ok((spread, wm, wc))
    }

    /// The 2n + 1 points of N(x, P) with their weights.
    fn draw<const N: usize>(&self, state: &Gaussian<N>) -> Result<SigmaSet<N>> {
        let (spread, wm, wc) = self.weights(N)?;
        let root = CholeskyFactor::new(&(state.covariance() * spread), "scaled sigma covariance")?;
        let l = root.l();
        let x = *state.mean();
        let mut points = Vec::with_capacity(2 * N + 1);
        points.push(x);
        points.extend((0..N).map(|k| x + l.column(k)));
        points.extend((0..N).map(|k| x - l.column(k)));
        Ok(SigmaSet { points, wm, wc })
    }
}

/// Sigma points and their mean and covariance weights.
struct SigmaSet<const N: usize> {
    points: Vec<SVector<f64, N>>,
    wm: Vec<f64>,
    wc: Vec<f64>,
}

/// How a Gaussian is carried through nonlinear models.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum GaussianFilter {
    /// The extended Kalman filter: the Kalman filter itself on linear models.
    Extended,
    /// The unscented Kalman filter with these sigma points.
    Unscented(SigmaPoints),
}

fn check_interval(dt_s: f64) -> Result<f64> {
    ensure_non_negative(dt_s, "dt_s")
}

impl GaussianFilter {
    /// The prediction Δ seconds ahead.
    pub fn predict<T, const N: usize>(
        &self,
        motion: &T,
        state: &Gaussian<N>,
        dt_s: f64,
    ) -> Result<Gaussian<N>>
    where
        T: MotionModel<N> + ?Sized,
    {
        check_interval(dt_s)?;
        let x = state.mean();
        let q = motion.noise_covariance(x, dt_s);
        let (mean, cov) = match self {
            GaussianFilter::Extended => {
                let f = motion.jacobian(x, dt_s);
                (
                    motion.propagate(x, dt_s),
                    f * state.covariance() * f.transpose() + q,
                )
            }
            GaussianFilter::Unscented(sigma) => {
                let mut set = sigma.draw(state)?;
                for p in &mut set.points {
                    *p = motion.propagate(p, dt_s);
                }
                let mean = weighted_sum(&set.points, &set.wm);
                (mean, weighted_outer(&set.points, &set.wc, &mean) + q)
            }
        };
        check_finite_matrix(&mean, "predicted mean")?;
        check_finite_matrix(&cov, "predicted covariance")?;
        Ok(Gaussian::from_parts(mean, symmetrise(&cov)))
    }

    /// The measurement update of a predicted state with z, and its innovation.
    pub fn update<O, const N: usize, const M: usize>(
        &self,
        sensor: &O,
        predicted: &Gaussian<N>,
        z: &SVector<f64, M>,
    ) -> Result<Updated<N, M>>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        check_finite_matrix(z, "measurement")?;
        match self {
            GaussianFilter::Extended => extended_update(sensor, predicted, z),
            GaussianFilter::Unscented(sigma) => unscented_update(sigma, sensor, predicted, z),
        }
    }
}

/// The predicted measurement N(ẑ, S) of a state, for gating: a measurement's distance to it
/// uses the model's residual, so angles are compared the short way round.
#[derive(Debug, Clone)]
pub struct MeasurementPrediction<const M: usize> {
    mean: SVector<f64, M>,
    chol: CholeskyFactor<M>,
}

impl<const M: usize> MeasurementPrediction<M> {
    /// ẑ.
    pub fn mean(&self) -> &SVector<f64, M> {
        &self.mean
    }

    /// (z − ẑ)ᵀ S⁻¹ (z − ẑ), the residual formed by `sensor`.
    pub fn mahalanobis_sq<O, const N: usize>(&self, sensor: &O, z: &SVector<f64, M>) -> f64
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        self.chol.mahalanobis_sq(&sensor.residual(z, &self.mean))
    }
}

impl GaussianFilter {
    /// N(ẑ, S) for `predicted` seen by `sensor`: linearised (EKF) or by the unscented
    /// transform (UKF), as this filter's update forms it.
    pub fn predict_measurement<O, const N: usize, const M: usize>(
        &self,
        sensor: &O,
        predicted: &Gaussian<N>,
    ) -> Result<MeasurementPrediction<M>>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        let (mean, spread) = match self {
            GaussianFilter::Extended => {
                let lin = linearise(sensor, predicted)?;
                (lin.zhat, lin.hp * lin.h.transpose())
            }
            GaussianFilter::Unscented(sigma) => {
                let ut = unscented_measurement(sigma, sensor, predicted)?;
                (ut.zhat, ut.spread)
            }
        };
        let s = symmetrise(&(spread + sensor.noise()));
        Ok(MeasurementPrediction {
            mean,
            chol: CholeskyFactor::new(&s, "innovation covariance")?,
        })
    }
}

/// The EKF's view of a prediction: ẑ = h(x⁻), H = ∂h/∂x at x⁻ and H P⁻, checked finite.
struct Linearised<const N: usize, const M: usize> {
    zhat: SVector<f64, M>,
    h: SMatrix<f64, M, N>,
    hp: SMatrix<f64, M, N>,
}

fn linearise<O, const N: usize, const M: usize>(
    sensor: &O,
    predicted: &Gaussian<N>,
) -> Result<Linearised<N, M>>
where
    O: MeasurementModel<N, M> + ?Sized,
{
    let x = predicted.mean();
    let h = sensor.jacobian(x);
    check_finite_matrix(&h, "measurement Jacobian")?;
    let zhat = sensor.measure(x);
    check_finite_matrix(&zhat, "predicted measurement")?;
    Ok(Linearised {
        zhat,
        hp: h * predicted.covariance(),
        h,
    })
}

/// The UKF's view of a prediction: its sigma points through h, ẑ (checked finite),
/// Σ Wcᵢ (ζᵢ − ẑ)(ζᵢ − ẑ)ᵀ and the cross covariance Σ Wcᵢ (χᵢ − x⁻)(ζᵢ − ẑ)ᵀ.
struct Transformed<const N: usize, const M: usize> {
    zhat: SVector<f64, M>,
    spread: SMatrix<f64, M, M>,
    cross: SMatrix<f64, N, M>,
}

fn unscented_measurement<O, const N: usize, const M: usize>(
    sigma: &SigmaPoints,
    sensor: &O,
    predicted: &Gaussian<N>,
) -> Result<Transformed<N, M>>
where
    O: MeasurementModel<N, M> + ?Sized,
{
    let set = sigma.draw(predicted)?;
    let zs: Vec<SVector<f64, M>> = set.points.iter().map(|p| sensor.measure(p)).collect();
    let zhat = sensor.weighted_mean(&zs, &set.wm);
    check_finite_matrix(&zhat, "predicted measurement")?;
    let x = predicted.mean();
    let mut spread = SMatrix::<f64, M, M>::zeros();
    let mut cross = SMatrix::<f64, N, M>::zeros();
    for ((p, zi), w) in set.points.iter().zip(&zs).zip(&set.wc) {
        let dz = sensor.residual(zi, &zhat);
        spread += dz * dz.transpose() * *w;
        cross += (p - x) * dz.transpose() * *w;
    }
    Ok(Transformed {
        zhat,
        spread,
        cross,
    })
}

/// The EKF update: H = ∂h/∂x at x⁻, residual z − h(x⁻) (wrapped by the model), Joseph form.
fn extended_update<O, const N: usize, const M: usize>(
    sensor: &O,
    predicted: &Gaussian<N>,
    z: &SVector<f64, M>,
) -> Result<Updated<N, M>>
where
    O: MeasurementModel<N, M> + ?Sized,
{
    let Linearised { zhat, h, hp } = linearise(sensor, predicted)?;
    let r = sensor.noise();
    let innovated =
        innovation_from_residual(hp, hp * h.transpose(), &r, sensor.residual(z, &zhat))?;
    Ok(joseph_update(innovated, predicted, &r, |a| {
        a * h.transpose()
    }))
}

/// The UKF update (Wan & van der Merwe 2000, eq. 17): sigma points of N(x⁻, P⁻) through h,
/// S = Σ Wcᵢ (ζᵢ − ẑ)(ζᵢ − ẑ)ᵀ + R, P_xz = Σ Wcᵢ (χᵢ − x⁻)(ζᵢ − ẑ)ᵀ, K = P_xz S⁻¹,
/// P = P⁻ − K S Kᵀ.
fn unscented_update<O, const N: usize, const M: usize>(
    sigma: &SigmaPoints,
    sensor: &O,
    predicted: &Gaussian<N>,
    z: &SVector<f64, M>,
) -> Result<Updated<N, M>>
where
    O: MeasurementModel<N, M> + ?Sized,
{
    let Transformed {
        zhat,
        spread,
        cross,
    } = unscented_measurement(sigma, sensor, predicted)?;
    // Passing Pxzᵀ as "H P" and S − R as "H P Hᵀ" gives S, its factor and the likelihood from
    // the same code as the EKF.
    let r = sensor.noise();
    let residual = sensor.residual(z, &zhat);
    let innovated = innovation_from_residual(cross.transpose(), spread, &r, residual)?;
    let s_full = innovated.innovation.covariance;
    let gain = innovated.chol.solve(&cross.transpose()).transpose();
    let mean = predicted.mean() + gain * innovated.innovation.residual;
    let cov = predicted.covariance() - gain * s_full * gain.transpose();
    check_finite_matrix(&cov, "updated covariance")?;
    Ok(Updated {
        state: Gaussian::from_parts(mean, symmetrise(&cov)),
        innovation: innovated.innovation,
    })
}

fn weighted_sum<const N: usize>(points: &[SVector<f64, N>], weights: &[f64]) -> SVector<f64, N> {
    points
        .iter()
        .zip(weights)
        .fold(SVector::zeros(), |acc, (p, w)| acc + p * *w)
}

/// Σ Wcᵢ (xᵢ − x̄)(xᵢ − x̄)ᵀ.
fn weighted_outer<const N: usize>(
    points: &[SVector<f64, N>],
    weights: &[f64],
    mean: &SVector<f64, N>,
) -> SMatrix<f64, N, N> {
    points
        .iter()
        .zip(weights)
        .fold(SMatrix::zeros(), |acc, (p, w)| {
            let d = p - mean;
            acc + d * d.transpose() * *w
        })
}
