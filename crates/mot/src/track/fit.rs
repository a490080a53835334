//! The model and the detection-score densities fitted to a file (`[fit]`, `[scores]`).

use super::*;

/// Detections by frame.
type ByFrame = std::collections::BTreeMap<Frame, Vec<MotRow>>;

/// A file's detections by MCMCDA measurement id: frame by frame, file order within a frame,
/// the order in which [`problem_of`] pushes them, so the problem's id of each is its place.
pub(super) struct Detections(Vec<MotRow>);

impl Detections {
    /// None yet, for a problem grown frame by frame.
    pub(super) fn new() -> Self {
        Self(Vec::new())
    }

    /// A frame's detections, pushed to the problem in this order.
    pub(super) fn extend(&mut self, frame: &[MotRow]) {
        self.0.extend_from_slice(frame);
    }

    /// The detection the problem calls `m`.
    pub(super) fn of(&self, m: MeasId) -> &MotRow {
        &self.0[m as usize]
    }

    /// How many.
    pub(super) fn len(&self) -> usize {
        self.0.len()
    }

    /// In id order.
    pub(super) fn iter(&self) -> std::slice::Iter<'_, MotRow> {
        self.0.iter()
    }
}

/// The detections in measurement-id order, and by frame.
pub(super) fn detections_by_frame(rows: &[MotRow]) -> (Detections, ByFrame) {
    let mut by_frame = ByFrame::new();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(*r);
    }
    let detections = Detections(by_frame.values().flatten().copied().collect());
    (detections, by_frame)
}

/// [`detections_by_frame`] and the problem of their centres, with each detection's score
/// ratio when `scores` is given. `new` makes the empty problem: [`Problem::empty`] for
/// MCMCDA's chain, [`Problem::without_neighbourhoods`] for GNN, which reads no neighbourhood
/// (with d̄ = 24 at 25 fps, building them was half of a one-sample online run).
pub(super) fn problem_of(
    model: &mcmcda::Model,
    rows: &[MotRow],
    scores: Option<&ScoreModel>,
    new: fn(&mcmcda::Model, Frame) -> Problem,
) -> Result<(Detections, ByFrame, Problem)> {
    let (detections, by_frame) = detections_by_frame(rows);
    let first = by_frame.keys().next().copied().unwrap_or(0);
    let mut problem = new(model, first);
    for (frame, dets) in &by_frame {
        problem.push_scan_scored(*frame, &centres(dets), &score_ratios(scores, dets))?;
    }
    Ok((detections, by_frame, problem))
}

/// ln f₁(s)/f₀(s) of each detection's score (all 0 without a score model).
pub(super) fn score_ratios(scores: Option<&ScoreModel>, dets: &[MotRow]) -> Vec<f64> {
    dets.iter()
        .map(|d| scores.map_or(0.0, |m| m.log_ratio(d.confidence)))
        .collect()
}

pub(super) fn centres(dets: &[MotRow]) -> Vec<Vec2> {
    dets.iter().map(|d| d.bbox.centre()).collect()
}

/// The model fitted to the detections: starting from `base`, GNN tracks the file and its
/// confident tracks (at least `min_track_detections` detections) give moment estimates, which
/// become the next round's model:
/// - p_d = detections / frames spanned, over the confident tracks;
/// - clutter per frame = detections in no track of three or more / frames of the file;
/// - births per frame = confident tracks / frames, p_z = confident tracks / frames they span;
/// - R and q per axis from the second differences of consecutive detections: with the
///   discrete white-noise-acceleration model (Q = q G Gᵀ), Var(z₊₁ − 2z + z₋₁) = 6R + q/2 and
///   Var(z₊₂ − 2z + z₋₂) = 6R + 5q, solved for R and q;
/// - the newborn velocity variance from the central differences (minus their R/2);
/// - v̄ at least 1.5 times the 99th percentile of the speeds between detections.
///
/// Estimates are clamped to sane ranges, and a round without confident tracks keeps the
/// model it had. `[model]` keys of `--config` override the result.
pub fn fit_model(base: &McmcdaConfig, rows: &[MotRow], fit: &FitConfig) -> Result<McmcdaConfig> {
    let mut config = base.clone();
    for _ in 0..fit.iterations {
        let model = config.check()?;
        let (detections, by_frame, problem) =
            problem_of(&model, rows, None, Problem::without_neighbourhoods)?;
        let (Some(first), Some(last)) = (
            by_frame.keys().next().copied(),
            by_frame.keys().next_back().copied(),
        ) else {
            break;
        };
        let n_frames = f64::from(last - first) + 1.0;
        let gnn = NearestNeighbourConfig::default();
        let tracks = nearest_neighbour_tracks(&model, &problem, problem.all_scans()?, &gnn)?;
        let confident: Vec<&Vec<MeasId>> = tracks
            .iter()
            .filter(|t| t.len() >= fit.min_track_detections)
            .collect();
        if confident.is_empty() {
            break;
        }
        let mut moments = Moments::of(&confident, &problem, &detections);
        let assigned: usize = tracks.iter().filter(|t| t.len() >= 3).map(Vec::len).sum();
        let clutter = (rows.len() as f64 - assigned as f64).max(0.0) / n_frames;
        config.p_detect = (moments.n_det / moments.n_span).clamp(0.3, 0.99);
        config.clutter_per_scan = clutter.clamp(0.01, 1e3);
        config.births_per_scan = (confident.len() as f64 / n_frames).clamp(1e-3, 1e2);
        config.p_disappear = (confident.len() as f64 / moments.n_span).clamp(1e-4, 0.5);
        if !moments.fit_noise_and_speed(&mut config, fit)? {
            break;
        }
    }
    Ok(config)
}

/// The sums of the confident tracks that [`fit_model`]'s moment estimates read.
struct Moments {
    /// Detections, and frames spanned, over the tracks.
    n_det: f64,
    n_span: f64,
    /// Sums of squares per axis, in box widths (x) and heights (y): lag-1 second
    /// differences, lag-2, central velocities; and how many of each.
    v1: [f64; 2],
    v2: [f64; 2],
    vel: [f64; 2],
    n1: f64,
    n2: f64,
    /// Speeds between consecutive detections in box widths per frame, and box sizes.
    speeds: Vec<f64>,
    widths: Vec<f64>,
    heights: Vec<f64>,
}

impl Moments {
    fn of(confident: &[&Vec<MeasId>], problem: &Problem, detections: &Detections) -> Self {
        let size = |m: MeasId| {
            let b = detections.of(m).bbox;
            [b.width, b.height]
        };
        let mut s = Self {
            n_det: 0.0,
            n_span: 0.0,
            v1: [0.0; 2],
            v2: [0.0; 2],
            vel: [0.0; 2],
            n1: 0.0,
            n2: 0.0,
            speeds: Vec::new(),
            widths: Vec::new(),
            heights: Vec::new(),
        };
        for t in confident {
            s.n_det += t.len() as f64;
            let scans: Vec<usize> = t.iter().map(|&m| problem.scan_of(m)).collect();
            s.n_span += (scans[scans.len() - 1] - scans[0] + 1) as f64;
            // Ordered, so that the sums (and the fitted model) do not depend on hashing.
            let at: std::collections::BTreeMap<usize, MeasId> =
                t.iter().map(|&m| (problem.scan_of(m), m)).collect();
            for pair in t.windows(2) {
                let gap = (problem.scan_of(pair[1]) - problem.scan_of(pair[0])) as f64;
                let d = (problem.position(pair[1]) - problem.position(pair[0])).norm() / gap;
                s.speeds.push(d / size(pair[1])[0]);
            }
            for (&scan, &m) in &at {
                let z = problem.position(m);
                let wh = size(m);
                s.widths.push(wh[0]);
                s.heights.push(wh[1]);
                if let (Some(&a), Some(&b)) = (at.get(&(scan.wrapping_sub(1))), at.get(&(scan + 1)))
                {
                    let (a, b) = (problem.position(a), problem.position(b));
                    let d = b - 2.0 * z + a;
                    let v = (b - a) / 2.0;
                    for k in 0..2 {
                        s.v1[k] += (d[k] / wh[k]).powi(2);
                        s.vel[k] += (v[k] / wh[k]).powi(2);
                    }
                    s.n1 += 1.0;
                }
                if let (Some(&a), Some(&b)) = (at.get(&(scan.wrapping_sub(2))), at.get(&(scan + 2)))
                {
                    let d = problem.position(b) - 2.0 * z + problem.position(a);
                    for k in 0..2 {
                        s.v2[k] += (d[k] / wh[k]).powi(2);
                    }
                    s.n2 += 1.0;
                }
            }
        }
        s
    }

    /// R, q, the newborn velocity variance, v̄ and d̄ from the sums (see [`fit_model`]);
    /// `false` when there is no box to scale them by (the fit stops).
    fn fit_noise_and_speed(&mut self, config: &mut McmcdaConfig, fit: &FitConfig) -> Result<bool> {
        let inflation = fit.noise_inflation;
        // The noise grows with the box: the relative moments are turned into pixels at a
        // large box (the 90th percentile of widths and heights), so that gates hold for the
        // nearest people.
        let percentile = |v: &mut Vec<f64>, p: usize| {
            v.sort_by(f64::total_cmp);
            v.get(v.len() * p / 100).copied()
        };
        let (Some(w90), Some(h90)) = (
            percentile(&mut self.widths, 90),
            percentile(&mut self.heights, 90),
        ) else {
            return Ok(false);
        };
        let scale = [w90 * w90, h90 * h90];
        let (v1, v2, vel, n1, n2) = (self.v1, self.v2, self.vel, self.n1, self.n2);
        if n1 >= 10.0 && n2 >= 10.0 {
            let (mut r, mut q) = ([0.0; 2], [0.0; 2]);
            for k in 0..2 {
                let (a, b) = (v1[k] / n1, v2[k] / n2);
                q[k] = ((b - a) / 4.5).max(1e-3 * a.max(1e-9));
                r[k] = ((a - 0.5 * q[k]) / 6.0).max(1e-2 * a.max(1e-9));
            }
            let q_px = (q[0] * scale[0] + q[1] * scale[1]) / 2.0 * inflation;
            config.motion = ConstantVelocity2::mcmcda(config.motion.dt_s(), q_px)?;
            config.measurement_noise = nalgebra::Matrix2::new(
                r[0] * scale[0] * inflation,
                0.0,
                0.0,
                r[1] * scale[1] * inflation,
            );
            let vv = (0..2)
                .map(|k| (vel[k] / n1 - r[k] / 2.0).max(r[k]) * scale[k])
                .fold(0.0, f64::max);
            if let TrackInit::FirstMeasurement { .. } = config.track_init {
                config.track_init = TrackInit::FirstMeasurement {
                    velocity_variance: Some(vv),
                };
            }
        }
        if let Some(p99) = percentile(&mut self.speeds.clone(), 99) {
            config.max_speed = config.max_speed.max(1.5 * p99 * w90);
        }
        // A track may bridge the frames in which its target moves about `gap_box_widths` box
        // widths (an occlusion by a passer-by lasts about that long).
        if let Some(p50) = percentile(&mut self.speeds, 50) {
            let frames = (fit.gap_box_widths / p50.max(1e-3))
                .round()
                .clamp(3.0, 30.0);
            config.max_gap = frames as u32;
        }
        Ok(true)
    }
}

/// The score densities of the file (the amplitude-feature likelihood of Lerro & Bar-Shalom
/// 1993, IEEE AES 29(2), with the detector's confidence as the feature): GNN (`gnn`) tracks
/// the file with `model` (kinematics only); f₁ is the density of the scores of detections in its
/// confident tracks (≥ `min_track_detections`), f₀ of those in no track of three or more
/// (clutter, with some missed true detections in it, which only makes the ratio milder). Each
/// is a Gaussian kernel density (Silverman's bandwidth, 0.9 min(sd, IQR/1.34) n^(−1/5)) with
/// one pseudo-observation spread uniformly over the file's score range, so that a score where
/// one sample is thin does not give an extreme ratio; ln f₁/f₀ is tabulated on 64 points and
/// clamped to ±`max_log_ratio`. None when scores are off, do not vary over the file, or
/// either sample has fewer than 10 scores.
pub fn fit_scores(
    model: &McmcdaConfig,
    rows: &[MotRow],
    fit: &FitConfig,
    gnn: &NearestNeighbourConfig,
    config: &ScoreConfig,
) -> Result<Option<ScoreModel>> {
    if !config.enabled || rows.is_empty() {
        return Ok(None);
    }
    let (lo, hi) = rows
        .iter()
        .map(|r| r.confidence)
        .filter(|s| s.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
            (a.min(s), b.max(s))
        });
    // Also false for NaN bounds (no finite score at all) and for a span beyond f64 (scores
    // near ±1.8e308: the grid's step would be infinite and every density NaN).
    let varies = (hi - lo).is_finite() && hi - lo > 1e-9 * hi.abs().max(1.0);
    if !varies {
        return Ok(None);
    }
    let checked = model.check()?;
    let (detections, _, problem) =
        problem_of(&checked, rows, None, Problem::without_neighbourhoods)?;
    let window = problem.all_scans()?;
    let tracks = nearest_neighbour_tracks(&checked, &problem, window, gnn)?;
    let mut in_track = vec![0usize; detections.len()];
    for t in &tracks {
        for &m in t {
            in_track[m as usize] = t.len();
        }
    }
    let sample = |keep: &dyn Fn(usize) -> bool| -> Vec<f64> {
        detections
            .iter()
            .zip(&in_track)
            .filter(|(d, n)| keep(**n) && d.confidence.is_finite())
            .map(|(d, _)| d.confidence)
            .collect()
    };
    let min_len = fit.min_track_detections;
    let track = sample(&|n| n >= min_len);
    let clutter = sample(&|n| n < 3);
    if track.len() < 10 || clutter.len() < 10 {
        return Ok(None);
    }
    let step = (hi - lo) / (SCORE_GRID - 1) as f64;
    let grid: Vec<f64> = (0..SCORE_GRID).map(|i| lo + step * i as f64).collect();
    let density = |v: &[f64]| score_density(v, &grid, step, hi - lo);
    let (f1, f0) = (density(&track), density(&clutter));
    let bound = config.max_log_ratio;
    let log_ratio = f1
        .iter()
        .zip(&f0)
        .map(|(a, b)| (a.ln() - b.ln()).clamp(-bound, bound))
        .collect();
    Ok(Some(ScoreModel {
        lo,
        hi,
        log_ratio,
        track: moments(&track),
        clutter: moments(&clutter),
    }))
}

/// Size, mean and sample standard deviation.
fn moments(v: &[f64]) -> (usize, f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    (v.len(), mean, sd)
}

/// The density of the scores `v` at the `grid` points: a Gaussian kernel estimate with
/// Silverman's bandwidth (0.9 min(σ, IQR/1.34) n^(−1/5), never narrower than the grid's
/// `step`), mixed with one uniform pseudo-observation over the score range `span` so that no
/// density is 0.
fn score_density(v: &[f64], grid: &[f64], step: f64, span: f64) -> Vec<f64> {
    let (_, _, sd) = moments(v);
    let n = v.len() as f64;
    let mut sorted = v.to_vec();
    sorted.sort_by(f64::total_cmp);
    let iqr = sorted[sorted.len() * 3 / 4] - sorted[sorted.len() / 4];
    let spread = if iqr > 0.0 { sd.min(iqr / 1.34) } else { sd };
    // Never narrower than the grid's step (a constant sample would be a spike).
    let h = (0.9 * spread * n.powf(-0.2)).max(step);
    grid.iter()
        .map(|&x| {
            let kde = v
                .iter()
                .map(|s| (-0.5 * ((x - s) / h).powi(2)).exp())
                .sum::<f64>()
                / (n * h * (2.0 * std::f64::consts::PI).sqrt());
            (n * kde + 1.0 / span) / (n + 1.0)
        })
        .collect()
}
