//! Two-view refinement by non-linear least squares on reprojection error: Levenberg-Marquardt
//! over the relative pose (rotation as a left increment exp([ω]×) R, translation on the unit
//! sphere in a tangent basis) and every triangulated point, with the points eliminated by the
//! Schur complement (each point's 3 × 3 block is independent), so a step costs O(n).
//!
//! View 1 is fixed at the identity and |t| = 1, which removes the seven-parameter gauge
//! freedom of two views. Residuals are in normalised image units: at focal length f they are
//! the pixel residuals over f.

use nalgebra::{Matrix2x3, Matrix3, Rotation3, SMatrix, SVector, Vector2, Vector3};
use serde::{Deserialize, Serialize};
use tracker_model::ensure_positive;

use crate::error::{Error, Result, invalid};
use crate::geometry::{Pose, skew, triangulate};

/// Settings of [`refine_two_view`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RefineConfig {
    /// Most LM iterations (default 30).
    pub max_iterations: usize,
    /// Initial damping λ relative to the mean diagonal of the normal matrix (default 1e-3).
    pub initial_damping: f64,
    /// Stop when the cost falls by less than this fraction in an accepted step (default
    /// 1e-10).
    pub tolerance: f64,
}

impl Default for RefineConfig {
    fn default() -> Self {
        Self {
            max_iterations: 30,
            initial_damping: 1e-3,
            tolerance: 1e-10,
        }
    }
}

impl RefineConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        if self.max_iterations == 0 {
            return Err(invalid(
                "max_iterations",
                "0; refinement needs a step".into(),
            ));
        }
        ensure_positive(self.initial_damping, "initial_damping")?;
        ensure_positive(self.tolerance, "tolerance")?;
        Ok(())
    }
}

/// What [`refine_two_view`] returns.
#[derive(Debug, Clone)]
pub struct Refined {
    /// The refined pose, |t| = 1.
    pub pose: Pose,
    /// The refined points in view 1's frame.
    pub points: Vec<Vector3<f64>>,
    /// ½ Σ r² before the first step.
    pub initial_cost: f64,
    /// ½ Σ r² at the end.
    pub final_cost: f64,
    /// RMS reprojection error per image coordinate at the end (normalised units).
    pub rms_reprojection: f64,
    /// LM iterations run.
    pub iterations: usize,
}

/// An orthonormal pair spanning the plane perpendicular to the unit vector `t`.
pub(crate) fn tangent_basis(t: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if t.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let b1 = t.cross(&helper).normalize();
    let b2 = t.cross(&b1);
    (b1, b2)
}

/// Jacobian of the perspective division at Y.
fn jac_project(y: &Vector3<f64>) -> Matrix2x3<f64> {
    let iz = 1.0 / y.z;
    Matrix2x3::new(iz, 0.0, -y.x * iz * iz, 0.0, iz, -y.y * iz * iz)
}

fn residuals(
    pose: &Pose,
    x: &Vector3<f64>,
    x1: &Vector2<f64>,
    x2: &Vector2<f64>,
) -> (Vector2<f64>, Vector2<f64>) {
    let y = pose.apply(x);
    (
        Vector2::new(x.x / x.z, x.y / x.z) - x1,
        Vector2::new(y.x / y.z, y.y / y.z) - x2,
    )
}

fn cost(pose: &Pose, points: &[Vector3<f64>], x1: &[Vector2<f64>], x2: &[Vector2<f64>]) -> f64 {
    points
        .iter()
        .zip(x1.iter().zip(x2))
        .map(|(x, (a, b))| {
            let (r1, r2) = residuals(pose, x, a, b);
            0.5 * (r1.norm_squared() + r2.norm_squared())
        })
        .sum()
}

/// The analytic Jacobians of one point's residuals: (∂r₁/∂X, ∂r₂/∂X, ∂r₂/∂(ω, α, β)).
pub(crate) fn jacobians(
    pose: &Pose,
    x: &Vector3<f64>,
) -> (Matrix2x3<f64>, Matrix2x3<f64>, SMatrix<f64, 2, 5>) {
    let (b1, b2) = tangent_basis(&pose.translation);
    let rx = pose.rotation * x;
    let y = rx + pose.translation;
    let jp2 = jac_project(&y);
    let j1x = jac_project(x);
    let j2x = jp2 * pose.rotation.matrix();
    let dy_dw = -skew(&rx);
    let mut dy_dc = SMatrix::<f64, 3, 5>::zeros();
    dy_dc.fixed_view_mut::<3, 3>(0, 0).copy_from(&dy_dw);
    dy_dc.set_column(3, &b1);
    dy_dc.set_column(4, &b2);
    (j1x, j2x, jp2 * dy_dc)
}

/// Applies a camera step δ = (ω, α, β).
pub(crate) fn step_pose(pose: &Pose, delta: &SVector<f64, 5>) -> Pose {
    let (b1, b2) = tangent_basis(&pose.translation);
    let w = Vector3::new(delta[0], delta[1], delta[2]);
    let rotation = Rotation3::new(w) * pose.rotation;
    let t = (pose.translation + delta[3] * b1 + delta[4] * b2).normalize();
    Pose {
        rotation,
        translation: t,
    }
}

/// Levenberg-Marquardt on the reprojection error of both views over the pose and the points,
/// starting from `pose` (|t| is normalised to 1) and the DLT triangulation of every
/// correspondence. Fewer than 8 correspondences or a point that does not triangulate in front
/// of both cameras is an error.
pub fn refine_two_view(
    pose: &Pose,
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    config: &RefineConfig,
) -> Result<Refined> {
    let (mut pose, mut points) = two_view_start(pose, x1, x2, config)?;
    let initial_cost = cost(&pose, &points, x1, x2);
    let mut current = initial_cost;
    let mut lambda: Option<f64> = None;
    let mut iterations = 0;
    while iterations < config.max_iterations {
        iterations += 1;
        let normal = TwoViewNormal::build(&pose, &points, x1, x2);
        let lam = *lambda.get_or_insert_with(|| normal.initial_damping(config));
        let Some((dc, v_inv)) = normal.solve_camera(lam)? else {
            lambda = Some(lam * 10.0);
            continue;
        };
        let new_pose = step_pose(&pose, &dc);
        let new_points = normal.step_points(&points, &v_inv, &dc);
        let new_cost = cost(&new_pose, &new_points, x1, x2);
        if new_cost.is_finite() && new_cost < current {
            let decrease = (current - new_cost) / current.max(1e-300);
            pose = new_pose;
            points = new_points;
            current = new_cost;
            lambda = Some((lam / 10.0).max(1e-15));
            if decrease < config.tolerance || current < 1e-30 {
                break;
            }
        } else {
            lambda = Some(lam * 10.0);
            if lam > 1e12 {
                break;
            }
        }
    }
    let rms_reprojection = (2.0 * current / (4 * x1.len()) as f64).sqrt();
    Ok(Refined {
        pose,
        points,
        initial_cost,
        final_cost: current,
        rms_reprojection,
        iterations,
    })
}

/// Checks the inputs of [`refine_two_view`] (in its order of errors) and returns the starting
/// pose with |t| = 1 and the starting points: the DLT triangulation of each correspondence
/// (Hartley & Zisserman 2004, §12.2), or, for a point at infinity or behind either camera, a
/// far point on the first ray that LM moves.
fn two_view_start(
    pose: &Pose,
    x1: &[Vector2<f64>],
    x2: &[Vector2<f64>],
    config: &RefineConfig,
) -> Result<(Pose, Vec<Vector3<f64>>)> {
    config.check()?;
    if x1.len() != x2.len() {
        return Err(Error::LengthMismatch {
            first: x1.len(),
            second: x2.len(),
        });
    }
    if x1.len() < crate::essential::MIN_POINTS {
        return Err(Error::TooFewCorrespondences {
            found: x1.len(),
            needed: crate::essential::MIN_POINTS,
        });
    }
    let tn = pose.translation.norm();
    if !(tn.is_finite() && tn > 0.0) {
        return Err(Error::ZeroBaseline {
            parallax_rad: 0.0,
            threshold_rad: 0.0,
        });
    }
    let pose = Pose {
        rotation: pose.rotation,
        translation: pose.translation / tn,
    };
    // Points that fail to triangulate (at infinity or behind) start at a far point on the
    // first ray; LM moves them.
    let points: Vec<Vector3<f64>> = x1
        .iter()
        .zip(x2)
        .map(|(a, b)| match triangulate(&pose, a, b) {
            Some(p) if p.z > 0.0 && pose.apply(&p).z > 0.0 => p,
            _ => Vector3::new(a.x, a.y, 1.0) * 1e3,
        })
        .collect();
    Ok((pose, points))
}

/// A solved pose step δ = (ω, α, β) and the inverses of the damped point blocks.
type PoseStep = (SVector<f64, 5>, Vec<Matrix3<f64>>);

/// The two-view normal equations by blocks (the sparse structure of Triggs et al. 2000's
/// bundle adjustment with one free camera): U (5 × 5, the pose's rotation and tangent
/// translation), V (3 × 3 per point), W (5 × 3 per point) and the gradients.
struct TwoViewNormal {
    u: SMatrix<f64, 5, 5>,
    g_c: SVector<f64, 5>,
    v: Vec<Matrix3<f64>>,
    w: Vec<SMatrix<f64, 5, 3>>,
    g_p: Vec<Vector3<f64>>,
}

impl TwoViewNormal {
    /// Accumulates the blocks over every correspondence at the current pose and points.
    fn build(
        pose: &Pose,
        points: &[Vector3<f64>],
        x1: &[Vector2<f64>],
        x2: &[Vector2<f64>],
    ) -> Self {
        let mut u = SMatrix::<f64, 5, 5>::zeros();
        let mut g_c = SVector::<f64, 5>::zeros();
        let mut v = Vec::with_capacity(points.len());
        let mut w = Vec::with_capacity(points.len());
        let mut g_p = Vec::with_capacity(points.len());
        for (x, (a, b)) in points.iter().zip(x1.iter().zip(x2)) {
            let (r1, r2) = residuals(pose, x, a, b);
            let (j1x, j2x, j2c) = jacobians(pose, x);
            u += j2c.transpose() * j2c;
            g_c += j2c.transpose() * r2;
            v.push(j1x.transpose() * j1x + j2x.transpose() * j2x);
            w.push(j2c.transpose() * j2x);
            g_p.push(j1x.transpose() * r1 + j2x.transpose() * r2);
        }
        Self { u, g_c, v, w, g_p }
    }

    /// The first damping λ: `initial_damping` times the mean diagonal of the normal matrix.
    fn initial_damping(&self, config: &RefineConfig) -> f64 {
        let (u, v) = (&self.u, &self.v);
        let mean_diag =
            (u.trace() + v.iter().map(Matrix3::trace).sum::<f64>()) / (5 + 3 * v.len()) as f64;
        config.initial_damping * mean_diag.max(1e-12)
    }

    /// The pose step of the damped system (Marquardt: λ on the diagonal, scaled by it) with
    /// the points eliminated by the Schur complement, and the inverses of the damped point
    /// blocks. `Ok(None)` when the reduced 5 × 5 system is not positive definite (the caller
    /// raises λ); an error when a point block is singular.
    fn solve_camera(&self, lam: f64) -> Result<Option<PoseStep>> {
        let u = self.u;
        let damp3 = |m: &Matrix3<f64>| {
            m + Matrix3::from_diagonal(&m.diagonal()) * lam + Matrix3::identity() * 1e-12
        };
        let mut s = u
            + SMatrix::<f64, 5, 5>::from_diagonal(&u.diagonal()) * lam
            + SMatrix::<f64, 5, 5>::identity() * 1e-12;
        let mut rhs = -self.g_c;
        let mut v_inv = Vec::with_capacity(self.v.len());
        for ((vi, wi), gi) in self.v.iter().zip(&self.w).zip(&self.g_p) {
            let Some(inv) = damp3(vi).try_inverse() else {
                return Err(Error::Numerical {
                    what: "a point block of the refinement is singular",
                });
            };
            s -= wi * inv * wi.transpose();
            rhs += wi * (inv * gi);
            v_inv.push(inv);
        }
        Ok(s.cholesky().map(|c| (c.solve(&rhs), v_inv)))
    }

    /// Each point's back-substituted step, x + V*⁻¹ (−g − Wᵀ δc).
    fn step_points(
        &self,
        points: &[Vector3<f64>],
        v_inv: &[Matrix3<f64>],
        dc: &SVector<f64, 5>,
    ) -> Vec<Vector3<f64>> {
        points
            .iter()
            .zip(v_inv.iter().zip(self.w.iter().zip(&self.g_p)))
            .map(|(x, (inv, (wi, gi)))| x + inv * (-gi - wi.transpose() * dc))
            .collect()
    }
}
