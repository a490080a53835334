//! A rotating 2-D surveillance radar over trajectories. The beam turns once per `period_s`
//! and a revolution is `dwells` beam positions: dwell k points at bearing 2πk/dwells
//! (counter-clockwise from east) at time k·period/dwells and sees the sector of that width
//! around it. Every aircraft in the sector and in range is detected with probability
//! `p_detect`, its plot its true ground range and bearing at the dwell's time plus Gaussian
//! noise; clutter is Poisson, uniform in range and bearing over the sector.

use mcmcda::View;
use nalgebra::SVector;
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal, Poisson};
use serde::{Deserialize, Serialize};
use tracker_model::{
    Error as ModelError, RangeBearing, ensure_in_range, ensure_non_negative, ensure_positive,
    wrap_angle_rad,
};

use crate::error::Result;
use crate::trajectory::Trajectory;

/// The most dwells one simulation may produce.
pub const MAX_DWELLS: usize = 10_000_000;

/// The most dwells per revolution.
pub const MAX_DWELLS_PER_REVOLUTION: u32 = 3600;

/// A rotating radar's site, timing, accuracy, detection and clutter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotatingRadar {
    /// East, north, metres.
    pub position: [f64; 2],
    /// One revolution, seconds.
    pub period_s: f64,
    /// Beam positions per revolution.
    pub dwells: u32,
    /// Nearest range seen, metres.
    pub min_range_m: f64,
    /// Farthest range seen, metres.
    pub max_range_m: f64,
    /// Range noise σ, metres.
    pub sigma_range_m: f64,
    /// Bearing noise σ, radians.
    pub sigma_bearing_rad: f64,
    /// Probability of detecting an aircraft in the beam.
    pub p_detect: f64,
    /// Mean false alarms per revolution over the whole coverage.
    pub clutter_per_revolution: f64,
}

/// One beam position's plots.
#[derive(Debug, Clone, PartialEq)]
pub struct RadarDwell {
    /// When, seconds.
    pub time_s: f64,
    /// The beam's bearing, radians.
    pub beam_rad: f64,
    /// The plots: [range m, bearing rad].
    pub plots: Vec<SVector<f64, 2>>,
    /// For each plot, the index of the trajectory it came from, or `None` for clutter.
    pub origins: Vec<Option<usize>>,
}

impl RotatingRadar {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        if !self.position.iter().all(|v| v.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "radar position",
            }
            .into());
        }
        ensure_in_range(self.period_s, 0.1, 3600.0, "period_s")?;
        if self.dwells == 0 || self.dwells > MAX_DWELLS_PER_REVOLUTION {
            return Err(ModelError::InvalidParameter {
                name: "dwells",
                reason: format!("{} must be 1 to {MAX_DWELLS_PER_REVOLUTION}", self.dwells),
            }
            .into());
        }
        ensure_non_negative(self.min_range_m, "min_range_m")?;
        ensure_in_range(self.max_range_m, self.min_range_m + 1.0, 1e7, "max_range_m")?;
        ensure_positive(self.sigma_range_m, "sigma_range_m")?;
        ensure_positive(self.sigma_bearing_rad, "sigma_bearing_rad")?;
        ensure_in_range(self.p_detect, 0.0, 1.0, "p_detect")?;
        ensure_in_range(
            self.clutter_per_revolution,
            0.0,
            1e5,
            "clutter_per_revolution",
        )?;
        Ok(())
    }

    /// The sector width, radians.
    pub fn beam_width_rad(&self) -> f64 {
        std::f64::consts::TAU / f64::from(self.dwells)
    }

    /// The radar's measurement model on a state whose first two components are east, north.
    pub fn measurement_model<const N: usize>(&self) -> Result<RangeBearing<N>> {
        Ok(RangeBearing::at(
            self.position,
            self.sigma_range_m,
            self.sigma_bearing_rad,
        )?)
    }

    /// ln λ: the false alarms per metre of range per radian of bearing.
    pub fn clutter_log_density(&self) -> f64 {
        let volume = (self.max_range_m - self.min_range_m) * std::f64::consts::TAU;
        (self.clutter_per_revolution.max(1e-9) / volume).ln()
    }

    /// Whether [range, bearing] is in range and in the dwell's sector.
    pub fn in_view(&self, beam_rad: f64, z: &SVector<f64, 2>) -> bool {
        self.view(beam_rad, 0.0, z) == View::In
    }

    /// How a tracker sees [range, bearing] from the dwell at `beam_rad`: in, at the edge or
    /// out of the beam's sector widened by `margin_rad` each side, and out beyond the range.
    pub fn view(&self, beam_rad: f64, margin_rad: f64, z: &SVector<f64, 2>) -> View {
        if (self.min_range_m..=self.max_range_m).contains(&z[0]) {
            sector_view(z[1], beam_rad, self.beam_width_rad(), margin_rad)
        } else {
            View::Out
        }
    }

    /// Every dwell from `start_s` to `end_s` over `trajectories`.
    pub fn simulate<R: Rng + ?Sized>(
        &self,
        trajectories: &[Trajectory],
        start_s: f64,
        end_s: f64,
        rng: &mut R,
    ) -> Result<Vec<RadarDwell>> {
        self.check()?;
        let step = self.period_s / f64::from(self.dwells);
        let first = (start_s / step).ceil();
        let count = ((end_s / step).floor() - first + 1.0).max(0.0);
        if !count.is_finite() || count > MAX_DWELLS as f64 {
            return Err(ModelError::InvalidParameter {
                name: "end_s",
                reason: format!(
                    "{count} dwells from {start_s} s to {end_s} s; at most {MAX_DWELLS}"
                ),
            }
            .into());
        }
        let noise_r = Normal::new(0.0, self.sigma_range_m).map_err(invalid_noise)?;
        let noise_b = Normal::new(0.0, self.sigma_bearing_rad).map_err(invalid_noise)?;
        let clutter_mean = self.clutter_per_revolution / f64::from(self.dwells);
        let clutter = (clutter_mean > 0.0)
            .then(|| Poisson::new(clutter_mean))
            .transpose()
            .map_err(|e| invalid_noise(format!("{e:?}")))?;
        let mut dwells = Vec::with_capacity(count as usize);
        for k in 0..count as u64 {
            let index = first + k as f64;
            let time_s = index * step;
            let beam_rad = wrap_angle_rad(self.beam_width_rad() * (index % f64::from(self.dwells)));
            let mut dwell = RadarDwell {
                time_s,
                beam_rad,
                plots: Vec::new(),
                origins: Vec::new(),
            };
            for (i, trajectory) in trajectories.iter().enumerate() {
                let Some(state) = trajectory.at(time_s) else {
                    continue;
                };
                let (de, dn) = (
                    state.position[0] - self.position[0],
                    state.position[1] - self.position[1],
                );
                let z = SVector::<f64, 2>::new(de.hypot(dn), dn.atan2(de));
                if self.in_view(beam_rad, &z) && rng.random_bool(self.p_detect) {
                    dwell.plots.push(SVector::<f64, 2>::new(
                        z[0] + noise_r.sample(rng),
                        wrap_angle_rad(z[1] + noise_b.sample(rng)),
                    ));
                    dwell.origins.push(Some(i));
                }
            }
            let false_alarms = clutter.map_or(0, |p| p.sample(rng) as u64);
            for _ in 0..false_alarms {
                let r = rng.random_range(self.min_range_m..self.max_range_m);
                let offset = (rng.random::<f64>() - 0.5) * self.beam_width_rad();
                dwell
                    .plots
                    .push(SVector::<f64, 2>::new(r, wrap_angle_rad(beam_rad + offset)));
                dwell.origins.push(None);
            }
            dwells.push(dwell);
        }
        Ok(dwells)
    }
}

/// A bearing against the sector of `width` centred on `centre`: farther than `margin` outside,
/// out; within `margin` of its border, at the edge; else in (all radians).
pub(crate) fn sector_view(bearing: f64, centre: f64, width: f64, margin: f64) -> View {
    let off = wrap_angle_rad(bearing - centre).abs() - 0.5 * width;
    if off > margin {
        View::Out
    } else if off > -margin {
        View::Edge
    } else {
        View::In
    }
}

fn invalid_noise(e: impl std::fmt::Debug) -> crate::Error {
    ModelError::InvalidParameter {
        name: "radar noise",
        reason: format!("{e:?}"),
    }
    .into()
}
