//! A synthetic pedestrian scene for Oh & Jung's (2015) evaluation protocol, in the shape of
//! their PETS2009 S2L1 sequence: walkers enter from the image border, head roughly across the
//! scene, turn and change speed smoothly, and are seen with Gaussian detector noise. The masked
//! crossings of their true tracks ([`gaps_from_mask`]) become gaps whose methods see only the
//! noisy observations ([`cut_gaps`]); [`scene_window`] chooses one window fit for all the gaps
//! of a scene from those observations.
//!
//! [`SceneConfig::check`] gives the [`Scene`] that draws; every draw comes from the generator
//! passed in, walker by walker.

#[cfg(test)]
mod tests;

use nalgebra::Vector2;
use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};
use tracker_model::{
    Region2, Track, TrackId, TrackPoint, TrackSet, ensure_non_negative, ensure_positive,
};

use crate::error::{Result, invalid_parameter};
use crate::gap::{Baseline, Observation, window_cv_errors};
use crate::protocol::{GapCase, gaps_from_mask};

/// The scene's settings, in pixels and frames. [`SceneConfig::check`] turns them into the
/// [`Scene`] that draws.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneConfig {
    /// Image width (px).
    pub width: f64,
    /// Image height (px).
    pub height: f64,
    /// Walkers, each entering at a random frame of the first half.
    pub n_walkers: usize,
    /// Frames (at least 2).
    pub n_frames: u32,
    /// Mean walking speed (px per frame).
    pub speed: f64,
    /// Standard deviation of the heading's turn-rate change per frame (rad).
    pub turn_noise: f64,
    /// Relative speed drift per frame (standard deviation).
    pub speed_noise: f64,
    /// Detector noise on the observed positions (standard deviation per axis, px).
    pub detection_sigma: f64,
}

impl SceneConfig {
    /// Checks the sizes and noise levels before anything is drawn (an empty range would make
    /// the generator panic) and gives the scene that draws.
    pub fn check(&self) -> Result<Scene> {
        ensure_positive(self.width, "width")?;
        ensure_positive(self.height, "height")?;
        ensure_positive(self.speed, "speed")?;
        ensure_non_negative(self.turn_noise, "turn_noise")?;
        ensure_non_negative(self.speed_noise, "speed_noise")?;
        ensure_non_negative(self.detection_sigma, "detection_sigma")?;
        if self.n_frames < 2 {
            return Err(invalid_parameter(
                "n_frames",
                format!("{} frames; a scene needs at least 2", self.n_frames),
            ));
        }
        Ok(Scene { config: *self })
    }
}

/// A checked [`SceneConfig`]: simulates the walkers.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    config: SceneConfig,
}

/// A masked crossing with what the methods see of it.
#[derive(Debug, Clone, PartialEq)]
pub struct ObservedGap {
    /// The crossing, with the true positions before, inside and after the mask.
    pub case: GapCase,
    /// The noisy observations at the frames of `case.before`.
    pub before: Vec<Observation>,
    /// The noisy observations at the frames of `case.after`.
    pub after: Vec<Observation>,
}

impl Scene {
    /// The settings it was checked from.
    pub fn config(&self) -> &SceneConfig {
        &self.config
    }

    /// One walker: enters at a random frame of the first half from a random border point,
    /// heads for a random point near the centre (so that many walkers cross a central mask),
    /// turns smoothly (an integrated random turn rate, decaying by 0.9 per frame) and changes
    /// speed smoothly (kept within 0.3 to 2 times `speed`), until it leaves the image or the
    /// sequence ends. Returns its true and observed tracks, both labelled `id`, or `None` when
    /// it is in view for fewer than three frames.
    pub fn walker<R: Rng + ?Sized>(&self, id: u64, rng: &mut R) -> Result<Option<(Track, Track)>> {
        let p = &self.config;
        let start = rng.random_range(0..p.n_frames / 2);
        let (w, h) = (p.width, p.height);
        let side = rng.random_range(0..4);
        let along: f64 = rng.random();
        let mut pos = match side {
            0 => Vector2::new(along * w, 1.0),
            1 => Vector2::new(along * w, h - 1.0),
            2 => Vector2::new(1.0, along * h),
            _ => Vector2::new(w - 1.0, along * h),
        };
        // Aim at a point near the centre so that many walkers cross the mask.
        let target = Vector2::new(
            w / 2.0 + rng.random_range(-0.25..0.25) * w,
            h / 2.0 + rng.random_range(-0.25..0.25) * h,
        );
        let mut heading = (target.y - pos.y).atan2(target.x - pos.x);
        let mut turn_rate = 0.0;
        let mut speed = p.speed * rng.random_range(0.7..1.3);
        let (mut truth, mut seen) = (Vec::new(), Vec::new());
        for f in start..p.n_frames {
            if !(0.0..=w).contains(&pos.x) || !(0.0..=h).contains(&pos.y) {
                break;
            }
            truth.push(TrackPoint::at(f, pos));
            let noise: Vector2<f64> = Vector2::from_fn(|_, _| StandardNormal.sample(rng));
            seen.push(TrackPoint::at(f, pos + noise * p.detection_sigma));
            let n: f64 = StandardNormal.sample(rng);
            turn_rate = 0.9 * turn_rate + p.turn_noise * n;
            heading += turn_rate;
            let s: f64 = StandardNormal.sample(rng);
            speed = (speed * (1.0 + p.speed_noise * s)).clamp(0.3 * p.speed, 2.0 * p.speed);
            pos += Vector2::new(heading.cos(), heading.sin()) * speed;
        }
        if truth.len() < 3 {
            return Ok(None);
        }
        Ok(Some((
            Track::from_points(TrackId(id), truth)?,
            Track::from_points(TrackId(id), seen)?,
        )))
    }

    /// Every walker's true and observed tracks (walkers 0, 1, … drawn in order from `rng`;
    /// those in view for fewer than three frames left out).
    pub fn simulate<R: Rng + ?Sized>(&self, rng: &mut R) -> Result<(TrackSet, TrackSet)> {
        let (mut truth, mut seen) = (Vec::new(), Vec::new());
        for id in 0..self.config.n_walkers as u64 {
            if let Some((t, s)) = self.walker(id, rng)? {
                truth.push(t);
                seen.push(s);
            }
        }
        Ok((TrackSet::from_tracks(truth)?, TrackSet::from_tracks(seen)?))
    }
}

/// The masked crossings of the true tracks ([`gaps_from_mask`]), each with the observed
/// positions of the same track at the frames seen before and after it: the gaps are cut from
/// the truth, the methods see the noisy observations. A frame missing from `seen` is left out.
pub fn cut_gaps(truth: &TrackSet, seen: &TrackSet, mask: &Region2) -> Vec<ObservedGap> {
    let observed = |c: &GapCase, side: &[Observation]| -> Vec<Observation> {
        let track = seen.get(c.truth_id);
        side.iter()
            .filter_map(|o| {
                track.and_then(|t| t.at(o.frame)).map(|q| Observation {
                    frame: o.frame,
                    position: q.location.position(),
                })
            })
            .collect()
    };
    gaps_from_mask(truth, mask)
        .into_iter()
        .map(|case| {
            let (before, after) = (observed(&case, &case.before), observed(&case, &case.after));
            ObservedGap {
                case,
                before,
                after,
            }
        })
        .collect()
}

/// One window for every gap of a scene: the candidate of the window fit `method`
/// ([`Baseline::WindowCubic`] or [`Baseline::WindowBSpline`]) with the least cross-validation
/// error ([`window_cv_errors`]) summed over the gaps, chosen from the observations only (the
/// first of equal sums). `None` when no candidate fits every gap; with no gap, the first
/// candidate.
pub fn scene_window(gaps: &[ObservedGap], method: &Baseline) -> Result<Option<usize>> {
    let candidates = match method {
        Baseline::WindowCubic(config) | Baseline::WindowBSpline(config) => &config.candidates,
        _ => {
            return Err(invalid_parameter(
                "method",
                format!("{method:?} has no window to choose"),
            ));
        }
    };
    let mut total = vec![0.0; candidates.len()];
    for gap in gaps {
        for (t, e) in total
            .iter_mut()
            .zip(window_cv_errors(&gap.before, &gap.after, method)?)
        {
            *t += e.unwrap_or(f64::INFINITY);
        }
    }
    let best = (0..total.len())
        .filter(|&k| total[k].is_finite())
        .min_by(|&i, &j| total[i].total_cmp(&total[j]));
    Ok(best.map(|k| candidates[k]))
}
