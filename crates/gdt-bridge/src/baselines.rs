//! The baselines GDT is compared with. Each works on one coordinate: samples (t_i, p_i) with
//! strictly increasing t_i.
//!
//! * [`linear`]: piecewise-linear interpolation;
//! * [`natural_cubic_spline`]: the natural cubic spline through every sample (a knot at every
//!   sample, SciPy's `CubicSpline(bc_type='natural')`);
//! * [`BSpline::fit_lsq`] / [`lsq_bspline`]: the weighted least-squares cubic B-spline on an
//!   explicit knot vector (SciPy's `make_lsq_spline`); [`gap_knots`] is Oh & Jung's (2015)
//!   comparison's knot rule (uniform interior knots on each side of the gap);
//! * [`SmoothingSpline`]: the cubic smoothing spline (Reinsch 1967) with λ chosen by
//!   generalized cross-validation (Craven & Wahba 1979), SciPy's `make_smoothing_spline`.

use serde::{Deserialize, Serialize};
use tracker_model::ensure_positive;

use crate::error::{Error, Result, invalid_parameter};
use crate::search::golden_section;

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

/// The cubic spline with values `g` and second derivatives `m` at the knots `times`, at `x`
/// (outside the knots, the end pieces continue).
fn cubic_piece(times: &[f64], g: &[f64], m: &[f64], x: f64) -> f64 {
    let i = interval(times, x);
    let (a, b) = (times[i + 1] - x, x - times[i]);
    let hi = times[i + 1] - times[i];
    m[i] * a.powi(3) / (6.0 * hi)
        + m[i + 1] * b.powi(3) / (6.0 * hi)
        + (g[i] / hi - m[i] * hi / 6.0) * a
        + (g[i + 1] / hi - m[i + 1] * hi / 6.0) * b
}

/// The natural cubic spline (zero second derivative at both ends) through the samples,
/// evaluated at `at`. Knots: every sample. Second derivatives M_i solve the tridiagonal system
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
        .map(|&x| cubic_piece(times, values, &m, x))
        .collect())
}

// ---------------------------------------------------------------------------------------------
// Least-squares cubic B-spline

/// Settings of the least-squares B-spline baseline of Oh & Jung's comparison (see
/// [`gap_knots`]). Every value is valid: there is nothing to check (whether the samples
/// determine the spline is checked when fitting).
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

/// The knot rule of the B-spline baseline in Oh & Jung's comparison: 4 clamped knots at the
/// first and at the last sample, and `interior_knots_per_side` knots spread uniformly between
/// the first and the last sample of each side (the samples at or before `gap.0`, and those at
/// or after `gap.1`). A side with fewer than two samples gets no interior knot. With 2 per
/// side over two segments of ≈ 90 samples this is 8 coefficients for ≈ 200 frames.
pub fn gap_knots(times: &[f64], gap: (f64, f64), interior_knots_per_side: usize) -> Vec<f64> {
    let (Some(&t0), Some(&t1)) = (times.first(), times.last()) else {
        return Vec::new();
    };
    let mut knots = vec![t0; 4];
    let before: Vec<f64> = times.iter().copied().filter(|&t| t <= gap.0).collect();
    let after: Vec<f64> = times.iter().copied().filter(|&t| t >= gap.1).collect();
    for side in [&before, &after] {
        if side.len() < 2 {
            continue;
        }
        let (a, b) = (side[0], side[side.len() - 1]);
        for k in 1..=interior_knots_per_side {
            let knot = a + (b - a) * k as f64 / (interior_knots_per_side + 1) as f64;
            if knot > t0 && knot < t1 {
                knots.push(knot);
            }
        }
    }
    knots.extend([t1; 4]);
    let n_knots = knots.len();
    knots[4..n_knots - 4].sort_by(f64::total_cmp);
    knots
}

/// A cubic spline in B-spline form: knots t_0..t_{n+3} and n coefficients. It is defined on
/// the base interval [t_3, t_n]; outside it the end polynomial pieces continue (SciPy's
/// `BSpline(extrapolate=True)`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BSpline {
    knots: Vec<f64>,
    coefficients: Vec<f64>,
}

/// The cubic degree.
const K: usize = 3;

/// The knot span μ (t_μ ≤ x < t_{μ+1}, K ≤ μ < n) whose polynomial piece is used at `x`;
/// outside the base interval the end spans.
fn span(knots: &[f64], n_basis: usize, x: f64) -> usize {
    // The last μ in [K, n−1] with t_μ ≤ x; knots are non-decreasing.
    let upper = knots[K + 1..n_basis].partition_point(|&t| t <= x);
    let mut mu = K + upper;
    // Repeated knots make empty spans; step back to a non-empty one.
    while mu > K && knots[mu] >= knots[mu + 1] {
        mu -= 1;
    }
    mu
}

/// The four cubic B-splines that are non-zero on span μ, N_{μ−3..=μ}(x), by de Boor's
/// recursion (de Boor 1978, ch. X; Piegl & Tiller 1997, Algorithm A2.2). On a non-empty span
/// every denominator is at least t_{μ+1} − t_μ > 0.
fn nonzero_basis(knots: &[f64], mu: usize, x: f64) -> [f64; 4] {
    let mut n = [1.0, 0.0, 0.0, 0.0];
    let (mut left, mut right) = ([0.0; 4], [0.0; 4]);
    for j in 1..=K {
        left[j] = x - knots[mu + 1 - j];
        right[j] = knots[mu + j] - x;
        let mut saved = 0.0;
        for r in 0..j {
            let temp = n[r] / (right[r + 1] + left[j - r]);
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    n
}

impl BSpline {
    /// The weighted least-squares cubic spline on `knots` (non-decreasing, finite, at least 8,
    /// no value more than 4 times, every sample time inside [t_3, t_{n}]): minimises
    /// Σ (w_i (S(t_i) − p_i))², weights multiplying residuals as in SciPy's `make_lsq_spline`.
    ///
    /// Each sample's four non-zero basis values come from one de Boor recursion; the normal
    /// equations BᵀW²B c = BᵀW²p are banded (half-bandwidth 3) and solved by a banded
    /// Cholesky factorisation, O(n_samples + n_coefficients) in time and memory. A pivot that
    /// vanishes means that the samples do not determine the coefficients (Schoenberg-Whitney
    /// fails: a coefficient without data): [`Error::RankDeficientFit`].
    pub fn fit_lsq(times: &[f64], values: &[f64], weights: &[f64], knots: &[f64]) -> Result<Self> {
        let n_basis = check_lsq(times, values, weights, knots)?;
        let (mut gram, mut rhs) = lsq_normal_equations(times, values, weights, knots, n_basis);
        banded_cholesky(&mut gram)?;
        banded_solve(&gram, &mut rhs);
        Ok(Self {
            knots: knots.to_vec(),
            coefficients: rhs,
        })
    }

    /// The knots.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The coefficients, one per basis function.
    pub fn coefficients(&self) -> &[f64] {
        &self.coefficients
    }

    /// S(x); outside the base interval the end pieces continue.
    pub fn value(&self, x: f64) -> f64 {
        let n_basis = self.coefficients.len();
        let mu = span(&self.knots, n_basis, x);
        let b = nonzero_basis(&self.knots, mu, x);
        (0..4).map(|r| b[r] * self.coefficients[mu - K + r]).sum()
    }
}

/// Checks the inputs of [`BSpline::fit_lsq`] in its order of errors (samples, weights, knots,
/// sample times inside the base interval, at least as many samples as coefficients) and
/// returns the number of basis functions.
fn check_lsq(times: &[f64], values: &[f64], weights: &[f64], knots: &[f64]) -> Result<usize> {
    check_samples(times, values, 1, "a cubic B-spline")?;
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
    check_knots(knots)?;
    let n_basis = knots.len() - K - 1;
    let (lo, hi) = (knots[K], knots[n_basis]);
    if let Some(&t) = times.iter().find(|&&t| t < lo || t > hi) {
        return Err(Error::SampleOutsideKnots {
            time: t,
            lower: lo,
            upper: hi,
        });
    }
    if times.len() < n_basis {
        return Err(Error::TooFewSamples {
            what: "the B-spline's coefficients",
            len: times.len(),
            min: n_basis,
        });
    }
    Ok(n_basis)
}

/// The weighted normal equations BᵀW²B c = BᵀW²p of the least-squares spline, banded: the
/// lower band of the normal matrix, gram\[c\]\[d\] = G\[c\]\[c − d\] for d = 0..=3, and the
/// right-hand side. Each sample adds the outer product of its four non-zero basis values
/// (de Boor 1978).
fn lsq_normal_equations(
    times: &[f64],
    values: &[f64],
    weights: &[f64],
    knots: &[f64],
    n_basis: usize,
) -> (Vec<[f64; 4]>, Vec<f64>) {
    // Lower band of the normal matrix: gram[c][d] = G[c][c − d], d = 0..=3.
    let mut gram = vec![[0.0; 4]; n_basis];
    let mut rhs = vec![0.0; n_basis];
    for ((&t, &p), &w) in times.iter().zip(values).zip(weights) {
        let mu = span(knots, n_basis, t);
        let b = nonzero_basis(knots, mu, t);
        let w2 = w * w;
        let first = mu - K;
        for r in 0..4 {
            let wr = w2 * b[r];
            rhs[first + r] += wr * p;
            for c in 0..=r {
                gram[first + r][r - c] += wr * b[c];
            }
        }
    }
    (gram, rhs)
}

/// Banded Cholesky factorisation G = L Lᵀ in place (half-bandwidth 3; Golub & Van Loan,
/// "Matrix Computations", band Cholesky): gram\[i\]\[d\] becomes L\[i\]\[i − d\]. A pivot at
/// rounding level against the scale of its diagonal is [`Error::RankDeficientFit`].
fn banded_cholesky(gram: &mut [[f64; 4]]) -> Result<()> {
    let n_basis = gram.len();
    for i in 0..n_basis {
        for d in (0..4).rev() {
            if d > i {
                continue;
            }
            let j = i - d;
            let mut s = gram[i][d];
            // Σ_k L[i][k] L[j][k] over k < j within both bands.
            for k in i.saturating_sub(3)..j {
                s -= gram[i][i - k] * gram[j][j - k];
            }
            if d == 0 {
                // The pivot against the scale of the diagonal: a coefficient no sample
                // informs leaves a pivot at rounding level.
                let scale = gram_diag_scale(gram, i, s);
                if s <= scale * 1e-13 {
                    return Err(Error::RankDeficientFit);
                }
                gram[i][0] = s.sqrt();
            } else {
                gram[i][d] = s / gram[j][0];
            }
        }
    }
    Ok(())
}

/// Solves L Lᵀ c = rhs in place with the banded factor of [`banded_cholesky`]: forward
/// substitution L z = rhs, then back substitution Lᵀ c = z.
fn banded_solve(gram: &[[f64; 4]], rhs: &mut [f64]) {
    let n_basis = gram.len();
    for i in 0..n_basis {
        let mut s = rhs[i];
        for k in i.saturating_sub(3)..i {
            s -= gram[i][i - k] * rhs[k];
        }
        rhs[i] = s / gram[i][0];
    }
    for i in (0..n_basis).rev() {
        let mut s = rhs[i];
        for k in i + 1..(i + 4).min(n_basis) {
            s -= gram[k][k - i] * rhs[k];
        }
        rhs[i] = s / gram[i][0];
    }
}

/// The magnitude a pivot is compared with: the larger of the row's original diagonal (not kept
/// separately, so bounded by what remains plus what was subtracted) and the smallest positive
/// normal number.
fn gram_diag_scale(gram: &[[f64; 4]], i: usize, pivot: f64) -> f64 {
    let subtracted: f64 = (i.saturating_sub(3)..i)
        .map(|k| gram[i][i - k] * gram[i][i - k])
        .sum();
    (pivot.abs() + subtracted).max(f64::MIN_POSITIVE)
}

/// Checks a cubic spline's knot vector.
fn check_knots(knots: &[f64]) -> Result<()> {
    let bad = |reason: String| Err(invalid_parameter("knots", reason));
    if knots.len() < 2 * (K + 1) {
        return bad(format!(
            "{} knots: a cubic spline needs at least 8",
            knots.len()
        ));
    }
    if let Some(t) = knots.iter().find(|t| !t.is_finite()) {
        return bad(format!("knot {t} is not finite"));
    }
    if let Some(w) = knots.windows(2).find(|w| w[1] < w[0]) {
        return bad(format!(
            "knot {} follows {}: knots must not decrease",
            w[1], w[0]
        ));
    }
    // Non-decreasing knots: the first and fifth of a run are equal exactly when all five are.
    if let Some(w) = knots.windows(K + 2).find(|w| w[K + 1] <= w[0]) {
        return bad(format!("knot {} appears more than 4 times", w[0]));
    }
    let n_basis = knots.len() - K - 1;
    if knots[K] >= knots[n_basis] {
        return bad("the base interval [t_3, t_n] is empty".into());
    }
    Ok(())
}

/// The weighted least-squares cubic B-spline on `knots` (see [`BSpline::fit_lsq`]) evaluated at
/// `at`.
pub fn lsq_bspline(
    times: &[f64],
    values: &[f64],
    weights: &[f64],
    knots: &[f64],
    at: &[f64],
) -> Result<Vec<f64>> {
    let spline = BSpline::fit_lsq(times, values, weights, knots)?;
    Ok(at.iter().map(|&x| spline.value(x)).collect())
}

// ---------------------------------------------------------------------------------------------
// Smoothing spline

/// How [`SmoothingSpline::fit_gcv`] searches for λ: a grid over log₁₀(λ / h³), h the mean
/// sample spacing (λ ∫f''² against a sum of squares is in units of time³), then a
/// golden-section search around the best grid point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GcvConfig {
    /// Smallest log₁₀(λ / h³) tried.
    pub log10_min: f64,
    /// Largest log₁₀(λ / h³) tried.
    pub log10_max: f64,
    /// Grid points (at least 2).
    pub grid_points: usize,
    /// Golden-section iterations after the grid.
    pub refine_iterations: usize,
}

impl Default for GcvConfig {
    fn default() -> Self {
        // From interpolation (λ/h³ = 1e-4: the fit follows every sample) to the least-squares
        // line (1e12 against a highest penalty eigenvalue ≈ 16/h³ and a lowest ≈ (π/T)⁴ T for
        // T up to ≈ 10⁴ samples).
        Self {
            log10_min: -4.0,
            log10_max: 12.0,
            grid_points: 33,
            refine_iterations: 20,
        }
    }
}

impl GcvConfig {
    /// Checks the search range.
    pub fn check(&self) -> Result<()> {
        if !(self.log10_min.is_finite()
            && self.log10_max.is_finite()
            && self.log10_min < self.log10_max)
        {
            return Err(invalid_parameter(
                "log10_min, log10_max",
                format!(
                    "[{}, {}] is not a finite, non-empty range",
                    self.log10_min, self.log10_max
                ),
            ));
        }
        if self.grid_points < 2 {
            return Err(invalid_parameter(
                "grid_points",
                format!("{}: at least 2 are needed", self.grid_points),
            ));
        }
        Ok(())
    }
}

/// The cubic smoothing spline: the f minimising Σ (p_i − f(t_i))² + λ ∫ f''(t)² dt, a natural
/// cubic spline with a knot at every sample (Reinsch 1967; Green & Silverman 1994, §2.3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SmoothingSpline {
    times: Vec<f64>,
    /// Fitted values g_i = f(t_i).
    fitted: Vec<f64>,
    /// Second derivatives f''(t_i) (zero at both ends).
    second: Vec<f64>,
    /// The smoothing parameter.
    lambda: f64,
    /// The generalized cross-validation score n RSS / (n − tr A)² (Craven & Wahba 1979).
    gcv: f64,
    /// Effective degrees of freedom tr A(λ).
    edf: f64,
}

/// Reinsch's banded matrices for the sample times: with h_i = t_{i+1} − t_i, column c of Q
/// (c = 0..n−3) holds 1/h_c, −1/h_c − 1/h_{c+1}, 1/h_{c+1} in rows c, c+1, c+2, and R is
/// tridiagonal with R_cc = (h_c + h_{c+1})/3, R_{c,c+1} = h_{c+1}/6.
struct Reinsch {
    /// Q's three non-zeros per column.
    q: Vec<[f64; 3]>,
    /// QᵀQ's band: [c][d] = (QᵀQ)_{c,c+d}, d = 0..=2.
    qtq: Vec<[f64; 3]>,
    /// R's band: [c][d] = R_{c,c+d}, d = 0..=1.
    r: Vec<[f64; 2]>,
}

impl Reinsch {
    fn new(times: &[f64]) -> Self {
        let h: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        let m = times.len() - 2;
        let q: Vec<[f64; 3]> = (0..m)
            .map(|c| [1.0 / h[c], -1.0 / h[c] - 1.0 / h[c + 1], 1.0 / h[c + 1]])
            .collect();
        let qtq = (0..m)
            .map(|c| {
                let [a, b, e] = q[c];
                let d1 = if c + 1 < m {
                    b * q[c + 1][0] + e * q[c + 1][1]
                } else {
                    0.0
                };
                let d2 = if c + 2 < m { e * q[c + 2][0] } else { 0.0 };
                [a * a + b * b + e * e, d1, d2]
            })
            .collect();
        let r = (0..m)
            .map(|c| {
                [
                    (h[c] + h[c + 1]) / 3.0,
                    if c + 1 < m { h[c + 1] / 6.0 } else { 0.0 },
                ]
            })
            .collect();
        Self { q, qtq, r }
    }

    /// Qᵀ y.
    fn qt(&self, y: &[f64]) -> Vec<f64> {
        self.q
            .iter()
            .enumerate()
            .map(|(c, [a, b, e])| a * y[c] + b * y[c + 1] + e * y[c + 2])
            .collect()
    }

    /// Q γ (length n).
    fn q_times(&self, gamma: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; gamma.len() + 2];
        for (c, (col, g)) in self.q.iter().zip(gamma).enumerate() {
            for (r, v) in col.iter().enumerate() {
                out[c + r] += v * g;
            }
        }
        out
    }
}

/// LDLᵀ of the symmetric pentadiagonal B = R + λ QᵀQ: d, L_{i+1,i} and L_{i+2,i}.
struct Ldl {
    d: Vec<f64>,
    l1: Vec<f64>,
    l2: Vec<f64>,
}

impl Ldl {
    fn new(reinsch: &Reinsch, lambda: f64) -> Result<Self> {
        let m = reinsch.r.len();
        let band = |c: usize, k: usize| -> f64 {
            let r = if k < 2 { reinsch.r[c][k] } else { 0.0 };
            r + lambda * reinsch.qtq[c][k]
        };
        let (mut d, mut l1, mut l2) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        for j in 0..m {
            let mut dj = band(j, 0);
            if j >= 1 {
                dj -= l1[j - 1] * l1[j - 1] * d[j - 1];
            }
            if j >= 2 {
                dj -= l2[j - 2] * l2[j - 2] * d[j - 2];
            }
            // B is positive definite (R is, and λ QᵀQ is semi-definite); a non-positive pivot
            // can only come from overflow or a degenerate λ.
            if !(dj > 0.0 && dj.is_finite()) {
                return Err(Error::RankDeficientFit);
            }
            d[j] = dj;
            if j + 1 < m {
                // B_{j+1,j} − L_{j+1,j−1} L_{j,j−1} d_{j−1}.
                let mut s = band(j, 1);
                if j >= 1 {
                    s -= l2[j - 1] * l1[j - 1] * d[j - 1];
                }
                l1[j] = s / dj;
            }
            if j + 2 < m {
                l2[j] = band(j, 2) / dj;
            }
        }
        Ok(Self { d, l1, l2 })
    }

    fn solve(&self, rhs: &[f64]) -> Vec<f64> {
        let m = rhs.len();
        let mut z = rhs.to_vec();
        for i in 0..m {
            if i >= 1 {
                z[i] -= self.l1[i - 1] * z[i - 1];
            }
            if i >= 2 {
                z[i] -= self.l2[i - 2] * z[i - 2];
            }
        }
        for (zi, di) in z.iter_mut().zip(&self.d) {
            *zi /= di;
        }
        for i in (0..m).rev() {
            if i + 1 < m {
                z[i] -= self.l1[i] * z[i + 1];
            }
            if i + 2 < m {
                z[i] -= self.l2[i] * z[i + 2];
            }
        }
        z
    }

    /// tr(B⁻¹ G) for a symmetric pentadiagonal G, from the band of Σ = B⁻¹ alone (Hutchinson &
    /// de Hoog 1985): Lᵀ Σ = D⁻¹ L⁻¹ is upper triangular with diagonal 1/d_i, so, from the
    /// last row up, Σ_{i,j} = δ_ij/d_i − L_{i+1,i} Σ_{i+1,j} − L_{i+2,i} Σ_{i+2,j} for j ≥ i.
    fn trace_inverse_times(&self, g: &[[f64; 3]]) -> f64 {
        let m = self.d.len();
        // s[i] = [Σ_ii, Σ_{i,i+1}, Σ_{i,i+2}].
        let mut s = vec![[0.0; 3]; m];
        let at = |s: &[[f64; 3]], i: usize, j: usize| -> f64 {
            // Σ_{i,j} for j ≥ i within the band, zero beyond the matrix.
            if j >= m { 0.0 } else { s[i][j - i] }
        };
        for i in (0..m).rev() {
            let (a, b) = (
                if i + 1 < m { self.l1[i] } else { 0.0 },
                if i + 2 < m { self.l2[i] } else { 0.0 },
            );
            let sym = |s: &[[f64; 3]], x: usize, y: usize| -> f64 {
                if x >= m || y >= m {
                    0.0
                } else if x <= y {
                    at(s, x, y)
                } else {
                    at(s, y, x)
                }
            };
            let s02 = -(a * sym(&s, i + 1, i + 2) + b * sym(&s, i + 2, i + 2));
            let s01 = -(a * sym(&s, i + 1, i + 1) + b * sym(&s, i + 2, i + 1));
            let s00 = 1.0 / self.d[i] - (a * s01 + b * s02);
            s[i] = [s00, s01, s02];
        }
        (0..m)
            .map(|i| s[i][0] * g[i][0] + 2.0 * (s[i][1] * g[i][1] + s[i][2] * g[i][2]))
            .sum()
    }
}

impl SmoothingSpline {
    /// The smoothing spline with a given λ ≥ 0 (λ = 0: the natural interpolating spline;
    /// λ → ∞: the least-squares line). At least 3 samples. Reinsch's algorithm: the second
    /// derivatives γ at the interior samples solve (R + λ QᵀQ) γ = Qᵀ p, and the fitted
    /// values are g = p − λ Q γ; O(n).
    pub fn fit(times: &[f64], values: &[f64], lambda: f64) -> Result<Self> {
        check_samples(times, values, 3, "a smoothing spline")?;
        if !(lambda >= 0.0 && lambda.is_finite()) {
            return Err(invalid_parameter(
                "lambda",
                format!("{lambda} must be finite and non-negative"),
            ));
        }
        let reinsch = Reinsch::new(times);
        Self::fit_with(times, values, &reinsch, lambda)
    }

    fn fit_with(times: &[f64], values: &[f64], reinsch: &Reinsch, lambda: f64) -> Result<Self> {
        let n = times.len();
        let ldl = Ldl::new(reinsch, lambda)?;
        let gamma = ldl.solve(&reinsch.qt(values));
        let qg = reinsch.q_times(&gamma);
        let fitted: Vec<f64> = values
            .iter()
            .zip(&qg)
            .map(|(p, v)| p - lambda * v)
            .collect();
        let rss: f64 = values
            .iter()
            .zip(&fitted)
            .map(|(p, g)| (p - g) * (p - g))
            .sum();
        // tr A = n − λ tr(B⁻¹ QᵀQ), since A = I − λ Q B⁻¹ Qᵀ.
        let edf = n as f64 - lambda * ldl.trace_inverse_times(&reinsch.qtq);
        let nf = n as f64;
        let gcv = nf * rss / ((nf - edf) * (nf - edf));
        let mut second = Vec::with_capacity(n);
        second.push(0.0);
        second.extend(gamma);
        second.push(0.0);
        Ok(Self {
            times: times.to_vec(),
            fitted,
            second,
            lambda,
            gcv,
            edf,
        })
    }

    /// The smoothing spline whose λ minimises the generalized cross-validation score
    /// GCV(λ) = n RSS(λ) / (n − tr A(λ))² (Craven & Wahba 1979), searched as `config` says.
    ///
    /// ```
    /// use gdt_bridge::{GcvConfig, SmoothingSpline};
    ///
    /// // A noisy parabola: GCV smooths it (2 < effective degrees of freedom < 40).
    /// let t: Vec<f64> = (0..40).map(f64::from).collect();
    /// let y: Vec<f64> = t.iter().map(|x| 0.05 * x * x + (x * 7.3).sin() * 0.5).collect();
    /// let s = SmoothingSpline::fit_gcv(&t, &y, &GcvConfig::default())?;
    /// assert!(s.edf() > 2.0 && s.edf() < 40.0);
    /// assert!((s.value(20.5) - 0.05 * 20.5 * 20.5).abs() < 1.0);
    /// # Ok::<(), gdt_bridge::Error>(())
    /// ```
    pub fn fit_gcv(times: &[f64], values: &[f64], config: &GcvConfig) -> Result<Self> {
        check_samples(times, values, 3, "a smoothing spline")?;
        config.check()?;
        let reinsch = Reinsch::new(times);
        let n = times.len();
        let h = (times[n - 1] - times[0]) / (n - 1) as f64;
        let scale = h * h * h;
        let at = |log10: f64| Self::fit_with(times, values, &reinsch, scale * 10f64.powf(log10));
        // A score that is not finite (RSS = 0 at tr A = n) never wins.
        let score = |s: &Self| {
            if s.gcv.is_finite() {
                s.gcv
            } else {
                f64::INFINITY
            }
        };
        let step = (config.log10_max - config.log10_min) / (config.grid_points - 1) as f64;
        let mut best: Option<(f64, Self)> = None;
        for k in 0..config.grid_points {
            let x = config.log10_min + step * k as f64;
            let s = at(x)?;
            if best.as_ref().is_none_or(|(_, b)| score(&s) < score(b)) {
                best = Some((x, s));
            }
        }
        let Some((x_best, mut best)) = best else {
            return Err(Error::RankDeficientFit);
        };
        // Golden-section search on [x − step, x + step] (the grid point's neighbours).
        let bracket = (
            (x_best - step).max(config.log10_min),
            (x_best + step).min(config.log10_max),
        );
        let [f1, f2] = golden_section(bracket, config.refine_iterations, &at, |a, b| {
            score(a) < score(b)
        })?;
        for s in [f1, f2] {
            if score(&s) < score(&best) {
                best = s;
            }
        }
        Ok(best)
    }

    /// f(x); outside the samples the fit continues as a straight line with the end slope (a
    /// natural spline has zero second derivative at its ends).
    pub fn value(&self, x: f64) -> f64 {
        let (t, g, m) = (&self.times, &self.fitted, &self.second);
        let n = t.len();
        if x < t[0] {
            let h = t[1] - t[0];
            // S'(t_0) = Δ_0 − h (2 M_0 + M_1) / 6.
            let slope = (g[1] - g[0]) / h - h * (2.0 * m[0] + m[1]) / 6.0;
            return g[0] + slope * (x - t[0]);
        }
        if x > t[n - 1] {
            let h = t[n - 1] - t[n - 2];
            // S'(t_{n−1}) = Δ_{n−2} + h (M_{n−2} + 2 M_{n−1}) / 6.
            let slope = (g[n - 1] - g[n - 2]) / h + h * (m[n - 2] + 2.0 * m[n - 1]) / 6.0;
            return g[n - 1] + slope * (x - t[n - 1]);
        }
        cubic_piece(t, g, m, x)
    }

    /// The fitted values f(t_i).
    pub fn fitted(&self) -> &[f64] {
        &self.fitted
    }

    /// The smoothing parameter λ.
    pub fn lambda(&self) -> f64 {
        self.lambda
    }

    /// The generalized cross-validation score n RSS / (n − tr A)².
    pub fn gcv(&self) -> f64 {
        self.gcv
    }

    /// The effective degrees of freedom tr A(λ), from 2 (a line) to n (interpolation).
    pub fn edf(&self) -> f64 {
        self.edf
    }
}
