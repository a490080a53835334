//! Gaussian states and the matrix checks every covariance goes through.

use nalgebra::{Cholesky, SMatrix, SVector};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// ln(2π), used by every Gaussian log-density.
pub const LN_2PI: f64 = 1.837_877_066_409_345_3;

/// A multivariate Gaussian N(mean, covariance) over an `N`-dimensional state.
///
/// Built through [`Gaussian::new`], which rejects non-finite values and covariances that are not
/// symmetric positive definite; the Kalman operations keep both properties (Joseph-form update,
/// explicit symmetrisation), so a `Gaussian` is always valid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawGaussian<N>", into = "RawGaussian<N>")]
pub struct Gaussian<const N: usize> {
    mean: SVector<f64, N>,
    covariance: SMatrix<f64, N, N>,
}

#[derive(Serialize, Deserialize)]
struct RawGaussian<const N: usize> {
    mean: SVector<f64, N>,
    covariance: SMatrix<f64, N, N>,
}

impl<const N: usize> TryFrom<RawGaussian<N>> for Gaussian<N> {
    type Error = Error;
    fn try_from(raw: RawGaussian<N>) -> Result<Self> {
        Gaussian::new(raw.mean, raw.covariance)
    }
}

impl<const N: usize> From<Gaussian<N>> for RawGaussian<N> {
    fn from(g: Gaussian<N>) -> Self {
        RawGaussian {
            mean: g.mean,
            covariance: g.covariance,
        }
    }
}

impl<const N: usize> Gaussian<N> {
    /// A Gaussian after checking that the mean is finite and the covariance symmetric positive
    /// definite.
    pub fn new(mean: SVector<f64, N>, covariance: SMatrix<f64, N, N>) -> Result<Self> {
        check_finite_matrix(&mean, "state mean")?;
        cholesky_checked(&covariance, "state covariance")?;
        Ok(Self { mean, covariance })
    }

    /// Builds without the checks; for results of operations that preserve validity.
    pub(crate) fn from_parts(mean: SVector<f64, N>, covariance: SMatrix<f64, N, N>) -> Self {
        Self { mean, covariance }
    }

    /// The mean vector.
    pub fn mean(&self) -> &SVector<f64, N> {
        &self.mean
    }

    /// The covariance matrix (symmetric positive definite).
    pub fn covariance(&self) -> &SMatrix<f64, N, N> {
        &self.covariance
    }

    /// Splits into (mean, covariance).
    pub fn into_parts(self) -> (SVector<f64, N>, SMatrix<f64, N, N>) {
        (self.mean, self.covariance)
    }

    /// Squared Mahalanobis distance (x − m)ᵀ P⁻¹ (x − m); with x the true state this is the
    /// normalised estimation error squared (NEES).
    pub fn mahalanobis_sq(&self, x: &SVector<f64, N>) -> Result<f64> {
        let chol = cholesky_checked(&self.covariance, "state covariance")?;
        Ok(mahalanobis_sq_with(&chol, &(x - self.mean)))
    }

    /// Log-density at `x`.
    pub fn log_pdf(&self, x: &SVector<f64, N>) -> Result<f64> {
        let chol = cholesky_checked(&self.covariance, "state covariance")?;
        Ok(log_normal_with(&chol, &(x - self.mean)))
    }
}

/// Checks every entry of a matrix for NaN or infinity.
pub fn check_finite_matrix<const R: usize, const C: usize>(
    m: &SMatrix<f64, R, C>,
    what: &'static str,
) -> Result<()> {
    if m.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Error::NonFinite { what })
    }
}

/// Checks symmetry to a relative tolerance of 1e-9 of the largest entry.
pub fn check_symmetric<const N: usize>(m: &SMatrix<f64, N, N>, what: &'static str) -> Result<()> {
    let scale = m.amax().max(f64::MIN_POSITIVE);
    for i in 0..N {
        for j in (i + 1)..N {
            if (m[(i, j)] - m[(j, i)]).abs() > 1e-9 * scale {
                return Err(Error::NotSymmetric { what });
            }
        }
    }
    Ok(())
}

/// Cholesky factor of a symmetric positive-definite matrix, or an error naming it.
pub fn cholesky_checked<const N: usize>(
    m: &SMatrix<f64, N, N>,
    what: &'static str,
) -> Result<Cholesky<f64, nalgebra::Const<N>>> {
    check_finite_matrix(m, what)?;
    check_symmetric(m, what)?;
    Cholesky::new(*m).ok_or(Error::NotPositiveDefinite { what })
}

/// Checks that a matrix is symmetric positive semi-definite, to rounding level (process noise may be singular,
/// e.g. the MCMCDA model's G Σ Gᵀ has rank 2 in a 4-D state).
pub fn check_positive_semidefinite<const N: usize>(
    m: &SMatrix<f64, N, N>,
    what: &'static str,
) -> Result<()> {
    check_finite_matrix(m, what)?;
    check_symmetric(m, what)?;
    // A PSD matrix plus a tiny ridge is positive definite; an indefinite one is not (unless its
    // negative eigenvalue is below rounding level, which we accept as zero).
    let ridge = 1e-12 * m.amax().max(f64::MIN_POSITIVE);
    let shifted = m + SMatrix::<f64, N, N>::identity() * ridge;
    if Cholesky::new(shifted).is_some() {
        Ok(())
    } else {
        Err(Error::NotPositiveDefinite { what })
    }
}

/// (Pᵀ + P)/2: removes the asymmetry that rounding adds in covariance products.
pub(crate) fn symmetrise<const N: usize>(m: &SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
    (m + m.transpose()) * 0.5
}

/// r ᵀ S⁻¹ r given the Cholesky factor of S.
pub(crate) fn mahalanobis_sq_with<const N: usize>(
    chol: &Cholesky<f64, nalgebra::Const<N>>,
    r: &SVector<f64, N>,
) -> f64 {
    // Solve L y = r; then rᵀ S⁻¹ r = yᵀ y.
    let y = chol
        .l_dirty()
        .solve_lower_triangular(r)
        .unwrap_or_else(|| SVector::repeat(f64::INFINITY));
    y.norm_squared()
}

/// log N(r; 0, S) given the Cholesky factor of S.
pub(crate) fn log_normal_with<const N: usize>(
    chol: &Cholesky<f64, nalgebra::Const<N>>,
    r: &SVector<f64, N>,
) -> f64 {
    let half_log_det: f64 = chol.l_dirty().diagonal().iter().map(|d| d.ln()).sum();
    -0.5 * (mahalanobis_sq_with(chol, r) + N as f64 * LN_2PI) - half_log_det
}
