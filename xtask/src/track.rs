//! `cargo xtask track --tracker mcmcda|gnn --input DETS.txt --out TRACKS.txt`: runs a tracker
//! on MOTChallenge detections (box centres as point measurements) and writes MOTChallenge
//! tracks (smoothed centres, each track's mean detection size).

use std::fs;
use std::io::BufReader;
use std::path::Path;

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use mcmcda::{
    McmcdaConfig, MeasId, NearestNeighbourConfig, OnlineConfig, OnlineTracker, Problem, TrackEnd,
    TrackInit, nearest_neighbour_tracks, smoothed_tracks,
};
use nalgebra::Matrix2;
use phd_filter::{FusionConfig, Motion, NoLocalDetectors, PhdConfig, PhdTracker, SmcPhd};
use serde::Deserialize;
use tracker_model::{
    BoundingBox, ConstantVelocity2, Frame, MotRow, Point2, Track, TrackPoint, TrackSet, format_mot,
    parse_mot,
};

use crate::Outcome;

/// Which tracker `track` runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Tracker {
    /// Online sliding-window MCMCDA.
    Mcmcda,
    /// Global nearest neighbour with M-of-N confirmation.
    Gnn,
    /// SMC-PHD on boxes (global detections only: no images, so no local detectors).
    Phd,
}

/// The optional `--config` TOML: any of the three tables, each field optional. Fields of
/// `[model]` override the model scaled to the detections.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TrackConfig {
    model: Option<toml::Table>,
    #[serde(default)]
    online: OnlineConfig,
    #[serde(default)]
    gnn: NearestNeighbourConfig,
    /// Fields of `phd_filter::PhdConfig`, overriding a configuration scaled to the boxes.
    phd: Option<toml::Table>,
}

/// A model scaled to the detections when no `--config` model is given: lengths follow the
/// median box width w (measurement σ = 0.1 w, speed ≤ w per frame, acceleration σ = 0.05 w),
/// the region is the detections' bounding box.
fn default_model(rows: &[MotRow]) -> Result<McmcdaConfig> {
    let mut widths: Vec<f64> = rows.iter().map(|r| r.bbox.width).collect();
    widths.sort_by(f64::total_cmp);
    let w = widths[widths.len() / 2].max(1.0);
    let (mut lo, mut hi) = (
        Point2::repeat(f64::INFINITY),
        Point2::repeat(f64::NEG_INFINITY),
    );
    for r in rows {
        let c = r.bbox.centre();
        lo = lo.inf(&c);
        hi = hi.sup(&c);
    }
    let extent = hi - lo;
    let volume = (extent.x.max(w) * extent.y.max(w)).max(1.0);
    Ok(McmcdaConfig {
        volume,
        births_per_scan: 0.1,
        clutter_per_scan: 1.0,
        p_disappear: 0.01,
        p_detect: 0.8,
        motion: ConstantVelocity2::mcmcda(1.0, (0.05 * w).powi(2))?,
        measurement_noise: Matrix2::identity() * (0.1 * w).powi(2),
        max_speed: w,
        track_init: TrackInit::FirstMeasurement {
            velocity_variance: Some((0.3 * w).powi(2)),
        },
        track_end: TrackEnd::Undetected,
        ..McmcdaConfig::default()
    })
}

/// Reads MOTChallenge detections; errors name the file and line.
pub(crate) fn read_detections(input: &Path) -> Result<Vec<MotRow>> {
    let file = fs::File::open(input).with_context(|| format!("cannot open {}", input.display()))?;
    let rows = parse_mot(BufReader::new(file))
        .with_context(|| format!("{} is not a valid MOTChallenge file", input.display()))?;
    if rows.is_empty() {
        bail!("{} holds no detections", input.display());
    }
    Ok(rows)
}

/// Reads the optional configuration file.
fn read_config(config: Option<&Path>) -> Result<TrackConfig> {
    match config {
        Some(path) => {
            let text = fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            toml::from_str(&text).with_context(|| format!("in {}", path.display()))
        }
        None => Ok(TrackConfig::default()),
    }
}

/// Tracks `rows` (box centres as points) and returns boxed tracks with ids from 1: smoothed
/// centres, each track's mean detection size.
pub(crate) fn track_detections(
    tracker: Tracker,
    rows: &[MotRow],
    settings: &TrackConfig,
    seed: u64,
) -> Result<TrackSet> {
    match tracker {
        Tracker::Phd => track_boxes_phd(rows, settings, seed),
        Tracker::Mcmcda => track_points(true, rows, settings, seed),
        Tracker::Gnn => track_points(false, rows, settings, seed),
    }
}

/// SMC-PHD on the boxes themselves.
fn track_boxes_phd(rows: &[MotRow], settings: &TrackConfig, seed: u64) -> Result<TrackSet> {
    let config = overridden(&default_phd(rows), settings.phd.as_ref(), "phd")?;
    let mut phd = PhdTracker::new(
        SmcPhd::new(config, seed)?,
        None::<NoLocalDetectors>,
        FusionConfig::default(),
    )?;
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<BoundingBox>> = Default::default();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(r.bbox);
    }
    let (first, last) = match (by_frame.keys().next(), by_frame.keys().last()) {
        (Some(a), Some(b)) => (*a, *b),
        _ => bail!("no detections"),
    };
    for frame in first..=last {
        let boxes = by_frame.get(&frame).map(Vec::as_slice).unwrap_or(&[]);
        phd.step(frame, boxes)?;
    }
    Ok(phd.tracks()?)
}

/// Online MCMCDA (`use_mcmcda`) or GNN on the box centres; boxes get each track's mean
/// detection size.
fn track_points(
    use_mcmcda: bool,
    rows: &[MotRow],
    settings: &TrackConfig,
    seed: u64,
) -> Result<TrackSet> {
    let model = overridden(&default_model(rows)?, settings.model.as_ref(), "model")?.check()?;
    // Detections by frame, in file order within a frame; ids follow that order.
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<MotRow>> = Default::default();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(*r);
    }
    let detections: Vec<MotRow> = by_frame.values().flatten().copied().collect();
    let first = by_frame.keys().next().copied().unwrap_or(0);
    let centres = |dets: &[MotRow]| {
        dets.iter()
            .map(|d| d.bbox.centre())
            .collect::<Vec<Point2>>()
    };
    let (associations, problem): (Vec<(u64, Vec<MeasId>)>, Problem) = if use_mcmcda {
        let mut online = OnlineTracker::new(model.clone(), first, settings.online, seed)?;
        for (frame, dets) in &by_frame {
            online.push_scan(*frame, &centres(dets))?;
        }
        let result = online.finish()?;
        (result.associations, result.problem)
    } else {
        let mut problem = Problem::empty(&model, first);
        for (frame, dets) in &by_frame {
            problem.push_scan(*frame, &centres(dets))?;
        }
        let window = 0..=problem.n_scans() - 1;
        let tracks = nearest_neighbour_tracks(&model, &problem, window, &settings.gnn)?;
        let labelled = tracks.into_iter().zip(0..).map(|(t, i)| (i, t)).collect();
        (labelled, problem)
    };
    let mut tracks = Vec::with_capacity(associations.len());
    for (label, meas) in &associations {
        let smoothed = smoothed_tracks(&model, &problem, std::slice::from_ref(meas), label + 1)?;
        let n = meas.len() as f64;
        let width = meas
            .iter()
            .map(|&m| detections[m as usize].bbox.width)
            .sum::<f64>()
            / n;
        let height = meas
            .iter()
            .map(|&m| detections[m as usize].bbox.height)
            .sum::<f64>()
            / n;
        for t in smoothed.tracks() {
            let points = t
                .points()
                .iter()
                .map(|p| {
                    Ok(TrackPoint::boxed(
                        p.frame,
                        BoundingBox::from_centre(p.location.position(), width, height)?,
                    ))
                })
                .collect::<Result<Vec<_>>>()?;
            tracks.push(Track::from_points(t.id(), points)?);
        }
    }
    Ok(TrackSet::from_tracks(tracks)?)
}

/// A PHD configuration scaled to the detections: noise and motion from the median box
/// size, clutter uniform over the image extent and the range of box sizes.
fn default_phd(rows: &[MotRow]) -> PhdConfig {
    let median = |f: fn(&MotRow) -> f64| {
        let mut v: Vec<f64> = rows.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2].max(1.0)
    };
    let range = |f: fn(&MotRow) -> f64| {
        let (lo, hi) = rows
            .iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        (hi - lo).max(1.0)
    };
    let (w, h) = (median(|r| r.bbox.width), median(|r| r.bbox.height));
    PhdConfig {
        measurement_volume: range(|r| r.bbox.centre().x)
            * range(|r| r.bbox.centre().y)
            * range(|r| r.bbox.width)
            * range(|r| r.bbox.height),
        measurement_std: [0.1 * w, 0.05 * h, 0.1 * w, 0.05 * h],
        motion: Motion::RandomWalk {
            position_std: 0.1 * w,
            size_std: 0.02 * h,
        },
        // Public detectors miss far more than the seed's 5 %; a lower p_D keeps a track
        // through a missed detection.
        p_detect: 0.8,
        particles_per_target: 300,
        birth_particles: 100,
        ..PhdConfig::default()
    }
}

/// Merges the fields of `overrides` into `base` (both serde structs) and checks the result.
fn overridden<T: Clone + serde::Serialize + serde::de::DeserializeOwned>(
    base: &T,
    overrides: Option<&toml::Table>,
    what: &str,
) -> Result<T> {
    let Some(overrides) = overrides else {
        return Ok(base.clone());
    };
    let mut table = toml::Table::try_from(base)?;
    table.extend(overrides.clone());
    table
        .try_into()
        .with_context(|| format!("in the [{what}] table of the configuration"))
}

/// Runs the command.
#[expect(clippy::print_stdout, reason = "a one-line summary on the terminal")]
pub fn run(
    tracker: Tracker,
    input: &Path,
    out: &Path,
    config: Option<&Path>,
    seed: u64,
) -> Outcome {
    let rows = read_detections(input)?;
    let set = track_detections(tracker, &rows, &read_config(config)?, seed)?;
    fs::write(out, format_mot(&set.to_mot_rows(0.0)))
        .with_context(|| format!("cannot write {}", out.display()))?;
    println!(
        "{} tracks ({} boxes) from {} detections written to {}",
        set.len(),
        set.n_points(),
        rows.len(),
        out.display()
    );
    Ok(true)
}
