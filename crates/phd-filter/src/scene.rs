//! Simulated pedestrian scenes for Yoon et al. 2016's experiment: people walking across a sidewalk
//! seen in perspective (nearer people are lower in the image and larger, and hide those
//! behind them), a global detector that misses people (more often when they are occluded) and
//! fires falsely, and local detectors that follow one person each with their own failures:
//! position noise, slow drift, loss under occlusion, and re-locking onto the person in front.

use std::collections::BTreeMap;
use std::sync::Arc;

use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Poisson, StandardNormal};
use serde::{Deserialize, Serialize};
use tracker_model::{
    BoundingBox, Frame, LocalDetector, LocalDetectorFactory, Track, TrackId, TrackPoint, TrackSet,
    ensure_in_range, ensure_non_negative, ensure_positive,
};

use crate::error::{Error, Result};

/// A pedestrian scene and its global detector.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SceneConfig {
    /// Image width and height (pixels).
    pub image: [f64; 2],
    /// Frames to simulate.
    pub n_frames: u32,
    /// People in view at the first frame.
    pub initial_people: usize,
    /// Expected people entering per frame (from the left or right edge).
    pub arrivals_per_frame: f64,
    /// Walking speed range (pixels per frame at a box height of 100 pixels; scaled by
    /// perspective).
    pub speed: [f64; 2],
    /// The band of image rows where feet touch the ground, [far, near].
    pub ground_rows: [f64; 2],
    /// Box heights at the far and near rows.
    pub heights: [f64; 2],
    /// Global detector: detection probability of an unoccluded person.
    pub p_detect: f64,
    /// Global detector: detection probability of a person more than half hidden.
    pub p_detect_occluded: f64,
    /// Global detector: expected false boxes per frame.
    pub false_positives: f64,
    /// Global detector: standard deviation of box edges as a fraction of the height.
    pub box_noise: f64,
}

impl SceneConfig {
    /// An ETH-like crowded sidewalk: about 30 % of people missed, 0.9 false boxes per frame.
    pub fn eth_like() -> Self {
        Self::default()
    }

    /// A PETS-like scene seen from higher up: fewer occlusions and misses.
    pub fn pets_like() -> Self {
        Self {
            initial_people: 6,
            arrivals_per_frame: 0.03,
            ground_rows: [150.0, 470.0],
            heights: [50.0, 90.0],
            p_detect: 0.93,
            p_detect_occluded: 0.5,
            false_positives: 0.3,
            ..Self::default()
        }
    }

    /// Checks every field; [`SceneConfig::simulate`] calls it.
    pub fn check(&self) -> Result<()> {
        for v in self.image {
            ensure_positive(v, "image")?;
        }
        ensure_non_negative(self.speed[0], "speed")?;
        ensure_in_range(self.speed[1], self.speed[0], f64::INFINITY, "speed")?;
        let [far, near] = self.ground_rows;
        if !(far.is_finite() && near.is_finite() && near > far) {
            return Err(Error::InvalidParameter {
                name: "ground_rows",
                reason: format!(
                    "[{far}, {near}]: the near row must be finite and below the far one"
                ),
            });
        }
        for h in self.heights {
            ensure_positive(h, "heights")?;
        }
        ensure_in_range(self.p_detect, 0.0, 1.0, "p_detect")?;
        ensure_in_range(self.p_detect_occluded, 0.0, 1.0, "p_detect_occluded")?;
        ensure_non_negative(self.false_positives, "false_positives")?;
        ensure_non_negative(self.arrivals_per_frame, "arrivals_per_frame")?;
        ensure_non_negative(self.box_noise, "box_noise")?;
        Ok(())
    }
}

impl Default for SceneConfig {
    fn default() -> Self {
        Self {
            image: [640.0, 480.0],
            n_frames: 300,
            initial_people: 9,
            arrivals_per_frame: 0.05,
            speed: [0.8, 2.2],
            ground_rows: [250.0, 470.0],
            heights: [70.0, 190.0],
            p_detect: 0.8,
            p_detect_occluded: 0.25,
            false_positives: 0.9,
            box_noise: 0.04,
        }
    }
}

/// Truth at one frame: each person's id, box and the fraction of it hidden by people in front.
pub type FrameTruth = Vec<(TrackId, BoundingBox, f64)>;

/// A simulated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// True boxes of every person.
    pub truth: TrackSet,
    /// Per frame: who is where and how hidden.
    pub by_frame: Arc<BTreeMap<Frame, FrameTruth>>,
    /// The global detector's boxes per frame (index = frame).
    pub detections: Vec<Vec<BoundingBox>>,
}

struct Walker {
    id: TrackId,
    x: f64,
    foot: f64,
    vx: f64,
    vy: f64,
}

fn normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

impl SceneConfig {
    fn height_at(&self, foot: f64) -> f64 {
        let t = (foot - self.ground_rows[0]) / (self.ground_rows[1] - self.ground_rows[0]);
        self.heights[0] + t.clamp(0.0, 1.0) * (self.heights[1] - self.heights[0])
    }

    fn walker_box(&self, w: &Walker) -> BoundingBox {
        let h = self.height_at(w.foot);
        BoundingBox {
            left: w.x - 0.2 * h,
            top: w.foot - h,
            width: 0.4 * h,
            height: h,
        }
    }

    fn spawn<R: Rng + ?Sized>(&self, id: u64, inside: bool, rng: &mut R) -> Walker {
        let foot = rng.random_range(self.ground_rows[0]..self.ground_rows[1]);
        let scale = self.height_at(foot) / 100.0;
        let speed = rng.random_range(self.speed[0]..=self.speed[1]) * scale;
        let rightwards = rng.random_bool(0.5);
        let x = if inside {
            rng.random_range(0.0..self.image[0])
        } else if rightwards {
            -0.2 * self.height_at(foot)
        } else {
            self.image[0] + 0.2 * self.height_at(foot)
        };
        Walker {
            id: TrackId(id),
            x,
            foot,
            vx: if rightwards { speed } else { -speed },
            vy: 0.0,
        }
    }

    /// One frame of walking: every walker moves, those who left the image go, and newcomers
    /// arrive at the edges.
    fn walk<R: Rng + ?Sized>(
        &self,
        walkers: &mut Vec<Walker>,
        next_id: &mut u64,
        arrivals: &Poisson<f64>,
        rng: &mut R,
    ) {
        for w in walkers.iter_mut() {
            w.x += w.vx;
            w.vy = 0.8 * w.vy + 0.05 * normal(rng);
            w.foot = (w.foot + w.vy).clamp(self.ground_rows[0], self.ground_rows[1]);
            w.vx += 0.02 * normal(rng);
        }
        walkers.retain(|w| {
            let b = self.walker_box(w);
            b.right() > 0.0 && b.left < self.image[0]
        });
        for _ in 0..arrivals.sample(rng) as u64 {
            *next_id += 1;
            walkers.push(self.spawn(*next_id - 1, false, rng));
        }
    }

    /// One frame seen: each walker's box and hidden fraction, and the global detector's boxes
    /// (the people it finds, then its false boxes).
    fn observe<R: Rng + ?Sized>(
        &self,
        walkers: &[Walker],
        false_positives: &Poisson<f64>,
        rng: &mut R,
    ) -> (FrameTruth, Vec<BoundingBox>) {
        let boxes: Vec<BoundingBox> = walkers.iter().map(|w| self.walker_box(w)).collect();
        let mut truth: FrameTruth = Vec::with_capacity(walkers.len());
        let mut found = Vec::new();
        for (w, b) in walkers.iter().zip(&boxes) {
            // Hidden fraction: the largest share of this box covered by one nearer person.
            let hidden = walkers
                .iter()
                .zip(&boxes)
                .filter(|(o, _)| o.foot > w.foot)
                .map(|(_, ob)| b.intersection_area(ob) / b.area())
                .fold(0.0, f64::max);
            truth.push((w.id, *b, hidden));
            let p = if hidden > 0.5 {
                self.p_detect_occluded
            } else {
                self.p_detect
            };
            if rng.random_bool(p) {
                let s = self.box_noise * b.height;
                found.push(BoundingBox {
                    left: b.left + s * normal(rng),
                    top: b.top + s * normal(rng),
                    width: (b.width + s * normal(rng)).max(2.0),
                    height: (b.height + s * normal(rng)).max(4.0),
                });
            }
        }
        for _ in 0..false_positives.sample(rng) as u64 {
            let foot = rng.random_range(self.ground_rows[0]..self.ground_rows[1]);
            let h = self.height_at(foot) * rng.random_range(0.7..1.3);
            let x = rng.random_range(0.0..self.image[0]);
            found.push(BoundingBox {
                left: x - 0.2 * h,
                top: foot - h,
                width: 0.4 * h,
                height: h,
            });
        }
        (truth, found)
    }

    /// Draws a scene; every random draw comes from `rng`.
    pub fn simulate<R: Rng + ?Sized>(&self, rng: &mut R) -> Result<Scene> {
        self.check()?;
        let poisson = |rate: f64, name: &'static str| {
            Poisson::new(rate.max(1e-12)).map_err(|e| Error::InvalidParameter {
                name,
                reason: format!("{rate}: {e}"),
            })
        };
        let arrivals = poisson(self.arrivals_per_frame, "arrivals_per_frame")?;
        let false_positives = poisson(self.false_positives, "false_positives")?;
        let mut next_id = 0;
        let mut walkers: Vec<Walker> = (0..self.initial_people)
            .map(|_| {
                next_id += 1;
                self.spawn(next_id - 1, true, rng)
            })
            .collect();
        let mut points: BTreeMap<TrackId, Vec<TrackPoint>> = BTreeMap::new();
        let mut by_frame = BTreeMap::new();
        let mut detections = Vec::with_capacity(self.n_frames as usize);
        for frame in 0..self.n_frames {
            if frame > 0 {
                self.walk(&mut walkers, &mut next_id, &arrivals, rng);
            }
            let (truth, found) = self.observe(&walkers, &false_positives, rng);
            for (id, b, _) in &truth {
                points
                    .entry(*id)
                    .or_default()
                    .push(TrackPoint::boxed(frame, *b));
            }
            by_frame.insert(frame, truth);
            detections.push(found);
        }
        let tracks = points
            .into_iter()
            .map(|(id, p)| Track::from_points(id, p))
            .collect::<tracker_model::Result<Vec<_>>>()?;
        Ok(Scene {
            truth: TrackSet::from_tracks(tracks)?,
            by_frame: Arc::new(by_frame),
            detections,
        })
    }
}

/// Failure model of the simulated local detectors.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LocalDetectorSim {
    /// Standard deviation of each box edge per frame, as a fraction of the height.
    pub noise: f64,
    /// Standard deviation of the drift's step per frame, as a fraction of the height; a
    /// confirmation by the tracker halves the drift (online re-training).
    pub drift: f64,
    /// A person counts as occluded when more than this fraction is hidden.
    pub occlusion: f64,
    /// Probability per occluded frame of losing the person (returning nothing).
    pub p_lost: f64,
    /// Probability per occluded frame of re-locking onto the person in front.
    pub p_relock: f64,
}

impl LocalDetectorSim {
    /// Checks every field; [`SimulatedDetectors::new`] calls it.
    pub fn check(&self) -> Result<()> {
        ensure_non_negative(self.noise, "noise")?;
        ensure_non_negative(self.drift, "drift")?;
        ensure_in_range(self.occlusion, 0.0, 1.0, "occlusion")?;
        ensure_in_range(self.p_lost, 0.0, 1.0, "p_lost")?;
        ensure_in_range(self.p_relock, 0.0, 1.0, "p_relock")?;
        if self.p_lost + self.p_relock > 1.0 {
            return Err(Error::InvalidParameter {
                name: "p_lost",
                reason: format!(
                    "{} with p_relock {}: the two outcomes of an occluded frame cannot exceed 1 \
                     together",
                    self.p_lost, self.p_relock
                ),
            });
        }
        Ok(())
    }
}

impl Default for LocalDetectorSim {
    fn default() -> Self {
        Self {
            noise: 0.03,
            drift: 0.01,
            occlusion: 0.5,
            p_lost: 0.5,
            p_relock: 0.1,
        }
    }
}

/// Spawns simulated local detectors that follow the scene's truth.
pub struct SimulatedDetectors {
    truth: Arc<BTreeMap<Frame, FrameTruth>>,
    config: LocalDetectorSim,
    seed: u64,
    spawned: u64,
}

impl SimulatedDetectors {
    /// A factory over `scene`'s truth; detector i draws from ChaCha8(`seed`) stream i.
    pub fn new(scene: &Scene, config: LocalDetectorSim, seed: u64) -> Result<Self> {
        config.check()?;
        Ok(Self {
            truth: Arc::clone(&scene.by_frame),
            config,
            seed,
            spawned: 0,
        })
    }
}

impl LocalDetectorFactory for SimulatedDetectors {
    fn spawn(&mut self, frame: Frame, initial: &BoundingBox) -> Box<dyn LocalDetector> {
        // It locks onto whoever overlaps the initial box most (possibly nobody).
        let target = self.truth.get(&frame).and_then(|people| {
            people
                .iter()
                .map(|(id, b, _)| (*id, b.iou(initial)))
                .filter(|(_, iou)| *iou > 0.3)
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(id, _)| id)
        });
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(self.spawned);
        self.spawned += 1;
        Box::new(SimulatedDetector {
            truth: Arc::clone(&self.truth),
            config: self.config,
            target,
            drift: [0.0; 2],
            rng,
        })
    }
}

/// A local detector that sees the truth through its failure model.
struct SimulatedDetector {
    truth: Arc<BTreeMap<Frame, FrameTruth>>,
    config: LocalDetectorSim,
    target: Option<TrackId>,
    drift: [f64; 2],
    rng: ChaCha8Rng,
}

impl LocalDetector for SimulatedDetector {
    fn detect(&mut self, frame: Frame, _around: &BoundingBox) -> Option<BoundingBox> {
        let people = self.truth.get(&frame)?;
        let target = self.target?;
        let (_, b, hidden) = people.iter().find(|(id, _, _)| *id == target)?;
        let mut seen = *b;
        if *hidden > self.config.occlusion {
            let u: f64 = self.rng.random();
            if u < self.config.p_relock {
                // The person in front is the one covering most of this box.
                let front = people
                    .iter()
                    .filter(|(id, ob, _)| *id != target && ob.bottom() > b.bottom())
                    .max_by(|x, y| {
                        b.intersection_area(&x.1)
                            .total_cmp(&b.intersection_area(&y.1))
                    });
                if let Some((id, ob, _)) = front {
                    self.target = Some(*id);
                    seen = *ob;
                }
            } else if u < self.config.p_relock + self.config.p_lost {
                return None;
            }
        }
        let h = seen.height;
        for d in &mut self.drift {
            *d += self.config.drift * h * normal(&mut self.rng);
        }
        let s = self.config.noise * h;
        Some(BoundingBox {
            left: seen.left + self.drift[0] + s * normal(&mut self.rng),
            top: seen.top + self.drift[1] + s * normal(&mut self.rng),
            width: (seen.width + s * normal(&mut self.rng)).max(2.0),
            height: (seen.height + s * normal(&mut self.rng)).max(4.0),
        })
    }

    fn confirm(&mut self, _frame: Frame, _confirmed: &BoundingBox) {
        self.drift = self.drift.map(|d| 0.5 * d);
    }
}
