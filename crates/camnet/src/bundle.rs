//! Joint refinement of the network (a small bundle adjustment, Triggs et al. 2000, an
//! optional step beyond Meingast et al. 2007): Levenberg-Marquardt on the reprojection error of every observation over all
//! camera poses and all triangulated track points, the points eliminated by the Schur
//! complement (each point's 3 × 3 block is independent; the reduced camera system is dense
//! 6(m−1) × 6(m−1) for m cameras, small for a camera network).
//!
//! Gauge: camera 0 is fixed; the global scale, which the reprojection error does not see, is
//! held by rescaling after every accepted step so that the mean distance of the camera
//! centres from camera 0 keeps its initial value (a rescaling changes no residual). The
//! damping keeps the reduced system positive definite along the scale direction.
//! Parameterisation as in [`crate::refine_two_view`]: rotation as a left increment
//! exp(\[ω\]×) R, translation additive. Residuals in normalised image units.

use nalgebra::{DMatrix, DVector, Matrix2x3, Matrix3, Rotation3, SMatrix, Vector2, Vector3};

use crate::error::{Error, Result, invalid};
use crate::geometry::{Pose, skew};
use crate::refine::RefineConfig;

/// One image observation of one point by one camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BundleObservation {
    /// Index of the camera (0 is held fixed).
    pub camera: usize,
    /// Index of the point.
    pub point: usize,
    /// Normalised image coordinates.
    pub x: Vector2<f64>,
}

/// What [`bundle_adjust`] returns.
#[derive(Debug, Clone)]
pub struct Bundle {
    /// Refined poses `camera_from_camera0` (camera 0 unchanged).
    pub poses: Vec<Pose>,
    /// Refined points in camera 0's frame.
    pub points: Vec<Vector3<f64>>,
    /// RMS reprojection error per image coordinate at the start (normalised units).
    pub initial_rms: f64,
    /// The same at the end.
    pub final_rms: f64,
    /// LM iterations run.
    pub iterations: usize,
}

type Block63 = SMatrix<f64, 6, 3>;
type Block26 = SMatrix<f64, 2, 6>;

fn jac_project(y: &Vector3<f64>) -> Matrix2x3<f64> {
    let iz = 1.0 / y.z;
    Matrix2x3::new(iz, 0.0, -y.x * iz * iz, 0.0, iz, -y.y * iz * iz)
}

/// ½ Σ r², or `None` when a point falls behind a camera.
fn cost(poses: &[Pose], points: &[Vector3<f64>], obs: &[BundleObservation]) -> Option<f64> {
    let mut c = 0.0;
    for o in obs {
        let y = poses[o.camera].apply(&points[o.point]);
        if y.z <= 0.0 {
            return None;
        }
        c += 0.5 * (Vector2::new(y.x / y.z, y.y / y.z) - o.x).norm_squared();
    }
    Some(c)
}

fn mean_centre_distance(poses: &[Pose]) -> f64 {
    let c0 = poses[0].centre();
    poses.iter().map(|p| (p.centre() - c0).norm()).sum::<f64>() / poses.len() as f64
}

/// Levenberg-Marquardt over all poses but camera 0's and all points, from the given start.
/// Errors: fewer than two cameras, an index out of range, a point seen by fewer than two
/// cameras, a non-finite input, a point behind a camera at the start, or zero spread of the
/// camera centres (no scale to hold).
pub fn bundle_adjust(
    poses: &[Pose],
    points: &[Vector3<f64>],
    observations: &[BundleObservation],
    config: &RefineConfig,
) -> Result<Bundle> {
    config.check()?;
    let n_cams = poses.len();
    let (scale0, initial_cost) = check_bundle(poses, points, observations)?;
    let n_obs = observations.len().max(1);
    let mut poses = poses.to_vec();
    let mut points = points.to_vec();
    // Observations grouped by point.
    let mut by_point: Vec<Vec<usize>> = vec![Vec::new(); points.len()];
    for (i, o) in observations.iter().enumerate() {
        by_point[o.point].push(i);
    }
    let dim = 6 * (n_cams - 1);
    let mut current = initial_cost;
    let mut lambda: Option<f64> = None;
    let mut iterations = 0;
    while iterations < config.max_iterations && current > 1e-30 {
        iterations += 1;
        let normal = NormalEquations::build(&poses, &points, observations, dim);
        let lam = *lambda.get_or_insert_with(|| normal.initial_damping(config));
        let Some((dc, v_inv)) = normal.solve_cameras(&by_point, observations, lam)? else {
            lambda = Some(lam * 10.0);
            if lam > 1e12 {
                break;
            }
            continue;
        };
        let (mut new_poses, mut new_points) =
            normal.step(&poses, &points, &by_point, observations, &dc, &v_inv);
        hold_scale(&mut new_poses, &mut new_points, scale0);
        match cost(&new_poses, &new_points, observations) {
            Some(new_cost) if new_cost.is_finite() && new_cost < current => {
                let decrease = (current - new_cost) / current.max(1e-300);
                poses = new_poses;
                points = new_points;
                current = new_cost;
                lambda = Some((lam / 10.0).max(1e-15));
                if decrease < config.tolerance {
                    break;
                }
            }
            _ => {
                lambda = Some(lam * 10.0);
                if lam > 1e12 {
                    break;
                }
            }
        }
    }
    let rms = |c: f64| (2.0 * c / (2 * n_obs) as f64).sqrt();
    Ok(Bundle {
        poses,
        points,
        initial_rms: rms(initial_cost),
        final_rms: rms(current),
        iterations,
    })
}

/// Checks the inputs of [`bundle_adjust`] (the errors it documents, in that order) and
/// returns the gauge's scale (the mean distance of the camera centres from camera 0) and the
/// initial cost ½ Σ r².
fn check_bundle(
    poses: &[Pose],
    points: &[Vector3<f64>],
    observations: &[BundleObservation],
) -> Result<(f64, f64)> {
    let n_cams = poses.len();
    if n_cams < 2 {
        return Err(invalid("poses", format!("{n_cams}; need at least 2")));
    }
    let mut seen = vec![0usize; points.len()];
    for o in observations {
        if o.camera >= n_cams || o.point >= points.len() {
            return Err(invalid(
                "observations",
                format!("camera {} / point {} out of range", o.camera, o.point),
            ));
        }
        if !(o.x.x.is_finite() && o.x.y.is_finite()) {
            return Err(invalid("observations", "a non-finite image point".into()));
        }
        seen[o.point] += 1;
    }
    if let Some(p) = seen.iter().position(|&n| n < 2) {
        return Err(invalid(
            "observations",
            format!("point {p} is seen by fewer than 2 cameras"),
        ));
    }
    if points.iter().any(|x| !x.iter().all(|v| v.is_finite()))
        || poses
            .iter()
            .any(|p| !p.translation.iter().all(|v| v.is_finite()))
    {
        return Err(invalid("poses / points", "not finite".into()));
    }
    let scale0 = mean_centre_distance(poses);
    if !(scale0 > 0.0 && scale0.is_finite()) {
        return Err(Error::ZeroBaseline {
            parallax_rad: 0.0,
            threshold_rad: 0.0,
        });
    }
    let Some(initial_cost) = cost(poses, points, observations) else {
        return Err(invalid(
            "points",
            "a point is behind a camera that sees it".into(),
        ));
    };
    Ok((scale0, initial_cost))
}

/// A solved camera step δc and the inverses of the damped point blocks.
type CameraStep = (DVector<f64>, Vec<Matrix3<f64>>);

/// The Gauss-Newton normal equations JᵀJ δ = −Jᵀr of one LM iteration, by blocks as in the
/// sparse bundle adjustment of Triggs et al. 2000: U (cameras, dense), V (3 × 3 per
/// point), W (camera × point, 6 × 3 per observation; a camera sees a point once), and the
/// gradients of the cameras and of the points.
struct NormalEquations {
    /// 6(m−1): the free camera parameters (camera 0 is the gauge).
    dim: usize,
    u: DMatrix<f64>,
    g_c: DVector<f64>,
    v: Vec<Matrix3<f64>>,
    g_p: Vec<Vector3<f64>>,
    /// Per observation; `None` for camera 0's.
    w: Vec<Option<Block63>>,
}

impl NormalEquations {
    /// Accumulates the blocks over every observation at the current poses and points.
    fn build(
        poses: &[Pose],
        points: &[Vector3<f64>],
        observations: &[BundleObservation],
        dim: usize,
    ) -> Self {
        let mut u = DMatrix::<f64>::zeros(dim, dim);
        let mut g_c = DVector::<f64>::zeros(dim);
        let mut v = vec![Matrix3::<f64>::zeros(); points.len()];
        let mut g_p = vec![Vector3::<f64>::zeros(); points.len()];
        let mut w: Vec<Option<Block63>> = vec![None; observations.len()];
        for (i, o) in observations.iter().enumerate() {
            let pose = &poses[o.camera];
            let rx = pose.rotation * points[o.point];
            let y = rx + pose.translation;
            let r = Vector2::new(y.x / y.z, y.y / y.z) - o.x;
            let jp = jac_project(&y);
            let jx = jp * pose.rotation.matrix();
            v[o.point] += jx.transpose() * jx;
            g_p[o.point] += jx.transpose() * r;
            if o.camera == 0 {
                continue;
            }
            let mut dy = SMatrix::<f64, 3, 6>::zeros();
            dy.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-skew(&rx)));
            dy.fixed_view_mut::<3, 3>(0, 3)
                .copy_from(&Matrix3::identity());
            let jc: Block26 = jp * dy;
            let k = 6 * (o.camera - 1);
            let mut ub = u.view_mut((k, k), (6, 6));
            ub += jc.transpose() * jc;
            let mut gb = g_c.rows_mut(k, 6);
            gb += jc.transpose() * r;
            w[i] = Some(jc.transpose() * jx);
        }
        Self {
            dim,
            u,
            g_c,
            v,
            g_p,
            w,
        }
    }

    /// The first damping λ: `initial_damping` times the mean diagonal of JᵀJ (the usual
    /// Levenberg-Marquardt start, Hartley & Zisserman 2004, appendix 6).
    fn initial_damping(&self, config: &RefineConfig) -> f64 {
        let (u, v, dim) = (&self.u, &self.v, self.dim);
        let mean_diag = (u.trace() + v.iter().map(Matrix3::trace).sum::<f64>())
            / (dim + 3 * v.len()).max(1) as f64;
        config.initial_damping * mean_diag.max(1e-12)
    }

    /// The camera step δc of the damped reduced camera system S δc = rhs, the points
    /// eliminated by the Schur complement (Triggs et al. 2000), and the inverses of the
    /// damped point blocks for the back-substitution. `Ok(None)` when S is not positive
    /// definite (the caller raises λ); an error when a point block is singular.
    fn solve_cameras(
        &self,
        by_point: &[Vec<usize>],
        observations: &[BundleObservation],
        lam: f64,
    ) -> Result<Option<CameraStep>> {
        let (u, v, w, g_p) = (&self.u, &self.v, &self.w, &self.g_p);
        // Damped reduced camera system S δc = rhs (Marquardt: λ times the diagonal).
        let mut s = u.clone();
        for d in 0..self.dim {
            s[(d, d)] += lam * u[(d, d)] + 1e-12;
        }
        let mut rhs = -&self.g_c;
        let mut v_inv = Vec::with_capacity(v.len());
        for (p, obs_p) in by_point.iter().enumerate() {
            let vd =
                v[p] + Matrix3::from_diagonal(&v[p].diagonal()) * lam + Matrix3::identity() * 1e-12;
            let Some(inv) = vd.try_inverse() else {
                return Err(Error::Numerical {
                    what: "a point block of the bundle adjustment is singular",
                });
            };
            for &i in obs_p {
                let Some(wi) = &w[i] else { continue };
                let ki = 6 * (observations[i].camera - 1);
                let wi_inv = wi * inv;
                let mut rb = rhs.rows_mut(ki, 6);
                rb += wi_inv * g_p[p];
                for &j in obs_p {
                    let Some(wj) = &w[j] else { continue };
                    let kj = 6 * (observations[j].camera - 1);
                    let mut sb = s.view_mut((ki, kj), (6, 6));
                    sb -= wi_inv * wj.transpose();
                }
            }
            v_inv.push(inv);
        }
        Ok(s.cholesky().map(|c| (c.solve(&rhs), v_inv)))
    }

    /// The candidate poses and points after the step: δc applied to every camera but 0 (a left
    /// rotation increment, an additive translation), and each point's step back-substituted,
    /// δxₚ = V*ₚ⁻¹ (−gₚ − Σ Wᵢᵀ δc) (Triggs et al. 2000).
    fn step(
        &self,
        poses: &[Pose],
        points: &[Vector3<f64>],
        by_point: &[Vec<usize>],
        observations: &[BundleObservation],
        dc: &DVector<f64>,
        v_inv: &[Matrix3<f64>],
    ) -> (Vec<Pose>, Vec<Vector3<f64>>) {
        let mut new_poses = poses.to_vec();
        for (c, pose) in new_poses.iter_mut().enumerate().skip(1) {
            let d = dc.rows(6 * (c - 1), 6);
            let omega = Vector3::new(d[0], d[1], d[2]);
            pose.rotation = Rotation3::new(omega) * pose.rotation;
            pose.translation += Vector3::new(d[3], d[4], d[5]);
        }
        let mut new_points = points.to_vec();
        for (p, obs_p) in by_point.iter().enumerate() {
            let mut b = -self.g_p[p];
            for &i in obs_p {
                if let Some(wi) = &self.w[i] {
                    let k = 6 * (observations[i].camera - 1);
                    b -= wi.transpose() * dc.fixed_rows::<6>(k);
                }
            }
            new_points[p] += v_inv[p] * b;
        }
        (new_poses, new_points)
    }
}

/// Holds the global scale (the gauge the residuals do not see): the similarity
/// X' = s (X − C₀) + C₀ about camera 0's centre, with t'_c = s t_c + (s − 1) R_c C₀, maps
/// every camera-frame point y_c to s y_c, so no image point moves; s brings the mean centre
/// distance back to `scale0`.
fn hold_scale(poses: &mut [Pose], points: &mut [Vector3<f64>], scale0: f64) {
    let scale = scale0 / mean_centre_distance(poses);
    if scale.is_finite() && scale > 0.0 {
        let c0 = poses[0].centre();
        for pose in poses.iter_mut().skip(1) {
            pose.translation = pose.translation * scale + (pose.rotation * c0) * (scale - 1.0);
        }
        for x in points {
            *x = (*x - c0) * scale + c0;
        }
    }
}
