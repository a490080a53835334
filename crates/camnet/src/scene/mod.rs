//! A simulated scene of Meingast, Oh & Sastry's (ICCV 2007) experiment: people walking on a
//! ground plane, calibrated cameras on a ring, each aimed off-centre so that neighbouring views
//! overlap and distant ones may not, and each camera's blob detector, which reports a visible,
//! detected person's centroid, top and bottom with Gaussian pixel noise, misses some and adds
//! false blobs. The truth (who made each blob, where the cameras are) stays beside the
//! measurements, only to score a [`Network`](crate::Network) with [`score_pairs`] and
//! [`align_cameras`].
//!
//! [`SceneConfig::check`] gives the [`Scene`] that draws. Every draw comes from the generator
//! passed in, in a fixed order: [`Scene::walk`], then [`Scene::cameras`], then each camera's
//! blobs, camera by camera ([`Scene::track_cameras`]).

mod score;
#[cfg(test)]
mod tests;

use mcmcda::{McmcdaConfig, OnlineConfig, TrackEnd};
use nalgebra::{Matrix2, Vector2, Vector3};
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal, Poisson};
use tracker_model::{
    ConstantVelocity2, Frame, Vec2, ensure_in_range, ensure_non_negative, ensure_positive,
};

use crate::error::{Error, Result, invalid};
use crate::geometry::{Intrinsics, Pose, project};
use crate::network::CameraTracks;
use crate::tracks::{Blob, ImageTrackConfig, image_tracks};

pub use score::{Alignment, PairScore, PairTally, align_cameras, majority, overlap, score_pairs};

/// The scene's settings: cameras, people and the blob detector. [`SceneConfig::check`] turns
/// them into the [`Scene`] that draws.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneConfig {
    /// Cameras on a ring (3 to 64).
    pub n_cameras: usize,
    /// Ring radius, m.
    pub ring_radius_m: f64,
    /// Camera heights, drawn uniformly in [low, high), m.
    pub camera_height_m: [f64; 2],
    /// Each camera aims at a point this far from the centre, turned `aim_turn_deg` from its
    /// inward direction, so neighbouring views overlap and distant ones may not.
    pub aim_offset_m: f64,
    /// See `aim_offset_m`.
    pub aim_turn_deg: f64,
    /// Image width and height, px (each 16 to 16384).
    pub image_size: [f64; 2],
    /// Focal length, px.
    pub focal_px: f64,
    /// People walking, each for part of the run (1 to 1000).
    pub n_people: usize,
    /// Half side of the square the people walk in, m.
    pub area_half_m: f64,
    /// Walking speed, m per frame.
    pub speed_m_per_frame: f64,
    /// Person heights, drawn uniformly in [low, high), m.
    pub person_height_m: [f64; 2],
    /// Frames (2 to 100 000).
    pub n_frames: u32,
    /// Detection probability of a visible person.
    pub p_detect: f64,
    /// False blobs per frame per camera (Poisson mean, at most 1000).
    pub false_blobs_per_frame: f64,
}

impl SceneConfig {
    /// Checks every count, size and range before anything is drawn (a reversed range or an
    /// empty image would make the generator panic, a huge count run for hours) and gives the
    /// scene that draws.
    pub fn check(&self) -> Result<Scene> {
        let counts = [
            ("n_cameras", self.n_cameras, 3, 64),
            ("n_people", self.n_people, 1, 1000),
            ("n_frames", self.n_frames as usize, 2, 100_000),
        ];
        for (name, value, lo, hi) in counts {
            if !(lo..=hi).contains(&value) {
                return Err(invalid(name, format!("{value} is outside {lo}..={hi}")));
            }
        }
        let ranges = [
            ("camera_height_m", self.camera_height_m),
            ("person_height_m", self.person_height_m),
        ];
        for (name, [lo, hi]) in ranges {
            if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo < hi) {
                return Err(invalid(name, format!("[{lo}, {hi}] needs 0 < low < high")));
            }
        }
        for (side, value) in ["width", "height"].into_iter().zip(self.image_size) {
            if !(16.0..=16384.0).contains(&value) {
                return Err(invalid(
                    "image_size",
                    format!("the {side} is {value} px; it must be in [16, 16384]"),
                ));
            }
        }
        let positive = [
            ("ring_radius_m", self.ring_radius_m),
            ("focal_px", self.focal_px),
            ("area_half_m", self.area_half_m),
            ("speed_m_per_frame", self.speed_m_per_frame),
        ];
        for (name, value) in positive {
            ensure_positive(value, name)?;
        }
        for (name, value) in [
            ("aim_offset_m", self.aim_offset_m),
            ("aim_turn_deg", self.aim_turn_deg),
        ] {
            if !value.is_finite() {
                return Err(invalid(name, format!("{value} is not finite")));
            }
        }
        ensure_in_range(
            self.false_blobs_per_frame,
            0.0,
            1000.0,
            "false_blobs_per_frame",
        )?;
        ensure_in_range(self.p_detect, 0.0, 1.0, "p_detect")?;
        Ok(Scene { config: *self })
    }
}

/// A checked [`SceneConfig`]: simulates people, cameras and blobs.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    config: SceneConfig,
}

/// One person's walk on the ground plane (z = 0), at frames `start..end`.
#[derive(Debug, Clone, PartialEq)]
pub struct Person {
    /// The first frame the person is in the scene.
    pub start: Frame,
    /// One past the last frame.
    pub end: Frame,
    /// Height, m.
    pub height: f64,
    /// Ground position at each frame from `start`.
    pub ground: Vec<Vector3<f64>>,
}

/// One camera's blobs with their truth.
#[derive(Debug, Clone, PartialEq)]
pub struct Detections {
    /// Blobs per frame, every frame of the scene in order.
    pub scans: Vec<(Frame, Vec<Blob>)>,
    /// Each blob's true person (`None` for a false blob), in the order of `scans`.
    pub labels: Vec<Vec<Option<usize>>>,
}

/// Every camera's image tracks with their truth, the input of [`localise`](crate::localise)
/// and of [`score_pairs`].
#[derive(Debug, Clone)]
pub struct TrackedCameras {
    /// Each camera's intrinsics and image tracks, in camera order.
    pub cameras: Vec<CameraTracks>,
    /// Each track's majority person ([`majority`]), per camera: the truth used only to score.
    pub labels: Vec<Vec<Option<usize>>>,
}

impl Scene {
    /// The settings it was checked from.
    pub fn config(&self) -> &SceneConfig {
        &self.config
    }

    /// The cameras' pinhole intrinsics: the focal length of the settings, the principal point
    /// at the image centre.
    pub fn intrinsics(&self) -> Intrinsics {
        let c = &self.config;
        Intrinsics {
            fx: c.focal_px,
            fy: c.focal_px,
            cx: 0.5 * c.image_size[0],
            cy: 0.5 * c.image_size[1],
        }
    }

    /// The people: each walks for between half and all of the frames, from a random point of
    /// the square towards random waypoints, turning smoothly (at most 0.1 rad per frame) at
    /// constant speed.
    pub fn walk<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<Person> {
        let c = &self.config;
        let n = c.n_frames;
        (0..c.n_people)
            .map(|_| {
                let len = rng.random_range(n / 2..=n);
                let start = rng.random_range(0..=n - len);
                let a = c.area_half_m;
                let mut pos = Vector3::new(rng.random_range(-a..a), rng.random_range(-a..a), 0.0);
                let mut goal = Vector3::new(rng.random_range(-a..a), rng.random_range(-a..a), 0.0);
                let mut ground = Vec::with_capacity(len as usize);
                let mut heading = (goal - pos).normalize();
                for _ in 0..len {
                    if (goal - pos).norm() < 1.0 {
                        goal = Vector3::new(rng.random_range(-a..a), rng.random_range(-a..a), 0.0);
                    }
                    // Turn smoothly towards the waypoint (at most 6° per frame).
                    let want = (goal - pos).normalize();
                    let angle = heading.y.atan2(heading.x);
                    let target = want.y.atan2(want.x);
                    let d = (target - angle + std::f64::consts::PI)
                        .rem_euclid(std::f64::consts::TAU)
                        - std::f64::consts::PI;
                    let angle = angle + d.clamp(-0.1, 0.1);
                    heading = Vector3::new(angle.cos(), angle.sin(), 0.0);
                    pos += heading * c.speed_m_per_frame;
                    ground.push(pos);
                }
                Person {
                    start,
                    end: start + len,
                    height: rng.random_range(c.person_height_m[0]..c.person_height_m[1]),
                    ground,
                }
            })
            .collect()
    }

    /// The cameras (`camera_from_world` poses): evenly spaced on the ring with a random jitter
    /// of the angle, at random heights, each aimed at a point 0.8 m above the ground
    /// `aim_offset_m` from the centre, turned `aim_turn_deg` from straight across.
    pub fn cameras<R: Rng + ?Sized>(&self, rng: &mut R) -> Result<Vec<Pose>> {
        let c = &self.config;
        (0..c.n_cameras)
            .map(|k| {
                let theta = std::f64::consts::TAU * k as f64 / c.n_cameras as f64
                    + rng.random_range(-0.15..0.15);
                let h = rng.random_range(c.camera_height_m[0]..c.camera_height_m[1]);
                let centre = Vector3::new(
                    c.ring_radius_m * theta.cos(),
                    c.ring_radius_m * theta.sin(),
                    h,
                );
                let aim = theta + std::f64::consts::PI + c.aim_turn_deg.to_radians();
                let target =
                    Vector3::new(c.aim_offset_m * aim.cos(), c.aim_offset_m * aim.sin(), 0.8);
                Pose::look_at(&centre, &target).ok_or_else(|| Error::BadCamera {
                    index: k,
                    reason: "it looks straight down".into(),
                })
            })
            .collect()
    }

    /// One camera's blob detector over every frame: each person whose head and feet are in
    /// the image is detected with probability `p_detect`, its centroid (the body's middle),
    /// top and bottom jittered by Gaussian noise of σ = `noise_px`; then a Poisson number of
    /// false blobs, uniform over the image, 40 to 160 px tall.
    pub fn detect<R: Rng + ?Sized>(
        &self,
        cam: &Pose,
        people: &[Person],
        noise_px: f64,
        rng: &mut R,
    ) -> Result<Detections> {
        let c = &self.config;
        ensure_non_negative(noise_px, "noise_px")?;
        let noise = Normal::new(0.0, noise_px.max(1e-12))
            .map_err(|e| invalid("noise_px", e.to_string()))?;
        let clutter = Poisson::new(c.false_blobs_per_frame.max(1e-9))
            .map_err(|e| invalid("false_blobs_per_frame", e.to_string()))?;
        let k = self.intrinsics();
        let (w, h) = (c.image_size[0], c.image_size[1]);
        let inside = |u: &Vector2<f64>| u.x >= 0.0 && u.x < w && u.y >= 0.0 && u.y < h;
        let mut scans = Vec::new();
        let mut labels = Vec::new();
        for f in 0..c.n_frames {
            let mut blobs = Vec::new();
            let mut who = Vec::new();
            for (i, person) in people.iter().enumerate() {
                if f < person.start || f >= person.end {
                    continue;
                }
                let g = person.ground[(f - person.start) as usize];
                let px =
                    |z: f64| project(&cam.apply(&(g + Vector3::z() * z))).map(|x| k.to_pixel(&x));
                let (Some(top), Some(mid), Some(bottom)) =
                    (px(person.height), px(0.5 * person.height), px(0.0))
                else {
                    continue;
                };
                if !(inside(&top) && inside(&bottom)) || rng.random::<f64>() >= c.p_detect {
                    continue;
                }
                let mut jitter =
                    |v: Vector2<f64>| v + Vector2::new(noise.sample(rng), noise.sample(rng));
                blobs.push(Blob {
                    centre: jitter(mid),
                    top: jitter(top),
                    bottom: jitter(bottom),
                });
                who.push(Some(i));
            }
            let n_false = clutter.sample(rng) as usize;
            for _ in 0..n_false {
                let centre = Vec2::new(rng.random_range(0.0..w), rng.random_range(0.0..h));
                let half = rng.random_range(20.0..80.0);
                blobs.push(Blob {
                    centre,
                    top: centre - Vec2::new(0.0, half),
                    bottom: centre + Vec2::new(0.0, half),
                });
                who.push(None);
            }
            scans.push((f, blobs));
            labels.push(who);
        }
        Ok(Detections { scans, labels })
    }

    /// The per-camera online MCMCDA matched to this scene's detector (Meingast, Oh & Sastry
    /// 2007 track objects in each image before matching): the image as the surveillance
    /// volume, the detector's false-blob rate and detection probability, measurement noise
    /// following the pixel noise (σ = 2 · max(`noise_px`, 0.5) px), up to 60 px per frame,
    /// gaps of up to 4 frames, an 8-frame window with `samples_per_scan` samples per frame,
    /// and tracks of at least 10 blobs.
    pub fn image_track_config(
        &self,
        noise_px: f64,
        samples_per_scan: u64,
    ) -> Result<ImageTrackConfig> {
        let c = &self.config;
        let sigma = noise_px.max(0.5);
        let model = McmcdaConfig {
            volume: c.image_size[0] * c.image_size[1],
            births_per_scan: 0.05,
            clutter_per_scan: c.false_blobs_per_frame.max(0.01),
            p_disappear: 0.01,
            p_detect: c.p_detect.min(0.99),
            motion: ConstantVelocity2::mcmcda(1.0, 4.0)?,
            measurement_noise: Matrix2::identity() * (2.0 * sigma).powi(2),
            max_gap: 4,
            max_speed: 60.0,
            track_end: TrackEnd::Undetected,
            ..McmcdaConfig::default()
        };
        Ok(ImageTrackConfig {
            model,
            online: OnlineConfig {
                window: 8,
                samples_per_scan,
                ..OnlineConfig::default()
            },
            min_length: 10,
        })
    }

    /// Detects the people in every camera's images and tracks them with `config` (Meingast,
    /// Oh & Sastry 2007 track objects in each image before matching): camera by camera, the
    /// blobs drawn from `rng` in that order, camera c's tracker seeded with `seed + c`. Each
    /// track's true person is its [`majority`].
    pub fn track_cameras<R: Rng + ?Sized>(
        &self,
        cams: &[Pose],
        people: &[Person],
        noise_px: f64,
        config: &ImageTrackConfig,
        rng: &mut R,
        seed: u64,
    ) -> Result<TrackedCameras> {
        let intrinsics = self.intrinsics();
        let mut cameras = Vec::with_capacity(cams.len());
        let mut labels = Vec::with_capacity(cams.len());
        for (c, cam) in cams.iter().enumerate() {
            let seen = self.detect(cam, people, noise_px, rng)?;
            let tracks = image_tracks(&seen.scans, config, seed.wrapping_add(c as u64))?;
            labels.push(tracks.iter().map(|t| majority(t, &seen.labels)).collect());
            cameras.push(CameraTracks { intrinsics, tracks });
        }
        Ok(TrackedCameras { cameras, labels })
    }
}
