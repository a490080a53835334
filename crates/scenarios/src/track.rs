//! Trackers for detection files: what `cargo xtask track` and the `mot-track` pipeline run.
//! MCMCDA and GNN track the box centres as point measurements and output smoothed centres with
//! each track's mean detection size; the SMC-PHD filter tracks the boxes themselves. Without a
//! configuration each tracker uses its model scaled to the boxes
//! ([`McmcdaConfig::for_boxes`], [`PhdConfig::for_boxes`]).

use std::fmt;
use std::str::FromStr;

use anyhow::{Context, Result, bail};
use mcmcda::{
    McmcdaConfig, MeasId, NearestNeighbourConfig, OnlineConfig, OnlineTracker, Problem,
    nearest_neighbour_tracks, smoothed_tracks,
};
use phd_filter::{PhdConfig, PhdTracker, SmcPhd};
use serde::Deserialize;
use tracker_model::{BoundingBox, Frame, MotRow, Track, TrackPoint, TrackSet, Vec2};

/// Which tracker runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Tracker {
    /// Online sliding-window MCMCDA.
    Mcmcda,
    /// Global nearest neighbour with M-of-N confirmation.
    Gnn,
    /// SMC-PHD on boxes (global detections only: no images, so no local detectors).
    Phd,
}

impl Tracker {
    /// Every tracker, in the order the command line lists them.
    pub const ALL: [Tracker; 3] = [Tracker::Mcmcda, Tracker::Gnn, Tracker::Phd];

    /// The name on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Tracker::Mcmcda => "mcmcda",
            Tracker::Gnn => "gnn",
            Tracker::Phd => "phd",
        }
    }
}

impl fmt::Display for Tracker {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Tracker {
    type Err = anyhow::Error;

    fn from_str(s: &str) -> Result<Self> {
        Tracker::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .with_context(|| format!("unknown tracker {s:?}; known: mcmcda, gnn, phd"))
    }
}

/// The optional configuration (TOML): any of the four tables, each field optional. Fields of
/// `[model]` and `[phd]` override the configurations scaled to the detections.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackConfig {
    model: Option<toml::Table>,
    #[serde(default)]
    online: OnlineConfig,
    #[serde(default)]
    gnn: NearestNeighbourConfig,
    /// Fields of `phd_filter::PhdConfig`, overriding a configuration scaled to the boxes.
    phd: Option<toml::Table>,
}

/// Tracks `rows` and returns boxed tracks with ids from 1.
pub fn track_detections(
    tracker: Tracker,
    rows: &[MotRow],
    settings: &TrackConfig,
    seed: u64,
) -> Result<TrackSet> {
    match tracker {
        Tracker::Phd => track_boxes_phd(rows, settings, seed),
        Tracker::Mcmcda | Tracker::Gnn => track_points(tracker, rows, settings, seed),
    }
}

/// SMC-PHD on the boxes themselves.
fn track_boxes_phd(rows: &[MotRow], settings: &TrackConfig, seed: u64) -> Result<TrackSet> {
    let config = overridden(
        &PhdConfig::for_boxes(&boxes(rows))?,
        settings.phd.as_ref(),
        "phd",
    )?;
    let mut phd = PhdTracker::global_only(SmcPhd::new(config, seed)?);
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

/// Online MCMCDA or GNN on the box centres; boxes get each track's mean detection size.
fn track_points(
    tracker: Tracker,
    rows: &[MotRow],
    settings: &TrackConfig,
    seed: u64,
) -> Result<TrackSet> {
    let model = overridden(
        &McmcdaConfig::for_boxes(&boxes(rows))?,
        settings.model.as_ref(),
        "model",
    )?
    .check()?;
    // Detections by frame, in file order within a frame; ids follow that order.
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<MotRow>> = Default::default();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(*r);
    }
    let detections: Vec<MotRow> = by_frame.values().flatten().copied().collect();
    let first = by_frame.keys().next().copied().unwrap_or(0);
    let centres = |dets: &[MotRow]| dets.iter().map(|d| d.bbox.centre()).collect::<Vec<Vec2>>();
    let (associations, problem): (Vec<(u64, Vec<MeasId>)>, Problem) = if tracker == Tracker::Mcmcda
    {
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
        let window = problem.all_scans()?;
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

fn boxes(rows: &[MotRow]) -> Vec<BoundingBox> {
    rows.iter().map(|r| r.bbox).collect()
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
