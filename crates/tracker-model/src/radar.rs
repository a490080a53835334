//! Radar measurements: range and bearing from a sensor in the plane, and range, bearing and
//! elevation in 3-D. Bearing is atan2(Δy, Δx), counter-clockwise from the x (east) axis as
//! [`bearing_rad`](crate::bearing_rad); elevation is above the horizontal plane. Angles are
//! wrapped in residuals and averaged on the circle, so a target due west (bearing ±π) is
//! tracked through the cut.

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, ensure_positive};
use crate::geometry::wrap_angle_rad;
use crate::nonlinear::MeasurementModel;

/// Where a measurement model finds the position in an N-component state, and where the sensor
/// stands; checked against N and for finiteness.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RadarSite<const D: usize> {
    /// Sensor position, metres.
    pub position: SVector<f64, D>,
    /// State index of each position coordinate (x, y[, z]).
    pub state_indices: SVector<usize, D>,
}

impl<const D: usize> RadarSite<D> {
    fn check(self, n: usize) -> Result<Self> {
        if self.position.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                what: "radar position",
            });
        }
        for (k, &i) in self.state_indices.iter().enumerate() {
            if i >= n || self.state_indices.iter().take(k).any(|&j| j == i) {
                return Err(Error::InvalidParameter {
                    name: "state_indices",
                    reason: format!(
                        "{:?} must be {D} distinct indices below the state size {n}",
                        self.state_indices.as_slice()
                    ),
                });
            }
        }
        Ok(self)
    }

    /// The target's offset from the sensor.
    fn offset<const N: usize>(&self, x: &SVector<f64, N>) -> [f64; D] {
        std::array::from_fn(|k| x[self.state_indices[k]] - self.position[k])
    }
}

/// Range and bearing, z = [r, θ], with standard deviations σ_r (m) and σ_θ (rad).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawRangeBearing", into = "RawRangeBearing")]
pub struct RangeBearing<const N: usize> {
    site: RadarSite<2>,
    sigma_range_m: f64,
    sigma_bearing_rad: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRangeBearing {
    site: RadarSite<2>,
    sigma_range_m: f64,
    sigma_bearing_rad: f64,
}

impl<const N: usize> TryFrom<RawRangeBearing> for RangeBearing<N> {
    type Error = Error;
    fn try_from(raw: RawRangeBearing) -> Result<Self> {
        RangeBearing::new(raw.site, raw.sigma_range_m, raw.sigma_bearing_rad)
    }
}

impl<const N: usize> From<RangeBearing<N>> for RawRangeBearing {
    fn from(m: RangeBearing<N>) -> Self {
        RawRangeBearing {
            site: m.site,
            sigma_range_m: m.sigma_range_m,
            sigma_bearing_rad: m.sigma_bearing_rad,
        }
    }
}

impl<const N: usize> RangeBearing<N> {
    /// A radar at `site` with positive noise standard deviations.
    pub fn new(site: RadarSite<2>, sigma_range_m: f64, sigma_bearing_rad: f64) -> Result<Self> {
        Ok(Self {
            site: site.check(N)?,
            sigma_range_m: ensure_positive(sigma_range_m, "sigma_range_m")?,
            sigma_bearing_rad: ensure_positive(sigma_bearing_rad, "sigma_bearing_rad")?,
        })
    }

    /// A radar at (x, y) on a state whose first two components are x and y.
    pub fn at(position: [f64; 2], sigma_range_m: f64, sigma_bearing_rad: f64) -> Result<Self> {
        let site = RadarSite {
            position: position.into(),
            state_indices: SVector::<usize, 2>::new(0, 1),
        };
        Self::new(site, sigma_range_m, sigma_bearing_rad)
    }

    /// The sensor.
    pub fn site(&self) -> &RadarSite<2> {
        &self.site
    }

    /// The plot z = [r, θ] as a position, with the covariance J R Jᵀ of the linearised
    /// conversion (J = ∂(x, y)/∂(r, θ)): how a track is started from one plot.
    pub fn position_of(&self, z: &SVector<f64, 2>) -> (SVector<f64, 2>, SMatrix<f64, 2, 2>) {
        let (sin, cos) = z[1].sin_cos();
        let p = self.site.position + SVector::<f64, 2>::new(cos, sin) * z[0];
        let j = SMatrix::<f64, 2, 2>::new(cos, -z[0] * sin, sin, z[0] * cos);
        (p, j * MeasurementModel::<N, 2>::noise(self) * j.transpose())
    }
}

impl<const N: usize> MeasurementModel<N, 2> for RangeBearing<N> {
    fn measure(&self, x: &SVector<f64, N>) -> SVector<f64, 2> {
        let [dx, dy] = self.site.offset(x);
        SVector::<f64, 2>::new(dx.hypot(dy), dy.atan2(dx))
    }

    /// ∂r/∂(x, y) = (Δx, Δy)/r, ∂θ/∂(x, y) = (−Δy, Δx)/r²; not finite at the sensor itself.
    fn jacobian(&self, x: &SVector<f64, N>) -> SMatrix<f64, 2, N> {
        let [dx, dy] = self.site.offset(x);
        let r2 = dx * dx + dy * dy;
        let r = r2.sqrt();
        let (ix, iy) = (self.site.state_indices[0], self.site.state_indices[1]);
        let mut j = SMatrix::<f64, 2, N>::zeros();
        j[(0, ix)] = dx / r;
        j[(0, iy)] = dy / r;
        j[(1, ix)] = -dy / r2;
        j[(1, iy)] = dx / r2;
        j
    }

    fn noise(&self) -> SMatrix<f64, 2, 2> {
        SMatrix::<f64, 2, 2>::from_diagonal(&SVector::<f64, 2>::new(
            self.sigma_range_m.powi(2),
            self.sigma_bearing_rad.powi(2),
        ))
    }

    fn residual(&self, z: &SVector<f64, 2>, predicted: &SVector<f64, 2>) -> SVector<f64, 2> {
        SVector::<f64, 2>::new(z[0] - predicted[0], wrap_angle_rad(z[1] - predicted[1]))
    }

    fn weighted_mean(&self, points: &[SVector<f64, 2>], weights: &[f64]) -> SVector<f64, 2> {
        let range = points.iter().zip(weights).map(|(p, w)| p[0] * w).sum();
        SVector::<f64, 2>::new(range, circular_mean(points, weights, 1))
    }
}

/// Range, bearing and elevation, z = [r, θ, φ], with standard deviations σ_r (m), σ_θ and σ_φ
/// (rad).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(
    try_from = "RawRangeBearingElevation",
    into = "RawRangeBearingElevation"
)]
pub struct RangeBearingElevation<const N: usize> {
    site: RadarSite<3>,
    sigmas: [f64; 3],
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRangeBearingElevation {
    site: RadarSite<3>,
    sigma_range_m: f64,
    sigma_bearing_rad: f64,
    sigma_elevation_rad: f64,
}

impl<const N: usize> TryFrom<RawRangeBearingElevation> for RangeBearingElevation<N> {
    type Error = Error;
    fn try_from(raw: RawRangeBearingElevation) -> Result<Self> {
        RangeBearingElevation::new(
            raw.site,
            [
                raw.sigma_range_m,
                raw.sigma_bearing_rad,
                raw.sigma_elevation_rad,
            ],
        )
    }
}

impl<const N: usize> From<RangeBearingElevation<N>> for RawRangeBearingElevation {
    fn from(m: RangeBearingElevation<N>) -> Self {
        RawRangeBearingElevation {
            site: m.site,
            sigma_range_m: m.sigmas[0],
            sigma_bearing_rad: m.sigmas[1],
            sigma_elevation_rad: m.sigmas[2],
        }
    }
}

impl<const N: usize> RangeBearingElevation<N> {
    /// A radar at `site` with positive standard deviations [σ_r, σ_θ, σ_φ].
    pub fn new(site: RadarSite<3>, sigmas: [f64; 3]) -> Result<Self> {
        ensure_positive(sigmas[0], "sigma_range_m")?;
        ensure_positive(sigmas[1], "sigma_bearing_rad")?;
        ensure_positive(sigmas[2], "sigma_elevation_rad")?;
        Ok(Self {
            site: site.check(N)?,
            sigmas,
        })
    }
}

impl<const N: usize> MeasurementModel<N, 3> for RangeBearingElevation<N> {
    fn measure(&self, x: &SVector<f64, N>) -> SVector<f64, 3> {
        let [dx, dy, dz] = self.site.offset(x);
        let ground = dx.hypot(dy);
        SVector::<f64, 3>::new(ground.hypot(dz), dy.atan2(dx), dz.atan2(ground))
    }

    /// With ρ the ground range: ∂r = Δ/r, ∂θ = (−Δy, Δx, 0)/ρ², ∂φ = (−Δx Δz/ρ, −Δy Δz/ρ, ρ)/r².
    fn jacobian(&self, x: &SVector<f64, N>) -> SMatrix<f64, 3, N> {
        let [dx, dy, dz] = self.site.offset(x);
        let rho2 = dx * dx + dy * dy;
        let rho = rho2.sqrt();
        let r2 = rho2 + dz * dz;
        let r = r2.sqrt();
        let [ix, iy, iz] = [0, 1, 2].map(|k| self.site.state_indices[k]);
        let mut j = SMatrix::<f64, 3, N>::zeros();
        j[(0, ix)] = dx / r;
        j[(0, iy)] = dy / r;
        j[(0, iz)] = dz / r;
        j[(1, ix)] = -dy / rho2;
        j[(1, iy)] = dx / rho2;
        j[(2, ix)] = -dx * dz / (rho * r2);
        j[(2, iy)] = -dy * dz / (rho * r2);
        j[(2, iz)] = rho / r2;
        j
    }

    fn noise(&self) -> SMatrix<f64, 3, 3> {
        SMatrix::<f64, 3, 3>::from_diagonal(&SVector::<f64, 3>::from(self.sigmas.map(|s| s * s)))
    }

    fn residual(&self, z: &SVector<f64, 3>, predicted: &SVector<f64, 3>) -> SVector<f64, 3> {
        SVector::<f64, 3>::new(
            z[0] - predicted[0],
            wrap_angle_rad(z[1] - predicted[1]),
            z[2] - predicted[2],
        )
    }

    fn weighted_mean(&self, points: &[SVector<f64, 3>], weights: &[f64]) -> SVector<f64, 3> {
        let mut mean = points
            .iter()
            .zip(weights)
            .fold(SVector::<f64, 3>::zeros(), |acc, (p, w)| acc + p * *w);
        mean[1] = circular_mean(points, weights, 1);
        mean
    }
}

/// atan2(Σ wᵢ sin θᵢ, Σ wᵢ cos θᵢ) of component `k`.
fn circular_mean<const M: usize>(points: &[SVector<f64, M>], weights: &[f64], k: usize) -> f64 {
    let (s, c) = points
        .iter()
        .zip(weights)
        .fold((0.0, 0.0), |(s, c), (p, w)| {
            let (sin, cos) = p[k].sin_cos();
            (s + w * sin, c + w * cos)
        });
    s.atan2(c)
}
