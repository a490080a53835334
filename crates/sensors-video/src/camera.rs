//! A pinhole camera on a mast and the angle profile: the number of foreground pixels in each of
//! N bearings (Kushwaha et al. 2008's detection function over 160 angles).
//!
//! Conventions: world x, y horizontal, z up, bearings counter-clockwise from +x. The camera at
//! `position` looks along `heading_rad`, pitched down by `tilt_rad`, no roll. Pixel (u, v) has
//! its centre at column u, row v (integer indices); u grows to the right, v downwards. Camera
//! axes in the world: right r = (sin h, −cos h, 0), forward f = (cos h cos t, sin h cos t,
//! −sin t), down d = f × r. The ray through (u, v) is f + r (u − c_x)/f_x + d (v − c_y)/f_y and
//! its bearing atan2 of its horizontal part. With no tilt this is the column formula
//! θ(u) = h − atan((u − c_x)/f_x) for every row (minus: columns to the right are clockwise).

use serde::{Deserialize, Serialize};
use tracker_model::{
    BearingProfile, SensorPose, Vec2, ensure_in_range, ensure_positive, wrap_angle_rad,
};

use crate::error::{Error, Result};

/// Intrinsics and pose of a pinhole camera.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PinholeCamera {
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Focal length in pixels, horizontal.
    pub fx: f64,
    /// Focal length in pixels, vertical.
    pub fy: f64,
    /// Principal point column.
    pub cx: f64,
    /// Principal point row.
    pub cy: f64,
    /// Position (x, y, height z), metres.
    pub position_m: [f64; 3],
    /// Bearing of the optical axis, radians counter-clockwise from +x.
    pub heading_rad: f64,
    /// Downward pitch of the optical axis, radians (0 = horizontal).
    pub tilt_rad: f64,
}

type V3 = [f64; 3];

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl PinholeCamera {
    /// Checks sizes, focal lengths and angles (|tilt| < π/2).
    pub fn check(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::ZeroSize {
                width: self.width,
                height: self.height,
            });
        }
        ensure_positive(self.fx, "fx")?;
        ensure_positive(self.fy, "fy")?;
        let finite = self.cx.is_finite()
            && self.cy.is_finite()
            && self.heading_rad.is_finite()
            && self.position_m.iter().all(|v| v.is_finite());
        if !finite {
            return Err(tracker_model::Error::NonFinite { what: "camera" }.into());
        }
        ensure_in_range(self.tilt_rad, -1.5, 1.5, "tilt_rad")?;
        Ok(())
    }

    /// Camera axes in world coordinates: (right, down, forward).
    pub fn axes(&self) -> (V3, V3, V3) {
        let (sh, ch) = self.heading_rad.sin_cos();
        let (st, ct) = self.tilt_rad.sin_cos();
        let r = [sh, -ch, 0.0];
        let f = [ch * ct, sh * ct, -st];
        (r, cross(f, r), f)
    }

    /// World direction (not normalised) of the ray through pixel (u, v).
    pub fn ray(&self, u: f64, v: f64) -> V3 {
        let (r, d, f) = self.axes();
        let (a, b) = ((u - self.cx) / self.fx, (v - self.cy) / self.fy);
        [
            f[0] + a * r[0] + b * d[0],
            f[1] + a * r[1] + b * d[1],
            f[2] + a * r[2] + b * d[2],
        ]
    }

    /// World bearing of the ray through pixel (u, v), radians.
    pub fn pixel_bearing_rad(&self, u: f64, v: f64) -> f64 {
        let d = self.ray(u, v);
        d[1].atan2(d[0])
    }

    /// World bearing of column u on the principal row (the column formula).
    pub fn column_bearing_rad(&self, u: f64) -> f64 {
        self.pixel_bearing_rad(u, self.cy)
    }

    /// Image position (u, v) of a world point, or `None` behind the camera.
    pub fn project(&self, point_m: V3) -> Option<(f64, f64)> {
        let (r, d, f) = self.axes();
        let q = [
            point_m[0] - self.position_m[0],
            point_m[1] - self.position_m[1],
            point_m[2] - self.position_m[2],
        ];
        let z = dot(q, f);
        (z > 1e-9).then(|| {
            (
                self.cx + self.fx * dot(q, r) / z,
                self.cy + self.fy * dot(q, d) / z,
            )
        })
    }

    /// The sensor pose of the camera on the ground plane.
    pub fn pose(&self) -> SensorPose {
        SensorPose {
            position: Vec2::new(self.position_m[0], self.position_m[1]),
            heading_rad: self.heading_rad,
        }
    }
}

/// Maps foreground masks to bearing profiles over `n_angles` equal bins spanning the image's
/// bearings (sensor-relative, from the leftmost to the rightmost pixel centre over all rows).
#[derive(Debug, Clone)]
pub struct AngleProfiler {
    camera: PinholeCamera,
    start_rad: f64,
    step_rad: f64,
    n_angles: usize,
    bin_of_pixel: Vec<u32>,
}

/// Default number of angles (the paper's 160).
pub const DEFAULT_N_ANGLES: usize = 160;

impl AngleProfiler {
    /// Precomputes each pixel's bin.
    pub fn new(camera: PinholeCamera, n_angles: usize) -> Result<Self> {
        camera.check()?;
        if n_angles == 0 {
            return Err(tracker_model::Error::InvalidParameter {
                name: "n_angles",
                reason: "must be at least 1".to_string(),
            }
            .into());
        }
        let (w, h) = (camera.width, camera.height);
        let rel: Vec<f64> = (0..h)
            .flat_map(|v| (0..w).map(move |u| (u, v)))
            .map(|(u, v)| {
                wrap_angle_rad(camera.pixel_bearing_rad(u as f64, v as f64) - camera.heading_rad)
            })
            .collect();
        let lo = rel.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = rel.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        // Bins of equal width whose outer edges are the extreme pixel centres; a one-column
        // image gets a tiny positive width.
        let step = ((hi - lo) / n_angles as f64).max(1e-9);
        let bin_of_pixel = rel
            .iter()
            .map(|&a| (((a - lo) / step).floor() as usize).min(n_angles - 1) as u32)
            .collect();
        Ok(Self {
            camera,
            start_rad: lo + step / 2.0,
            step_rad: step,
            n_angles,
            bin_of_pixel,
        })
    }

    /// The camera.
    pub fn camera(&self) -> &PinholeCamera {
        &self.camera
    }

    /// Sensor-relative angle of bin i's centre.
    pub fn bin_angle_rad(&self, i: usize) -> f64 {
        self.start_rad + i as f64 * self.step_rad
    }

    /// Counts of foreground pixels per bin (`foreground` row-major, camera-sized).
    pub fn counts(&self, foreground: &[bool]) -> Result<Vec<f64>> {
        if foreground.len() != self.bin_of_pixel.len() {
            return Err(Error::BufferSize {
                len: foreground.len(),
                expected: self.bin_of_pixel.len(),
                width: self.camera.width,
                height: self.camera.height,
                channels: 1,
            });
        }
        let mut counts = vec![0.0; self.n_angles];
        for (&fg, &b) in foreground.iter().zip(&self.bin_of_pixel) {
            if fg {
                counts[b as usize] += 1.0;
            }
        }
        Ok(counts)
    }

    /// Wraps per-bin values (counts, possibly filtered) as a [`BearingProfile`] sector.
    pub fn profile(&self, values: Vec<f64>) -> Result<BearingProfile> {
        Ok(BearingProfile::sector(
            self.camera.pose(),
            self.start_rad,
            self.step_rad,
            values,
        )?)
    }
}
