//! The simulated world: true trajectories (used only to generate what sensors observe, and
//! to score) and what each sensor observes in each frame.

use identity_mgmt::IdentityId;
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal, Poisson};
use serde::{Deserialize, Serialize};
use tracker_model::Vec2;

use crate::config::DmtimConfig;
use crate::error::{Result, invalid};

/// One true target: its identity and its position in each frame from `first_frame` on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthTarget {
    /// The identity it carries (e.g. a call sign).
    pub identity: IdentityId,
    /// The frame of `positions[0]`.
    pub first_frame: u64,
    /// One position per frame.
    pub positions: Vec<Vec2>,
}

impl TruthTarget {
    /// The position at `frame`, if the target exists then.
    pub fn at(&self, frame: u64) -> Option<Vec2> {
        let k = frame.checked_sub(self.first_frame)?;
        self.positions.get(usize::try_from(k).ok()?).copied()
    }

    /// A target flying straight between waypoints at a constant speed per frame, from
    /// `first_frame` until it reaches the last waypoint.
    pub fn along(
        identity: IdentityId,
        first_frame: u64,
        waypoints: &[Vec2],
        speed: f64,
    ) -> Result<Self> {
        if waypoints.len() < 2 || !(speed > 0.0 && speed.is_finite()) {
            return Err(invalid(
                "waypoints",
                format!(
                    "{} waypoints at speed {speed}: need ≥ 2 and a positive speed",
                    waypoints.len()
                ),
            ));
        }
        let mut positions = vec![waypoints[0]];
        let mut here = waypoints[0];
        let mut next = 1;
        while next < waypoints.len() {
            let mut step = speed;
            while next < waypoints.len() {
                let to = waypoints[next] - here;
                let d = to.norm();
                if d > step {
                    here += to * (step / d);
                    break;
                }
                here = waypoints[next];
                step -= d;
                next += 1;
            }
            positions.push(here);
        }
        Ok(Self {
            identity,
            first_frame,
            positions,
        })
    }
}

/// A transponder read or visual identification: where and which identity it names.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Read {
    /// The measured position of the target read.
    pub position: Vec2,
    /// The identity read (possibly wrong).
    pub identity: IdentityId,
    /// The measurement (index into the scan's points) the read came with: a transponder
    /// reply arrives with the radar plot of the target that sent it.
    pub point: usize,
    /// Whether it is right (for the event log only; the sensor does not see this).
    pub correct: bool,
}

/// What one sensor observes in one frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SensorScan {
    /// Position measurements (targets and clutter, shuffled by nothing: the tracker does not
    /// use the order).
    pub points: Vec<Vec2>,
    /// The true target behind each point (`None`: clutter). For scoring only; trackers and
    /// the identity layer do not read it.
    pub origins: Vec<Option<usize>>,
    /// Identity reads.
    pub reads: Vec<Read>,
}

/// Every sensor's scans: `scans[sensor][frame]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Observations {
    /// Frames 0..n_frames.
    pub n_frames: u64,
    /// Per sensor, per frame.
    pub scans: Vec<Vec<SensorScan>>,
}

impl Observations {
    /// Total number of measurements over all sensors and frames.
    pub fn n_measurements(&self) -> usize {
        self.scans.iter().flatten().map(|s| s.points.len()).sum()
    }
}

/// Simulates every sensor: each target inside a range is detected with p_d and measured
/// with Gaussian noise; Poisson clutter uniform over the disc; identity reads at the
/// sensors named in `config.local_info`. Sensors draw independently (their own noise).
pub fn observe(
    truth: &[TruthTarget],
    config: &DmtimConfig,
    n_frames: u64,
    rng: &mut impl Rng,
) -> Result<Observations> {
    config.check()?;
    let noise = Normal::new(0.0, config.sensing.noise_std_m)
        .map_err(|e| invalid("sensing.noise_std_m", e.to_string()))?;
    let clutter = if config.sensing.clutter_per_scan > 0.0 {
        Some(
            Poisson::new(config.sensing.clutter_per_scan)
                .map_err(|e| invalid("sensing.clutter_per_scan", e.to_string()))?,
        )
    } else {
        None
    };
    let li = &config.local_info;
    let mut scans = vec![Vec::new(); config.sensors.len()];
    for frame in 0..n_frames {
        for (s, sensor) in config.sensors.iter().enumerate() {
            let mut scan = SensorScan::default();
            let reads_here =
                li.sensors.contains(&s) && li.frames.is_none_or(|[a, b]| (a..b).contains(&frame));
            for (k, target) in truth.iter().enumerate() {
                let Some(p) = target.at(frame) else { continue };
                if !sensor.covers(p) {
                    continue;
                }
                let measured = p + Vec2::new(noise.sample(rng), noise.sample(rng));
                if rng.random::<f64>() >= config.sensing.p_detect {
                    continue;
                }
                scan.points.push(measured);
                scan.origins.push(Some(k));
                if reads_here && rng.random::<f64>() < li.probability {
                    let wrong = truth.len() > 1 && rng.random::<f64>() < li.error_rate;
                    let identity = if wrong {
                        let mut other = rng.random_range(0..truth.len() - 1);
                        if other >= k {
                            other += 1;
                        }
                        truth[other].identity
                    } else {
                        target.identity
                    };
                    scan.reads.push(Read {
                        position: measured,
                        identity,
                        point: scan.points.len() - 1,
                        correct: !wrong,
                    });
                }
            }
            if let Some(c) = &clutter {
                let n = c.sample(rng) as usize;
                for _ in 0..n {
                    let r = sensor.range_m * rng.random::<f64>().sqrt();
                    let a = std::f64::consts::TAU * rng.random::<f64>();
                    scan.points
                        .push(sensor.centre() + Vec2::new(r * a.cos(), r * a.sin()));
                    scan.origins.push(None);
                }
            }
            scans[s].push(scan);
        }
    }
    Ok(Observations { n_frames, scans })
}

/// The centralised view: one scan per frame with each target measured once (by the first
/// sensor that detected it, standing in for a central tracker's de-duplication of
/// overlapping radars, done here by origin) and every sensor's clutter. Built from the same
/// draws as the distributed run, so both see the same noise. Reads keep their sensors'
/// reads, attached to the kept points.
pub fn centralised(observations: &Observations, n_targets: usize) -> Observations {
    let mut out = Vec::new();
    for frame in 0..observations.n_frames {
        let f = frame as usize;
        let mut seen = vec![false; n_targets];
        let mut scan = SensorScan::default();
        for sensor_scans in &observations.scans {
            let s = &sensor_scans[f];
            let mut index = vec![None; s.points.len()];
            for (k, (&p, &o)) in s.points.iter().zip(&s.origins).enumerate() {
                if let Some(t) = o {
                    if seen.get(t).copied().unwrap_or(true) {
                        continue;
                    }
                    seen[t] = true;
                }
                index[k] = Some(scan.points.len());
                scan.points.push(p);
                scan.origins.push(o);
            }
            for r in &s.reads {
                if let Some(point) = index.get(r.point).copied().flatten() {
                    scan.reads.push(Read { point, ..r.clone() });
                }
            }
        }
        out.push(scan);
    }
    Observations {
        n_frames: observations.n_frames,
        scans: vec![out],
    }
}

/// The seven-radar scene of the scenario and the benchmark, after the paper's ATC example
/// (seven radars ATC1–ATC7, five aircraft T1–T5; the layout itself is ours, the paper's
/// figure is not recoverable): six radars on a hexagon of radius 30 around ATC7 at the
/// centre of a 100 × 100 region, each with range 20, so neighbours overlap; T1 and T2 cross
/// at a shallow angle near the centre, T3 crosses both, T4 and T5 appear mid-run (frames 30
/// and 40). Speeds are 1 per frame; 100 frames. Returns the sensors and the truth; the
/// caller sets the rest of the configuration.
pub fn seven_radars() -> Result<(Vec<crate::config::SensorSpec>, Vec<TruthTarget>)> {
    let mut sensors = Vec::new();
    for k in 0..6 {
        let a = std::f64::consts::FRAC_PI_3 * f64::from(k);
        sensors.push(crate::config::SensorSpec {
            name: format!("ATC{}", k + 1),
            centre: [50.0 + 30.0 * a.cos(), 50.0 + 30.0 * a.sin()],
            range_m: 20.0,
        });
    }
    sensors.push(crate::config::SensorSpec {
        name: "ATC7".into(),
        centre: [50.0, 50.0],
        range_m: 20.0,
    });
    let v = |x: f64, y: f64| Vec2::new(x, y);
    let truth = vec![
        TruthTarget::along(IdentityId(1), 0, &[v(5.0, 44.0), v(95.0, 56.0)], 1.0)?,
        TruthTarget::along(IdentityId(2), 0, &[v(5.0, 56.0), v(95.0, 44.0)], 1.0)?,
        TruthTarget::along(IdentityId(3), 8, &[v(48.0, 5.0), v(52.0, 95.0)], 1.0)?,
        TruthTarget::along(IdentityId(4), 30, &[v(25.0, 80.0), v(80.0, 25.0)], 1.0)?,
        TruthTarget::along(IdentityId(5), 40, &[v(78.0, 75.0), v(30.0, 35.0)], 1.0)?,
    ];
    Ok((sensors, truth))
}
