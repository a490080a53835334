//! `phd-images`: Yoon et al.'s (2016) Table 1 with local detectors that run on pixels. A
//! pedestrian scene from phd-filter's simulator (paths, perspective, occlusion, and a global
//! detector simulated from the truth with misses, box jitter and false boxes) is rendered as
//! video with sensors-video's people-like sprites; the same global detections are tracked by
//! the global-only SMC-PHD filter, GM-PHD, SMC-PHD fused with image-detector's online-boosting
//! local detectors (which see only the pixels), and SMC-PHD fused with phd-filter's
//! simulated local detectors (which follow the image content their first box holds, a person or background, as phd-filter models it). Each is scored by SR and FAF (eval-metrics'
//! `success_rate`, IoU ≥ 0.5, the definition the `phd-pedestrians` pipeline uses), as mean ±
//! 95 % CI over the reported runs, with the paired SR gain of each fused tracker.
//!
//! Fairness: the baselines' p_D is the global detector's recall measured on tuning runs drawn
//! from a seed separate from the reported ones; the fusion settings are the scenario file's,
//! the same for both fused trackers.

use std::sync::Arc;

use anyhow::{Result, ensure};
use eval_metrics::{MatchConfig, success_rate};
use image_detector::image::RgbImage;
use image_detector::{DetectorConfig, FrameFeed, ImageDetectors};
use phd_filter::scene::{LocalDetectorSim, Scene, SceneConfig, SimulatedDetectors};
use phd_filter::{
    FrameOutput, FusionConfig, GmConfig, GmPhd, PhdConfig, PhdFilter, PhdTracker, SmcPhd,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use sensors_video::{SpriteConfig, SpriteRenderer};
use serde::Deserialize;
use tracker_model::{BoundingBox, LocalDetectorFactory, TrackSet};

use crate::stats::mean_ci;
use crate::{
    Chart, Claim, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style, Table, fmt_num,
};

/// The `phd-images` pipeline.
pub struct PhdImages;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// A title for the report.
    title: String,
    /// Reported runs: streams 0..n_runs of the scenario's seed.
    n_runs: usize,
    /// Tuning runs (the baselines' p_D = recall measured on them): streams of this seed.
    tuning_seed: u64,
    n_tuning_runs: usize,
    scene: SceneConfig,
    /// The renderer; its width and height must equal `scene.image`.
    sprites: SpriteConfig,
    /// Filter settings shared by every method (p_D: see `fused_filter_p_detect`).
    filter: PhdConfig,
    #[serde(default)]
    gm: GmConfig,
    /// Fusion and detector management (eqs. 1-2, 9-10), the same for both fused trackers.
    fusion: FusionConfig,
    /// p_D of the fused filters.
    fused_filter_p_detect: f64,
    /// The image local detectors.
    #[serde(default)]
    detector: DetectorConfig,
    /// The simulated local detectors.
    local: LocalDetectorSim,
    /// Frame of the first reported run drawn with boxes.
    overlay_frame: u32,
    /// Yoon et al.'s Table 1 values for the sequence this scene is shaped after.
    paper: Option<Paper>,
}

/// Published values shown beside ours.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Paper {
    sequence: String,
    global_sr: f64,
    fused_sr: f64,
}

/// The four trackers.
const NAMES: [&str; 4] = [
    "global-only SMC-PHD",
    "GM-PHD",
    "SMC-PHD + image local detectors",
    "SMC-PHD + simulated local detectors",
];
const KEYS: [&str; 4] = ["smc_global", "gm", "fused_image", "fused_sim"];

/// SR and FAF of one tracker on one run.
#[derive(Debug, Clone, Copy)]
struct Score {
    sr: f64,
    faf: f64,
}

/// Everything `compute` measured.
pub struct Output {
    title: String,
    frames: u32,
    size: (usize, usize),
    recall: f64,
    detector: Vec<(f64, f64)>,
    /// Per method, per reported run.
    scores: [Vec<Score>; 4],
    /// First run: truth and the estimates of the global-only and image-fused trackers at the
    /// overlay frame.
    overlay: Option<Overlay>,
    paper: Option<Paper>,
}

/// One frame's boxes: the truth and two trackers' estimates.
struct Overlay {
    frame: u32,
    truth: Vec<BoundingBox>,
    global: Vec<BoundingBox>,
    fused: Vec<BoundingBox>,
}

struct Run {
    scene: Scene,
    frames: Vec<Arc<RgbImage>>,
    seeds: [u64; 4],
}

fn make_run(p: &Params, seed: u64, stream: u64, render: bool) -> Result<Run> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    let scene = p.scene.simulate(&mut rng)?;
    let seeds = [rng.random(), rng.random(), rng.random(), rng.random()];
    let mut frames = Vec::new();
    if render {
        let renderer = SpriteRenderer::new(p.sprites, &mut rng)?;
        for (f, people) in scene.by_frame.iter() {
            let boxes: Vec<(u64, BoundingBox)> =
                people.iter().map(|(id, b, _)| (id.0, *b)).collect();
            let frame = renderer.render(*f, &boxes, &mut rng)?;
            let (w, h) = (frame.width() as u32, frame.height() as u32);
            let image = RgbImage::from_raw(w, h, frame.into_data())
                .ok_or_else(|| anyhow::anyhow!("rendered frame {f} has the wrong size"))?;
            frames.push(Arc::new(image));
        }
    }
    Ok(Run {
        scene,
        frames,
        seeds,
    })
}

/// (share of true boxes some global box overlaps with IoU ≥ 0.5, global boxes matching
/// nobody per frame)
fn detector_quality(scene: &Scene) -> (f64, f64) {
    let (mut found, mut total, mut fp) = (0usize, 0usize, 0usize);
    for (dets, people) in scene.detections.iter().zip(scene.by_frame.values()) {
        total += people.len();
        found += people
            .iter()
            .filter(|(_, b, _)| dets.iter().any(|d| d.iou(b) >= 0.5))
            .count();
        fp += dets
            .iter()
            .filter(|d| people.iter().all(|(_, b, _)| d.iou(b) < 0.5))
            .count();
    }
    (
        found as f64 / total.max(1) as f64,
        fp as f64 / scene.detections.len().max(1) as f64,
    )
}

fn run_tracker<F: PhdFilter, D: LocalDetectorFactory>(
    mut tracker: PhdTracker<F, D>,
    run: &Run,
    feed: Option<&FrameFeed>,
) -> Result<(TrackSet, Vec<FrameOutput>)> {
    let mut out = Vec::with_capacity(run.scene.detections.len());
    for (f, boxes) in run.scene.detections.iter().enumerate() {
        let frame = u32::try_from(f)?;
        if let (Some(feed), Some(image)) = (feed, run.frames.get(f)) {
            feed.set(frame, Arc::clone(image));
        }
        out.push(tracker.step(frame, boxes)?);
    }
    Ok((tracker.tracks()?, out))
}

fn score(scene: &Scene, tracks: &TrackSet) -> Result<Score> {
    let sr = success_rate(&scene.truth, tracks, &MatchConfig::iou(0.5))?;
    Ok(Score {
        sr: sr.success_rate,
        faf: sr.false_alarms_per_frame,
    })
}

/// The fused SMC-PHD (the fused filter's p_D, the scenario's fusion settings) with `factory`'s
/// local detectors, run on `run`.
fn run_fused<D: LocalDetectorFactory>(
    p: &Params,
    filter: PhdConfig,
    factory: D,
    run: &Run,
    feed: Option<&FrameFeed>,
) -> Result<(TrackSet, Vec<FrameOutput>)> {
    run_tracker(
        PhdTracker::with_local_detectors(SmcPhd::new(filter, run.seeds[1])?, factory, p.fusion)?,
        run,
        feed,
    )
}

/// Runs method `m` on `run`; returns its score and its per-frame output.
fn track(
    p: &Params,
    baseline: PhdConfig,
    run: &Run,
    m: usize,
) -> Result<(Score, Vec<FrameOutput>)> {
    let fused_filter = PhdConfig {
        p_detect: p.fused_filter_p_detect,
        ..p.filter
    };
    let (tracks, frames) = match m {
        0 => run_tracker(
            PhdTracker::global_only(SmcPhd::new(baseline, run.seeds[0])?),
            run,
            None,
        )?,
        1 => run_tracker(
            PhdTracker::global_only(GmPhd::new(baseline, p.gm)?),
            run,
            None,
        )?,
        2 => {
            let feed = FrameFeed::new();
            let factory = ImageDetectors::new(p.detector.clone(), feed.clone(), run.seeds[2])?;
            run_fused(p, fused_filter, factory, run, Some(&feed))?
        }
        _ => {
            let factory = SimulatedDetectors::new(&run.scene, p.local, run.seeds[3])?;
            run_fused(p, fused_filter, factory, run, None)?
        }
    };
    Ok((score(&run.scene, &tracks)?, frames))
}

impl Pipeline for PhdImages {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, _rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let seed = env.seed;
        ensure!(p.n_runs >= 2, "n_runs must be at least 2 (for a CI)");
        ensure!(p.n_tuning_runs >= 1, "n_tuning_runs must be at least 1");
        ensure!(
            p.tuning_seed != seed,
            "tuning_seed must differ from the scenario's seed"
        );
        ensure!(
            (p.sprites.width as f64 - p.scene.image[0]).abs() < 0.5
                && (p.sprites.height as f64 - p.scene.image[1]).abs() < 0.5,
            "sprites.width/height must equal scene.image"
        );
        ensure!(
            p.fused_filter_p_detect > 0.0 && p.fused_filter_p_detect < 1.0,
            "fused_filter_p_detect is a probability in (0, 1)"
        );
        p.fusion.check()?;
        p.filter.check()?;
        p.local.check()?;
        p.detector.check()?;
        // The baselines' p_D: the global detector's recall on the tuning runs.
        let tuning: Vec<Run> = (0..p.n_tuning_runs as u64)
            .into_par_iter()
            .map(|i| make_run(p, p.tuning_seed, i, false))
            .collect::<Result<_>>()?;
        let recall = mean_ci(tuning.iter().map(|r| detector_quality(&r.scene).0)).0;
        let baseline = PhdConfig {
            p_detect: recall.clamp(0.05, 0.99),
            ..p.filter
        };
        env.progress.set_length((p.n_runs * 4) as u64);
        let runs: Vec<Run> = (0..p.n_runs as u64)
            .into_par_iter()
            .map(|i| make_run(p, seed, i, true))
            .collect::<Result<_>>()?;
        let jobs: Vec<(usize, usize)> = (0..runs.len())
            .flat_map(|r| (0..4).map(move |m| (r, m)))
            .collect();
        let results: Vec<(Score, Vec<FrameOutput>)> = jobs
            .par_iter()
            .map(|&(r, m)| {
                let out = track(p, baseline, &runs[r], m);
                env.progress.advance(1);
                out
            })
            .collect::<Result<_>>()?;
        let mut scores: [Vec<Score>; 4] = Default::default();
        for (&(_, m), (s, _)) in jobs.iter().zip(&results) {
            scores[m].push(*s);
        }
        let f = p.overlay_frame;
        let first = &runs[0];
        let estimates = |m: usize| -> Vec<BoundingBox> {
            results[m]
                .1
                .iter()
                .find(|o| o.frame == f)
                .map(|o| o.estimates.iter().map(|e| e.bbox).collect())
                .unwrap_or_default()
        };
        let overlay = first.scene.by_frame.get(&f).map(|people| Overlay {
            frame: f,
            truth: people.iter().map(|(_, b, _)| *b).collect(),
            global: estimates(0),
            fused: estimates(2),
        });
        Ok(Output {
            title: p.title.clone(),
            frames: p.scene.n_frames,
            size: (p.sprites.width, p.sprites.height),
            recall,
            detector: runs.iter().map(|r| detector_quality(&r.scene)).collect(),
            scores,
            overlay,
            paper: p.paper.clone(),
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut m = Metrics::new();
        m.insert("tuning_detector_recall".into(), out.recall);
        m.insert(
            "detector_recall".into(),
            mean_ci(out.detector.iter().map(|d| d.0)).0,
        );
        m.insert(
            "detector_false_per_frame".into(),
            mean_ci(out.detector.iter().map(|d| d.1)).0,
        );
        for (k, key) in KEYS.iter().enumerate() {
            let (sr, sr_ci) = mean_ci(out.scores[k].iter().map(|s| s.sr));
            let (faf, faf_ci) = mean_ci(out.scores[k].iter().map(|s| s.faf));
            m.insert(format!("{key}_sr"), sr);
            m.insert(format!("{key}_sr_ci95"), sr_ci);
            m.insert(format!("{key}_faf"), faf);
            m.insert(format!("{key}_faf_ci95"), faf_ci);
        }
        for (k, key) in [(2, "fused_image"), (3, "fused_sim")] {
            let (g, ci) = gain(out, k);
            m.insert(format!("{key}_minus_global_sr"), g);
            m.insert(format!("{key}_minus_global_sr_ci95"), ci);
        }
        m
    }

    fn present(out: &Output) -> Section {
        let mut figures = Vec::new();
        if let Some(overlay) = &out.overlay {
            figures.push(overlay_figure(out, overlay));
        }
        Section {
            title: format!(
                "SMC-PHD with image-based local detectors (Yoon et al. 2016): {}",
                out.title
            ),
            summary: summary(out),
            tables: vec![sr_table(out), per_run_table(out)],
            figures,
        }
    }

    fn claims(out: &Output) -> Vec<Claim> {
        let (g, ci) = gain(out, 2);
        let (faf, _) = mean_ci(out.scores[2].iter().map(|s| s.faf));
        vec![Claim::new(
            format!(
                "{}: SR with image local detectors above global-only SR (gain {} ± {} \
                     points), with FAF {} <= 1.0",
                out.title,
                fmt_num(100.0 * g),
                fmt_num(100.0 * ci),
                fmt_num(faf)
            ),
            g > 0.0 && faf <= 1.0,
        )]
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let Some(paper) = &out.paper else {
            return Vec::new();
        };
        let pct = |k: usize| {
            let (m, ci) = mean_ci(out.scores[k].iter().map(|s| s.sr));
            format!("{} ± {} %", fmt_num(100.0 * m), fmt_num(100.0 * ci))
        };
        vec![
            Headline {
                quantity: format!(
                    "SR, global-only SMC-PHD, {} ({}), rendered video",
                    out.title, paper.sequence
                ),
                paper: Some(format!("{} %", fmt_num(100.0 * paper.global_sr))),
                ours: pct(0),
                peer: None,
            },
            Headline {
                quantity: format!(
                    "SR, SMC-PHD fused with image local detectors, {} ({})",
                    out.title, paper.sequence
                ),
                paper: Some(format!("{} %", fmt_num(100.0 * paper.fused_sr))),
                ours: pct(2),
                peer: None,
            },
        ]
    }
}

/// The SR and FAF table in the measures of Yoon et al. (2016), Table 1: each tracker's mean ±
/// 95 % CI over the runs, with the paired SR gain of the fused trackers over global-only.
fn sr_table(out: &Output) -> Table {
    let mut t = Table::new(
        &format!(
            "SR and FAF, mean ± 95 % CI over {} runs ({} frames of {} × {} rendered video \
             each)",
            out.scores[0].len(),
            out.frames,
            out.size.0,
            out.size.1
        ),
        &[
            "tracker",
            "SR (%)",
            "FAF",
            "SR gain over global-only (points)",
        ],
    );
    for (k, name) in NAMES.iter().enumerate() {
        let (sr, sr_ci) = mean_ci(out.scores[k].iter().map(|s| s.sr));
        let (faf, faf_ci) = mean_ci(out.scores[k].iter().map(|s| s.faf));
        let g = if k >= 2 {
            let (g, ci) = gain(out, k);
            format!("{} ± {}", fmt_num(100.0 * g), fmt_num(100.0 * ci))
        } else {
            "-".to_string()
        };
        t.row(vec![
            (*name).to_string(),
            format!("{} ± {}", fmt_num(100.0 * sr), fmt_num(100.0 * sr_ci)),
            format!("{} ± {}", fmt_num(faf), fmt_num(faf_ci)),
            g,
        ]);
    }
    t
}

/// The per-run table: every tracker's SR on each reported run, behind the paired gains.
fn per_run_table(out: &Output) -> Table {
    let mut per_run = Table::new(
        "SR (%) per reported run",
        &["run", NAMES[0], NAMES[1], NAMES[2], NAMES[3]],
    );
    for r in 0..out.scores[0].len() {
        let mut row = vec![r.to_string()];
        row.extend((0..4).map(|k| fmt_num(100.0 * out.scores[k][r].sr)));
        per_run.row(row);
    }
    per_run
}

/// The report's summary: the rendered scene, the image local detectors, the simulated global
/// detector's quality and the baselines' p_D (measured on separate tuning runs).
fn summary(out: &Output) -> String {
    let (recall, fp) = (
        mean_ci(out.detector.iter().map(|d| d.0)).0,
        mean_ci(out.detector.iter().map(|d| d.1)).0,
    );
    format!(
        "The scene is rendered as video (people-like sprites with varied clothing over a \
         cluttered background, nearer people hiding farther ones) and the local detectors \
         of the image-fused tracker run on those pixels: HOG blocks, online boosting and an \
         RGB histogram (image-detector). The global detector is simulated from the truth \
         (recall {:.0} %, {} false boxes per frame on the reported runs). Baselines use \
         p_D = {:.2}, the recall measured on separate tuning runs. The report draws boxes \
         as outlines (the report has no raster images, so the rendered frame itself is not \
         shown).",
        100.0 * recall,
        fmt_num(fp),
        out.recall
    )
}

/// The "overlay" figure: the first reported run's overlay frame with the true boxes and the
/// global-only and image-fused trackers' estimates, as outlines in image coordinates.
fn overlay_figure(out: &Output, overlay: &Overlay) -> Figure {
    let Overlay {
        frame: f,
        truth,
        global,
        fused,
    } = overlay;
    let mut series = Vec::new();
    for (label, boxes, style, colour) in [
        ("people", truth, Style::Line, 7),
        ("global-only", global, Style::ThinLine, 0),
        ("image-fused", fused, Style::Line, 1),
    ] {
        for (i, b) in boxes.iter().enumerate() {
            series.push(Series::new(
                if i == 0 { label } else { "" },
                outline(b),
                style,
                colour,
            ));
        }
    }
    Figure::new(
        "overlay",
        &format!("First reported run, frame {f}: true boxes and each tracker's estimates"),
        Chart::new(
            &format!("Frame {f} ({} × {} pixels)", out.size.0, out.size.1),
            "x (px)",
            "y (px)",
            series,
        )
        .in_image_coordinates(),
    )
}

/// Paired SR gain of method `k` over global-only: mean ± 95 % CI over runs.
fn gain(out: &Output, k: usize) -> (f64, f64) {
    mean_ci(
        out.scores[k]
            .iter()
            .zip(&out.scores[0])
            .map(|(a, b)| a.sr - b.sr),
    )
}

/// A box as a closed polyline in image coordinates.
fn outline(b: &BoundingBox) -> Vec<(f64, f64)> {
    vec![
        (b.left, b.top),
        (b.right(), b.top),
        (b.right(), b.bottom()),
        (b.left, b.bottom()),
        (b.left, b.top),
    ]
}
