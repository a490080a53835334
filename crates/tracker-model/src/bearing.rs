//! Bearing profiles: a bearing-only sensor's evidence over angle (audio beam energies, video
//! foreground pixel counts per column) at a known pose, and their projection onto a
//! [`LikelihoodGrid`] (Kushwaha et al. 2008; our §5.4 reconstruction: L_s(c) = D_s(θ_{s,c})).

use std::f64::consts::TAU;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, ensure_non_negative, ensure_positive};
use crate::geometry::{Region2, Vec2, wrap_angle_rad};
use crate::grid::LikelihoodGrid;

#[cfg(test)]
mod tests;

/// Where a sensor stands and where its angle 0 points (radians counter-clockwise from the
/// world's +x axis).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorPose {
    /// Position in world coordinates, metres.
    pub position: Vec2,
    /// World bearing of the sensor's angle 0, radians.
    pub heading_rad: f64,
}

/// Evidence over bearing from one sensor: `values[i]` at sensor-relative angle
/// `start_rad + i·step_rad`, linearly interpolated between bins. A full-circle profile (audio
/// beams) wraps around; a sector profile (a camera's field of view) is zero more than half a
/// bin outside its first and last bins.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BearingProfile {
    pose: SensorPose,
    start_rad: f64,
    step_rad: f64,
    values: Vec<f64>,
    wraps: bool,
}

/// How a projected grid is scaled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum GridNormalisation {
    /// Σ_c L(c) = 1: each sensor contributes the same total evidence.
    #[default]
    Sum,
    /// max_c L(c) = 1: the profile's own scale, useful for display and for product fusion.
    Max,
    /// The profile's values as they are.
    None,
}

/// How a profile is projected: the normalisation and the sensing range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProjectionConfig {
    /// Scaling of the output grid.
    pub normalisation: GridNormalisation,
    /// Cells farther than this from the sensor get 0 (`None`: unlimited).
    pub max_range_m: Option<f64>,
    /// Cells nearer than this get 0: at the sensor itself the bearing is undefined.
    pub min_range_m: f64,
}

impl Default for ProjectionConfig {
    fn default() -> Self {
        Self {
            normalisation: GridNormalisation::Sum,
            max_range_m: None,
            min_range_m: 0.0,
        }
    }
}

impl ProjectionConfig {
    /// Checks the ranges: finite, non-negative, max > min.
    pub fn check(&self) -> Result<()> {
        ensure_non_negative(self.min_range_m, "min_range_m")?;
        if let Some(max) = self.max_range_m {
            ensure_positive(max, "max_range_m")?;
            if max <= self.min_range_m {
                return Err(Error::InvalidParameter {
                    name: "max_range_m",
                    reason: format!("{max} must exceed min_range_m = {}", self.min_range_m),
                });
            }
        }
        Ok(())
    }
}

impl BearingProfile {
    /// A profile covering the full circle with `values.len()` equal bins, bin 0 at the
    /// sensor's heading (the audio beamform: beam b at b·2π/B).
    pub fn full_circle(pose: SensorPose, values: Vec<f64>) -> Result<Self> {
        let step = TAU / values.len().max(1) as f64;
        Self::build(pose, 0.0, step, values, true)
    }

    /// A profile over a sector: bin i at `start_rad + i·step_rad` relative to the heading, zero
    /// outside (a camera's field of view, bins = image columns resampled to angles).
    pub fn sector(
        pose: SensorPose,
        start_rad: f64,
        step_rad: f64,
        values: Vec<f64>,
    ) -> Result<Self> {
        if step_rad * values.len() as f64 > TAU + 1e-9 {
            return Err(Error::InvalidParameter {
                name: "step_rad",
                reason: format!(
                    "{} bins of {step_rad} rad exceed a full circle",
                    values.len()
                ),
            });
        }
        Self::build(pose, start_rad, step_rad, values, false)
    }

    fn build(
        pose: SensorPose,
        start_rad: f64,
        step_rad: f64,
        values: Vec<f64>,
        wraps: bool,
    ) -> Result<Self> {
        if values.is_empty() {
            return Err(Error::Empty {
                what: "bearing profile",
            });
        }
        if !(pose.position.iter().all(|v| v.is_finite()) && pose.heading_rad.is_finite()) {
            return Err(Error::NonFinite {
                what: "sensor pose",
            });
        }
        if !start_rad.is_finite() {
            return Err(Error::NonFinite { what: "start_rad" });
        }
        ensure_positive(step_rad, "step_rad")?;
        if let Some((i, v)) = values
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(Error::InvalidParameter {
                name: "bearing profile",
                reason: format!("value {i} is {v}; values must be finite and >= 0"),
            });
        }
        Ok(Self {
            pose,
            start_rad,
            step_rad,
            values,
            wraps,
        })
    }

    /// The sensor's pose.
    pub fn pose(&self) -> &SensorPose {
        &self.pose
    }

    /// The bin values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Sensor-relative angle of bin `i`'s centre, radians.
    pub fn bin_angle_rad(&self, i: usize) -> f64 {
        self.start_rad + i as f64 * self.step_rad
    }

    /// The profile at world bearing `bearing_rad`: linear interpolation between the two
    /// nearest bins (circularly for a full-circle profile; a sector fades to 0 over the half
    /// bin beyond its ends).
    pub fn value_at(&self, bearing_rad: f64) -> f64 {
        let n = self.values.len();
        let rel = bearing_rad - self.pose.heading_rad - self.start_rad;
        if self.wraps {
            let x = rel.rem_euclid(TAU) / self.step_rad;
            let i = (x.floor() as usize) % n;
            let f = x - x.floor();
            (1.0 - f) * self.values[i] + f * self.values[(i + 1) % n]
        } else {
            // Angle measured from bin 0 in (−π, π], so a sector never sees a wrapped copy.
            let x = wrap_angle_rad(rel) / self.step_rad;
            let last = (n - 1) as f64;
            if x < -0.5 || x > last + 0.5 {
                0.0
            } else if x <= 0.0 {
                self.values[0]
            } else if x >= last {
                self.values[n - 1]
            } else {
                let i = x.floor() as usize;
                let f = x - x.floor();
                (1.0 - f) * self.values[i] + f * self.values[i + 1]
            }
        }
    }

    /// Projects the profile onto a grid over `region` with square cells of `cell_size`: each
    /// cell gets the profile at the bearing from the sensor to its centre, 0 outside the range
    /// limits, then the grid is scaled as configured. A grid with no evidence (all zero) is
    /// an error under `Sum` or `Max` normalisation.
    pub fn project(
        &self,
        region: Region2,
        cell_size: f64,
        config: &ProjectionConfig,
    ) -> Result<LikelihoodGrid> {
        config.check()?;
        let p = self.pose.position;
        let mut grid = LikelihoodGrid::from_fn(region, cell_size, |c: Vec2| {
            let d = c - p;
            let r = d.norm();
            if r < config.min_range_m || config.max_range_m.is_some_and(|m| r > m) {
                0.0
            } else {
                self.value_at(d.y.atan2(d.x))
            }
        })?;
        match config.normalisation {
            GridNormalisation::Sum => grid.normalise()?,
            GridNormalisation::Max => {
                let max = grid.values().iter().copied().fold(0.0, f64::max);
                if max <= 0.0 {
                    return Err(Error::InvalidParameter {
                        name: "likelihood grid",
                        reason: "the projected profile is zero everywhere".into(),
                    });
                }
                let (cols, rows) = grid.shape();
                for row in 0..rows {
                    for col in 0..cols {
                        let v = grid.value(col, row) / max;
                        grid.set(col, row, v)?;
                    }
                }
            }
            GridNormalisation::None => {}
        }
        Ok(grid)
    }
}
