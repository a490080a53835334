//! `video-mog`: the camera nodes of Kushwaha et al. (MFI 2008) on rendered scenes. The
//! adaptive background mixture of KaewTraKulPong & Bowden (2001) with OpenCV's defaults and
//! shadow detection segments people and a vehicle crossing a textured ground plane under
//! illumination drift, swaying foliage, glint and sensor noise. Reports foreground precision,
//! recall and F against the renderer's truth masks, the fraction of cast-shadow pixels labelled
//! shadow, one frame's mask beside the truth, and that frame's 160-angle profile against the
//! objects' true bearings.

use anyhow::Result;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use sensors_video::{
    AngleProfiler, BackgroundModel, DetectionFilter, DetectionFilterConfig, MogConfig, ObjectKind,
    PixelFormat, PostConfig, RenderedFrame, SHADOW, Scene, SceneConfig, SceneObject, clean,
};
use serde::Deserialize;

use crate::pipelines::mcmcda::mean_ci;
use crate::{
    Chart, Claim, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style, Table, fmt_num,
};

/// The `video-mog` pipeline.
pub struct VideoMog;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Rendered scenes, each on its own generator stream.
    n_runs: usize,
    /// Frames per scene (10 frames/s).
    n_frames: usize,
    /// Frames before this one are learning and not scored.
    score_from: usize,
    /// People per scene (plus one vehicle).
    n_people: usize,
    /// The frame of run 0 shown as mask and angle profile.
    plot_frame: usize,
    /// Angles of the profile.
    n_angles: usize,
    /// The mixture.
    mog: MogConfig,
    /// Morphology and blob filter.
    post: PostConfig,
    /// The detection-function filters.
    filter: DetectionFilterConfig,
}

/// One scene's scores.
#[derive(Debug, Clone, Copy)]
struct RunScore {
    tp: usize,
    fp: usize,
    fn_: usize,
    shadow_hit: usize,
    shadow_total: usize,
}

impl RunScore {
    fn precision(&self) -> f64 {
        self.tp as f64 / (self.tp + self.fp).max(1) as f64
    }
    fn recall(&self) -> f64 {
        self.tp as f64 / (self.tp + self.fn_).max(1) as f64
    }
    fn f(&self) -> f64 {
        2.0 * self.tp as f64 / (2 * self.tp + self.fp + self.fn_).max(1) as f64
    }
    fn shadow_rate(&self) -> f64 {
        self.shadow_hit as f64 / self.shadow_total.max(1) as f64
    }
}

/// What the pipeline computed.
pub struct Output {
    runs: Vec<RunScore>,
    /// Run 0 at the plot frame: truth and detected foreground pixels (x, −y).
    truth_px: Vec<(f64, f64)>,
    detected_px: Vec<(f64, f64)>,
    shadow_px: Vec<(f64, f64)>,
    /// (relative angle °, raw count) and (relative angle °, filtered count).
    profile: Vec<(f64, f64)>,
    filtered: Vec<(f64, f64)>,
    /// True relative bearings (°) of the objects visible in the plot frame.
    true_bearings_deg: Vec<f64>,
    /// For each visible object, |bearing − nearest bin with a filtered count ≥ half the max|.
    peak_errors_deg: Vec<f64>,
    n_frames: usize,
    score_from: usize,
}

fn scene(p: &Params, rng: &mut ChaCha8Rng) -> Result<Scene> {
    let cfg = SceneConfig::small();
    let mut objects = Vec::new();
    for i in 0..=p.n_people {
        let kind = if i == p.n_people {
            ObjectKind::Vehicle
        } else {
            ObjectKind::Person
        };
        let x = rng.random_range(10.0..22.0);
        let dir = if i % 2 == 0 { 1.0 } else { -1.0 };
        let speed = if kind == ObjectKind::Vehicle {
            3.0
        } else {
            rng.random_range(1.0..1.8)
        };
        let appear_s = 10.0 + 2.0 * i as f64;
        objects.push(SceneObject {
            kind,
            start_m: [x, -dir * 0.55 * x - dir * speed * appear_s],
            velocity_mps: [0.0, dir * speed],
            colour: [rng.random(), rng.random(), rng.random()],
            appear_s,
            vanish_s: 1e9,
        });
    }
    Ok(Scene::new(cfg, objects, rng)?)
}

/// One rendered scene (run `r`, drawn from `rng`): every frame through the background mixture
/// of KaewTraKulPong & Bowden (2001), the clean-up and the angle profile of Kushwaha et al.'s
/// camera node (MFI 2008); frames from `score_from` on are scored, and run 0's plot frame is
/// kept for the figures.
fn run_scene(p: &Params, r: usize, rng: &mut ChaCha8Rng) -> Result<(RunScore, Option<Output>)> {
    let scene = scene(p, rng)?;
    let cam = scene.config().camera;
    let (w, h) = (cam.width, cam.height);
    let profiler = AngleProfiler::new(cam, p.n_angles)?;
    let mut filter = DetectionFilter::new(p.filter);
    let mut model = BackgroundModel::new(&p.mog, w, h, PixelFormat::Rgb)?;
    let mut s = RunScore {
        tp: 0,
        fp: 0,
        fn_: 0,
        shadow_hit: 0,
        shadow_total: 0,
    };
    let mut plot = None;
    for k in 0..p.n_frames {
        let frame = scene.render(k, rng)?;
        let mask = model.apply(&frame.frame)?;
        let c = clean(&mask, &p.post)?;
        let counts = profiler.counts(&c.foreground)?;
        let filtered = filter.apply(&counts);
        if k >= p.score_from {
            score_frame(&mut s, &frame, &c.foreground, &mask.labels, w * h);
        }
        if r == 0 && k == p.plot_frame {
            let plotted = PlotFrame {
                frame: &frame,
                foreground: &c.foreground,
                labels: &mask.labels,
                counts: &counts,
                filtered: &filtered,
            };
            plot = Some(plot_output(p, &profiler, &plotted, w, h, cam.heading_rad));
        }
    }
    Ok((s, plot))
}

/// Adds one frame's foreground against the renderer's truth mask (true and false positives,
/// misses) and its cast-shadow pixels labelled shadow to `s`, over the first `n_pixels`.
fn score_frame(
    s: &mut RunScore,
    frame: &RenderedFrame,
    foreground: &[bool],
    labels: &[u8],
    n_pixels: usize,
) {
    for i in 0..n_pixels {
        match (foreground[i], frame.truth[i]) {
            (true, true) => s.tp += 1,
            (true, false) => s.fp += 1,
            (false, true) => s.fn_ += 1,
            _ => {}
        }
        if frame.shadow[i] {
            s.shadow_total += 1;
            s.shadow_hit += usize::from(labels[i] == SHADOW);
        }
    }
}

/// The plotted frame: the rendering with its truth, the cleaned foreground, the mixture's
/// labels and the angle profile before and after the detection-function filters.
struct PlotFrame<'a> {
    frame: &'a RenderedFrame,
    foreground: &'a [bool],
    labels: &'a [u8],
    counts: &'a [f64],
    filtered: &'a [f64],
}

/// The figures' data from the plotted frame: truth, detected and shadow pixels, the angle
/// profile, the visible objects' true bearings relative to the camera axis, and each
/// bearing's distance to the nearest bin with a filtered count ≥ half the maximum.
fn plot_output(
    p: &Params,
    profiler: &AngleProfiler,
    plotted: &PlotFrame<'_>,
    w: usize,
    h: usize,
    heading_rad: f64,
) -> Output {
    let PlotFrame {
        frame,
        foreground,
        labels,
        counts,
        filtered,
    } = plotted;
    let px = |f: &dyn Fn(usize) -> bool| -> Vec<(f64, f64)> {
        (0..w * h)
            .filter(|&i| f(i))
            .map(|i| ((i % w) as f64, (i / w) as f64))
            .collect()
    };
    let angle = |b: usize| profiler.bin_angle_rad(b).to_degrees();
    let visible: Vec<usize> = frame.boxes.iter().map(|b| b.0).collect();
    let true_bearings_deg: Vec<f64> = frame
        .bearings_rad
        .iter()
        .filter(|(i, _)| visible.contains(i))
        .map(|(_, b)| (b - heading_rad).to_degrees())
        .collect();
    let max = filtered.iter().copied().fold(0.0, f64::max);
    let peak_errors_deg = true_bearings_deg
        .iter()
        .map(|t| {
            (0..filtered.len())
                .filter(|&b| max > 0.0 && filtered[b] >= 0.5 * max)
                .map(|b| (angle(b) - t).abs())
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    Output {
        runs: Vec::new(),
        truth_px: px(&|i| frame.truth[i]),
        detected_px: px(&|i| foreground[i]),
        shadow_px: px(&|i| labels[i] == SHADOW),
        profile: counts
            .iter()
            .enumerate()
            .map(|(b, v)| (angle(b), *v))
            .collect(),
        filtered: filtered
            .iter()
            .enumerate()
            .map(|(b, v)| (angle(b), *v))
            .collect(),
        true_bearings_deg,
        peak_errors_deg,
        n_frames: p.n_frames,
        score_from: p.score_from,
    }
}

impl Pipeline for VideoMog {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, _env: &Env<'_>) -> Result<Output> {
        anyhow::ensure!(p.n_runs >= 2, "n_runs must be at least 2 for an interval");
        anyhow::ensure!(
            p.score_from < p.n_frames && p.plot_frame < p.n_frames,
            "frames out of range"
        );
        let base = rng.clone();
        let runs = (0..p.n_runs)
            .into_par_iter()
            .map(|r| {
                let mut rng = base.clone();
                rng.set_stream(r as u64);
                run_scene(p, r, &mut rng)
            })
            .collect::<Result<Vec<_>>>()?;
        let mut out = None;
        let mut scores = Vec::new();
        for (s, plot) in runs {
            scores.push(s);
            if plot.is_some() {
                out = plot;
            }
        }
        let mut out = out.ok_or_else(|| anyhow::anyhow!("run 0 produced no plot frame"))?;
        out.runs = scores;
        Ok(out)
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let m = Self::metrics(out);
        vec![
            Headline::of_metrics(
                &m,
                "foreground F-measure (background mixture, shadows removed)",
                (
                    "foreground_f_measure_mean",
                    Some("foreground_f_measure_ci95"),
                ),
                None,
            ),
            Headline::of_metrics(
                &m,
                "shadow pixels recognised as shadow",
                (
                    "foreground_shadow_rate_mean",
                    Some("foreground_shadow_rate_ci95"),
                ),
                None,
            ),
        ]
    }

    fn metrics(out: &Output) -> Metrics {
        let mut m = Metrics::new();
        let stat = |f: fn(&RunScore) -> f64| mean_ci(out.runs.iter().map(f));
        for (name, f) in [
            ("precision", RunScore::precision as fn(&RunScore) -> f64),
            ("recall", RunScore::recall),
            ("f_measure", RunScore::f),
            ("shadow_rate", RunScore::shadow_rate),
        ] {
            let (mean, ci) = stat(f);
            m.insert(format!("foreground_{name}_mean"), mean);
            m.insert(format!("foreground_{name}_ci95"), ci);
        }
        let max_err = out.peak_errors_deg.iter().copied().fold(0.0, f64::max);
        m.insert("profile_max_peak_error_deg".into(), max_err);
        m
    }

    fn claims(out: &Output) -> Vec<Claim> {
        let (f, _) = mean_ci(out.runs.iter().map(RunScore::f));
        let (p, _) = mean_ci(out.runs.iter().map(RunScore::precision));
        let (sh, _) = mean_ci(out.runs.iter().map(RunScore::shadow_rate));
        vec![
            Claim::new("mean foreground precision ≥ 0.95", p >= 0.95),
            Claim::new("mean foreground F-measure ≥ 0.9", f >= 0.9),
            Claim::new("mean shadow detection rate ≥ 0.8", sh >= 0.8),
            Claim::new(
                "in the plotted frame every visible object's bearing lies within 3° of a profile bin at ≥ half the maximum",
                !out.peak_errors_deg.is_empty() && out.peak_errors_deg.iter().all(|e| *e <= 3.0),
            ),
        ]
    }

    fn present(out: &Output) -> Section {
        Section {
            title: "Camera nodes: adaptive background mixture, shadows and angle profiles".into(),
            summary: summary(out),
            tables: vec![per_run_table(out)],
            figures: vec![mask_figure(out), profile_figure(out)],
        }
    }
}

/// The report's summary: the mixture of KaewTraKulPong & Bowden (2001) with OpenCV's
/// defaults on the rendered scenes, what was tuned where, and where it loses.
fn summary(out: &Output) -> String {
    let worst = out
        .runs
        .iter()
        .map(RunScore::f)
        .fold(f64::INFINITY, f64::min);
    format!(
        "KaewTraKulPong & Bowden's mixture with OpenCV bgsegm defaults (K = 5, L = 200, T = 0.7, \
         λ = 2.5, σ floor 15) and Horprasert-style shadows on rendered 160 × 120 colour scenes: \
         people and a vehicle of random colours cross a textured ground plane with ±10 % \
         illumination drift, swaying foliage, glint and noise σ = 3; intervals are 1.96·s/√n \
         over {} scenes. The post-processing and the shadow chromaticity threshold were chosen \
         on renderer seeds 1–3 of the unit tests, not on these streams. Where it loses: \
         precision stays high but recall drops on scenes where an object's colour is close \
         to the ground (camouflage, which no per-pixel colour model sees) or dark with the \
         ground's chromaticity (taken for shadow); the worst scene's F is {}. The angle \
         profile's peaks sit on the objects' true bearings (grey lines).",
        out.runs.len(),
        fmt_num(worst)
    )
}

/// The per-run table: each scene's foreground precision, recall and F against the truth
/// masks and its shadow detection rate, then their mean ± 95 % CI.
fn per_run_table(out: &Output) -> Table {
    let mut per_run = Table::new(
        &format!(
            "Foreground against the truth masks, frames {}–{} of each rendered scene (mask after closing and small-blob removal; shadows excluded)",
            out.score_from,
            out.n_frames - 1
        ),
        &[
            "run",
            "precision",
            "recall",
            "F",
            "shadow pixels labelled shadow",
        ],
    );
    for (r, s) in out.runs.iter().enumerate() {
        per_run.row(vec![
            r.to_string(),
            fmt_num(s.precision()),
            fmt_num(s.recall()),
            fmt_num(s.f()),
            fmt_num(s.shadow_rate()),
        ]);
    }
    let ci = |f: fn(&RunScore) -> f64| {
        let (m, c) = mean_ci(out.runs.iter().map(f));
        format!("{} ± {}", fmt_num(m), fmt_num(c))
    };
    per_run.row(vec![
        "mean ± 95 % CI".into(),
        ci(RunScore::precision),
        ci(RunScore::recall),
        ci(RunScore::f),
        ci(RunScore::shadow_rate),
    ]);
    per_run
}

/// The "mask-vs-truth" figure: run 0's plotted frame, truth object pixels, detected
/// foreground and pixels labelled shadow, in image coordinates.
fn mask_figure(out: &Output) -> Figure {
    Figure::new(
        "mask-vs-truth",
        "Run 0, plotted frame: truth object pixels, detected foreground and pixels labelled shadow",
        Chart::new(
            "Foreground mask against the truth",
            "column (px)",
            "row (px, growing downward)",
            vec![
                Series::new("truth inside", out.truth_px.clone(), Style::Markers, 7),
                Series::new("detected", out.detected_px.clone(), Style::Markers, 0),
                Series::new("shadow label", out.shadow_px.clone(), Style::Markers, 2),
                // The truth's edge over the detections, which would hide its inside.
                Series::new("truth edge", edge(&out.truth_px), Style::Markers, 3).in_front(),
            ],
        )
        .in_image_coordinates()
        .with_equal_aspect(),
    )
}

/// The pixels of `pixels` with a 4-neighbour outside the set: the region's edge.
fn edge(pixels: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let key = |(x, y): (f64, f64)| (x.round() as i64, y.round() as i64);
    let set: std::collections::HashSet<(i64, i64)> = pixels.iter().map(|&p| key(p)).collect();
    pixels
        .iter()
        .copied()
        .filter(|&p| {
            let (x, y) = key(p);
            [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|(dx, dy)| !set.contains(&(x + dx, y + dy)))
        })
        .collect()
}

/// The "angle-profile" figure: the detection function of Kushwaha et al.'s camera node (MFI
/// 2008), foreground pixels per angle before and after the filters, with the true object
/// bearings as grey lines.
fn profile_figure(out: &Output) -> Figure {
    let mut bearing_series = vec![
        Series::new(
            "foreground pixels per angle",
            out.profile.clone(),
            Style::Line,
            0,
        ),
        Series::new(
            "after persistence and spike filters",
            out.filtered.clone(),
            Style::Line,
            1,
        ),
    ];
    let top = out.profile.iter().map(|p| p.1).fold(1.0, f64::max);
    for t in &out.true_bearings_deg {
        bearing_series.push(Series::new(
            "",
            vec![(*t, 0.0), (*t, top)],
            Style::ThinLine,
            7,
        ));
    }
    Figure::new(
        "angle-profile",
        "Run 0, plotted frame: foreground pixels per angle (160 angles) and true object bearings (grey)",
        Chart::new(
            "Detection function over angle",
            "bearing relative to the camera axis (°)",
            "foreground pixels (count)",
            bearing_series,
        ),
    )
}
