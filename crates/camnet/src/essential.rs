//! The essential matrix: the normalised 8-point algorithm with the projection onto essential
//! matrices (two equal singular values, one zero), Sampson distances, RANSAC, the four-fold
//! decomposition with cheirality by triangulated depth, and the zero-baseline check.
//!
//! All points are normalised image coordinates (x = K⁻¹ u); E satisfies x₂ᵀ E x₁ = 0 for the
//! relative pose X₂ = R X₁ + t, E = \[t\]× R (Hartley & Zisserman §9.6, §11.2).

use nalgebra::{Matrix3, SMatrix, Vector2, Vector3};
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};
use tracker_model::{ensure_in_range, ensure_positive};

use crate::error::{Error, Result, invalid};
use crate::geometry::{Pose, homogeneous, triangulate};
use crate::refine::{RefineConfig, Refined, refine_two_view};

/// The fewest correspondences the 8-point algorithm takes.
pub const MIN_POINTS: usize = 8;

/// Points whose centred spread (smallest over largest singular value) is below this are
/// collinear.
pub const COLLINEAR_RATIO: f64 = 1e-9;

/// Settings of [`estimate_relative_pose`]. Distances are in normalised image units (a
/// threshold of p pixels with focal length f is p / f).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EssentialConfig {
    /// A correspondence is an inlier when its Sampson distance (the square root of the
    /// first-order geometric error) is at most this (default 1.5 px at f = 1000, 1.5e-3).
    pub threshold: f64,
    /// RANSAC stops once it has found, with this confidence, an all-inlier sample of the
    /// best consensus seen (default 0.999).
    pub confidence: f64,
    /// The most RANSAC samples (default 2000).
    pub max_iterations: usize,
    /// Local optimisation: each time a sample beats the best so far, E is re-estimated from
    /// all its inliers and the inliers counted again, up to this many times while the
    /// consensus grows (default 4).
    pub local_refits: usize,
    /// A pure rotation fitting the inliers with median angular residual below this (radians)
    /// is a zero baseline (default 1e-4, about 0.1 px at f = 1000).
    pub min_parallax_rad: f64,
    /// The non-linear refinement on reprojection error; `None` skips it.
    pub refine: Option<RefineConfig>,
}

impl Default for EssentialConfig {
    fn default() -> Self {
        Self {
            threshold: 1.5e-3,
            confidence: 0.999,
            max_iterations: 2000,
            local_refits: 4,
            min_parallax_rad: 1e-4,
            refine: Some(RefineConfig::default()),
        }
    }
}

impl EssentialConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        ensure_positive(self.threshold, "threshold")?;
        ensure_in_range(self.confidence, 0.0, 1.0 - 1e-12, "confidence")?;
        if self.max_iterations == 0 {
            return Err(invalid("max_iterations", "0; RANSAC needs a sample".into()));
        }
        ensure_positive(self.min_parallax_rad, "min_parallax_rad")?;
        if let Some(r) = &self.refine {
            r.check()?;
        }
        Ok(())
    }
}

/// Result of [`estimate_relative_pose`].
#[derive(Debug, Clone)]
pub struct TwoViewEstimate {
    /// E = \[t\]× R of the final pose, |t| = 1.
    pub essential: Matrix3<f64>,
    /// X₂ = R X₁ + t with |t| = 1.
    pub pose: Pose,
    /// Inlier flags, one per correspondence.
    pub inliers: Vec<bool>,
    /// Number of inliers.
    pub n_inliers: usize,
    /// RMS Sampson distance of the inliers under [`Self::essential`].
    pub rms_sampson: f64,
    /// RANSAC samples drawn.
    pub iterations: usize,
    /// The refinement's record, when it ran.
    pub refined: Option<Refined>,
}

fn check_input(x1: &[Vector2<f64>], x2: &[Vector2<f64>]) -> Result<()> {
    if x1.len() != x2.len() {
        return Err(Error::LengthMismatch {
            first: x1.len(),
            second: x2.len(),
        });
    }
    if x1.len() < MIN_POINTS {
        return Err(Error::TooFewCorrespondences {
            found: x1.len(),
            needed: MIN_POINTS,
        });
    }
    for (view, xs) in [(1, x1), (2, x2)] {
        if let Some(index) = xs
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(Error::NonFinitePoint { view, index });
        }
        let spread_ratio = spread_ratio(xs);
        if spread_ratio.is_nan() || spread_ratio < COLLINEAR_RATIO {
            return Err(Error::Collinear {
                view,
                spread_ratio,
                threshold: COLLINEAR_RATIO,
            });
        }
    }
    Ok(())
}

/// Smallest over largest singular value of the centred points (0 for points on a line).
fn spread_ratio(xs: &[Vector2<f64>]) -> f64 {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<Vector2<f64>>() / n;
    let cov = xs
        .iter()
        .map(|x| (x - mean) * (x - mean).transpose())
        .sum::<nalgebra::Matrix2<f64>>()
        / n;
    let eig = cov.symmetric_eigenvalues();
    let (lo, hi) = (eig.min(), eig.max());
    if hi <= 0.0 {
        return 0.0;
    }
    (lo.max(0.0) / hi).sqrt()
}

/// Hartley's normalisation: translate the centroid to 0 and scale the mean distance to √2.
fn normalisation(xs: &[Vector2<f64>], idx: &[usize]) -> Matrix3<f64> {
    let n = idx.len() as f64;
    let mean = idx.iter().map(|&i| xs[i]).sum::<Vector2<f64>>() / n;
    let mean_dist = idx.iter().map(|&i| (xs[i] - mean).norm()).sum::<f64>() / n;
    let s = if mean_dist > 0.0 {
        std::f64::consts::SQRT_2 / mean_dist
    } else {
        1.0
    };
    Matrix3::new(s, 0.0, -s * mean.x, 0.0, s, -s * mean.y, 0.0, 0.0, 1.0)
}

/// The nearest essential matrix in Frobenius norm: U diag(σ, σ, 0) Vᵀ with σ = (σ₁ + σ₂)/2,
/// scaled to unit Frobenius norm (σ = 1/√2).
pub fn project_to_essential(m: &Matrix3<f64>) -> Result<Matrix3<f64>> {
    let svd = m.try_svd(true, true, 1e-15, 200).ok_or(Error::Numerical {
        what: "SVD in the essential projection",
    })?;
    let (u, v_t) = svd.u.zip(svd.v_t).ok_or(Error::Numerical {
        what: "SVD in the essential projection",
    })?;
    // nalgebra sorts the singular values of a static matrix in decreasing order.
    let s = std::f64::consts::FRAC_1_SQRT_2;
    Ok(u * Matrix3::from_diagonal(&Vector3::new(s, s, 0.0)) * v_t)
}

/// The normalised 8-point algorithm (Hartley 1997) on the correspondences `idx` (at least 8),
/// followed by [`project_to_essential`]. The result has unit Frobenius norm.
pub fn eight_point_indices(
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    idx: &[usize],
) -> Result<Matrix3<f64>> {
    if idx.len() < MIN_POINTS {
        return Err(Error::TooFewCorrespondences {
            found: idx.len(),
            needed: MIN_POINTS,
        });
    }
    let t1 = normalisation(x1, idx);
    let t2 = normalisation(x2, idx);
    // Rows (x₂ x₁ᵀ) flattened row-major, so that row · vec(E) = x₂ᵀ E x₁. The 9 × 9 normal
    // matrix AᵀA would square the condition number; instead the rows are reduced by a QR-free
    // route: with n ≤ 9 we pad to 9 × 9, otherwise we take the SVD of the n × 9 matrix.
    let row = |i: usize| {
        let a = t1 * homogeneous(&x1[i]);
        let b = t2 * homogeneous(&x2[i]);
        nalgebra::RowSVector::<f64, 9>::from_fn(|_, k| b[k / 3] * a[k % 3])
    };
    let e_vec = if idx.len() <= 9 {
        let mut a = SMatrix::<f64, 9, 9>::zeros();
        for (r, &i) in idx.iter().enumerate() {
            a.set_row(r, &row(i));
        }
        null_vector(a.try_svd(false, true, 1e-15, 200))?
    } else {
        let mut a = nalgebra::DMatrix::<f64>::zeros(idx.len(), 9);
        for (r, &i) in idx.iter().enumerate() {
            a.set_row(r, &row(i));
        }
        let svd = a.try_svd(false, true, 1e-15, 200).ok_or(Error::Numerical {
            what: "SVD of the 8-point system",
        })?;
        let v_t = svd.v_t.ok_or(Error::Numerical {
            what: "SVD of the 8-point system",
        })?;
        let (k, _) = svd
            .singular_values
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .ok_or(Error::Numerical {
                what: "empty SVD of the 8-point system",
            })?;
        nalgebra::SVector::<f64, 9>::from_fn(|j, _| v_t[(k, j)])
    };
    let e_hat = Matrix3::from_fn(|r, c| e_vec[3 * r + c]);
    let e = t2.transpose() * e_hat * t1;
    let norm = e.norm();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(Error::Numerical {
            what: "8-point solution is zero or not finite",
        });
    }
    project_to_essential(&(e / norm))
}

fn null_vector(
    svd: Option<nalgebra::SVD<f64, nalgebra::U9, nalgebra::U9>>,
) -> Result<nalgebra::SVector<f64, 9>> {
    let svd = svd.ok_or(Error::Numerical {
        what: "SVD of the 8-point system",
    })?;
    let v_t = svd.v_t.ok_or(Error::Numerical {
        what: "SVD of the 8-point system",
    })?;
    let (k, _) = svd
        .singular_values
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .ok_or(Error::Numerical {
            what: "empty SVD of the 8-point system",
        })?;
    Ok(v_t.row(k).transpose())
}

/// [`eight_point_indices`] on every correspondence, after the input checks (length, finite,
/// at least 8, not collinear).
pub fn eight_point(x1: &[Vector2<f64>], x2: &[Vector2<f64>]) -> Result<Matrix3<f64>> {
    check_input(x1, x2)?;
    let idx: Vec<usize> = (0..x1.len()).collect();
    eight_point_indices(x1, x2, &idx)
}

/// The Sampson distance of one correspondence: |x₂ᵀ E x₁| / ‖(E x₁)₁,₂, (Eᵀ x₂)₁,₂‖, the
/// first-order approximation of the geometric reprojection distance.
pub fn sampson_distance(e: &Matrix3<f64>, x1: &Vector2<f64>, x2: &Vector2<f64>) -> f64 {
    let a = homogeneous(x1);
    let b = homogeneous(x2);
    let ea = e * a;
    let etb = e.transpose() * b;
    let num = b.dot(&ea);
    let den = ea.x * ea.x + ea.y * ea.y + etb.x * etb.x + etb.y * etb.y;
    if den <= 0.0 {
        return f64::INFINITY;
    }
    num.abs() / den.sqrt()
}

/// The four (R, t) of E = U diag(1,1,0) Vᵀ: R ∈ {U W Vᵀ, U Wᵀ Vᵀ}, t = ±u₃ (Hartley &
/// Zisserman Result 9.19), with U, V turned into rotations first.
pub fn decompose_essential(e: &Matrix3<f64>) -> Result<[Pose; 4]> {
    let svd = e.try_svd(true, true, 1e-15, 200).ok_or(Error::Numerical {
        what: "SVD in the essential decomposition",
    })?;
    let (mut u, mut v_t) = svd.u.zip(svd.v_t).ok_or(Error::Numerical {
        what: "SVD in the essential decomposition",
    })?;
    if u.determinant() < 0.0 {
        u = -u;
    }
    if v_t.determinant() < 0.0 {
        v_t = -v_t;
    }
    let w = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
    let ra = nalgebra::Rotation3::from_matrix_unchecked(u * w * v_t);
    let rb = nalgebra::Rotation3::from_matrix_unchecked(u * w.transpose() * v_t);
    let t: Vector3<f64> = u.column(2).into_owned();
    Ok([
        Pose {
            rotation: ra,
            translation: t,
        },
        Pose {
            rotation: ra,
            translation: -t,
        },
        Pose {
            rotation: rb,
            translation: t,
        },
        Pose {
            rotation: rb,
            translation: -t,
        },
    ])
}

/// How many of `idx` triangulate in front of both cameras under `pose`.
pub fn count_in_front(
    pose: &Pose,
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    idx: &[usize],
) -> usize {
    idx.iter()
        .filter(|&&i| {
            triangulate(pose, &x1[i], &x2[i]).is_some_and(|x| x.z > 0.0 && pose.apply(&x).z > 0.0)
        })
        .count()
}

/// The candidate of [`decompose_essential`] that puts most of `idx` in front of both cameras
/// (cheirality), with that count.
pub fn select_pose(
    e: &Matrix3<f64>,
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    idx: &[usize],
) -> Result<(Pose, usize)> {
    let candidates = decompose_essential(e)?;
    let mut best = (candidates[0], 0usize);
    for c in candidates {
        let n = count_in_front(&c, x1, x2, idx);
        if n > best.1 {
            best = (c, n);
        }
    }
    Ok(best)
}

/// Median angle (radians) between each second-view ray and the first-view ray turned by the
/// best-fitting rotation (Kabsch on unit rays): zero for coincident camera centres.
pub fn rotation_only_parallax(
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    idx: &[usize],
) -> Result<f64> {
    let rays = |x: &Vector2<f64>| homogeneous(x).normalize();
    let h = idx
        .iter()
        .map(|&i| rays(&x2[i]) * rays(&x1[i]).transpose())
        .sum::<Matrix3<f64>>();
    let svd = h.try_svd(true, true, 1e-15, 200).ok_or(Error::Numerical {
        what: "SVD of the rotation-only fit",
    })?;
    let (u, v_t) = svd.u.zip(svd.v_t).ok_or(Error::Numerical {
        what: "SVD of the rotation-only fit",
    })?;
    let mut d = Matrix3::identity();
    if (u * v_t).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = u * d * v_t;
    let mut angles: Vec<f64> = idx
        .iter()
        .map(|&i| {
            let c = rays(&x2[i]).dot(&(r * rays(&x1[i])));
            c.clamp(-1.0, 1.0).acos()
        })
        .collect();
    angles.sort_by(f64::total_cmp);
    Ok(angles.get(angles.len() / 2).copied().unwrap_or(0.0))
}

/// A least-squares 8-point fit on every correspondence, then up to `refits` refits on the
/// inliers while the consensus grows: the hypothesis for data that is mostly inliers (the
/// points of tracks already believed to match), where minimal samples are needlessly noisy.
/// Returns E and its inlier count.
pub fn fit_all_and_refit(
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    threshold: f64,
    refits: usize,
) -> Result<(Matrix3<f64>, usize)> {
    check_input(x1, x2)?;
    let all: Vec<usize> = (0..x1.len()).collect();
    let mut e = eight_point_indices(x1, x2, &all)?;
    let (mut flags, mut count, mut score) = consensus(&e, x1, x2, threshold);
    for _ in 0..refits {
        let idx: Vec<usize> = (0..x1.len()).filter(|&i| flags[i]).collect();
        let Ok(refit) = eight_point_indices(x1, x2, &idx) else {
            break;
        };
        let (f, c, sc) = consensus(&refit, x1, x2, threshold);
        if c < count || (c == count && sc >= score) {
            break;
        }
        (e, flags, count, score) = (refit, f, c, sc);
    }
    Ok((e, count))
}

/// Polishes `e` on the data: the pose of its inliers by cheirality, Levenberg-Marquardt on
/// their reprojection error ([`refine_two_view`]), E from the refined pose, inliers counted
/// again; `rounds` times while the consensus grows. Where the linear 8-point fit is poorly
/// conditioned (few, nearly-planar tracks seen from afar) this recovers the consensus a
/// least-squares fit only approaches. Returns E and its inlier count.
pub fn polish_essential(
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    e: &Matrix3<f64>,
    threshold: f64,
    rounds: usize,
    refine: &RefineConfig,
) -> Result<(Matrix3<f64>, usize)> {
    let (mut flags, mut count, mut score) = consensus(e, x1, x2, threshold);
    let mut e = *e;
    for _ in 0..rounds {
        let idx: Vec<usize> = (0..x1.len()).filter(|&i| flags[i]).collect();
        if idx.len() < MIN_POINTS {
            break;
        }
        let (pose, _) = select_pose(&e, x1, x2, &idx)?;
        let in1: Vec<Vector2<f64>> = idx.iter().map(|&i| x1[i]).collect();
        let in2: Vec<Vector2<f64>> = idx.iter().map(|&i| x2[i]).collect();
        let Ok(r) = refine_two_view(&pose, &in1, &in2, refine) else {
            break;
        };
        let e_new = r.pose.essential();
        let (f, c, sc) = consensus(&e_new, x1, x2, threshold);
        if c < count || (c == count && sc >= score) {
            break;
        }
        (e, flags, count, score) = (e_new, f, c, sc);
    }
    Ok((e, count))
}

/// Result of [`ransac_essential`].
#[derive(Debug, Clone)]
pub struct RansacResult {
    /// The essential matrix of the best consensus (re-estimated from its inliers).
    pub essential: Matrix3<f64>,
    /// Inlier flags.
    pub inliers: Vec<bool>,
    /// Number of inliers.
    pub n_inliers: usize,
    /// Samples drawn.
    pub iterations: usize,
}

fn consensus(
    e: &Matrix3<f64>,
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    threshold: f64,
) -> (Vec<bool>, usize, f64) {
    let mut n = 0;
    let mut score = 0.0;
    let flags = x1
        .iter()
        .zip(x2)
        .map(|(a, b)| {
            let d = sampson_distance(e, a, b);
            let inside = d <= threshold;
            if inside {
                n += 1;
                // MSAC-style tie-break: among equal counts prefer smaller residuals.
                score += d * d;
            }
            inside
        })
        .collect();
    (flags, n, score)
}

/// LO-RANSAC over minimal 8-point samples with the Sampson distance: each new best sample is
/// refitted on its inliers (up to `config.local_refits` times), and sampling stops adaptively
/// at `config.confidence` given the best consensus.
pub fn ransac_essential<R: Rng + ?Sized>(
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    config: &EssentialConfig,
    rng: &mut R,
) -> Result<RansacResult> {
    ransac_essential_from(x1, x2, None, config, rng)
}

/// [`ransac_essential`] that first scores `initial` (for instance a least-squares fit on all
/// points) as if it were a sample, so that a good starting hypothesis stops sampling early.
pub fn ransac_essential_from<R: Rng + ?Sized>(
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    initial: Option<&Matrix3<f64>>,
    config: &EssentialConfig,
    rng: &mut R,
) -> Result<RansacResult> {
    config.check()?;
    check_input(x1, x2)?;
    let n = x1.len();
    let mut best: Option<Hypothesis> = None;
    let mut needed = config.max_iterations;
    let mut iterations = 0;
    let mut sample = [0usize; MIN_POINTS];
    let mut initial = initial.copied();
    while iterations < needed.min(config.max_iterations) {
        iterations += 1;
        let e = if let Some(e) = initial.take() {
            e
        } else {
            draw_sample(n, &mut sample, rng);
            let Ok(e) = eight_point_indices(x1, x2, &sample) else {
                continue;
            };
            e
        };
        let (flags, count, score) = consensus(&e, x1, x2, config.threshold);
        if !better(count, score, &best) {
            continue;
        }
        let hypothesis = local_optimisation((e, count, score, flags), x1, x2, config);
        needed = iterations_needed(hypothesis.1, n, config);
        best = Some(hypothesis);
    }
    let (e, count, _, flags) = best.ok_or(Error::Numerical {
        what: "no RANSAC sample gave an essential matrix",
    })?;
    if count < MIN_POINTS {
        return Err(Error::TooFewCorrespondences {
            found: count,
            needed: MIN_POINTS,
        });
    }
    Ok(RansacResult {
        essential: e,
        inliers: flags,
        n_inliers: count,
        iterations,
    })
}

/// A RANSAC hypothesis: E, its inlier count, its MSAC score (Σ d² over the inliers) and its
/// inlier flags.
type Hypothesis = (Matrix3<f64>, usize, f64, Vec<bool>);

/// Eight distinct indices below `n` into `sample`, drawn uniformly from `rng` (rejection on
/// the few repeats): the minimal sample of the 8-point algorithm (Fischler & Bolles 1981's
/// RANSAC with Hartley 1997's normalised 8-point fit).
fn draw_sample<R: Rng + ?Sized>(n: usize, sample: &mut [usize; MIN_POINTS], rng: &mut R) {
    let mut k = 0;
    while k < MIN_POINTS {
        let i = rng.random_range(0..n);
        if !sample[..k].contains(&i) {
            sample[k] = i;
            k += 1;
        }
    }
}

/// Whether a consensus of `count` inliers with score `score` beats `best`: more inliers, or
/// as many with a smaller sum of squared distances (an MSAC-style tie-break, after Torr &
/// Zisserman 2000).
fn better(count: usize, score: f64, best: &Option<Hypothesis>) -> bool {
    match best {
        None => true,
        Some((_, c, s, _)) => count > *c || (count == *c && score < *s),
    }
}

/// Local optimisation (Chum, Matas & Kittler 2003): refit on the inliers of a new best sample
/// while the consensus grows, up to `config.local_refits` times. A minimal sample is noisy;
/// its inliers are not.
fn local_optimisation(
    sample: Hypothesis,
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    config: &EssentialConfig,
) -> Hypothesis {
    let n = x1.len();
    let (mut e, mut count, mut score, mut flags) = sample;
    for _ in 0..config.local_refits {
        let idx: Vec<usize> = (0..n).filter(|&i| flags[i]).collect();
        let Ok(refit) = eight_point_indices(x1, x2, &idx) else {
            break;
        };
        let (f, c, sc) = consensus(&refit, x1, x2, config.threshold);
        if c < count || (c == count && sc >= score) {
            break;
        }
        (e, flags, count, score) = (refit, f, c, sc);
    }
    (e, count, score, flags)
}

/// The adaptive number of samples (Fischler & Bolles 1981; Hartley & Zisserman 2004, §4.7):
/// k = ln(1 − confidence) / ln(1 − w⁸) for the inlier ratio w = `count` / `n`;
/// `config.max_iterations` when w = 0 or k is not finite (the loop caps k there too).
fn iterations_needed(count: usize, n: usize, config: &EssentialConfig) -> usize {
    let w = count as f64 / n as f64;
    let p_good = w.powi(MIN_POINTS as i32);
    if p_good >= 1.0 {
        1
    } else if p_good <= 0.0 {
        config.max_iterations
    } else {
        let k = (1.0 - config.confidence).ln() / (1.0 - p_good).ln();
        if k.is_finite() {
            k.ceil().max(1.0) as usize
        } else {
            config.max_iterations
        }
    }
}

/// The relative pose of view 2 with respect to view 1 from normalised correspondences:
/// [`ransac_essential`], the zero-baseline check on the inliers, decomposition with
/// cheirality ([`select_pose`]), and (when configured) [`refine_two_view`] on the inliers.
///
/// Errors: fewer than 8 correspondences or inliers ([`Error::TooFewCorrespondences`]), a view
/// whose points are collinear ([`Error::Collinear`]), coincident camera centres
/// ([`Error::ZeroBaseline`]).
pub fn estimate_relative_pose<R: Rng + ?Sized>(
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    config: &EssentialConfig,
    rng: &mut R,
) -> Result<TwoViewEstimate> {
    estimate_relative_pose_from(x1, x2, None, config, rng)
}

/// [`estimate_relative_pose`] with RANSAC started from `initial` ([`ransac_essential_from`]).
pub fn estimate_relative_pose_from<R: Rng + ?Sized>(
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    initial: Option<&Matrix3<f64>>,
    config: &EssentialConfig,
    rng: &mut R,
) -> Result<TwoViewEstimate> {
    let ransac = ransac_essential_from(x1, x2, initial, config, rng)?;
    let idx: Vec<usize> = (0..x1.len()).filter(|&i| ransac.inliers[i]).collect();
    let parallax_rad = rotation_only_parallax(x1, x2, &idx)?;
    if parallax_rad < config.min_parallax_rad {
        return Err(Error::ZeroBaseline {
            parallax_rad,
            threshold_rad: config.min_parallax_rad,
        });
    }
    let (mut pose, _) = select_pose(&ransac.essential, x1, x2, &idx)?;
    let mut refined = None;
    if let Some(rc) = &config.refine {
        let in1: Vec<Vector2<f64>> = idx.iter().map(|&i| x1[i]).collect();
        let in2: Vec<Vector2<f64>> = idx.iter().map(|&i| x2[i]).collect();
        let r = refine_two_view(&pose, &in1, &in2, rc)?;
        pose = r.pose;
        refined = Some(r);
    }
    let essential = pose.essential();
    let rms_sampson = (idx
        .iter()
        .map(|&i| sampson_distance(&essential, &x1[i], &x2[i]).powi(2))
        .sum::<f64>()
        / idx.len().max(1) as f64)
        .sqrt();
    Ok(TwoViewEstimate {
        essential,
        pose,
        n_inliers: ransac.n_inliers,
        inliers: ransac.inliers,
        rms_sampson,
        iterations: ransac.iterations,
        refined,
    })
}
