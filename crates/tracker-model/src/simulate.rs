//! The multi-target scenario simulator of the MCMCDA model (Oh, Russell & Sastry, TAC 2009,
//! §II): Poisson births uniform in the region, survival 1 − p_z per scan, detection with p_d,
//! Poisson clutter uniform in the region, constant-velocity motion.

use nalgebra::{Cholesky, Matrix2, SMatrix, Vector2, Vector4};
use rand::seq::SliceRandom;
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Poisson, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, ensure_in_range};
use crate::gaussian::{check_finite_matrix, cholesky_checked};
use crate::geometry::Region2;
use crate::models::{ConstantVelocity2, CvState, TransitionModel};
use crate::track::{Frame, Measurement, Origin, Scan, Track, TrackId, TrackPoint, TrackSet};

/// Everything that defines a simulated multi-target scenario. Defaults are the TAC 2009 batch
/// experiment with 10 targets over 10 scans.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimulationConfig {
    /// The surveillance region R; births and clutter are uniform in it.
    pub region: Region2,
    /// Number of scans T.
    pub n_scans: u32,
    /// Expected births per scan, λ_b·V.
    pub births_per_scan: f64,
    /// Probability p_z that a target disappears between two scans.
    pub p_disappear: f64,
    /// Detection probability p_d.
    pub p_detect: f64,
    /// Expected false alarms per scan, λ_f·V.
    pub clutter_per_scan: f64,
    /// Target motion (its sampling period is the scan period).
    pub motion: ConstantVelocity2,
    /// Position-measurement noise covariance R (rows in files, see [`crate::matrix_rows`]).
    #[serde(with = "crate::matrix_rows")]
    pub measurement_noise: Matrix2<f64>,
    /// A newborn's speed is uniform in [0, initial_speed_max] with a uniform heading.
    pub initial_speed_max: f64,
    /// If set, a target's speed is clipped to this bound after every step.
    pub max_speed: Option<f64>,
}

impl Default for SimulationConfig {
    fn default() -> Self {
        Self {
            region: Region2::new(Vector2::zeros(), Vector2::new(1000.0, 1000.0))
                .unwrap_or_else(|_| unreachable!("constant region is valid")),
            n_scans: 10,
            births_per_scan: 1.0,
            p_disappear: 1e-4,
            p_detect: 0.9,
            clutter_per_scan: 1.0,
            motion: ConstantVelocity2::mcmcda(1.0, 100.0)
                .unwrap_or_else(|_| unreachable!("constant model is valid")),
            measurement_noise: Matrix2::identity() * 100.0,
            initial_speed_max: 50.0,
            max_speed: Some(100.0),
        }
    }
}

/// A validated [`SimulationConfig`], ready to draw scenarios.
#[derive(Debug, Clone)]
pub struct Simulator {
    config: SimulationConfig,
    births: Option<Poisson<f64>>,
    clutter: Option<Poisson<f64>>,
    process_factor: SMatrix<f64, 4, 4>,
    measurement_factor: Matrix2<f64>,
}

/// A simulated scenario: the hidden truth and what the sensor reported.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Simulation {
    /// True trajectories (positions and velocities at every frame the target exists).
    pub truth: TrackSet,
    /// One scan per frame 0..n_scans, measurements shuffled, origins recorded.
    pub scans: Vec<Scan>,
}

impl SimulationConfig {
    /// Checks every field once and precomputes the noise factors.
    pub fn check(&self) -> Result<Simulator> {
        if self.n_scans == 0 {
            return Err(Error::InvalidParameter {
                name: "n_scans",
                reason: "must be at least 1".into(),
            });
        }
        let rate = |v: f64, name: &'static str| -> Result<Option<Poisson<f64>>> {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::InvalidParameter {
                    name,
                    reason: format!("{v} must be finite and >= 0"),
                });
            }
            if v == 0.0 {
                return Ok(None);
            }
            Poisson::new(v)
                .map(Some)
                .map_err(|e| Error::InvalidParameter {
                    name,
                    reason: e.to_string(),
                })
        };
        let births = rate(self.births_per_scan, "births_per_scan")?;
        let clutter = rate(self.clutter_per_scan, "clutter_per_scan")?;
        ensure_in_range(self.p_disappear, 0.0, 1.0, "p_disappear")?;
        ensure_in_range(self.p_detect, 0.0, 1.0, "p_detect")?;
        if !(self.initial_speed_max.is_finite() && self.initial_speed_max >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "initial_speed_max",
                reason: format!("{} must be finite and >= 0", self.initial_speed_max),
            });
        }
        if let Some(v) = self.max_speed
            && !(v.is_finite() && v > 0.0)
        {
            return Err(Error::InvalidParameter {
                name: "max_speed",
                reason: format!("{v} must be finite and > 0"),
            });
        }
        let measurement_factor =
            cholesky_checked(&self.measurement_noise, "measurement_noise")?.l();
        Ok(Simulator {
            births,
            clutter,
            process_factor: psd_factor(&self.motion.process_noise(1))?,
            measurement_factor,
            config: self.clone(),
        })
    }
}

/// A factor L with L Lᵀ = Q for a positive semi-definite Q (Q may be singular, as G Σ Gᵀ is),
/// from the symmetric eigen-decomposition.
fn psd_factor(q: &SMatrix<f64, 4, 4>) -> Result<SMatrix<f64, 4, 4>> {
    check_finite_matrix(q, "process noise")?;
    if let Some(ch) = Cholesky::new(*q) {
        return Ok(ch.l());
    }
    let eig = q.symmetric_eigen();
    let sqrt = eig.eigenvalues.map(|l| l.max(0.0).sqrt());
    Ok(eig.eigenvectors * SMatrix::<f64, 4, 4>::from_diagonal(&sqrt))
}

fn standard_normal<const N: usize, R: Rng + ?Sized>(rng: &mut R) -> SMatrix<f64, N, 1> {
    SMatrix::from_fn(|_, _| StandardNormal.sample(rng))
}

/// A target alive during simulation.
struct Alive {
    id: TrackId,
    state: CvState,
    track: Track,
}

impl Simulator {
    /// The checked configuration.
    pub fn config(&self) -> &SimulationConfig {
        &self.config
    }

    /// Draws one scenario. Every draw comes from `rng`, so a seeded generator reproduces the
    /// scenario exactly.
    pub fn simulate<R: Rng + ?Sized>(&self, rng: &mut R) -> Result<Simulation> {
        let cfg = &self.config;
        let f = cfg.motion.transition_matrix(1);
        let mut alive: Vec<Alive> = Vec::new();
        let mut finished: Vec<Track> = Vec::new();
        let mut scans = Vec::with_capacity(cfg.n_scans as usize);
        let mut next_id = 0u64;
        for frame in 0..cfg.n_scans {
            if frame > 0 {
                // Disappearance first, then motion of the survivors.
                let mut survivors = Vec::with_capacity(alive.len());
                for mut target in alive.drain(..) {
                    if rng.random_bool(cfg.p_disappear) {
                        finished.push(target.track);
                        continue;
                    }
                    target.state = f * target.state + self.process_factor * standard_normal(rng);
                    self.clip_speed(&mut target.state);
                    survivors.push(target);
                }
                alive = survivors;
            }
            let n_births = self.births.map_or(0, |p| p.sample(rng) as u64);
            for _ in 0..n_births {
                let position = cfg.region.sample_uniform(rng);
                let speed = cfg.initial_speed_max * rng.random::<f64>();
                let heading = std::f64::consts::TAU * rng.random::<f64>();
                let mut state = Vector4::new(
                    position.x,
                    position.y,
                    speed * heading.cos(),
                    speed * heading.sin(),
                );
                self.clip_speed(&mut state);
                let id = TrackId(next_id);
                next_id += 1;
                alive.push(Alive {
                    id,
                    state,
                    track: Track::new(id),
                });
            }
            let mut measurements = Vec::new();
            for target in &mut alive {
                target.track.push(TrackPoint {
                    velocity: Some(Vector2::new(target.state[2], target.state[3])),
                    ..TrackPoint::at(frame, Vector2::new(target.state[0], target.state[1]))
                })?;
                if rng.random_bool(cfg.p_detect) {
                    let noise = self.measurement_factor * standard_normal::<2, R>(rng);
                    measurements.push(Measurement {
                        value: Vector2::new(target.state[0], target.state[1]) + noise,
                        origin: Origin::Target(target.id),
                    });
                }
            }
            let n_clutter = self.clutter.map_or(0, |p| p.sample(rng) as u64);
            for _ in 0..n_clutter {
                measurements.push(Measurement {
                    value: cfg.region.sample_uniform(rng),
                    origin: Origin::Clutter,
                });
            }
            measurements.shuffle(rng);
            scans.push(Scan {
                frame: frame as Frame,
                measurements,
            });
        }
        for target in alive {
            finished.push(target.track);
        }
        finished.sort_by_key(Track::id);
        Ok(Simulation {
            truth: TrackSet::from_tracks(finished)?,
            scans,
        })
    }

    fn clip_speed(&self, state: &mut CvState) {
        if let Some(v_max) = self.config.max_speed {
            let speed = state[2].hypot(state[3]);
            if speed > v_max {
                // Shrink by two ulps more than needed so rounding cannot leave it above v_max.
                let scale = v_max / speed * (1.0 - 2.0 * f64::EPSILON);
                state[2] *= scale;
                state[3] *= scale;
            }
        }
    }
}
