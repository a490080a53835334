//! `phd-pedestrians`: seed 004's Table 1 on a simulated pedestrian scene. The same global
//! detections are tracked by the global-only SMC-PHD filter, by the SMC-PHD filter fed with
//! fused global and local detections, and by the GM-PHD filter; each is scored by success
//! rate and false alarms per frame, and by MOTA, IDF1 and HOTA.

use anyhow::Result;
use eval_metrics::{EvalConfig, MatchConfig, evaluate, success_rate};
use indicatif::ProgressBar;
use phd_filter::scene::{LocalDetectorSim, SceneConfig, SimulatedDetectors};
use phd_filter::{
    FrameOutput, FusionConfig, GmConfig, GmPhd, NoLocalDetectors, PhdConfig, PhdFilter, PhdTracker,
    SmcPhd,
};
use rand::RngExt;
use serde::Deserialize;
use tracker_model::{BoundingBox, LocalDetectorFactory, TrackSet};

use crate::plot::{Axes, Series, Style, chart};
use crate::report::{Plot, Section, Table, fmt_num};
use crate::scenario::{Metrics, PipelineOutput, Scenario};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Params {
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

/// Runs `filter` (with local detectors from `factory`, if any) over every frame.
fn run_tracker<F: PhdFilter, D: LocalDetectorFactory>(
    filter: F,
    factory: Option<D>,
    fusion: FusionConfig,
    detections: &[Vec<BoundingBox>],
    progress: &ProgressBar,
) -> Result<(TrackSet, Vec<FrameOutput>)> {
    let mut tracker = PhdTracker::new(filter, factory, fusion)?;
    let mut frames = Vec::with_capacity(detections.len());
    for (f, boxes) in detections.iter().enumerate() {
        frames.push(tracker.step(f as u32, boxes)?);
        progress.inc(1);
    }
    Ok((tracker.tracks()?, frames))
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

pub fn run(scenario: &Scenario, progress: &ProgressBar) -> Result<PipelineOutput> {
    let p: Params = scenario.params()?;
    let mut rng = scenario.rng();
    let scene = p.scene.simulate(&mut rng)?;
    let n = scene.detections.len() as u64;
    progress.set_length(3 * n);
    let (seed_global, seed_fused, seed_local): (u64, u64, u64) =
        (rng.random(), rng.random(), rng.random());
    let global = run_tracker(
        SmcPhd::new(p.filter, seed_global)?,
        None::<NoLocalDetectors>,
        p.fusion,
        &scene.detections,
        progress,
    )?;
    let fused = run_tracker(
        SmcPhd::new(p.filter, seed_fused)?,
        Some(SimulatedDetectors::new(&scene, p.local, seed_local)),
        p.fusion,
        &scene.detections,
        progress,
    )?;
    let gm = run_tracker(
        GmPhd::new(p.filter, p.gm)?,
        None::<NoLocalDetectors>,
        p.fusion,
        &scene.detections,
        progress,
    )?;
    let n_truth = scene.truth.n_points();
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
    let mut metrics = Metrics::new();
    metrics.insert("detector_recall".into(), detected_share);
    metrics.insert("detector_false_per_frame".into(), false_per_frame);
    let mut table = Table::new(
        &format!(
            "{}: {} frames, {} true boxes; the global detector finds {:.0} % of people and \
             makes {:.2} false boxes per frame",
            p.title,
            n,
            n_truth,
            100.0 * detected_share,
            false_per_frame
        ),
        &[
            "method", "SR", "FAF", "MOTA", "IDF1", "HOTA", "IDSW", "tracks",
        ],
    );
    let runs = [
        ("global-only SMC-PHD (refs [1,2])", "smc_global", &global),
        ("fused SMC-PHD (seed 004)", "smc_fused", &fused),
        ("GM-PHD", "gm", &gm),
    ];
    for (name, key, (tracks, _)) in &runs {
        let sr = success_rate(&scene.truth, tracks, &MatchConfig::iou(0.5))?;
        let r = evaluate(&scene.truth, tracks, &EvalConfig::default())?;
        for (m, v) in [
            ("sr", sr.success_rate),
            ("faf", sr.false_alarms_per_frame),
            ("mota", r.clear.mota),
            ("idf1", r.identity.idf1),
            ("hota", r.hota.hota),
            ("tracks", tracks.len() as f64),
        ] {
            metrics.insert(format!("{key}_{m}"), v);
        }
        table.row(vec![
            (*name).into(),
            format!("{:.1} %", 100.0 * sr.success_rate),
            format!("{:.2}", sr.false_alarms_per_frame),
            fmt_num(r.clear.mota),
            fmt_num(r.identity.idf1),
            fmt_num(r.hota.hota),
            r.clear.id_switches.to_string(),
            tracks.len().to_string(),
        ]);
    }
    let truth_count: Vec<(f64, f64)> = scene
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
    let cardinality = chart(
        &Axes {
            title: "Number of estimates against the number of people",
            x: "frame",
            y: "count",
        },
        &[
            Series::new("people", truth_count, Style::Line, 7),
            Series::new("global-only SMC-PHD", count(&global.1), Style::ThinLine, 0),
            Series::new("fused SMC-PHD", count(&fused.1), Style::Line, 1),
            Series::new("GM-PHD", count(&gm.1), Style::ThinLine, 2),
        ],
    )?;
    let mut plots = vec![Plot {
        name: "cardinality".into(),
        caption: "Estimated cardinality (reported targets) against the truth".into(),
        svg: cardinality,
    }];
    for &frame in &p.overlay_frames {
        let Some(people) = scene.by_frame.get(&frame) else {
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
        for (k, (name, _, (_, frames))) in runs.iter().enumerate() {
            if let Some(out) = frames.get(frame_index) {
                for (i, e) in out.estimates.iter().enumerate() {
                    let label = if i == 0 { *name } else { "" };
                    series.push(Series::new(label, outline(&e.bbox), Style::Line, k));
                }
            }
        }
        for d in scene.detections.get(frame_index).into_iter().flatten() {
            series.push(Series::new("", outline(d), Style::Markers, 3));
        }
        plots.push(Plot {
            name: format!("frame-{frame}"),
            caption: format!(
                "Frame {frame}: true boxes (grey), global detections (red corners), estimates \
                 of each method (coloured)"
            ),
            svg: chart(
                &Axes {
                    title: &format!("{}: frame {frame}", p.title),
                    x: "image x",
                    y: "−(image y)",
                },
                &series,
            )?,
        });
    }
    Ok(PipelineOutput {
        metrics,
        section: Section {
            title: format!("SMC-PHD with detector fusion (seed 004): {}", p.title),
            summary: format!(
                "Seed 004's Table 1 on a simulated scene. SR = tracked true boxes (IoU ≥ 0.5) / \
                 all true boxes; FAF = unmatched estimates per frame. p_D = {}, birth intensity \
                 {}, {} particles per target; local detectors start at confidence {} and are \
                 removed at {}.",
                p.filter.p_detect,
                p.filter.birth_rate,
                p.filter.particles_per_target,
                p.fusion.initial_confidence,
                p.fusion.removal_confidence
            ),
            tables: vec![table],
            plots,
        },
    })
}
