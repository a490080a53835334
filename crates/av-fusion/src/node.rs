//! Sensor nodes as the fusion node knows them (kind, pose, profile layout, clock offset,
//! weight) and the reports they send.
//!
//! A node sends only its profile values and the time stamp of its own clock; the fusion node
//! holds the pose (from calibration, possibly wrong) and the profile layout, and turns the
//! values into a [`BearingProfile`] when it projects them. So a calibration error is a wrong
//! pose here, not a change in what the sensor measures.

use sensors_audio::{Beamform, EnergyScaling};
use sensors_video::AngleProfiler;
use serde::{Deserialize, Serialize};
use tracker_model::{BearingProfile, SensorPose, ensure_non_negative};

use crate::error::{Error, Result, invalid};

/// What a node senses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SensorKind {
    /// A microphone array reporting beam energies over the full circle.
    Audio,
    /// A camera reporting foreground pixels per angle over its field of view.
    Video,
}

/// How a report's values lie over angle (sensor-relative, radians counter-clockwise from the
/// node's heading).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ProfileShape {
    /// `n_bins` equal bins over the full circle, bin 0 at the heading (audio beams).
    FullCircle {
        /// Number of beams.
        n_bins: usize,
    },
    /// Bin i at `start_rad + i·step_rad`, zero outside (a camera's field of view).
    Sector {
        /// Angle of bin 0's centre.
        start_rad: f64,
        /// Angle between bins.
        step_rad: f64,
        /// Number of bins.
        n_bins: usize,
    },
}

impl ProfileShape {
    /// Number of bins a report must carry.
    pub fn n_bins(&self) -> usize {
        match *self {
            Self::FullCircle { n_bins } | Self::Sector { n_bins, .. } => n_bins,
        }
    }
}

/// A sensor node as registered at the fusion node.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorNode {
    /// A name for reports and errors.
    pub name: String,
    /// Audio or video.
    pub kind: SensorKind,
    /// The pose the fusion node believes (calibrated; may differ from the truth).
    pub pose: SensorPose,
    /// Layout of the node's profile.
    pub shape: ProfileShape,
    /// Offset of the node's clock: its time stamps read fusion time + `clock_offset_s`, so
    /// the fusion node subtracts it (0 for a synchronised node).
    pub clock_offset_s: f64,
    /// Fusion weight w_s ≥ 0 (a multiplier in the weighted sum, an exponent in the product).
    pub weight: f64,
    /// Profile exponent γ_s > 0: the fusion node uses D_s(θ)^{γ_s} in place of the reported
    /// profile D_s(θ) (1 = as reported). γ > 1 sharpens a profile whose lobe is broader than
    /// the sensor's bearing error (a small microphone array's beams), γ < 1 tempers one that
    /// is narrower than its error; in the weighted sum this is the only way to change a lobe's
    /// width, in the product it acts before the floor (unlike w_s, which acts after it).
    #[serde(default = "unit_exponent")]
    pub exponent: f64,
    /// Lobe equalisation, applied before the exponent (`None`: the profile as reported).
    /// See [`LobeEqualisation`].
    #[serde(default)]
    pub lobes: Option<LobeEqualisation>,
}

/// Lifts a profile's weaker lobes towards its strongest, so that a second target's lobe
/// survives sharpening and fusion.
///
/// Every bin belongs to the lobe of the local maximum it climbs to (steepest ascent over its
/// neighbours, around the circle for a full-circle profile). With P the profile's maximum and
/// p_ℓ the peak of bin b's lobe, the value becomes
/// D'(b) = D(b) · (P / max(p_ℓ, η P))^β:
/// a lobe at least η P high is scaled by (P / p_ℓ)^β (β = 1: every such lobe reaches P, so a
/// quieter vehicle's beam is as tall as the louder one's; β = 0: unchanged), while the lobes
/// below η P, mostly noise, gain at most the factor η^{−β}. A profile raised to γ > 1 keeps
/// only its strongest lobe (a second at a half the height is at 0.5⁸ ≈ 0.004 under γ = 8); after
/// equalisation every lobe keeps its own width and is sharpened around its own peak.
/// A single lobe is unchanged (p_ℓ = P).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LobeEqualisation {
    /// η ∈ (0, 1]: lobes below η × the maximum are not lifted to it.
    pub min_fraction: f64,
    /// β ∈ [0, 1]: how far a lobe is lifted (1: to the maximum).
    pub power: f64,
}

impl LobeEqualisation {
    /// Checks η ∈ (0, 1] and β ∈ [0, 1].
    pub fn check(&self) -> Result<()> {
        if !(self.min_fraction > 0.0 && self.min_fraction <= 1.0) {
            return Err(invalid(
                "min_fraction",
                format!("{} is outside (0, 1]", self.min_fraction),
            ));
        }
        if !(self.power.is_finite() && (0.0..=1.0).contains(&self.power)) {
            return Err(invalid(
                "power",
                format!("{} is outside [0, 1]", self.power),
            ));
        }
        Ok(())
    }

    /// Equalises `values` in place (`circular`: the first and last bins are neighbours).
    /// Values must be finite and ≥ 0 (reports are checked on arrival).
    pub fn apply(&self, values: &mut [f64], circular: bool) {
        let n = values.len();
        let top = values.iter().copied().fold(0.0, f64::max);
        if n < 2 || top <= 0.0 {
            return;
        }
        // The uphill neighbour of each bin (itself at a local maximum or plateau).
        let neighbours = |b: usize| -> [Option<usize>; 2] {
            let left = if b > 0 {
                Some(b - 1)
            } else {
                circular.then_some(n - 1)
            };
            let right = if b + 1 < n {
                Some(b + 1)
            } else {
                circular.then_some(0)
            };
            [left, right]
        };
        let up: Vec<usize> = (0..n)
            .map(|b| {
                let mut best = b;
                for c in neighbours(b).into_iter().flatten() {
                    if values[c] > values[best] {
                        best = c;
                    }
                }
                best
            })
            .collect();
        let floor = self.min_fraction * top;
        let scaled: Vec<f64> = (0..n)
            .map(|b| {
                // Climb to the lobe's peak: each step is strictly uphill, so at most n steps.
                let mut m = b;
                while up[m] != m {
                    m = up[m];
                }
                values[b] * (top / values[m].max(floor)).powf(self.power)
            })
            .collect();
        values.copy_from_slice(&scaled);
    }
}

fn unit_exponent() -> f64 {
    1.0
}

impl SensorNode {
    /// An audio node with `n_beams` beams (bin 0 at the heading), synchronised, weight 1.
    pub fn audio(name: impl Into<String>, pose: SensorPose, n_beams: usize) -> Self {
        Self {
            name: name.into(),
            kind: SensorKind::Audio,
            pose,
            shape: ProfileShape::FullCircle { n_bins: n_beams },
            clock_offset_s: 0.0,
            weight: 1.0,
            exponent: 1.0,
            lobes: None,
        }
    }

    /// A video node whose profile layout is `profiler`'s and whose believed pose is `pose`
    /// (the camera's own pose when it is calibrated exactly), synchronised, weight 1.
    pub fn video(
        name: impl Into<String>,
        pose: SensorPose,
        profiler: &AngleProfiler,
        n_angles: usize,
    ) -> Self {
        let start_rad = profiler.bin_angle_rad(0);
        Self {
            name: name.into(),
            kind: SensorKind::Video,
            pose,
            shape: ProfileShape::Sector {
                start_rad,
                step_rad: profiler.bin_angle_rad(1) - start_rad,
                n_bins: n_angles,
            },
            clock_offset_s: 0.0,
            weight: 1.0,
            exponent: 1.0,
            lobes: None,
        }
    }

    /// Checks the numbers: finite pose and offset, weight ≥ 0, at least one bin, a sector
    /// with a positive step.
    pub fn check(&self) -> Result<()> {
        if !(self.pose.position.iter().all(|v| v.is_finite()) && self.pose.heading_rad.is_finite())
        {
            return Err(tracker_model::Error::NonFinite {
                what: "sensor pose",
            }
            .into());
        }
        if !self.clock_offset_s.is_finite() {
            return Err(tracker_model::Error::NonFinite {
                what: "clock_offset_s",
            }
            .into());
        }
        ensure_non_negative(self.weight, "weight")?;
        tracker_model::ensure_positive(self.exponent, "exponent")?;
        if let Some(l) = &self.lobes {
            l.check()?;
        }
        if self.shape.n_bins() == 0 {
            return Err(invalid(
                "n_bins",
                format!("sensor {:?} has a profile of 0 bins", self.name),
            ));
        }
        if let ProfileShape::Sector {
            start_rad,
            step_rad,
            ..
        } = self.shape
        {
            tracker_model::ensure_positive(step_rad, "step_rad")?;
            if !start_rad.is_finite() {
                return Err(tracker_model::Error::NonFinite { what: "start_rad" }.into());
            }
        }
        Ok(())
    }

    /// The report's values, lobe-equalised if the node says so and raised to the node's
    /// exponent γ_s, as a bearing profile at this
    /// node's believed pose.
    pub fn profile(&self, mut values: Vec<f64>) -> Result<BearingProfile> {
        if let Some(l) = &self.lobes {
            l.apply(
                &mut values,
                matches!(self.shape, ProfileShape::FullCircle { .. }),
            );
        }
        // Values are ≥ 0 (checked on arrival); the max-1 or sum-1 scaling of the fusion
        // removes the factor c^γ a rescaled report would bring. γ = 1 exactly skips the powf,
        // so such nodes give the same bytes as before γ existed.
        if self.exponent.to_bits() != 1.0f64.to_bits() {
            values.iter_mut().for_each(|v| *v = v.powf(self.exponent));
        }
        Ok(match self.shape {
            ProfileShape::FullCircle { .. } => BearingProfile::full_circle(self.pose, values)?,
            ProfileShape::Sector {
                start_rad,
                step_rad,
                ..
            } => BearingProfile::sector(self.pose, start_rad, step_rad, values)?,
        })
    }

    /// Fusion time of a time stamp of this node's clock.
    pub fn fusion_time_s(&self, local_time_s: f64) -> f64 {
        local_time_s - self.clock_offset_s
    }
}

/// One measurement from a node: its profile values at a time stamp of its own clock.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Index of the node in the fusion node's list.
    pub sensor: usize,
    /// Time stamp on the node's clock, seconds.
    pub local_time_s: f64,
    /// The profile values (beam energies, pixel counts), one per bin.
    pub values: Vec<f64>,
}

impl Report {
    /// A report from a beamform: its time stamp (which the caller puts on the node's clock)
    /// and its energies scaled as `scaling` says (minimum-subtracted is the usual choice: a
    /// small array's floor carries no direction).
    pub fn from_beamform(sensor: usize, beamform: &Beamform, scaling: EnergyScaling) -> Self {
        let min = beamform
            .energies
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let values = match scaling {
            EnergyScaling::Raw => beamform.energies.clone(),
            EnergyScaling::MinSubtracted => beamform.energies.iter().map(|e| e - min).collect(),
        };
        Self {
            sensor,
            local_time_s: beamform.time_s,
            values,
        }
    }

    /// Checks the time stamp and values (finite, values ≥ 0).
    pub(crate) fn check(&self) -> Result<()> {
        if !self.local_time_s.is_finite() {
            return Err(Error::BadReport {
                sensor: self.sensor,
                index: usize::MAX,
                value: self.local_time_s,
            });
        }
        if let Some((index, &value)) = self
            .values
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(Error::BadReport {
                sensor: self.sensor,
                index,
                value,
            });
        }
        Ok(())
    }
}
