//! The per-object detector: HOG blocks on a patch resampled so that the object is
//! `cells_w × cells_h` cells, online boosting over the blocks' values, and the colour model;
//! behind tracker-model's [`LocalDetector`] and [`LocalDetectorFactory`].
//!
//! * Search: for each scale s, the square-ish window `search` times the object's size
//!   (times s) centred on the predicted box is resampled (bilinear) to
//!   `search · cells_w · 8 × search · cells_h · 8` pixels and its HOG blocks are computed
//!   once; every object-sized window at a one-cell stride is scored by
//!   (1 − w_c) · (c + 1) / 2 + w_c · ρ, with c the boosting confidence and ρ the Bhattacharyya
//!   coefficient of its colour histogram against the model. The best window (refined by a
//!   parabola through its neighbours' scores) is returned if c > 0 and its score reaches
//!   `min_score`.
//! * Learning (at spawn and on every confirmation): a patch three times the object's size
//!   around the confirmed box; the centre window is the positive, the eight windows one object
//!   away (the annulus) and four nearer ones (two thirds of the width to each side, half the
//!   height above and below) are negatives, each followed by
//!   the positive again so the booster sees the classes balanced; the colour model moves
//!   towards the confirmed box's histogram at `colour_rate`.
//!
//! Scales are searched in parallel (rayon) and reduced in scale order; a detector's random
//! draws (new weak learners) come from its own `ChaCha8Rng` stream, so results do not depend on
//! the thread count.

use std::sync::{Arc, RwLock};

use image::RgbImage;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tracker_model::{
    BoundingBox, Frame, LocalDetector, LocalDetectorFactory, ensure_in_range, ensure_positive,
};

use crate::boost::{BoostConfig, OnlineBooster};
use crate::colour::ColourHistogram;
use crate::error::{Error, Result};
use crate::hog::{BLOCK_LEN, BlockGrid, CELL, OrientedIntegral, Plane};

/// Settings of an [`ImageDetector`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DetectorConfig {
    /// Object height in cells on the resampled patch (width follows the initial box's
    /// aspect, at least 2 cells).
    pub cells_high: usize,
    /// Side of the search window as a multiple of the object's (2).
    pub search: usize,
    /// Scales searched (relative box sizes). One by default: the tracker confirms the box,
    /// size included, every frame; `[0.95, 1.0, 1.05]` also follows size changes on its own,
    /// at three times the cost.
    pub scales: Vec<f64>,
    /// The booster.
    pub boost: BoostConfig,
    /// Colour histogram levels per channel (8).
    pub colour_bins: usize,
    /// w_c: weight of the colour coefficient in the score.
    pub colour_weight: f64,
    /// How fast the colour model follows confirmations.
    pub colour_rate: f64,
    /// Lowest score reported.
    pub min_score: f64,
    /// A box less than this fraction inside the image is neither searched nor learned.
    pub min_inside: f64,
    /// Learning passes over the first patch.
    pub init_rounds: usize,
    /// Subtracted from a window's score per unit of |ln scale|, so that the size changes only
    /// when another scale is clearly better.
    pub scale_penalty: f64,
}

impl Default for DetectorConfig {
    fn default() -> Self {
        Self {
            cells_high: 8,
            search: 2,
            scales: vec![1.0],
            boost: BoostConfig::default(),
            colour_bins: 8,
            colour_weight: 0.3,
            colour_rate: 0.05,
            min_score: 0.55,
            min_inside: 0.5,
            init_rounds: 3,
            scale_penalty: 0.5,
        }
    }
}

impl DetectorConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        ensure_in_range(self.cells_high as f64, 2.0, 64.0, "cells_high")?;
        ensure_in_range(self.search as f64, 1.0, 8.0, "search")?;
        if self.scales.is_empty() {
            return Err(tracker_model::Error::InvalidParameter {
                name: "scales",
                reason: "no scale to search".to_string(),
            }
            .into());
        }
        for &s in &self.scales {
            ensure_positive(s, "scales")?;
        }
        self.boost.check()?;
        ensure_in_range(self.colour_bins as f64, 1.0, 64.0, "colour_bins")?;
        ensure_in_range(self.colour_weight, 0.0, 1.0, "colour_weight")?;
        ensure_in_range(self.colour_rate, 0.0, 1.0, "colour_rate")?;
        ensure_in_range(self.min_score, 0.0, 1.0, "min_score")?;
        ensure_in_range(self.min_inside, 0.0, 1.0, "min_inside")?;
        ensure_in_range(self.scale_penalty, 0.0, f64::INFINITY, "scale_penalty")?;
        Ok(())
    }
}

/// What a search found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Detection {
    /// The box in image pixels.
    pub bbox: BoundingBox,
    /// The combined score in [0, 1].
    pub score: f64,
    /// The boosting confidence c ∈ [−1, 1].
    pub boost: f64,
    /// The Bhattacharyya coefficient ρ ∈ [0, 1].
    pub colour: f64,
}

/// A patch resampled around a box: its pixels, HOG blocks and the map back to the image.
struct Patch {
    plane: Plane,
    width: usize,
    /// Image coordinates of the patch's (0, 0) corner and pixels of the patch per image pixel.
    origin: (f64, f64),
    scale: (f64, f64),
}

/// Fraction of `b` inside a `w × h` image.
fn inside_fraction(b: &BoundingBox, w: f64, h: f64) -> f64 {
    let ix = (b.right().min(w) - b.left.max(0.0)).max(0.0);
    let iy = (b.bottom().min(h) - b.top.max(0.0)).max(0.0);
    ix * iy / b.area().max(f64::MIN_POSITIVE)
}

/// Resamples (bilinear, edges clamped) the region `k` objects wide centred on `b` so the
/// object is `cw × ch` cells.
fn patch(image: &RgbImage, b: &BoundingBox, k: usize, cw: usize, ch: usize) -> Option<Patch> {
    let (iw, ih) = (image.width() as usize, image.height() as usize);
    let (pw, ph) = (k * cw * CELL, k * ch * CELL);
    let scale = (
        (cw * CELL) as f64 / b.width.max(1e-6),
        (ch * CELL) as f64 / b.height.max(1e-6),
    );
    let c = b.centre();
    let origin = (
        c.x - k as f64 * b.width / 2.0,
        c.y - k as f64 * b.height / 2.0,
    );
    let raw = image.as_raw();
    let mut rgb = vec![0.0f32; pw * ph * 3];
    // Source coordinates of each column, precomputed.
    let cols: Vec<(usize, usize, f32)> = (0..pw)
        .map(|u| {
            let x = (origin.0 + (u as f64 + 0.5) / scale.0 - 0.5).clamp(0.0, (iw - 1) as f64);
            let x0 = x.floor() as usize;
            (x0, (x0 + 1).min(iw - 1), (x - x0 as f64) as f32)
        })
        .collect();
    for v in 0..ph {
        let y = (origin.1 + (v as f64 + 0.5) / scale.1 - 0.5).clamp(0.0, (ih - 1) as f64);
        let y0 = y.floor() as usize;
        let y1 = (y0 + 1).min(ih - 1);
        let fy = (y - y0 as f64) as f32;
        let (r0, r1) = (
            &raw[y0 * iw * 3..(y0 + 1) * iw * 3],
            &raw[y1 * iw * 3..(y1 + 1) * iw * 3],
        );
        let out = &mut rgb[v * pw * 3..(v + 1) * pw * 3];
        for (u, &(x0, x1, fx)) in cols.iter().enumerate() {
            for ch in 0..3 {
                let a = f32::from(r0[x0 * 3 + ch]) * (1.0 - fx) + f32::from(r0[x1 * 3 + ch]) * fx;
                let b = f32::from(r1[x0 * 3 + ch]) * (1.0 - fx) + f32::from(r1[x1 * 3 + ch]) * fx;
                out[u * 3 + ch] = a * (1.0 - fy) + b * fy;
            }
        }
    }
    let plane = Plane::new(pw, ph, 3, rgb).ok()?;
    Some(Patch {
        plane,
        width: pw,
        origin,
        scale,
    })
}

/// The detector of one object.
pub struct ImageDetector {
    config: DetectorConfig,
    cells_w: usize,
    cells_h: usize,
    booster: OnlineBooster,
    colour: ColourHistogram,
    rng: ChaCha8Rng,
    /// Whether a first patch has been learned.
    trained: bool,
    feed: FrameFeed,
}

impl ImageDetector {
    /// A detector for the object in `initial`, trained on `image` if given; random draws from
    /// `rng`.
    pub fn new(
        config: DetectorConfig,
        image: Option<&RgbImage>,
        initial: &BoundingBox,
        mut rng: ChaCha8Rng,
        feed: FrameFeed,
    ) -> Result<Self> {
        config.check()?;
        let cells_h = config.cells_high;
        let aspect = initial.width / initial.height.max(1e-6);
        let cells_w = ((cells_h as f64 * aspect).round() as usize).clamp(2, 4 * cells_h);
        let n_features = (cells_w - 1) * (cells_h - 1) * BLOCK_LEN;
        let booster = OnlineBooster::new(config.boost, n_features, &mut rng)?;
        let mut d = Self {
            colour: ColourHistogram::empty(config.colour_bins),
            config,
            cells_w,
            cells_h,
            booster,
            rng,
            trained: false,
            feed,
        };
        if let Some(image) = image {
            for _ in 0..d.config.init_rounds.max(1) {
                d.learn(image, initial);
            }
        }
        Ok(d)
    }

    /// Whether the detector has learned from at least one patch.
    pub fn is_trained(&self) -> bool {
        self.trained
    }

    /// The object's size on the resampled patch, in cells (width, height).
    pub fn cells(&self) -> (usize, usize) {
        (self.cells_w, self.cells_h)
    }

    fn feature_at<'a>(
        &self,
        blocks: &'a BlockGrid,
        x0: usize,
        y0: usize,
    ) -> impl Fn(usize) -> f64 + 'a {
        let bw = self.cells_w - 1;
        move |f: usize| {
            let (b, k) = (f / BLOCK_LEN, f % BLOCK_LEN);
            f64::from(blocks.value(x0 + b % bw, y0 + b / bw, k))
        }
    }

    /// The colour histogram of the object-sized window with top-left pixel (px, py).
    fn window_colour(&self, p: &Patch, px: usize, py: usize) -> ColourHistogram {
        let rect = [px, py, px + self.cells_w * CELL, py + self.cells_h * CELL];
        ColourHistogram::of_rect(p.plane.data(), p.width, rect, 2, self.config.colour_bins)
    }

    /// Learns the object in box `at` of `image` (positives and annulus negatives, colour).
    pub fn learn(&mut self, image: &RgbImage, at: &BoundingBox) {
        let (iw, ih) = (f64::from(image.width()), f64::from(image.height()));
        if inside_fraction(at, iw, ih) < self.config.min_inside {
            return;
        }
        let (cw, ch) = (self.cells_w, self.cells_h);
        let Some(p) = patch(image, at, 3, cw, ch) else {
            return;
        };
        let Ok(blocks) = BlockGrid::compute(&p.plane) else {
            return;
        };
        let mut negatives: Vec<(usize, usize)> = Vec::with_capacity(10);
        for y in [0, ch, 2 * ch] {
            for x in [0, cw, 2 * cw] {
                if (x, y) != (cw, ch) {
                    negatives.push((x, y));
                }
            }
        }
        // Nearer negatives: about two thirds of the width and half the height away.
        let (sx, sy) = (
            ((2 * cw) as f64 / 3.0).round().max(1.0) as usize,
            (ch / 2).max(1),
        );
        for (x, y) in [(cw - sx, ch), (cw + sx, ch), (cw, ch - sy), (cw, ch + sy)] {
            negatives.push((x, y));
        }
        let mut rng = self.rng.clone();
        {
            let pos = self.feature_at(&blocks, cw, ch);
            // Positive first so every weak learner has seen it.
            let booster = &mut self.booster;
            booster.update(&pos, true, &mut rng);
            for &(x, y) in &negatives {
                let bw = cw - 1;
                let blocks = &blocks;
                let neg = move |f: usize| {
                    let (b, k) = (f / BLOCK_LEN, f % BLOCK_LEN);
                    f64::from(blocks.value(x + b % bw, y + b / bw, k))
                };
                booster.update(neg, false, &mut rng);
                booster.update(&pos, true, &mut rng);
            }
        }
        self.rng = rng;
        let seen = self.window_colour(&p, cw * CELL, ch * CELL);
        if self.trained {
            self.colour.blend(&seen, self.config.colour_rate as f32);
        } else {
            self.colour = seen;
        }
        self.trained = true;
    }

    /// Searches `image` around `around`: the best window over every scale with its score, or
    /// `None` (untrained, box mostly outside the image, or nothing above the thresholds).
    ///
    /// Windows are tried every `X_STEP` pixels across and `Y_STEP` down on the resampled
    /// patch: one integral of the orientation votes per scale gives the cell grids at every
    /// sub-cell offset. The colour coefficient is computed for the `COLOUR_CANDIDATES`
    /// windows of each scale the booster likes best.
    pub fn search(&self, image: &RgbImage, around: &BoundingBox) -> Option<Detection> {
        let (iw, ih) = (f64::from(image.width()), f64::from(image.height()));
        if !self.trained || inside_fraction(around, iw, ih) < self.config.min_inside {
            return None;
        }
        let (cw, ch) = (self.cells_w, self.cells_h);
        // Per scale: (score, conf, rho, px, py), and the patch.
        let per_scale: Vec<Option<(Patch, Candidate)>> = self
            .config
            .scales
            .par_iter()
            .map(|&s| self.search_scale(image, around, s))
            .collect();
        // Best over scales (ties: the earlier scale).
        let (p, (score, conf, rho, px, py)) = per_scale.iter().flatten().fold(
            None,
            |acc: Option<&(Patch, Candidate)>, x| match acc {
                Some(a) if a.1.0 >= x.1.0 => Some(a),
                _ => Some(x),
            },
        )?;
        if *conf <= 0.0 || *score < self.config.min_score {
            return None;
        }
        let bbox = BoundingBox {
            left: p.origin.0 + *px as f64 / p.scale.0,
            top: p.origin.1 + *py as f64 / p.scale.1,
            width: (cw * CELL) as f64 / p.scale.0,
            height: (ch * CELL) as f64 / p.scale.1,
        };
        Some(Detection {
            bbox,
            score: *score,
            boost: *conf,
            colour: *rho,
        })
    }

    /// The best window at scale `s`: the patch `search` times the box (times s) around its
    /// centre, the `COLOUR_CANDIDATES` windows the booster likes best, and among them the best
    /// by (1 − w_c)(c + 1)/2 + w_c ρ minus the scale penalty (ties: the booster's order).
    /// `None` when the patch is empty or has no window.
    fn search_scale(
        &self,
        image: &RgbImage,
        around: &BoundingBox,
        s: f64,
    ) -> Option<(Patch, Candidate)> {
        let (cw, ch, k) = (self.cells_w, self.cells_h, self.config.search);
        let wc = self.config.colour_weight;
        let c = around.centre();
        let b = BoundingBox {
            left: c.x - around.width * s / 2.0,
            top: c.y - around.height * s / 2.0,
            width: around.width * s,
            height: around.height * s,
        };
        let p = patch(image, &b, k, cw, ch)?;
        let mut boosted = self.boosted_windows(&p);
        // Best first; ties in a fixed order (top-left first).
        let order = |a: &(f64, usize, usize), b: &(f64, usize, usize)| {
            b.0.total_cmp(&a.0).then(a.2.cmp(&b.2)).then(a.1.cmp(&b.1))
        };
        if boosted.len() > COLOUR_CANDIDATES {
            boosted.select_nth_unstable_by(COLOUR_CANDIDATES, order);
            boosted.truncate(COLOUR_CANDIDATES);
        }
        boosted.sort_by(order);
        let penalty = self.config.scale_penalty * s.ln().abs();
        let best = boosted
            .iter()
            .map(|&(conf, px, py)| {
                let rho = if wc > 0.0 {
                    self.window_colour(&p, px, py).bhattacharyya(&self.colour)
                } else {
                    0.0
                };
                let score = (1.0 - wc) * (conf + 1.0) / 2.0 + wc * rho - penalty;
                (score, conf, rho, px, py)
            })
            .fold(None, |acc: Option<Candidate>, x| match acc {
                Some(a) if a.0 >= x.0 => Some(a),
                _ => Some(x),
            })?;
        Some((p, best))
    }

    /// The boosting confidence of every object-sized window of patch `p`, every `X_STEP`
    /// pixels across and `Y_STEP` down, as (confidence, left, top): one integral of the
    /// orientation votes gives the HOG cell grid (Dalal & Triggs 2005) at each sub-cell
    /// offset, and its blocks feed the online booster (Grabner & Bischof 2006).
    fn boosted_windows(&self, p: &Patch) -> Vec<(f64, usize, usize)> {
        let (cw, ch, k) = (self.cells_w, self.cells_h, self.config.search);
        let integral = OrientedIntegral::compute(&p.plane);
        let (max_px, max_py) = ((k - 1) * cw * CELL, (k - 1) * ch * CELL);
        let mut boosted: Vec<(f64, usize, usize)> =
            Vec::with_capacity((CELL / X_STEP) * (CELL / Y_STEP) * (k * cw) * (k * ch));
        for oy in (0..CELL).step_by(Y_STEP) {
            for ox in (0..CELL).step_by(X_STEP) {
                let Some(cells) = integral.cells(ox, oy) else {
                    continue;
                };
                let blocks = BlockGrid::from_cells(&cells);
                for py in (oy..=max_py).step_by(CELL) {
                    for px in (ox..=max_px).step_by(CELL) {
                        let (x0, y0) = (px / CELL, py / CELL);
                        if x0 + cw > cells.cells_x() || y0 + ch > cells.cells_y() {
                            continue;
                        }
                        let conf = self
                            .booster
                            .soft_confidence(self.feature_at(&blocks, x0, y0));
                        boosted.push((conf, px, py));
                    }
                }
            }
        }
        boosted
    }
}

/// A scored window: (score, boosting confidence, colour coefficient, left, top) on the patch.
type Candidate = (f64, f64, f64, usize, usize);

/// Horizontal step between searched windows on the resampled patch (pixels).
pub const X_STEP: usize = 2;
/// Vertical step between searched windows on the resampled patch (pixels).
pub const Y_STEP: usize = 4;
/// Windows per scale whose colour is compared.
pub const COLOUR_CANDIDATES: usize = 8;

impl LocalDetector for ImageDetector {
    fn detect(&mut self, frame: Frame, around: &BoundingBox) -> Option<BoundingBox> {
        let image = self.feed.get(frame)?;
        self.search(&image, around).map(|d| d.bbox)
    }

    fn confirm(&mut self, frame: Frame, confirmed: &BoundingBox) {
        if let Some(image) = self.feed.get(frame) {
            self.learn(&image, confirmed);
        }
    }
}

/// A frame's number and picture.
type Picture = (Frame, Arc<RgbImage>);

/// The current frame, shared by the code that reads the video and every detector: the
/// caller sets frame k's image before running the tracker on frame k.
#[derive(Debug, Clone, Default)]
pub struct FrameFeed {
    current: Arc<RwLock<Option<Picture>>>,
}

impl FrameFeed {
    /// An empty feed.
    pub fn new() -> Self {
        Self::default()
    }

    /// Makes `image` the picture of `frame`.
    pub fn set(&self, frame: Frame, image: Arc<RgbImage>) {
        if let Ok(mut g) = self.current.write() {
            *g = Some((frame, image));
        }
    }

    /// The picture of `frame`, if it is the current one.
    pub fn get(&self, frame: Frame) -> Option<Arc<RgbImage>> {
        let g = self.current.read().ok()?;
        g.as_ref()
            .filter(|(f, _)| *f == frame)
            .map(|(_, im)| Arc::clone(im))
    }
}

/// Spawns [`ImageDetector`]s reading frames from a [`FrameFeed`]; detector i draws from
/// ChaCha8(`seed`) stream i.
pub struct ImageDetectors {
    config: DetectorConfig,
    feed: FrameFeed,
    seed: u64,
    spawned: u64,
}

impl ImageDetectors {
    /// A factory; the configuration is checked here.
    pub fn new(config: DetectorConfig, feed: FrameFeed, seed: u64) -> Result<Self> {
        config.check()?;
        Ok(Self {
            config,
            feed,
            seed,
            spawned: 0,
        })
    }

    /// The feed its detectors read.
    pub fn feed(&self) -> &FrameFeed {
        &self.feed
    }

    /// Detectors spawned so far.
    pub fn spawned(&self) -> u64 {
        self.spawned
    }

    /// A detector for the object in `initial` at `frame`, as its concrete type (trained on
    /// the feed's image if it holds `frame`).
    pub fn detector(&mut self, frame: Frame, initial: &BoundingBox) -> Result<ImageDetector> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(self.spawned);
        self.spawned += 1;
        let image = self.feed.get(frame);
        ImageDetector::new(
            self.config.clone(),
            image.as_deref(),
            initial,
            rng,
            self.feed.clone(),
        )
    }
}

impl LocalDetectorFactory for ImageDetectors {
    fn spawn(&mut self, frame: Frame, initial: &BoundingBox) -> Box<dyn LocalDetector> {
        match self.detector(frame, initial) {
            Ok(d) => Box::new(d),
            // The configuration was checked in `new`, so this does not happen; a detector that
            // never finds anything is the safe answer if it does.
            Err(_) => Box::new(Blind),
        }
    }
}

/// A detector that never finds anything.
struct Blind;

impl LocalDetector for Blind {
    fn detect(&mut self, _frame: Frame, _around: &BoundingBox) -> Option<BoundingBox> {
        None
    }
}

/// Runs `detect` of every detector on `frame` in parallel (one task per detector, results
/// in detector order): for callers that drive many [`ImageDetector`]s themselves.
pub fn detect_all(
    detectors: &mut [ImageDetector],
    frame: Frame,
    around: &[BoundingBox],
) -> Result<Vec<Option<BoundingBox>>> {
    same_count(detectors, around)?;
    Ok(detectors
        .par_iter_mut()
        .zip(around.par_iter())
        .map(|(d, a)| d.detect(frame, a))
        .collect())
}

/// One box per detector, or [`Error::BoxCount`] (a zip would silently drop the extra ones).
fn same_count(detectors: &[ImageDetector], boxes: &[BoundingBox]) -> Result<()> {
    if detectors.len() == boxes.len() {
        Ok(())
    } else {
        Err(Error::BoxCount {
            detectors: detectors.len(),
            boxes: boxes.len(),
        })
    }
}

/// Runs `confirm` of every detector on `frame` in parallel (each learns from its own box and
/// draws from its own random stream, so the result does not depend on the thread count).
pub fn confirm_all(
    detectors: &mut [ImageDetector],
    frame: Frame,
    confirmed: &[BoundingBox],
) -> Result<()> {
    same_count(detectors, confirmed)?;
    detectors
        .par_iter_mut()
        .zip(confirmed.par_iter())
        .for_each(|(d, b)| d.confirm(frame, b));
    Ok(())
}
