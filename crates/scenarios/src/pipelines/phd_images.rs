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
//! Fairness: every filter's p_D is the global detector's recall measured on tuning runs drawn
//! from a seed separate from the reported ones; the fusion settings are the scenario file's,
//! the same for every fused tracker. A control fuses local detectors that are blind (they
//! never report), so the fused tracker's machinery without any image content shows what the
//! images themselves add. Claims are made on fresh runs (a third seed, `docs/seeds.md`) by
//! paired 95 % t intervals, with the verdict of their first run recorded.

use std::collections::BTreeMap;

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

use crate::seeds::check_disjoint;
use crate::stats::{Paired, Verdict, mean_ci};
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
    /// Tuning runs (every filter's p_D = recall measured on them): streams of this seed.
    tuning_seed: u64,
    n_tuning_runs: usize,
    /// Fresh runs, generated after the settings were frozen (the claims are made on them):
    /// streams 0..n_fresh_runs of this seed.
    fresh_seed: u64,
    n_fresh_runs: usize,
    /// The verdict of each claim of [`CLAIMS`] on the fresh runs, recorded from their first run.
    fresh_verdicts: BTreeMap<String, Verdict>,
    scene: SceneConfig,
    /// The renderer; its width and height must equal `scene.image`.
    sprites: SpriteConfig,
    /// Filter settings shared by every method (p_D: the measured recall).
    filter: PhdConfig,
    #[serde(default)]
    gm: GmConfig,
    /// Fusion and detector management (eqs. 1-2, 9-10), the same for every fused tracker.
    fusion: FusionConfig,
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

/// The trackers: the two baselines, the fused tracker with image and with simulated local
/// detectors, and the control with blind ones.
const NAMES: [&str; METHODS] = [
    "global-only SMC-PHD",
    "GM-PHD",
    "SMC-PHD + image local detectors",
    "SMC-PHD + simulated local detectors",
    "SMC-PHD + blind local detectors (control)",
];
const KEYS: [&str; METHODS] = [
    "smc_global",
    "gm",
    "fused_image",
    "fused_sim",
    "fused_blind",
];
const METHODS: usize = 5;

/// SR (higher is better) or FAF (lower is better).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Measure {
    Sr,
    Faf,
}

/// The claims, made on the fresh runs: (key, measure, method, the method it is at least as good
/// as). The image-fused tracker's SR against global-only (what fusion gains) and against the
/// blind control (what the images add beyond the fused tracker's own management), and its
/// false alarms against global-only's (where fusion pays).
const CLAIMS: [(&str, Measure, usize, usize); 3] = [
    ("image_sr_ge_global", Measure::Sr, 2, 0),
    ("image_sr_ge_blind", Measure::Sr, 2, 4),
    ("image_faf_le_global", Measure::Faf, 2, 0),
];

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
    scores: PerMethod,
    /// Per method, per fresh run.
    fresh: PerMethod,
    fresh_verdicts: BTreeMap<String, Verdict>,
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

/// Runs method `m` on `run` with `filter` (p_D the measured recall); returns its score and its
/// per-frame output.
fn track(p: &Params, filter: PhdConfig, run: &Run, m: usize) -> Result<(Score, Vec<FrameOutput>)> {
    let (tracks, frames) = match m {
        0 => run_tracker(
            PhdTracker::global_only(SmcPhd::new(filter, run.seeds[0])?),
            run,
            None,
        )?,
        1 => run_tracker(
            PhdTracker::global_only(GmPhd::new(filter, p.gm)?),
            run,
            None,
        )?,
        2 => {
            let feed = FrameFeed::new();
            let factory = ImageDetectors::new(p.detector.clone(), feed.clone(), run.seeds[2])?;
            run_fused(p, filter, factory, run, Some(&feed))?
        }
        3 => {
            let factory = SimulatedDetectors::new(&run.scene, p.local, run.seeds[3])?;
            run_fused(p, filter, factory, run, None)?
        }
        _ => {
            let blind = LocalDetectorSim {
                p_detect: 0.0,
                p_detect_occluded: 0.0,
                p_drift: 0.0,
                p_stale: 0.0,
                ..p.local
            };
            let factory = SimulatedDetectors::new(&run.scene, blind, run.seeds[3])?;
            run_fused(p, filter, factory, run, None)?
        }
    };
    Ok((score(&run.scene, &tracks)?, frames))
}

/// The checks before anything runs: run counts, the three seeds apart, the renderer's size,
/// a recorded verdict for every claim, and the configurations.
fn check(p: &Params, seed: u64) -> Result<()> {
    ensure!(p.n_runs >= 2, "n_runs must be at least 2 (for a CI)");
    ensure!(
        p.n_fresh_runs >= 2,
        "n_fresh_runs must be at least 2 (for a CI)"
    );
    ensure!(p.n_tuning_runs >= 1, "n_tuning_runs must be at least 1");
    check_disjoint(&[
        ("tuning", &[p.tuning_seed]),
        ("reported", &[seed]),
        ("fresh", &[p.fresh_seed]),
    ])?;
    ensure!(
        (p.sprites.width as f64 - p.scene.image[0]).abs() < 0.5
            && (p.sprites.height as f64 - p.scene.image[1]).abs() < 0.5,
        "sprites.width/height must equal scene.image"
    );
    for (key, ..) in CLAIMS {
        ensure!(
            p.fresh_verdicts.contains_key(key),
            "fresh_verdicts has no verdict for {key:?}"
        );
    }
    if let Some(k) = p
        .fresh_verdicts
        .keys()
        .find(|k| !CLAIMS.iter().any(|(c, ..)| c == k))
    {
        anyhow::bail!("fresh_verdicts names {k:?}, which is no claim");
    }
    p.fusion.check()?;
    p.filter.check()?;
    p.local.check()?;
    p.detector.check()?;
    Ok(())
}

/// Streams 0..n of `seed`, rendered.
fn make_runs(p: &Params, seed: u64, n: usize) -> Result<Vec<Run>> {
    (0..n as u64)
        .into_par_iter()
        .map(|i| make_run(p, seed, i, true))
        .collect()
}

/// Each method's scores, run by run.
type PerMethod = [Vec<Score>; METHODS];

/// Every method on every run: the scores per method, and the first run's per-frame output
/// per method (for the overlay).
fn score_runs(
    p: &Params,
    filter: PhdConfig,
    runs: &[Run],
    env: &Env<'_>,
) -> Result<(PerMethod, Vec<Vec<FrameOutput>>)> {
    let jobs: Vec<(usize, usize)> = (0..runs.len())
        .flat_map(|r| (0..METHODS).map(move |m| (r, m)))
        .collect();
    let results: Vec<(Score, Vec<FrameOutput>)> = jobs
        .par_iter()
        .map(|&(r, m)| {
            let out = track(p, filter, &runs[r], m);
            env.progress.advance(1);
            out
        })
        .collect::<Result<_>>()?;
    let mut scores: PerMethod = Default::default();
    let mut first = Vec::with_capacity(METHODS);
    for (&(r, m), (score, frames)) in jobs.iter().zip(results) {
        scores[m].push(score);
        if r == 0 {
            first.push(frames);
        }
    }
    Ok((scores, first))
}

impl Pipeline for PhdImages {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, _rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        check(p, env.seed)?;
        // Every filter's p_D: the global detector's recall on the tuning runs.
        let tuning: Vec<Run> = (0..p.n_tuning_runs as u64)
            .into_par_iter()
            .map(|i| make_run(p, p.tuning_seed, i, false))
            .collect::<Result<_>>()?;
        let recall = mean_ci(tuning.iter().map(|r| detector_quality(&r.scene).0)).0;
        let filter = PhdConfig {
            p_detect: recall.clamp(0.05, 0.99),
            ..p.filter
        };
        env.progress
            .set_length(((p.n_runs + p.n_fresh_runs) * METHODS) as u64);
        let runs = make_runs(p, env.seed, p.n_runs)?;
        let (scores, first) = score_runs(p, filter, &runs, env)?;
        let (fresh, _) = score_runs(p, filter, &make_runs(p, p.fresh_seed, p.n_fresh_runs)?, env)?;
        let f = p.overlay_frame;
        let estimates = |m: usize| -> Vec<BoundingBox> {
            first[m]
                .iter()
                .find(|o| o.frame == f)
                .map(|o| o.estimates.iter().map(|e| e.bbox).collect())
                .unwrap_or_default()
        };
        let overlay = runs[0].scene.by_frame.get(&f).map(|people| Overlay {
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
            fresh,
            fresh_verdicts: p.fresh_verdicts.clone(),
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
        for (prefix, scores) in [("", &out.scores), ("fresh_", &out.fresh)] {
            for (k, key) in KEYS.iter().enumerate() {
                let (sr, sr_ci) = mean_ci(scores[k].iter().map(|s| s.sr));
                let (faf, faf_ci) = mean_ci(scores[k].iter().map(|s| s.faf));
                m.insert(format!("{prefix}{key}_sr"), sr);
                m.insert(format!("{prefix}{key}_sr_ci95"), sr_ci);
                m.insert(format!("{prefix}{key}_faf"), faf);
                m.insert(format!("{prefix}{key}_faf_ci95"), faf_ci);
            }
            for (k, key) in KEYS.iter().enumerate().skip(2) {
                let g = gain(scores, k, 0);
                m.insert(format!("{prefix}{key}_minus_global_sr"), g.mean);
                m.insert(format!("{prefix}{key}_minus_global_sr_low"), g.low);
            }
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
            tables: vec![
                sr_table(out, "reported", &out.scores),
                sr_table(out, "fresh", &out.fresh),
                per_run_table("reported", &out.scores),
                per_run_table("fresh", &out.fresh),
            ],
            figures,
        }
    }

    fn claims(out: &Output) -> Vec<Claim> {
        CLAIMS
            .iter()
            .map(|&(key, measure, k, j)| {
                // Oriented so that ≥ 0 favours method k.
                let (paired, what, unit) = match measure {
                    Measure::Sr => (gain(&out.fresh, k, j).scaled(100.0), "SR ≥", "points"),
                    Measure::Faf => (
                        faf_saving(&out.fresh, k, j),
                        "FAF ≤",
                        "false boxes per frame",
                    ),
                };
                let verdict = Verdict::of(&paired, 0.0);
                let recorded = out.fresh_verdicts[key];
                Claim::new(
                    format!(
                        "{}: {}'s {what} {}'s on the {} fresh runs: paired difference {} {unit} \
                         (95 % t, positive favours the first) — {} (recorded: {})",
                        out.title,
                        NAMES[k],
                        NAMES[j],
                        out.fresh[k].len(),
                        paired.show(),
                        verdict.name(),
                        recorded.name()
                    ),
                    verdict == recorded,
                )
            })
            .collect()
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

/// The SR and FAF table in the measures of Yoon et al. (2016), Table 1, on one set of runs:
/// each tracker's mean ± 95 % CI, with the paired SR gain of the fused trackers over
/// global-only.
fn sr_table(out: &Output, set: &str, scores: &PerMethod) -> Table {
    let mut t = Table::new(
        &format!(
            "SR and FAF on the {} {set} runs, mean ± 95 % CI ({} frames of {} × {} rendered \
             video each)",
            scores[0].len(),
            out.frames,
            out.size.0,
            out.size.1
        ),
        &[
            "tracker",
            "SR (%)",
            "FAF",
            "SR gain over global-only (points, mean [95 % paired t])",
        ],
    );
    for (k, name) in NAMES.iter().enumerate() {
        let (sr, sr_ci) = mean_ci(scores[k].iter().map(|s| s.sr));
        let (faf, faf_ci) = mean_ci(scores[k].iter().map(|s| s.faf));
        let g = if k >= 2 {
            gain(scores, k, 0).scaled(100.0).show()
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

/// The per-run table of one set: every tracker's SR on each run, behind the paired gains.
fn per_run_table(set: &str, scores: &PerMethod) -> Table {
    let mut header = vec!["run"];
    header.extend(NAMES);
    let mut per_run = Table::new(&format!("SR (%) per {set} run"), &header);
    for r in 0..scores[0].len() {
        let mut row = vec![r.to_string()];
        row.extend(scores.iter().map(|s| fmt_num(100.0 * s[r].sr)));
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
         (recall {:.0} %, {} false boxes per frame on the reported runs). Every filter, \
         fused or not, uses p_D = {:.2}, the recall measured on separate tuning runs. The \
         control fuses blind local detectors (they never report), so it shows what the fused \
         tracker's own management does without any image content. The report draws boxes \
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

/// Paired SR gain of method `k` over method `j`, per run: mean and 95 % t interval.
fn gain(scores: &PerMethod, k: usize, j: usize) -> Paired {
    let sr = |m: usize| scores[m].iter().map(|s| s.sr).collect::<Vec<_>>();
    Paired::of(&sr(k), &sr(j))
}

/// Paired FAF of method `j` minus method `k`, per run (positive: `k` has fewer false alarms).
fn faf_saving(scores: &PerMethod, k: usize, j: usize) -> Paired {
    let faf = |m: usize| scores[m].iter().map(|s| s.faf).collect::<Vec<_>>();
    Paired::of(&faf(j), &faf(k))
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
