//! Cameras, poses, triangulation and similarity alignment.
//!
//! Conventions: a pose maps points from a reference frame into the camera's frame,
//! X_cam = R X_ref + t (`camera_from_reference`); the camera looks along +z; normalised image
//! coordinates are x = (X/Z, Y/Z) = K⁻¹ u.

use nalgebra::{Matrix3, Matrix4, Rotation3, Vector2, Vector3};
use serde::{Deserialize, Serialize};
use tracker_model::ensure_positive;

use crate::error::{Error, Result};

/// Pinhole intrinsics without skew or distortion: u = f_x x + c_x, v = f_y y + c_y.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Intrinsics {
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
}

impl Intrinsics {
    /// Checks that the focal lengths are positive and everything is finite.
    pub fn check(&self) -> Result<()> {
        ensure_positive(self.fx, "fx")?;
        ensure_positive(self.fy, "fy")?;
        if !(self.cx.is_finite() && self.cy.is_finite()) {
            return Err(crate::error::invalid(
                "principal point",
                format!("({}, {}) is not finite", self.cx, self.cy),
            ));
        }
        Ok(())
    }

    /// Pixel → normalised image coordinates (K⁻¹ u).
    pub fn normalise(&self, pixel: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new((pixel.x - self.cx) / self.fx, (pixel.y - self.cy) / self.fy)
    }

    /// Normalised image coordinates → pixel (K x).
    pub fn to_pixel(&self, x: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new(self.fx * x.x + self.cx, self.fy * x.y + self.cy)
    }

    /// The geometric mean focal length: pixel thresholds divide by it to become normalised.
    pub fn mean_focal(&self) -> f64 {
        (self.fx * self.fy).sqrt()
    }
}

/// A rigid transform X_cam = R X_ref + t.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// R.
    pub rotation: Rotation3<f64>,
    /// t.
    pub translation: Vector3<f64>,
}

impl Pose {
    /// The identity (the reference camera).
    pub fn identity() -> Self {
        Self {
            rotation: Rotation3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// The pose of a camera at `centre` looking at `target` with the world z axis up: image x
    /// to the right, image y down, optical axis +z. `None` when the camera looks straight up
    /// or down (or at itself).
    pub fn look_at(centre: &Vector3<f64>, target: &Vector3<f64>) -> Option<Self> {
        let forward = (target - centre).try_normalize(1e-12)?;
        let right = forward.cross(&Vector3::z()).try_normalize(1e-12)?;
        let down = forward.cross(&right);
        let r = Matrix3::from_rows(&[right.transpose(), down.transpose(), forward.transpose()]);
        let rotation = Rotation3::from_matrix_unchecked(r);
        Some(Self {
            rotation,
            translation: -(rotation * centre),
        })
    }

    /// Maps a reference-frame point into the camera frame.
    pub fn apply(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * x + self.translation
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Self {
        let r_inv = self.rotation.inverse();
        Self {
            rotation: r_inv,
            translation: -(r_inv * self.translation),
        }
    }

    /// `self ∘ first`: first `first`, then `self`.
    pub fn compose(&self, first: &Pose) -> Self {
        Self {
            rotation: self.rotation * first.rotation,
            translation: self.rotation * first.translation + self.translation,
        }
    }

    /// The camera centre in the reference frame, −Rᵀ t.
    pub fn centre(&self) -> Vector3<f64> {
        -(self.rotation.inverse() * self.translation)
    }

    /// The essential matrix \[t\]× R of this relative pose (x₂ᵀ E x₁ = 0).
    pub fn essential(&self) -> Matrix3<f64> {
        skew(&self.translation) * self.rotation.matrix()
    }
}

/// \[v\]×, the cross-product matrix.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Homogeneous normalised point (x, y, 1).
pub(crate) fn homogeneous(x: &Vector2<f64>) -> Vector3<f64> {
    Vector3::new(x.x, x.y, 1.0)
}

/// Perspective division; `None` behind or on the camera plane.
pub fn project(x: &Vector3<f64>) -> Option<Vector2<f64>> {
    (x.z > 0.0).then(|| Vector2::new(x.x / x.z, x.y / x.z))
}

/// Linear (DLT) triangulation of one correspondence between view 1 at the identity and view 2
/// at `pose`: the right singular vector of the 4×4 system of smallest singular value. The
/// result is in view 1's frame; `None` when it is at infinity or the SVD fails.
pub fn triangulate(pose: &Pose, x1: &Vector2<f64>, x2: &Vector2<f64>) -> Option<Vector3<f64>> {
    let r = pose.rotation.matrix();
    let t = &pose.translation;
    // Rows of P₂ = [R | t].
    let p2 = |i: usize| nalgebra::RowVector4::new(r[(i, 0)], r[(i, 1)], r[(i, 2)], t[i]);
    let p1 = |i: usize| {
        let mut row = nalgebra::RowVector4::zeros();
        row[i] = 1.0;
        row
    };
    let a = Matrix4::from_rows(&[
        p1(2) * x1.x - p1(0),
        p1(2) * x1.y - p1(1),
        p2(2) * x2.x - p2(0),
        p2(2) * x2.y - p2(1),
    ]);
    let svd = a.try_svd(false, true, 1e-15, 100)?;
    let v_t = svd.v_t?;
    let (i_min, _) = svd
        .singular_values
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    let h = v_t.row(i_min);
    if h[3].abs() < 1e-14 {
        return None;
    }
    let x = Vector3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3]);
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// A similarity transform y = s R x + t.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Similarity {
    /// s.
    pub scale: f64,
    /// R.
    pub rotation: Rotation3<f64>,
    /// t.
    pub translation: Vector3<f64>,
}

impl Similarity {
    /// Applies the transform.
    pub fn apply(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.scale * (self.rotation * x) + self.translation
    }
}

/// Umeyama's (1991) least-squares similarity taking `from` onto `to`: minimises
/// Σ |to_i − (s R from_i + t)|² with det R = +1. Needs at least three points not all on a line
/// for a unique answer; fewer than two points or no spread is an error.
pub fn umeyama(from: &[Vector3<f64>], to: &[Vector3<f64>]) -> Result<Similarity> {
    if from.len() != to.len() {
        return Err(Error::LengthMismatch {
            first: from.len(),
            second: to.len(),
        });
    }
    if from.len() < 2 {
        return Err(Error::TooFewCorrespondences {
            found: from.len(),
            needed: 2,
        });
    }
    let n = from.len() as f64;
    let mu_x = from.iter().sum::<Vector3<f64>>() / n;
    let mu_y = to.iter().sum::<Vector3<f64>>() / n;
    let var_x = from.iter().map(|x| (x - mu_x).norm_squared()).sum::<f64>() / n;
    if var_x <= 0.0 || !var_x.is_finite() {
        return Err(Error::Numerical {
            what: "Umeyama alignment of points without spread",
        });
    }
    let cov = from
        .iter()
        .zip(to)
        .map(|(x, y)| (y - mu_y) * (x - mu_x).transpose())
        .sum::<Matrix3<f64>>()
        / n;
    let svd = cov
        .try_svd(true, true, 1e-15, 200)
        .ok_or(Error::Numerical {
            what: "SVD in Umeyama alignment",
        })?;
    let (u, v_t) = svd.u.zip(svd.v_t).ok_or(Error::Numerical {
        what: "SVD in Umeyama alignment",
    })?;
    let mut s = Matrix3::identity();
    if u.determinant() * v_t.determinant() < 0.0 {
        s[(2, 2)] = -1.0;
    }
    let r = u * s * v_t;
    let d = svd.singular_values;
    let scale = (d[0] * s[(0, 0)] + d[1] * s[(1, 1)] + d[2] * s[(2, 2)]) / var_x;
    let rotation = Rotation3::from_matrix_unchecked(r);
    Ok(Similarity {
        scale,
        rotation,
        translation: mu_y - scale * (rotation * mu_x),
    })
}

/// The angle of the rotation R_a R_bᵀ, degrees.
pub fn rotation_error_deg(a: &Rotation3<f64>, b: &Rotation3<f64>) -> f64 {
    // atan2 of the sine and cosine parts keeps precision near 0 (acos of the trace does not).
    let m = (a * b.inverse()).into_inner();
    let sin = 0.5
        * Vector3::new(
            m[(2, 1)] - m[(1, 2)],
            m[(0, 2)] - m[(2, 0)],
            m[(1, 0)] - m[(0, 1)],
        )
        .norm();
    let cos = 0.5 * (m.trace() - 1.0);
    sin.atan2(cos).to_degrees()
}

/// The angle between two directions, degrees (0 for a zero vector is not meaningful: NaN).
pub fn angle_between_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b)).to_degrees()
}
