//! Regions, bounding boxes and bearings.

use nalgebra::{SVector, Vector2};
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A vector in the plane: a position, a velocity or an offset. (Not nalgebra's `Point2`,
/// which is a different type; this is its `Vector2<f64>`.)
pub type Vec2 = Vector2<f64>;

/// An axis-aligned box [lower, upper] in `D` dimensions: the surveillance region.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawRegion<D>", into = "RawRegion<D>")]
pub struct Region<const D: usize> {
    lower: SVector<f64, D>,
    upper: SVector<f64, D>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRegion<const D: usize> {
    lower: SVector<f64, D>,
    upper: SVector<f64, D>,
}

impl<const D: usize> TryFrom<RawRegion<D>> for Region<D> {
    type Error = Error;
    fn try_from(raw: RawRegion<D>) -> Result<Self> {
        Region::new(raw.lower, raw.upper)
    }
}

impl<const D: usize> From<Region<D>> for RawRegion<D> {
    fn from(r: Region<D>) -> Self {
        RawRegion {
            lower: r.lower,
            upper: r.upper,
        }
    }
}

/// The 2-D surveillance region.
pub type Region2 = Region<2>;

impl<const D: usize> Region<D> {
    /// A region; every bound must be finite and `lower < upper` on every axis.
    pub fn new(lower: SVector<f64, D>, upper: SVector<f64, D>) -> Result<Self> {
        if D == 0 {
            return Err(Error::Empty { what: "region" });
        }
        for axis in 0..D {
            let (lo, hi) = (lower[axis], upper[axis]);
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(Error::InvalidParameter {
                    name: "region",
                    reason: format!("axis {axis}: lower {lo} must be finite and below upper {hi}"),
                });
            }
        }
        Ok(Self { lower, upper })
    }

    /// The lower corner.
    pub fn lower(&self) -> &SVector<f64, D> {
        &self.lower
    }

    /// The upper corner.
    pub fn upper(&self) -> &SVector<f64, D> {
        &self.upper
    }

    /// Side lengths.
    pub fn extent(&self) -> SVector<f64, D> {
        self.upper - self.lower
    }

    /// Volume (area in 2-D): the V of λ_b·V and λ_f·V.
    pub fn volume(&self) -> f64 {
        self.extent().iter().product()
    }

    /// Whether `p` lies in the closed region.
    pub fn contains(&self, p: &SVector<f64, D>) -> bool {
        (0..D).all(|i| p[i] >= self.lower[i] && p[i] <= self.upper[i])
    }

    /// A point drawn uniformly from the region.
    pub fn sample_uniform<R: Rng + ?Sized>(&self, rng: &mut R) -> SVector<f64, D> {
        SVector::from_fn(|i, _| {
            let u: f64 = rng.random();
            self.lower[i] + u * (self.upper[i] - self.lower[i])
        })
    }
}

impl Region<2> {
    /// The square [0, side]², as in the MCMCDA experiments.
    pub fn square(side: f64) -> Result<Self> {
        Self::new(Vec2::zeros(), Vec2::new(side, side))
    }
}

/// An image-style bounding box: `left`, `top` are the top-left corner, y grows downward.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundingBox {
    /// x of the left edge.
    pub left: f64,
    /// y of the top edge.
    pub top: f64,
    /// Width (≥ 0).
    pub width: f64,
    /// Height (≥ 0).
    pub height: f64,
}

impl BoundingBox {
    /// A box with finite coordinates and non-negative size.
    pub fn new(left: f64, top: f64, width: f64, height: f64) -> Result<Self> {
        for (v, what) in [
            (left, "box left"),
            (top, "box top"),
            (width, "box width"),
            (height, "box height"),
        ] {
            if !v.is_finite() {
                return Err(Error::NonFinite { what });
            }
        }
        if width < 0.0 || height < 0.0 {
            return Err(Error::InvalidParameter {
                name: "box size",
                reason: format!("width {width} and height {height} must be >= 0"),
            });
        }
        Ok(Self {
            left,
            top,
            width,
            height,
        })
    }

    /// A box of the given size centred on `centre`.
    pub fn from_centre(centre: Vec2, width: f64, height: f64) -> Result<Self> {
        Self::new(
            centre.x - width / 2.0,
            centre.y - height / 2.0,
            width,
            height,
        )
    }

    /// The centre point.
    #[inline]
    pub fn centre(&self) -> Vec2 {
        Vec2::new(self.left + self.width / 2.0, self.top + self.height / 2.0)
    }

    /// x of the right edge.
    #[inline]
    pub fn right(&self) -> f64 {
        self.left + self.width
    }

    /// y of the bottom edge.
    #[inline]
    pub fn bottom(&self) -> f64 {
        self.top + self.height
    }

    /// Area.
    #[inline]
    pub fn area(&self) -> f64 {
        self.width * self.height
    }

    /// Area of the intersection with `other` (0 when disjoint or touching).
    #[inline]
    pub fn intersection_area(&self, other: &Self) -> f64 {
        let w = (self.right().min(other.right()) - self.left.max(other.left)).max(0.0);
        let h = (self.bottom().min(other.bottom()) - self.top.max(other.top)).max(0.0);
        w * h
    }

    /// Intersection over union in [0, 1]; two zero-area boxes have IoU 0, even when identical,
    /// because a degenerate box carries no extent to overlap.
    #[inline]
    pub fn iou(&self, other: &Self) -> f64 {
        let inter = self.intersection_area(other);
        let union = self.area() + other.area() - inter;
        if union > 0.0 { inter / union } else { 0.0 }
    }
}

/// Bearing from `from` to `to` in radians, counter-clockwise from the +x axis, in (−π, π].
pub fn bearing_rad(from: &Vec2, to: &Vec2) -> f64 {
    let d = to - from;
    d.y.atan2(d.x)
}

/// Wraps an angle into (−π, π].
pub fn wrap_angle_rad(angle: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let a = (angle + PI).rem_euclid(TAU) - PI;
    if a <= -PI { a + TAU } else { a }
}
