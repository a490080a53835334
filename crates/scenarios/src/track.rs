//! Trackers for detection files: what `cargo xtask track` and the `mot-track` pipeline run.
//! MCMCDA and GNN track the box centres as point measurements and output smoothed centres with
//! each track's mean detection size; the SMC-PHD filter tracks the boxes themselves. Without a
//! configuration each tracker uses its model scaled to the boxes
//! ([`McmcdaConfig::for_boxes`], [`PhdConfig::for_boxes`]).
//!
//! No tracker's cost grows with gaps in the frame numbers: MCMCDA's and GNN's `Problem` stores
//! only non-empty scans, and the PHD path steps the frames with detections plus at most the
//! first few empty frames of a gap (until the filter has forgotten what came before; see
//! `coast_frames`).

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
    let cap = coast_frames(config.p_survive, config.p_detect);
    let mut phd = PhdTracker::global_only(SmcPhd::new(config, seed)?);
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<BoundingBox>> = Default::default();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(r.bbox);
    }
    if by_frame.is_empty() {
        bail!("no detections");
    }
    // Frames with detections are stepped; an empty frame in between is a predict plus an
    // update with no measurement, which scales every weight by p_S (1 − p_D) and adds no
    // births (they come from measurements). So only the first `cap` empty frames of a gap are
    // stepped: after them, what the filter carried over weighs less than 1e-12 of what it
    // did, and the rest of the gap is skipped. The cost is bounded by the detection frames,
    // not by the span of frame numbers.
    let mut previous: Option<Frame> = None;
    for (&frame, boxes) in &by_frame {
        if let Some(prev) = previous {
            let empty = u64::from(frame) - u64::from(prev) - 1;
            for k in 1..=empty.min(cap) {
                // k ≤ frame − prev − 1, so prev + k < frame fits a Frame.
                phd.step(prev + k as Frame, &[])?;
            }
        }
        phd.step(frame, boxes)?;
        previous = Some(frame);
    }
    Ok(phd.tracks()?)
}

/// How many empty frames the PHD path steps through before it skips the rest of a gap: the
/// smallest k with (p_S (1 − p_D))^k < 1e-12, at most [`MAX_COAST_FRAMES`].
fn coast_frames(p_survive: f64, p_detect: f64) -> u64 {
    let per_frame = (p_survive * (1.0 - p_detect)).ln();
    let k = (1e-12f64.ln() / per_frame).ceil();
    if k.is_finite() && k >= 1.0 {
        (k as u64).min(MAX_COAST_FRAMES)
    } else {
        1
    }
}

/// The most empty frames stepped in one gap, whatever p_S and p_D say (with p_S (1 − p_D)
/// near 1 the filter forgets slowly; this bounds the cost of a gap).
const MAX_COAST_FRAMES: u64 = 10_000;

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

#[cfg(test)]
mod tests {
    use super::*;

    /// Two walkers seen in frames 1-20, then again four billion frames later.
    fn rows_with_a_jump() -> Vec<MotRow> {
        let far = 4_000_000_000u32;
        let frames = (1..=20).chain(far..far + 20);
        frames
            .flat_map(|f| {
                let t = f64::from(f % 32);
                [(100.0 + 8.0 * t, 200.0), (400.0, 100.0 + 6.0 * t)].map(|(x, y)| MotRow {
                    frame: f,
                    id: -1,
                    // Sizes vary a little, as detections do (the PHD's clutter density
                    // divides by the spread of box sizes).
                    bbox: BoundingBox::new(x, y, 40.0 + f64::from(f % 5), 90.0 + f64::from(f % 7))
                        .unwrap(),
                    confidence: 1.0,
                    world: [-1.0; 3],
                })
            })
            .collect()
    }

    #[test]
    fn a_jump_of_four_billion_frames_costs_no_more_than_the_next_frame() {
        // Every tracker steps the frames with detections (and a few empty ones after each),
        // never the four billion empty frames between.
        let rows = rows_with_a_jump();
        for tracker in Tracker::ALL {
            let tracks = track_detections(tracker, &rows, &TrackConfig::default(), 1).unwrap();
            let last = tracks
                .tracks()
                .iter()
                .flat_map(|t| t.points().iter().map(|p| p.frame))
                .max();
            assert!(last >= Some(4_000_000_000), "{tracker}: {last:?}");
            assert!(!tracks.is_empty(), "{tracker}");
        }
    }

    #[test]
    fn the_phd_path_coasts_until_the_filter_has_forgotten() {
        // p_S (1 − p_D) = 0.99 · 0.2: 0.198^k < 1e-12 from k = 18 (by hand: ln 1e-12 / ln 0.198
        // = 27.63 / 1.619 = 17.06).
        assert_eq!(coast_frames(0.99, 0.8), 18);
        // Nearly no forgetting: bounded.
        assert_eq!(coast_frames(0.999_999, 1e-9), MAX_COAST_FRAMES);
    }
}
