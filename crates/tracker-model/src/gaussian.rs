//! Gaussian states and the matrix checks every covariance goes through.

use nalgebra::{SMatrix, SVector};
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
#[serde(deny_unknown_fields)]
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
        Ok(chol.mahalanobis_sq(&(x - self.mean)))
    }

    /// Log-density at `x`.
    pub fn log_pdf(&self, x: &SVector<f64, N>) -> Result<f64> {
        let chol = cholesky_checked(&self.covariance, "state covariance")?;
        Ok(chol.log_normal(&(x - self.mean)))
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

/// Cholesky factor of a symmetric positive-definite matrix, after checking that it is finite
/// and symmetric; an error naming the matrix otherwise.
pub fn cholesky_checked<const N: usize>(
    m: &SMatrix<f64, N, N>,
    what: &'static str,
) -> Result<CholeskyFactor<N>> {
    check_finite_matrix(m, what)?;
    check_symmetric(m, what)?;
    CholeskyFactor::new(m, what)
}

/// The lower-triangular Cholesky factor L (L Lᵀ = A) of a small symmetric positive-definite
/// matrix.
///
/// nalgebra's general factorisation and triangular solves loop over dynamic column views; for
/// the 2×2 to 6×6 covariances of tracking, these fixed-size loops unroll completely and make
/// the whole filter-smoother several times faster (see docs/benchmarks.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CholeskyFactor<const N: usize> {
    /// Row-major L; plain arrays let the compiler drop bounds checks and unroll.
    l: [[f64; N]; N],
    /// 1 / Lᵢᵢ, so the substitutions multiply instead of divide.
    inv_diag: [f64; N],
}

#[expect(
    clippy::needless_range_loop,
    reason = "index loops mirror the textbook substitution formulas"
)]
impl<const N: usize> CholeskyFactor<N> {
    /// Factorises `a`, reading only its lower triangle; a non-positive (or NaN) pivot is a
    /// [`Error::NotPositiveDefinite`] naming `what`.
    pub fn new(a: &SMatrix<f64, N, N>, what: &'static str) -> Result<Self> {
        let mut l = [[0.0; N]; N];
        let mut inv_diag = [0.0; N];
        for j in 0..N {
            let mut d = a[(j, j)];
            for k in 0..j {
                d -= l[j][k] * l[j][k];
            }
            if d.is_nan() || d <= 0.0 {
                return Err(Error::NotPositiveDefinite { what });
            }
            let ljj = d.sqrt();
            l[j][j] = ljj;
            inv_diag[j] = 1.0 / ljj;
            for i in (j + 1)..N {
                let mut s = a[(i, j)];
                for k in 0..j {
                    s -= l[i][k] * l[j][k];
                }
                l[i][j] = s * inv_diag[j];
            }
        }
        Ok(Self { l, inv_diag })
    }

    /// L.
    pub fn l(&self) -> SMatrix<f64, N, N> {
        SMatrix::from_fn(|i, j| self.l[i][j])
    }

    /// Solves L Y = B. Rows are processed in order and every right-hand side at once, so the
    /// innermost loop runs over the columns of B and vectorises.
    pub fn solve_lower<const C: usize>(&self, b: &SMatrix<f64, N, C>) -> SMatrix<f64, N, C> {
        let mut y = [[0.0; C]; N];
        for i in 0..N {
            let mut row = [0.0; C];
            for (c, v) in row.iter_mut().enumerate() {
                *v = b[(i, c)];
            }
            for k in 0..i {
                let lik = self.l[i][k];
                for c in 0..C {
                    row[c] -= lik * y[k][c];
                }
            }
            for c in 0..C {
                y[i][c] = row[c] * self.inv_diag[i];
            }
        }
        SMatrix::from_fn(|i, c| y[i][c])
    }

    /// Solves A X = B (forward substitution with L, then back substitution with Lᵀ).
    pub fn solve<const C: usize>(&self, b: &SMatrix<f64, N, C>) -> SMatrix<f64, N, C> {
        let y = self.solve_lower(b);
        let mut x = [[0.0; C]; N];
        for i in (0..N).rev() {
            let mut row = [0.0; C];
            for (c, v) in row.iter_mut().enumerate() {
                *v = y[(i, c)];
            }
            for k in (i + 1)..N {
                let lki = self.l[k][i];
                for c in 0..C {
                    row[c] -= lki * x[k][c];
                }
            }
            for c in 0..C {
                x[i][c] = row[c] * self.inv_diag[i];
            }
        }
        SMatrix::from_fn(|i, c| x[i][c])
    }

    /// 1 / Lᵢᵢ.
    pub fn inv_diag(&self, i: usize) -> f64 {
        self.inv_diag[i]
    }

    /// ½ log det A = Σ log Lᵢᵢ.
    pub fn half_log_det(&self) -> f64 {
        (0..N).map(|i| self.l[i][i].ln()).sum()
    }

    /// rᵀ A⁻¹ r.
    pub fn mahalanobis_sq(&self, r: &SVector<f64, N>) -> f64 {
        self.solve_lower(r).norm_squared()
    }

    /// log N(r; 0, A).
    pub fn log_normal(&self, r: &SVector<f64, N>) -> f64 {
        self.log_normal_given(self.mahalanobis_sq(r))
    }

    /// log N(r; 0, A) from an already computed rᵀ A⁻¹ r.
    pub fn log_normal_given(&self, mahalanobis_sq: f64) -> f64 {
        -0.5 * (mahalanobis_sq + N as f64 * LN_2PI) - self.half_log_det()
    }
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
    CholeskyFactor::new(&shifted, what).map(|_| ())
}

/// (Pᵀ + P)/2: removes the asymmetry that rounding adds in covariance products.
pub(crate) fn symmetrise<const N: usize>(m: &SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
    (m + m.transpose()) * 0.5
}
