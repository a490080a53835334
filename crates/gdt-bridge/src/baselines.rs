//! The baselines GDT is compared with (Oh & Jung 2015, Table 1): linear interpolation, the natural
//! cubic spline through the observed samples (SciPy's `CubicSpline(bc_type='natural')`), and a
//! weighted least-squares cubic B-spline with clamped knots (SciPy's `make_lsq_spline`).
//! Each works on one coordinate: samples (t_i, p_i) with strictly increasing t_i.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use tracker_model::ensure_positive;

use crate::error::{Error, Result};

/// Checks the samples of a method (`what`) that needs at least `min` of them.
fn check_samples(times: &[f64], values: &[f64], min: usize, what: &'static str) -> Result<()> {
    if times.len() != values.len() {
        return Err(Error::LengthMismatch {
            what: "values",
            n_times: times.len(),
            len: values.len(),
        });
    }
    if times.len() < min {
        return Err(Error::TooFewSamples {
            what,
            len: times.len(),
            min,
        });
    }
    if let Some(index) =
        (0..times.len()).find(|&i| !(times[i].is_finite() && values[i].is_finite()))
    {
        return Err(Error::NonFiniteSample {
            index,
            time: times[index],
            value: values[index],
        });
    }
    if let Some(w) = times.windows(2).find(|w| w[1] <= w[0]) {
        return Err(Error::TimesOutOfOrder {
            time: w[1],
            last: w[0],
        });
    }
    Ok(())
}

/// The index i of the interval [t_i, t_{i+1}] holding `x` (clamped to the end intervals, so
/// values outside the samples extrapolate the end pieces).
fn interval(times: &[f64], x: f64) -> usize {
    times
        .partition_point(|&t| t <= x)
        .saturating_sub(1)
        .min(times.len() - 2)
}

/// Piecewise-linear interpolation of the samples at `at`.
pub fn linear(times: &[f64], values: &[f64], at: &[f64]) -> Result<Vec<f64>> {
    check_samples(times, values, 2, "a linear interpolation")?;
    Ok(at
        .iter()
        .map(|&x| {
            let i = interval(times, x);
            let w = (x - times[i]) / (times[i + 1] - times[i]);
            values[i] + w * (values[i + 1] - values[i])
        })
        .collect())
}

/// The natural cubic spline (zero second derivative at both ends) through the samples,
/// evaluated at `at`. Second derivatives M_i solve the tridiagonal system
/// h_{i−1} M_{i−1} + 2(h_{i−1} + h_i) M_i + h_i M_{i+1} = 6 (Δ_i − Δ_{i−1}) by the Thomas
/// algorithm (the system is strictly diagonally dominant, so no pivoting is needed).
pub fn natural_cubic_spline(times: &[f64], values: &[f64], at: &[f64]) -> Result<Vec<f64>> {
    check_samples(times, values, 2, "a natural cubic spline")?;
    let n = times.len();
    let h: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let slope: Vec<f64> = (0..n - 1)
        .map(|i| (values[i + 1] - values[i]) / h[i])
        .collect();
    let mut m = vec![0.0; n];
    if n > 2 {
        // Unknowns M_1..M_{n−2}; forward elimination then back substitution.
        let k = n - 2;
        let mut diag: Vec<f64> = (1..=k).map(|i| 2.0 * (h[i - 1] + h[i])).collect();
        let mut rhs: Vec<f64> = (1..=k).map(|i| 6.0 * (slope[i] - slope[i - 1])).collect();
        for r in 1..k {
            let factor = h[r] / diag[r - 1];
            diag[r] -= factor * h[r];
            rhs[r] -= factor * rhs[r - 1];
        }
        m[k] = rhs[k - 1] / diag[k - 1];
        for r in (0..k - 1).rev() {
            m[r + 1] = (rhs[r] - h[r + 1] * m[r + 2]) / diag[r];
        }
    }
    Ok(at
        .iter()
        .map(|&x| {
            let i = interval(times, x);
            let (a, b) = (times[i + 1] - x, x - times[i]);
            let hi = h[i];
            m[i] * a.powi(3) / (6.0 * hi)
                + m[i + 1] * b.powi(3) / (6.0 * hi)
                + (values[i] / hi - m[i] * hi / 6.0) * a
                + (values[i + 1] / hi - m[i + 1] * hi / 6.0) * b
        })
        .collect())
}

/// Settings of the least-squares B-spline baseline. Every value is valid: there is nothing
/// to check (whether the samples determine the spline is checked when fitting).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BSplineConfig {
    /// Interior knots per side of the gap, spread uniformly over each side's samples (none is
    /// placed inside the gap, so every knot span has data: Schoenberg-Whitney).
    pub interior_knots_per_side: usize,
}

impl Default for BSplineConfig {
    fn default() -> Self {
        Self {
            interior_knots_per_side: 2,
        }
    }
}

/// Cox-de Boor: the values of all cubic B-spline basis functions of `knots` at `x` (x within
/// the clamped end knots; at the right end the last non-empty span is used).
fn basis(knots: &[f64], x: f64) -> Vec<f64> {
    let last = knots.len() - 1;
    let span = if x >= knots[last] {
        (0..last).rev().find(|&i| knots[i] < knots[i + 1])
    } else {
        (0..last).rev().find(|&i| knots[i] <= x && x < knots[i + 1])
    };
    let mut b = vec![0.0; last];
    if let Some(i) = span {
        b[i] = 1.0;
    }
    for degree in 1..=3 {
        for i in 0..last - degree {
            let left_den = knots[i + degree] - knots[i];
            let right_den = knots[i + degree + 1] - knots[i + 1];
            let left = if left_den > 0.0 {
                (x - knots[i]) / left_den * b[i]
            } else {
                0.0
            };
            let right = if right_den > 0.0 {
                (knots[i + degree + 1] - x) / right_den * b[i + 1]
            } else {
                0.0
            };
            b[i] = left + right;
        }
    }
    b.truncate(knots.len() - 4);
    b
}

/// A weighted least-squares cubic B-spline fitted to samples on both sides of a gap
/// (minimising Σ (w_i (S(t_i) − p_i))², weights multiplying residuals as in SciPy), evaluated at
/// `at`. Knots: 4 clamped knots at each end and `interior_knots_per_side` uniform interior
/// knots among the samples before `gap_start` and after `gap_end`.
pub fn lsq_bspline(
    times: &[f64],
    values: &[f64],
    weights: &[f64],
    gap: (f64, f64),
    config: &BSplineConfig,
    at: &[f64],
) -> Result<Vec<f64>> {
    check_samples(times, values, 4, "a cubic B-spline")?;
    if weights.len() != times.len() {
        return Err(Error::LengthMismatch {
            what: "weights",
            n_times: times.len(),
            len: weights.len(),
        });
    }
    for w in weights {
        ensure_positive(*w, "weights")?;
    }
    let (t0, t1) = (times[0], times[times.len() - 1]);
    let before: Vec<f64> = times.iter().copied().filter(|&t| t <= gap.0).collect();
    let after: Vec<f64> = times.iter().copied().filter(|&t| t >= gap.1).collect();
    let mut knots = vec![t0; 4];
    for side in [&before, &after] {
        if side.len() < 2 {
            continue;
        }
        let (a, b) = (side[0], side[side.len() - 1]);
        for k in 1..=config.interior_knots_per_side {
            let knot = a + (b - a) * k as f64 / (config.interior_knots_per_side + 1) as f64;
            if knot > t0 && knot < t1 {
                knots.push(knot);
            }
        }
    }
    knots.extend([t1; 4]);
    let n_knots = knots.len();
    knots[4..n_knots - 4].sort_by(f64::total_cmp);
    let n_basis = knots.len() - 4;
    if times.len() < n_basis {
        return Err(Error::TooFewSamples {
            what: "the B-spline's coefficients",
            len: times.len(),
            min: n_basis,
        });
    }
    let design = DMatrix::from_fn(times.len(), n_basis, |r, c| {
        weights[r] * basis(&knots, times[r])[c]
    });
    let rhs = DVector::from_iterator(times.len(), values.iter().zip(weights).map(|(v, w)| v * w));
    // Least squares by QR of the weighted design matrix: R c = Qᵀ b.
    let qr = design.qr();
    let qtb = qr.q().transpose() * rhs;
    let coeffs = qr
        .r()
        .solve_upper_triangular(&qtb)
        .ok_or(Error::RankDeficientFit)?;
    Ok(at
        .iter()
        .map(|&x| {
            basis(&knots, x.clamp(t0, t1))
                .iter()
                .zip(coeffs.iter())
                .map(|(b, c)| b * c)
                .sum()
        })
        .collect())
}
