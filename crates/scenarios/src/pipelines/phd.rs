//! `phd-pedestrians`: Yoon et al.'s (2016) Table 1 on a simulated pedestrian scene. The same global
//! detections are tracked by the global-only SMC-PHD filter, by the SMC-PHD filter fed with
//! fused global and local detections, and by the GM-PHD filter; each is scored by success
//! rate and false alarms per frame, and by MOTA, IDF1 and HOTA.

use anyhow::Result;
use eval_metrics::{EvalConfig, EvalReport, MatchConfig, SuccessRate, evaluate, success_rate};
use phd_filter::scene::{LocalDetectorSim, Scene, SceneConfig, SimulatedDetectors};
use phd_filter::{
    FrameOutput, FusionConfig, GmConfig, GmPhd, PhdConfig, PhdFilter, PhdTracker, SmcPhd,
};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use tracker_model::{BoundingBox, LocalDetectorFactory, TrackSet};

use crate::{
    Chart, Env, Figure, Metrics, Pipeline, Progress, Section, Series, Style, Table, fmt_num,
};

/// The `phd-pedestrians` pipeline.
pub struct PhdPedestrians;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// A title for the report ("ETH-like sidewalk 1", ...).
    title: String,
    scene: SceneConfig,
    filter: PhdConfig,
    #[serde(default)]
    gm: GmConfig,
    #[serde(default)]
    fusion: FusionConfig,
    #[serde(default)]
    local: LocalDetectorSim,
    /// Frames drawn with box overlays.
    overlay_frames: Vec<u32>,
}

/// One tracker's output on the scene and its scores.
pub struct MethodResult {
    /// Name in the table and legends.
    name: &'static str,
    /// Prefix of its metric keys.
    key: &'static str,
    /// Its tracks.
    tracks: TrackSet,
    /// What it reported in each frame.
    frames: Vec<FrameOutput>,
    /// Yoon et al.'s (2016) success rate and false alarms per frame.
    sr: SuccessRate,
    /// CLEAR MOT, identity and HOTA metrics.
    report: EvalReport,
}

/// The scene, the detector's quality and each tracker's results.
pub struct Output {
    title: String,
    filter: PhdConfig,
    fusion: FusionConfig,
    overlay_frames: Vec<u32>,
    /// The simulated truth and global detections.
    scene: Scene,
    /// Share of true boxes the global detector finds (IoU ≥ 0.5).
    detected_share: f64,
    /// Global detections matching nobody, per frame.
    false_per_frame: f64,
    /// Global-only SMC-PHD, fused SMC-PHD, GM-PHD.
    methods: [MethodResult; 3],
}

/// Runs `tracker` over every frame.
fn run_tracker<F: PhdFilter, D: LocalDetectorFactory>(
    mut tracker: PhdTracker<F, D>,
    detections: &[Vec<BoundingBox>],
    progress: &dyn Progress,
) -> Result<(TrackSet, Vec<FrameOutput>)> {
    let mut frames = Vec::with_capacity(detections.len());
    for (f, boxes) in detections.iter().enumerate() {
        frames.push(tracker.step(f as u32, boxes)?);
        progress.advance(1);
    }
    Ok((tracker.tracks()?, frames))
}

/// Scores one tracker's output against the truth.
fn score(
    name: &'static str,
    key: &'static str,
    scene: &Scene,
    (tracks, frames): (TrackSet, Vec<FrameOutput>),
) -> Result<MethodResult> {
    let sr = success_rate(&scene.truth, &tracks, &MatchConfig::iou(0.5))?;
    let report = evaluate(&scene.truth, &tracks, &EvalConfig::default())?;
    Ok(MethodResult {
        name,
        key,
        tracks,
        frames,
        sr,
        report,
    })
}

/// (share of true boxes the global detector finds, its false boxes per frame)
fn detector_quality(scene: &Scene) -> (f64, f64) {
    let n_truth = scene.truth.n_points();
    let n = scene.detections.len() as u64;
    let detected_share = {
        let per_frame = scene
            .detections
            .iter()
            .zip(scene.by_frame.values())
            .map(|(dets, people)| {
                people
                    .iter()
                    .filter(|(_, b, _)| dets.iter().any(|d| d.iou(b) >= 0.5))
                    .count()
            })
            .sum::<usize>();
        per_frame as f64 / n_truth.max(1) as f64
    };
    let false_per_frame = {
        let fp: usize = scene
            .detections
            .iter()
            .zip(scene.by_frame.values())
            .map(|(dets, people)| {
                dets.iter()
                    .filter(|d| people.iter().all(|(_, b, _)| d.iou(b) < 0.5))
                    .count()
            })
            .sum();
        fp as f64 / n as f64
    };
    (detected_share, false_per_frame)
}

/// A box as a closed polyline.
fn outline(b: &BoundingBox) -> Vec<(f64, f64)> {
    // The image's y grows downwards; the chart's upwards, so rows are negated.
    vec![
        (b.left, -b.top),
        (b.right(), -b.top),
        (b.right(), -b.bottom()),
        (b.left, -b.bottom()),
        (b.left, -b.top),
    ]
}

impl Pipeline for PhdPedestrians {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let scene = p.scene.simulate(rng)?;
        let n = scene.detections.len() as u64;
        env.progress.set_length(3 * n);
        let (seed_global, seed_fused, seed_local): (u64, u64, u64) =
            (rng.random(), rng.random(), rng.random());
        let global = run_tracker(
            PhdTracker::global_only(SmcPhd::new(p.filter, seed_global)?),
            &scene.detections,
            env.progress,
        )?;
        let fused = run_tracker(
            PhdTracker::with_local_detectors(
                SmcPhd::new(p.filter, seed_fused)?,
                SimulatedDetectors::new(&scene, p.local, seed_local)?,
                p.fusion,
            )?,
            &scene.detections,
            env.progress,
        )?;
        let gm = run_tracker(
            PhdTracker::global_only(GmPhd::new(p.filter, p.gm)?),
            &scene.detections,
            env.progress,
        )?;
        let methods = [
            score(
                "global-only SMC-PHD (refs [1,2])",
                "smc_global",
                &scene,
                global,
            )?,
            score(
                "fused SMC-PHD (Yoon et al. 2016)",
                "smc_fused",
                &scene,
                fused,
            )?,
            score("GM-PHD", "gm", &scene, gm)?,
        ];
        let (detected_share, false_per_frame) = detector_quality(&scene);
        Ok(Output {
            title: p.title.clone(),
            filter: p.filter,
            fusion: p.fusion,
            overlay_frames: p.overlay_frames.clone(),
            scene,
            detected_share,
            false_per_frame,
            methods,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        metrics.insert("detector_recall".into(), out.detected_share);
        metrics.insert("detector_false_per_frame".into(), out.false_per_frame);
        for m in &out.methods {
            for (name, v) in [
                ("sr", m.sr.success_rate),
                ("faf", m.sr.false_alarms_per_frame),
                ("mota", m.report.clear.mota),
                ("idf1", m.report.identity.idf1),
                ("hota", m.report.hota.hota),
                ("tracks", m.tracks.len() as f64),
            ] {
                metrics.insert(format!("{}_{name}", m.key), v);
            }
        }
        metrics
    }

    fn present(out: &Output) -> Section {
        let mut figures = vec![Figure::new(
            "cardinality",
            "Estimated cardinality (reported targets) against the truth",
            cardinality_chart(out),
        )];
        figures.extend(overlay_figures(out));
        Section {
            title: format!(
                "SMC-PHD with detector fusion (Yoon et al. 2016): {}",
                out.title
            ),
            summary: format!(
                "Yoon et al.'s (2016) Table 1 on a simulated scene. SR = tracked true boxes (IoU ≥ 0.5) / \
                 all true boxes; FAF = unmatched estimates per frame. p_D = {}, birth intensity \
                 {}, {} particles per target; local detectors start at confidence {} and are \
                 removed at {}.",
                out.filter.p_detect,
                out.filter.birth_rate,
                out.filter.particles_per_target,
                out.fusion.initial_confidence,
                out.fusion.removal_confidence
            ),
            tables: vec![table(out)],
            figures,
        }
    }
}

/// Yoon et al.'s (2016) Table 1 for the three trackers.
fn table(out: &Output) -> Table {
    let mut table = Table::new(
        &format!(
            "{}: {} frames, {} true boxes; the global detector finds {:.0} % of people and \
             makes {:.2} false boxes per frame",
            out.title,
            out.scene.detections.len(),
            out.scene.truth.n_points(),
            100.0 * out.detected_share,
            out.false_per_frame
        ),
        &[
            "method", "SR", "FAF", "MOTA", "IDF1", "HOTA", "IDSW", "tracks",
        ],
    );
    for m in &out.methods {
        table.row(vec![
            m.name.into(),
            format!("{:.1} %", 100.0 * m.sr.success_rate),
            format!("{:.2}", m.sr.false_alarms_per_frame),
            fmt_num(m.report.clear.mota),
            fmt_num(m.report.identity.idf1),
            fmt_num(m.report.hota.hota),
            m.report.clear.id_switches.to_string(),
            m.tracks.len().to_string(),
        ]);
    }
    table
}

/// Estimated cardinality of each tracker against the number of people, per frame.
fn cardinality_chart(out: &Output) -> Chart {
    let truth_count: Vec<(f64, f64)> = out
        .scene
        .by_frame
        .iter()
        .map(|(f, people)| (f64::from(*f), people.len() as f64))
        .collect();
    let count = |frames: &[FrameOutput]| -> Vec<(f64, f64)> {
        frames
            .iter()
            .map(|o| (f64::from(o.frame), o.estimates.len() as f64))
            .collect()
    };
    let [global, fused, gm] = &out.methods;
    Chart::new(
        "Number of estimates against the number of people",
        "frame",
        "count",
        vec![
            Series::new("people", truth_count, Style::Line, 7),
            Series::new(
                "global-only SMC-PHD",
                count(&global.frames),
                Style::ThinLine,
                0,
            ),
            Series::new("fused SMC-PHD", count(&fused.frames), Style::Line, 1),
            Series::new("GM-PHD", count(&gm.frames), Style::ThinLine, 2),
        ],
    )
}

/// True boxes, detections and every tracker's estimates in each overlay frame.
fn overlay_figures(out: &Output) -> Vec<Figure> {
    let mut figures = Vec::new();
    for &frame in &out.overlay_frames {
        let Some(people) = out.scene.by_frame.get(&frame) else {
            continue;
        };
        let mut series: Vec<Series> = people
            .iter()
            .map(|(_, b, _)| Series::new("", outline(b), Style::ThinLine, 7))
            .collect();
        if let Some(first) = series.first_mut() {
            first.label = "truth".into();
        }
        let frame_index = frame as usize;
        for (k, m) in out.methods.iter().enumerate() {
            if let Some(o) = m.frames.get(frame_index) {
                for (i, e) in o.estimates.iter().enumerate() {
                    let label = if i == 0 { m.name } else { "" };
                    series.push(Series::new(label, outline(&e.bbox), Style::Line, k));
                }
            }
        }
        for d in out.scene.detections.get(frame_index).into_iter().flatten() {
            series.push(Series::new("", outline(d), Style::Markers, 3));
        }
        figures.push(Figure::new(
            &format!("frame-{frame}"),
            &format!(
                "Frame {frame}: true boxes (grey), global detections (red corners), estimates \
                 of each method (coloured)"
            ),
            Chart::new(
                &format!("{}: frame {frame}", out.title),
                "image x",
                "−(image y)",
                series,
            ),
        ));
    }
    figures
}
