//! An aircraft's horizontal trajectory: time-stamped positions (and velocities where the
//! source gives them) in a local east-north frame, interpolated linearly between samples.

use crate::error::{Error, Result};

/// One sample of a trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Seconds from the collection's start.
    pub time_s: f64,
    /// East, north, metres.
    pub position: [f64; 2],
    /// East, north velocity, m/s.
    pub velocity: [f64; 2],
}

/// Where an aircraft is at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kinematics {
    /// East, north, metres.
    pub position: [f64; 2],
    /// East, north velocity, m/s.
    pub velocity: [f64; 2],
}

/// A gap-free trajectory of one aircraft (a collection's longer gaps split an aircraft into
/// several trajectories with the same label).
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    label: String,
    samples: Vec<Sample>,
}

impl Trajectory {
    /// A trajectory of at least two samples, strictly increasing in time, all finite.
    pub fn new(label: String, samples: Vec<Sample>) -> Result<Self> {
        if samples.len() < 2 {
            return Err(Error::Collection(format!(
                "trajectory {label} has {} samples; at least two are needed",
                samples.len()
            )));
        }
        let finite = samples.iter().all(|s| {
            s.time_s.is_finite() && s.position.iter().chain(&s.velocity).all(|v| v.is_finite())
        });
        if !finite || samples.windows(2).any(|w| w[1].time_s <= w[0].time_s) {
            return Err(Error::Collection(format!(
                "trajectory {label}: samples must be finite and strictly increasing in time"
            )));
        }
        Ok(Self { label, samples })
    }

    /// The aircraft's label (its ICAO 24-bit address for ADS-B).
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The samples.
    pub fn samples(&self) -> &[Sample] {
        &self.samples
    }

    /// First and last sample times.
    pub fn span(&self) -> (f64, f64) {
        (
            self.samples[0].time_s,
            self.samples[self.samples.len() - 1].time_s,
        )
    }

    /// Position and velocity at `time_s`, linear between samples; `None` outside the span.
    pub fn at(&self, time_s: f64) -> Option<Kinematics> {
        let (first, last) = self.span();
        if !(first..=last).contains(&time_s) {
            return None;
        }
        let i = self
            .samples
            .partition_point(|s| s.time_s <= time_s)
            .clamp(1, self.samples.len() - 1);
        let (a, b) = (&self.samples[i - 1], &self.samples[i]);
        let w = (time_s - a.time_s) / (b.time_s - a.time_s);
        let lerp = |p: [f64; 2], q: [f64; 2]| [p[0] + w * (q[0] - p[0]), p[1] + w * (q[1] - p[1])];
        Some(Kinematics {
            position: lerp(a.position, b.position),
            velocity: lerp(a.velocity, b.velocity),
        })
    }

    /// The turn rate at `time_s`, rad/s (counter-clockwise positive): the change of the
    /// velocity's direction from `time_s − half_window_s` to `time_s + half_window_s`;
    /// `None` near the ends or when the aircraft is nearly still.
    pub fn turn_rate_at(&self, time_s: f64, half_window_s: f64) -> Option<f64> {
        let before = self.at(time_s - half_window_s)?;
        let after = self.at(time_s + half_window_s)?;
        let heading = |v: [f64; 2]| (v[0].hypot(v[1]) > 1.0).then(|| v[1].atan2(v[0]));
        let change =
            tracker_model::wrap_angle_rad(heading(after.velocity)? - heading(before.velocity)?);
        Some(change / (2.0 * half_window_s))
    }
}
