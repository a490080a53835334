//! Realistic pedestrian detection files: a seeded generator of MOTChallenge ground truth and
//! detections for the `mot-realistic` pipeline, `cargo xtask walkers` and the Stone Soup peer
//! script (`docs/comparisons/stonesoup_realistic.py`).
//!
//! The scene is a ground plane seen by a pinhole camera (focal length `focal_px`, height
//! `camera_height_m`, horizon at `horizon_px`), so a walker's box grows as it comes nearer:
//! foot row − horizon = f·H_c / Z and box height = f·1.7 m / Z. Walkers enter from outside the
//! image (or stand in it at the start), walk at 1.0-1.6 m/s, and now and then stop, turn or
//! change speed; some turn back, which gives short tracks. Boxes are cut at the image border
//! (the truth box is the visible part), and people nearer the camera occlude those behind.
//!
//! The detector model, simulated from the truth as a detector would err (it never looks at the
//! truth to correct itself): a visible person is detected with probability
//! `recall · (1 − occluded fraction)^1.5`, with every edge jittered by `jitter` of the box size;
//! false boxes come at `false_per_frame` per frame, two thirds of them anywhere on the ground
//! plane with a plausible size, one third near a real person (a shifted part-body box). Scores:
//! true boxes ≈ N(0.72, 0.15) lowered by occlusion, false boxes ≈ N(0.45, 0.15): lower on
//! average, overlapping.

use crate::error::{Result, invalid};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, Poisson};
use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, Frame, MotRow};

/// The scene, the walkers and the detector.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WalkersConfig {
    /// Image width, pixels.
    pub width_px: f64,
    /// Image height, pixels.
    pub height_px: f64,
    /// Focal length, pixels.
    pub focal_px: f64,
    /// Row of the horizon, pixels.
    pub horizon_px: f64,
    /// Camera height above the ground, metres.
    pub camera_height_m: f64,
    /// Frames per second.
    pub fps: f64,
    /// Length of the sequence, seconds.
    pub duration_s: f64,
    /// Walkers entering per second.
    pub arrivals_per_s: f64,
    /// Walkers already in view at the first frame.
    pub initial_walkers: usize,
    /// Detection probability of a fully visible person.
    pub recall: f64,
    /// σ of each box edge's jitter, as a fraction of the box width (x) or height (y).
    pub jitter: f64,
    /// Expected false boxes per frame.
    pub false_per_frame: f64,
}

impl Default for WalkersConfig {
    fn default() -> Self {
        Self {
            width_px: 960.0,
            height_px: 540.0,
            focal_px: 700.0,
            horizon_px: 150.0,
            camera_height_m: 2.5,
            fps: 25.0,
            duration_s: 16.0,
            arrivals_per_s: 0.5,
            initial_walkers: 6,
            recall: 0.88,
            jitter: 0.03,
            false_per_frame: 0.5,
        }
    }
}

/// A generated sequence: MOTChallenge ground truth (ids from 1) and detections (id −1, the
/// score in the confidence column).
#[derive(Debug, Clone)]
pub struct Sequence {
    /// Visible part of every person in view, every frame.
    pub gt: Vec<MotRow>,
    /// What the simulated detector reported.
    pub detections: Vec<MotRow>,
    /// Frames (1..=n_frames).
    pub n_frames: Frame,
}

/// Person height, metres.
const PERSON_HEIGHT_M: f64 = 1.7;
/// Width / height of a person's box.
const ASPECT: f64 = 0.41;
/// Depth range walkers use, metres.
const DEPTH_M: (f64, f64) = (5.0, 22.0);

/// A walker on the ground plane (X lateral, Z depth, metres).
struct Walker {
    x: f64,
    z: f64,
    heading: f64,
    speed: f64,
    /// The speed it returns to after a stop.
    cruise: f64,
    /// Seconds left of a stop.
    stop_left: f64,
    /// Turn rate, rad/s, and seconds it lasts.
    turn_rate: f64,
    turn_left: f64,
    /// Size factor (people differ in height).
    scale: f64,
    /// Set once it has been in view; it leaves for good when it is out again.
    seen: bool,
    gone: bool,
}

impl WalkersConfig {
    fn check(&self) -> Result<()> {
        for (name, v) in [
            ("width_px", self.width_px),
            ("height_px", self.height_px),
            ("focal_px", self.focal_px),
            ("camera_height_m", self.camera_height_m),
            ("fps", self.fps),
            ("duration_s", self.duration_s),
        ] {
            tracker_model::ensure_positive(v, name)?;
        }
        for (name, v) in [
            ("arrivals_per_s", self.arrivals_per_s),
            ("jitter", self.jitter),
            ("false_per_frame", self.false_per_frame),
        ] {
            tracker_model::ensure_non_negative(v, name)?;
        }
        tracker_model::ensure_in_range(self.recall, 0.0, 1.0, "recall")?;
        if self.fps * self.duration_s > 1e6 {
            return Err(invalid(
                "duration_s",
                format!(
                    "fps · duration_s = {} frames is over a million",
                    self.fps * self.duration_s
                ),
            ));
        }
        Ok(())
    }

    /// The full (untruncated) box of a walker, or `None` behind the camera.
    fn full_box(&self, w: &Walker) -> Option<[f64; 4]> {
        if w.z <= 0.5 {
            return None;
        }
        let foot = self.horizon_px + self.focal_px * self.camera_height_m / w.z;
        let h = self.focal_px * PERSON_HEIGHT_M * w.scale / w.z;
        let cx = self.width_px / 2.0 + self.focal_px * w.x / w.z;
        let bw = ASPECT * h;
        Some([cx - bw / 2.0, foot - h, cx + bw / 2.0, foot])
    }

    /// A walker entering at the left or right border, or (`inside`) standing in view.
    fn spawn(&self, rng: &mut ChaCha8Rng, inside: bool) -> Walker {
        let z = DEPTH_M.0 + (DEPTH_M.1 - DEPTH_M.0) * rng.random::<f64>();
        let half_view = self.width_px / 2.0 / self.focal_px * z;
        let from_left = rng.random::<f64>() < 0.5;
        let x = if inside {
            half_view * (2.0 * rng.random::<f64>() - 1.0) * 0.85
        } else if from_left {
            -half_view - 0.5
        } else {
            half_view + 0.5
        };
        // Mostly across the view, some diagonally in depth.
        let across = if inside {
            if rng.random::<f64>() < 0.5 {
                0.0
            } else {
                std::f64::consts::PI
            }
        } else if from_left {
            0.0
        } else {
            std::f64::consts::PI
        };
        let heading = across + 0.5 * (2.0 * rng.random::<f64>() - 1.0);
        let cruise = 1.0 + 0.6 * rng.random::<f64>();
        Walker {
            x,
            z,
            heading,
            speed: cruise,
            cruise,
            stop_left: 0.0,
            turn_rate: 0.0,
            turn_left: 0.0,
            scale: 0.9 + 0.2 * rng.random::<f64>(),
            seen: inside,
            gone: false,
        }
    }

    /// One time step of `dt` seconds: stops, turns, speed changes, then the move.
    fn walk(&self, w: &mut Walker, dt: f64, rng: &mut ChaCha8Rng) {
        // Events per second.
        let (stop_rate, turn_rate, speed_rate, back_rate) = (0.06, 0.12, 0.15, 0.02);
        if w.stop_left > 0.0 {
            w.stop_left -= dt;
            w.speed = if w.stop_left > 0.0 { 0.0 } else { w.cruise };
        } else if rng.random::<f64>() < stop_rate * dt {
            w.stop_left = 1.0 + 3.0 * rng.random::<f64>();
            w.speed = 0.0;
        }
        if w.turn_left > 0.0 {
            w.turn_left -= dt;
            w.heading += w.turn_rate * dt;
        } else if rng.random::<f64>() < turn_rate * dt {
            w.turn_left = 0.5 + rng.random::<f64>();
            w.turn_rate = (2.0 * rng.random::<f64>() - 1.0) * 1.2;
        } else if rng.random::<f64>() < back_rate * dt {
            // Turns back within a second.
            w.turn_left = 1.0;
            w.turn_rate = std::f64::consts::PI * if rng.random::<f64>() < 0.5 { 1.0 } else { -1.0 };
        }
        if w.stop_left <= 0.0 && rng.random::<f64>() < speed_rate * dt {
            w.cruise = (w.cruise * (0.7 + 0.6 * rng.random::<f64>())).clamp(0.6, 2.0);
            w.speed = w.cruise;
        }
        w.x += w.speed * w.heading.cos() * dt;
        w.z += w.speed * w.heading.sin() * dt;
        // Depth stays in range: the walker turns away from the limit.
        if w.z < DEPTH_M.0 || w.z > DEPTH_M.1 {
            w.z = w.z.clamp(DEPTH_M.0, DEPTH_M.1);
            w.heading = -w.heading;
        }
    }

    /// Generates the sequence of ChaCha8 seeded with `seed` (what `cargo xtask walkers` and the
    /// `mot-realistic` pipeline call).
    pub fn generate_seeded(&self, seed: u64) -> Result<Sequence> {
        use rand::SeedableRng;
        self.generate(&mut ChaCha8Rng::seed_from_u64(seed))
    }

    /// Generates a sequence; every draw comes from `rng`.
    pub fn generate(&self, rng: &mut ChaCha8Rng) -> Result<Sequence> {
        self.check()?;
        let n_frames = (self.fps * self.duration_s).round().max(1.0) as Frame;
        let dt = 1.0 / self.fps;
        let unit = Normal::new(0.0, 1.0).map_err(|e| invalid("jitter", e.to_string()))?;
        let arrivals = self.arrivals_per_s * dt;
        let mut walkers: Vec<Walker> = (0..self.initial_walkers)
            .map(|_| self.spawn(rng, true))
            .collect();
        let mut gt = Vec::new();
        let mut detections = Vec::new();
        for frame in 1..=n_frames {
            if frame > 1 {
                for w in walkers.iter_mut().filter(|w| !w.gone) {
                    self.walk(w, dt, rng);
                }
                if arrivals > 0.0 && rng.random::<f64>() < arrivals {
                    walkers.push(self.spawn(rng, false));
                }
            }
            let visible = self.visible(&mut walkers);
            let occluded = occlusion(&visible);
            for (&(i, _, cut), &occ) in visible.iter().zip(&occluded) {
                gt.push(row(frame, i as i64 + 1, cut, 1.0)?);
                if let Some(d) = self.detect(frame, cut, occ, &unit, rng)? {
                    detections.push(d);
                }
            }
            self.false_detections(frame, &visible, &unit, rng, &mut detections)?;
            // Walkers that never came into view within 20 s leave the simulation.
            let limit = (20.0 * self.fps) as usize;
            if (frame as usize).is_multiple_of(limit.max(1)) {
                for w in walkers.iter_mut().filter(|w| !w.seen) {
                    w.gone = true;
                }
            }
        }
        Ok(Sequence {
            gt,
            detections,
            n_frames,
        })
    }

    /// The walkers in view: (walker index, full box, box cut by the image border), at least a
    /// fifth of the person and 4 pixels wide. A walker that was seen and leaves the view is
    /// gone.
    fn visible(&self, walkers: &mut [Walker]) -> Vec<(usize, [f64; 4], [f64; 4])> {
        let (img_w, img_h) = (self.width_px, self.height_px);
        let mut visible = Vec::new();
        for (i, w) in walkers.iter_mut().enumerate() {
            if w.gone {
                continue;
            }
            let Some(full) = self.full_box(w) else {
                continue;
            };
            let cut = [
                full[0].max(0.0),
                full[1].max(0.0),
                full[2].min(img_w),
                full[3].min(img_h),
            ];
            let area = (full[2] - full[0]) * (full[3] - full[1]);
            let cut_area = (cut[2] - cut[0]).max(0.0) * (cut[3] - cut[1]).max(0.0);
            if cut_area >= 0.2 * area && cut[2] - cut[0] >= 4.0 {
                w.seen = true;
                visible.push((i, full, cut));
            } else if w.seen {
                w.gone = true;
            }
        }
        visible
    }

    /// The detector on one visible box `cut`, occluded by the fraction `occ`: found with
    /// probability recall · (1 − occ)^1.5, its edges jittered, its score lower the more it is
    /// occluded.
    fn detect(
        &self,
        frame: Frame,
        cut: [f64; 4],
        occ: f64,
        unit: &Normal<f64>,
        rng: &mut ChaCha8Rng,
    ) -> Result<Option<MotRow>> {
        let p = self.recall * (1.0 - occ).powf(1.5);
        if rng.random::<f64>() >= p {
            return Ok(None);
        }
        let (bw, bh) = (cut[2] - cut[0], cut[3] - cut[1]);
        let mut b = [
            cut[0] + self.jitter * bw * unit.sample(rng),
            cut[1] + self.jitter * bh * unit.sample(rng),
            cut[2] + self.jitter * bw * unit.sample(rng),
            cut[3] + self.jitter * bh * unit.sample(rng),
        ];
        clip(&mut b, self.width_px, self.height_px);
        let score = (0.72 + 0.15 * unit.sample(rng) - 0.3 * occ).clamp(0.05, 1.0);
        if b[2] - b[0] > 1.0 && b[3] - b[1] > 1.0 {
            return Ok(Some(row(frame, -1, b, score)?));
        }
        Ok(None)
    }

    /// A Poisson number of false detections: a third are part-body or shifted boxes on a
    /// visible person, the rest person-sized boxes anywhere on the ground.
    fn false_detections(
        &self,
        frame: Frame,
        visible: &[(usize, [f64; 4], [f64; 4])],
        unit: &Normal<f64>,
        rng: &mut ChaCha8Rng,
        detections: &mut Vec<MotRow>,
    ) -> Result<()> {
        let (img_w, img_h) = (self.width_px, self.height_px);
        let n_false = if self.false_per_frame > 0.0 {
            Poisson::new(self.false_per_frame)
                .map_err(|e| invalid("false_per_frame", e.to_string()))?
                .sample(rng) as usize
        } else {
            0
        };
        for _ in 0..n_false {
            let near = !visible.is_empty() && rng.random::<f64>() < 1.0 / 3.0;
            let mut b = if near {
                // A part-body or shifted box on a real person.
                let k = (rng.random::<f64>() * visible.len() as f64) as usize;
                let c = visible[k.min(visible.len() - 1)].2;
                let (bw, bh) = (c[2] - c[0], c[3] - c[1]);
                let dx = (0.3 + 0.4 * rng.random::<f64>()) * bw * sign(rng);
                let s = 0.5 + 0.4 * rng.random::<f64>();
                let top = c[1] + (1.0 - s) * bh * rng.random::<f64>();
                [c[0] + dx, top, c[0] + dx + bw, top + s * bh]
            } else {
                let z = DEPTH_M.0 + (DEPTH_M.1 - DEPTH_M.0) * rng.random::<f64>();
                let foot = self.horizon_px + self.focal_px * self.camera_height_m / z;
                let h = self.focal_px * PERSON_HEIGHT_M / z * (0.7 + 0.5 * rng.random::<f64>());
                let cx = img_w * rng.random::<f64>();
                let bw = ASPECT * h;
                [cx - bw / 2.0, foot - h, cx + bw / 2.0, foot]
            };
            clip(&mut b, img_w, img_h);
            let score = (0.45 + 0.15 * unit.sample(rng)).clamp(0.05, 1.0);
            if b[2] - b[0] > 1.0 && b[3] - b[1] > 1.0 {
                detections.push(row(frame, -1, b, score)?);
            }
        }
        Ok(())
    }
}

/// Occlusion by nearer people (larger foot row): the covered fraction of each visible box,
/// from the union approximated by the largest single overlap plus half the rest.
fn occlusion(visible: &[(usize, [f64; 4], [f64; 4])]) -> Vec<f64> {
    visible
        .iter()
        .map(|&(_, _, a)| {
            let area = (a[2] - a[0]) * (a[3] - a[1]);
            let mut overlaps: Vec<f64> = visible
                .iter()
                .filter(|&&(_, _, b)| b[3] > a[3])
                .map(|&(_, _, b)| {
                    let w = (a[2].min(b[2]) - a[0].max(b[0])).max(0.0);
                    let h = (a[3].min(b[3]) - a[1].max(b[1])).max(0.0);
                    w * h / area
                })
                .collect();
            overlaps.sort_by(|x, y| y.total_cmp(x));
            let first = overlaps.first().copied().unwrap_or(0.0);
            let rest: f64 = overlaps.iter().skip(1).sum();
            (first + 0.5 * rest).min(1.0)
        })
        .collect()
}

fn sign(rng: &mut ChaCha8Rng) -> f64 {
    if rng.random::<f64>() < 0.5 { -1.0 } else { 1.0 }
}

fn clip(b: &mut [f64; 4], w: f64, h: f64) {
    b[0] = b[0].clamp(0.0, w);
    b[2] = b[2].clamp(0.0, w);
    b[1] = b[1].clamp(0.0, h);
    b[3] = b[3].clamp(0.0, h);
}

/// A MOTChallenge row for the box [x1, y1, x2, y2] (coordinates rounded to 0.01 px, as the
/// files hold them).
fn row(frame: Frame, id: i64, b: [f64; 4], confidence: f64) -> Result<MotRow> {
    let r = |v: f64| (v * 100.0).round() / 100.0;
    let (left, top) = (r(b[0]), r(b[1]));
    Ok(MotRow {
        frame,
        id,
        bbox: BoundingBox::new(left, top, r(b[2] - left), r(b[3] - top))?,
        confidence: (confidence * 1000.0).round() / 1000.0,
        world: [-1.0; 3],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn seq(config: &WalkersConfig, seed: u64) -> Sequence {
        config
            .generate(&mut ChaCha8Rng::seed_from_u64(seed))
            .unwrap()
    }

    #[test]
    fn the_detector_matches_its_description() {
        let config = WalkersConfig::default();
        let s = seq(&config, 1);
        assert_eq!(s.n_frames, 400);
        // Recall 0.7-0.9 of the truth boxes (0.88 when unoccluded, less when occluded).
        let n_false_expected = 0.5 * 400.0;
        let n_true = s.detections.len() as f64 - n_false_expected;
        let recall = n_true / s.gt.len() as f64;
        assert!((0.65..0.9).contains(&recall), "recall {recall}");
        // Boxes stay in the image and some are cut by the border.
        assert!(s.gt.iter().chain(&s.detections).all(|r| {
            r.bbox.left >= 0.0 && r.bbox.right() <= 960.0 + 1e-9 && r.bbox.bottom() <= 540.0 + 1e-9
        }));
        assert!(s.gt.iter().any(|r| r.bbox.left == 0.0));
        assert!(s.gt.iter().any(|r| (r.bbox.right() - 960.0).abs() < 1e-9));
        // Scores: the best-matching detections score higher on average than unmatched ones.
        let (mut tp, mut fp) = (Vec::new(), Vec::new());
        for d in &s.detections {
            let best =
                s.gt.iter()
                    .filter(|g| g.frame == d.frame)
                    .map(|g| g.bbox.iou(&d.bbox))
                    .fold(0.0, f64::max);
            if best >= 0.5 { &mut tp } else { &mut fp }.push(d.confidence);
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        assert!(mean(&tp) > mean(&fp) + 0.15, "{} {}", mean(&tp), mean(&fp));
        // Overlapping: some false boxes score above the median true box.
        assert!(fp.iter().any(|&c| c > 0.72));
        // Several people over the sequence.
        let ids: std::collections::BTreeSet<i64> = s.gt.iter().map(|r| r.id).collect();
        assert!(ids.len() >= 8, "{}", ids.len());
    }

    #[test]
    fn seeds_reproduce_and_differ() {
        let config = WalkersConfig {
            fps: 10.0,
            duration_s: 20.0,
            ..WalkersConfig::default()
        };
        let (a, b, c) = (seq(&config, 3), seq(&config, 3), seq(&config, 4));
        assert_eq!(a.n_frames, 200);
        assert_eq!(a.detections, b.detections);
        assert_ne!(a.detections, c.detections);
    }

    #[test]
    fn bad_configurations_are_errors() {
        let bad = WalkersConfig {
            fps: 0.0,
            ..WalkersConfig::default()
        };
        assert!(
            bad.generate(&mut ChaCha8Rng::seed_from_u64(0))
                .unwrap_err()
                .to_string()
                .contains("fps")
        );
    }
}
