//! Simulated pedestrian scenes for Yoon et al.'s (2016) experiment: people walking across a
//! sidewalk seen in perspective (nearer people are lower in the image and larger, and hide those
//! behind them), a global detector that misses people (more often when they are occluded) and
//! fires falsely, and local detectors that see only what a real online-trained detector would:
//! the people inside a search window around the tracker's estimate, matched against the look
//! they learned at spawn (a person, or background if spawned on clutter), with their own miss
//! rate, box noise, occlusion and drift to a neighbour. The scene's truth generates the image
//! content, like a renderer; no detector looks a person up by identity to decide what to report.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Poisson, StandardNormal};
use serde::{Deserialize, Serialize};
use tracker_model::{
    BoundingBox, Frame, LocalDetector, LocalDetectorFactory, Track, TrackId, TrackPoint, TrackSet,
    ensure_in_range, ensure_non_negative, ensure_positive,
};

use crate::error::{Result, invalid_parameter};

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
            return Err(invalid_parameter(
                "ground_rows",
                format!("[{far}, {near}]: the near row must be finite and below the far one"),
            ));
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
            Poisson::new(rate.max(1e-12))
                .map_err(|e| invalid_parameter(name, format!("{rate}: {e}")))
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

/// What a simulated local detector sees and how it fails. A real online-trained detector
/// (Yoon et al. 2016: one per target, trained on the image patch where the target was
/// confirmed) searches a window around where it last was, responds to whatever there looks
/// most like what it learned, misses, and can be taken over by a look-alike that passes close.
/// Every field is stated in the scenario file; none of them lets the detector know who is who.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocalDetectorSim {
    /// Half-size of the search window around the centre of `around`, as a multiple of the
    /// height of `around`, on both axes. Objects whose box centre lies outside are not seen.
    pub search: f64,
    /// Probability per frame of finding its object when it is in the window and at most
    /// `occlusion` hidden (1 − the miss rate).
    pub p_detect: f64,
    /// The same when its object is more than `occlusion` hidden by a nearer person (a person
    /// hidden entirely is never found: there is nothing of them in the image).
    pub p_detect_occluded: f64,
    /// A person counts as occluded when more than this fraction of the box is hidden.
    pub occlusion: f64,
    /// Standard deviation of each box edge, as a fraction of the box height, when its object
    /// is not occluded.
    pub noise: f64,
    /// The same when its object is occluded (the box is worse).
    pub noise_occluded: f64,
    /// Probability per frame, when another person's box centre is inside the window, that
    /// the nearest such person takes the detector over (its response moves to the
    /// look-alike, which it follows from then on): drift.
    pub p_drift: f64,
    /// Probability per frame, when it does not find its object, of still reporting a box at
    /// the centre of its window (the response peak lies on the background): a stale report.
    pub p_stale: f64,
    /// At spawn it learns the look of the person whose box overlaps the initial box most, if
    /// that IoU is at least this; otherwise it learns the background patch (clutter) there.
    pub spawn_iou: f64,
}

impl LocalDetectorSim {
    /// Checks every field; [`SimulatedDetectors::new`] calls it.
    pub fn check(&self) -> Result<()> {
        ensure_positive(self.search, "search")?;
        for (name, v) in [
            ("p_detect", self.p_detect),
            ("p_detect_occluded", self.p_detect_occluded),
            ("occlusion", self.occlusion),
            ("p_drift", self.p_drift),
            ("p_stale", self.p_stale),
            ("spawn_iou", self.spawn_iou),
        ] {
            ensure_in_range(v, 0.0, 1.0, name)?;
        }
        ensure_non_negative(self.noise, "noise")?;
        ensure_non_negative(self.noise_occluded, "noise_occluded")?;
        Ok(())
    }
}

impl Default for LocalDetectorSim {
    /// A mediocre online tracker: it finds an unoccluded target 80 % of the time, an occluded
    /// one 30 %, with the global detector's box noise (4 % of the height; twice that when
    /// occluded), is taken over by a neighbour in its window with probability 0.05 per frame,
    /// and reports a stale box 10 % of the frames it finds nothing.
    fn default() -> Self {
        Self {
            search: 0.5,
            p_detect: 0.8,
            p_detect_occluded: 0.3,
            occlusion: 0.5,
            noise: 0.04,
            noise_occluded: 0.08,
            p_drift: 0.05,
            p_stale: 0.1,
            spawn_iou: 0.3,
        }
    }
}

/// What a simulated local detector has learned to look for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Template {
    /// The look of one person (the scene's id stands for the appearance the detector learned
    /// from the image patch; it is compared only with people inside the search window).
    Person(TrackId),
    /// A patch of background at this box (spawned on clutter): it stays where it is.
    Background(BoundingBox),
}

/// What the simulated local detectors of one factory did, for reports: how many were spawned
/// and how many of those on clutter, how often they were asked, drifted, found their object or
/// gave a stale report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DetectorCounts {
    /// Detectors spawned.
    pub spawned: u64,
    /// Of those, spawned on background (clutter).
    pub on_clutter: u64,
    /// Calls of `detect` over all detectors.
    pub detector_frames: u64,
    /// Take-overs by a neighbour.
    pub drifts: u64,
    /// Reports of the template's object.
    pub found: u64,
    /// Stale reports (nothing found, a box at the window's centre).
    pub stale: u64,
}

/// Shared counters behind [`DetectorCounts`] (the factory moves into the tracker; a handle
/// taken before reads them afterwards).
#[derive(Debug, Default)]
pub struct DetectorStats {
    spawned: AtomicU64,
    on_clutter: AtomicU64,
    detector_frames: AtomicU64,
    drifts: AtomicU64,
    found: AtomicU64,
    stale: AtomicU64,
}

impl DetectorStats {
    /// The counts so far.
    pub fn counts(&self) -> DetectorCounts {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        DetectorCounts {
            spawned: get(&self.spawned),
            on_clutter: get(&self.on_clutter),
            detector_frames: get(&self.detector_frames),
            drifts: get(&self.drifts),
            found: get(&self.found),
            stale: get(&self.stale),
        }
    }
}

fn bump(counter: &AtomicU64) {
    counter.fetch_add(1, Ordering::Relaxed);
}

/// Spawns simulated local detectors over a scene's image content (where people are and how
/// hidden, as a renderer would draw them).
pub struct SimulatedDetectors {
    content: Arc<BTreeMap<Frame, FrameTruth>>,
    config: LocalDetectorSim,
    seed: u64,
    spawned: u64,
    stats: Arc<DetectorStats>,
}

impl SimulatedDetectors {
    /// A factory over `scene`; detector i draws from ChaCha8(`seed`) stream i.
    pub fn new(scene: &Scene, config: LocalDetectorSim, seed: u64) -> Result<Self> {
        Self::over(Arc::clone(&scene.by_frame), config, seed)
    }

    /// A factory over explicit per-frame content (people's boxes and hidden fractions).
    pub fn over(
        content: Arc<BTreeMap<Frame, FrameTruth>>,
        config: LocalDetectorSim,
        seed: u64,
    ) -> Result<Self> {
        config.check()?;
        Ok(Self {
            content,
            config,
            seed,
            spawned: 0,
            stats: Arc::default(),
        })
    }

    /// A handle on the counters of every detector this factory spawns.
    pub fn stats(&self) -> Arc<DetectorStats> {
        Arc::clone(&self.stats)
    }

    /// A detector spawned at `frame` on `initial`, as its concrete type.
    pub fn detector(&mut self, frame: Frame, initial: &BoundingBox) -> SimulatedDetector {
        // What the patch inside the initial box shows: the person filling most of it, or
        // background when nobody overlaps it enough.
        let person = self.content.get(&frame).and_then(|people| {
            people
                .iter()
                .map(|(id, b, _)| (*id, b.iou(initial)))
                .filter(|(_, iou)| *iou >= self.config.spawn_iou && *iou > 0.0)
                .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
                .map(|(id, _)| id)
        });
        let template = person.map_or(Template::Background(*initial), Template::Person);
        bump(&self.stats.spawned);
        if matches!(template, Template::Background(_)) {
            bump(&self.stats.on_clutter);
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(self.spawned);
        self.spawned += 1;
        SimulatedDetector {
            content: Arc::clone(&self.content),
            config: self.config,
            template,
            rng,
            stats: Arc::clone(&self.stats),
        }
    }
}

impl LocalDetectorFactory for SimulatedDetectors {
    fn spawn(&mut self, frame: Frame, initial: &BoundingBox) -> Box<dyn LocalDetector> {
        Box::new(self.detector(frame, initial))
    }
}

/// A local detector that sees the objects inside its search window through its failure
/// model. It never asks where a given person is: it compares its template with what is in the
/// window.
pub struct SimulatedDetector {
    content: Arc<BTreeMap<Frame, FrameTruth>>,
    config: LocalDetectorSim,
    template: Template,
    rng: ChaCha8Rng,
    stats: Arc<DetectorStats>,
}

impl SimulatedDetector {
    /// What it currently looks for.
    pub fn template(&self) -> Template {
        self.template
    }

    fn noisy(&mut self, b: &BoundingBox, s: f64) -> BoundingBox {
        BoundingBox {
            left: b.left + s * normal(&mut self.rng),
            top: b.top + s * normal(&mut self.rng),
            width: (b.width + s * normal(&mut self.rng)).max(2.0),
            height: (b.height + s * normal(&mut self.rng)).max(4.0),
        }
    }
}

/// A person hidden by at least this fraction is not in the image at all: a detector that
/// sees only pixels can neither find nor drift to them (the fraction is an area ratio, so a
/// box inside a nearer one's may read a rounding error below 1).
const FULLY_HIDDEN: f64 = 1.0 - 1e-9;

impl LocalDetector for SimulatedDetector {
    fn detect(&mut self, frame: Frame, around: &BoundingBox) -> Option<BoundingBox> {
        bump(&self.stats.detector_frames);
        let c = around.centre();
        let half = self.config.search * around.height;
        let in_window = |b: &BoundingBox| {
            let d = b.centre() - c;
            d.x.abs() <= half && d.y.abs() <= half
        };
        let visible: Vec<(TrackId, BoundingBox, f64)> = self
            .content
            .get(&frame)
            .map(|people| {
                people
                    .iter()
                    .filter(|(_, b, hidden)| in_window(b) && *hidden < FULLY_HIDDEN)
                    .copied()
                    .collect()
            })
            .unwrap_or_default();
        // Drift: a look-alike inside the window can take the detector over.
        let nearest_other = visible
            .iter()
            .filter(|(id, _, _)| self.template != Template::Person(*id))
            .map(|(id, b, _)| (*id, (b.centre() - c).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        if let Some((id, _)) = nearest_other
            && self.rng.random_bool(self.config.p_drift)
        {
            self.template = Template::Person(id);
            bump(&self.stats.drifts);
        }
        let response = match self.template {
            Template::Person(id) => visible
                .iter()
                .find(|(other, _, _)| *other == id)
                .map(|(_, b, hidden)| (*b, *hidden)),
            Template::Background(b) => in_window(&b).then_some((b, 0.0)),
        };
        if let Some((b, hidden)) = response {
            let (p, noise) = if hidden > self.config.occlusion {
                (self.config.p_detect_occluded, self.config.noise_occluded)
            } else {
                (self.config.p_detect, self.config.noise)
            };
            if self.rng.random_bool(p) {
                bump(&self.stats.found);
                return Some(self.noisy(&b, noise * b.height));
            }
        }
        if self.rng.random_bool(self.config.p_stale) {
            bump(&self.stats.stale);
            return Some(self.noisy(around, self.config.noise * around.height));
        }
        None
    }
}
