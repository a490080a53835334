//! Synthetic traffic for machines without the real collection: aircraft that enter a square
//! region, fly straight legs joined by coordinated turns, and leave, sampled every second like
//! ADS-B. Everything random comes from the generator passed in.

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};
use tracker_model::{Error as ModelError, ensure_in_range, ensure_positive};

use crate::error::Result;
use crate::trajectory::{Sample, Trajectory};

/// The most aircraft a stand-in may have.
pub const MAX_STANDIN_AIRCRAFT: usize = 10_000;

/// The longest stand-in, seconds (a day).
pub const MAX_STANDIN_DURATION_S: f64 = 86_400.0;

/// The stand-in's traffic.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StandinConfig {
    /// Aircraft in all.
    pub aircraft: usize,
    /// Length, seconds; entries are spread uniformly over it.
    pub duration_s: f64,
    /// Half the side of the square region centred on the origin, metres.
    pub half_width_m: f64,
    /// Ground speeds are uniform between these, m/s.
    pub speed_m_s: [f64; 2],
    /// Straight legs last uniformly between these, seconds.
    pub leg_s: [f64; 2],
    /// Turn rates are uniform in magnitude between these, degrees per second, either way.
    pub turn_deg_s: [f64; 2],
    /// Heading changes per turn are uniform in magnitude between these, degrees.
    pub turn_change_deg: [f64; 2],
    /// Each aircraft flies uniformly between these, seconds, or until it leaves the region.
    pub life_s: [f64; 2],
}

fn ordered(pair: [f64; 2], lo: f64, hi: f64, name: &'static str) -> Result<()> {
    ensure_in_range(pair[0], lo, hi, name)?;
    ensure_in_range(pair[1], pair[0], hi, name)?;
    Ok(())
}

impl StandinConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        if self.aircraft == 0 || self.aircraft > MAX_STANDIN_AIRCRAFT {
            return Err(ModelError::InvalidParameter {
                name: "aircraft",
                reason: format!("{} must be 1 to {MAX_STANDIN_AIRCRAFT}", self.aircraft),
            }
            .into());
        }
        ensure_in_range(self.duration_s, 60.0, MAX_STANDIN_DURATION_S, "duration_s")?;
        ensure_positive(self.half_width_m, "half_width_m")?;
        ordered(self.speed_m_s, 1.0, 1000.0, "speed_m_s")?;
        ordered(self.leg_s, 1.0, MAX_STANDIN_DURATION_S, "leg_s")?;
        ordered(self.turn_deg_s, 0.01, 20.0, "turn_deg_s")?;
        ordered(self.turn_change_deg, 1.0, 360.0, "turn_change_deg")?;
        ordered(self.life_s, 60.0, MAX_STANDIN_DURATION_S, "life_s")?;
        Ok(())
    }

    /// The trajectories, labelled `standin-001` … in order of entry.
    pub fn generate<R: Rng + ?Sized>(&self, rng: &mut R) -> Result<Vec<Trajectory>> {
        self.check()?;
        let mut entries: Vec<f64> = (0..self.aircraft)
            .map(|_| rng.random_range(0.0..self.duration_s))
            .collect();
        entries.sort_by(f64::total_cmp);
        let mut out = Vec::with_capacity(self.aircraft);
        for (k, start) in entries.into_iter().enumerate() {
            let samples = self.fly(start, rng);
            if samples.len() >= 2 {
                out.push(Trajectory::new(format!("standin-{:03}", k + 1), samples)?);
            }
        }
        Ok(out)
    }

    fn uniform<R: Rng + ?Sized>(pair: [f64; 2], rng: &mut R) -> f64 {
        if pair[1] > pair[0] {
            rng.random_range(pair[0]..pair[1])
        } else {
            pair[0]
        }
    }

    /// One aircraft from its entry on the region's edge, heading inwards within ±45°, until
    /// its life ends, it leaves, or the stand-in ends.
    fn fly<R: Rng + ?Sized>(&self, start_s: f64, rng: &mut R) -> Vec<Sample> {
        let w = self.half_width_m;
        let side = rng.random_range(0..4u8);
        let along = rng.random_range(-w..w);
        let (mut position, inward) = match side {
            0 => ([-w, along], 0.0),
            1 => ([w, along], std::f64::consts::PI),
            2 => ([along, -w], std::f64::consts::FRAC_PI_2),
            _ => ([along, w], -std::f64::consts::FRAC_PI_2),
        };
        let mut heading = inward + rng.random_range(-0.25..0.25) * std::f64::consts::PI;
        let speed = Self::uniform(self.speed_m_s, rng);
        let end_s = (start_s + Self::uniform(self.life_s, rng)).min(self.duration_s);
        let mut samples = Vec::new();
        let mut t = start_s.ceil();
        let (mut turn_rate, mut phase_end) = (0.0, t + Self::uniform(self.leg_s, rng));
        while t <= end_s && position.iter().all(|c| c.abs() <= w * 1.0001) {
            let velocity = [speed * heading.cos(), speed * heading.sin()];
            samples.push(Sample {
                time_s: t,
                position,
                velocity,
            });
            if t >= phase_end {
                if turn_rate == 0.0 {
                    let rate = Self::uniform(self.turn_deg_s, rng).to_radians();
                    let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                    let change = Self::uniform(self.turn_change_deg, rng).to_radians();
                    turn_rate = sign * rate;
                    phase_end = t + change / rate;
                } else {
                    turn_rate = 0.0;
                    phase_end = t + Self::uniform(self.leg_s, rng);
                }
            }
            position = advance(position, heading, speed, turn_rate);
            heading += turn_rate;
            t += 1.0;
        }
        samples
    }
}

/// One second of a coordinated turn (a straight line when the rate is zero).
fn advance(p: [f64; 2], heading: f64, speed: f64, rate: f64) -> [f64; 2] {
    if rate == 0.0 {
        [p[0] + speed * heading.cos(), p[1] + speed * heading.sin()]
    } else {
        let r = speed / rate;
        [
            p[0] + r * ((heading + rate).sin() - heading.sin()),
            p[1] - r * ((heading + rate).cos() - heading.cos()),
        ]
    }
}
