//! Trackers over a rotating radar's dwells, and what they are scored on: the truth and the
//! tracks once per revolution, position and velocity errors, and the track breaks during
//! turns.
//!
//! Revolution n is frame n: an aircraft's truth point in it is where it was at the dwell
//! whose sector held it, and a track's point is its estimate at the first dwell of the
//! revolution that saw it; both are at the same time when the track is on its aircraft.

use std::collections::BTreeMap;

use mcmcda::{BirthPrior, Dwell, PlotGnn, PlotTrackState};
use nalgebra::SVector;
use tracker_model::{
    Frame, MeasurementModel, RangeBearing, StateEstimator, TrackId, TrackPoint, TrackSet, Vec2,
    assignment,
};

use crate::error::Result;
use crate::radar::{RadarDwell, RotatingRadar};
use crate::trajectory::Trajectory;

/// The revolution a time falls in.
fn revolution(radar: &RotatingRadar, time_s: f64) -> Frame {
    // Dwell times are k·period/dwells; a small offset keeps a revolution's first dwell in it.
    ((time_s + 1e-9) / radar.period_s).floor().max(0.0) as Frame
}

/// A tracker's confirmed states over the dwells, the first per track and revolution.
#[derive(Debug, Clone)]
pub struct RadarRun<const N: usize> {
    /// (revolution, state), in order of time.
    pub states: Vec<(Frame, PlotTrackState<N>)>,
    /// Births the tracker refused because it held its most tracks.
    pub births_refused: u64,
}

/// Runs `gnn` over `dwells` of `radar`, starting tracks with `birth`.
pub fn track_dwells<E, const N: usize>(
    gnn: &mut PlotGnn<E, N>,
    radar: &RotatingRadar,
    dwells: &[RadarDwell],
    birth: BirthPrior,
) -> Result<RadarRun<N>>
where
    E: StateEstimator<N>,
{
    let sensor: RangeBearing<N> = radar.measurement_model()?;
    let mut states = Vec::new();
    let mut seen: BTreeMap<TrackId, Frame> = BTreeMap::new();
    for dwell in dwells {
        let beam = dwell.beam_rad;
        let step = Dwell {
            time_s: dwell.time_s,
            sensor: &sensor,
            plots: &dwell.plots,
            // No edge margin: one of 5 σ_θ made the IMM's OSPA worse on the stand-in (719 →
            // 850 m at q = 3) for reasons not yet found (docs/aircraft.md).
            in_view: &|z: &SVector<f64, 2>| radar.view(beam, 0.0, z),
            birth: &|z: &SVector<f64, 2>| birth.at(&sensor, z),
        };
        let frame = revolution(radar, dwell.time_s);
        for state in gnn.step(&step)? {
            if seen.insert(state.id, frame) != Some(frame) {
                states.push((frame, state));
            }
        }
    }
    Ok(RadarRun {
        states,
        births_refused: gnn.births_refused(),
    })
}

/// An aircraft in view at a dwell: which trajectory, the revolution, the time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthPoint {
    /// Index into the trajectories.
    pub trajectory: usize,
    /// The revolution.
    pub frame: Frame,
    /// The dwell's time, seconds.
    pub time_s: f64,
}

/// Every aircraft in view of each revolution, at the first dwell that held it in its sector
/// and range (detected or not).
pub fn truth_points(
    radar: &RotatingRadar,
    trajectories: &[Trajectory],
    dwells: &[RadarDwell],
) -> Result<Vec<TruthPoint>> {
    let sensor: RangeBearing<2> = radar.measurement_model()?;
    let mut seen: BTreeMap<usize, Frame> = BTreeMap::new();
    let mut out = Vec::new();
    for dwell in dwells {
        let frame = revolution(radar, dwell.time_s);
        for (i, t) in trajectories.iter().enumerate() {
            let Some(k) = t.at(dwell.time_s) else {
                continue;
            };
            let z = sensor.measure(&SVector::<f64, 2>::from(k.position));
            if radar.in_view(dwell.beam_rad, &z) && seen.insert(i, frame) != Some(frame) {
                out.push(TruthPoint {
                    trajectory: i,
                    frame,
                    time_s: dwell.time_s,
                });
            }
        }
    }
    Ok(out)
}

/// The truth as tracks, trajectory i as track i + 1, one point per revolution in view.
pub fn truth_set(trajectories: &[Trajectory], points: &[TruthPoint]) -> Result<TrackSet> {
    let mut by_track: BTreeMap<usize, Vec<TrackPoint>> = BTreeMap::new();
    for p in points {
        if let Some(k) = trajectories[p.trajectory].at(p.time_s) {
            let point = TrackPoint::at(p.frame, Vec2::new(k.position[0], k.position[1]));
            by_track.entry(p.trajectory).or_default().push(point);
        }
    }
    let lists = by_track
        .into_iter()
        .map(|(i, points)| (TrackId(i as u64 + 1), points));
    Ok(TrackSet::from_point_lists(lists)?)
}

/// A run's tracks, one point per revolution.
pub fn track_set<const N: usize>(run: &RadarRun<N>) -> Result<TrackSet> {
    let mut by_track: BTreeMap<TrackId, Vec<TrackPoint>> = BTreeMap::new();
    for (frame, s) in &run.states {
        let m = s.estimate.mean();
        by_track
            .entry(s.id)
            .or_default()
            .push(TrackPoint::at(*frame, Vec2::new(m[0], m[1])));
    }
    Ok(TrackSet::from_point_lists(by_track)?)
}

/// Position and velocity errors of matched pairs, and breaks during turns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KinematicScore {
    /// RMS position error over matched (aircraft, track) pairs, metres.
    pub position_rmse_m: f64,
    /// RMS velocity error over the same pairs, m/s.
    pub velocity_rmse_m_s: f64,
    /// Matched pairs.
    pub matched: usize,
    /// Revolutions of a turning aircraft that was matched in its previous revolution.
    pub turning_chances: usize,
    /// Of those, the revolutions where it lost that track (to no track or another).
    pub turning_breaks: usize,
}

impl KinematicScore {
    /// Breaks per turning revolution.
    pub fn break_rate(&self) -> f64 {
        self.turning_breaks as f64 / self.turning_chances.max(1) as f64
    }
}

/// What [`score`] needs besides the run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScoreConfig {
    /// A track farther than this from an aircraft is not its match, metres.
    pub match_distance_m: f64,
    /// An aircraft turning faster than this is in a manoeuvre, rad/s.
    pub turn_rate_rad_s: f64,
    /// Half the window the turn rate is measured over, seconds.
    pub turn_half_window_s: f64,
}

/// Scores `run` against the truth: each revolution, aircraft and tracks are matched one to
/// one by the optimal assignment of their distances within `match_distance_m`.
pub fn score<const N: usize>(
    trajectories: &[Trajectory],
    points: &[TruthPoint],
    run: &RadarRun<N>,
    config: &ScoreConfig,
) -> KinematicScore {
    let mut tracks_by_frame: BTreeMap<Frame, Vec<&PlotTrackState<N>>> = BTreeMap::new();
    for (frame, s) in &run.states {
        tracks_by_frame.entry(*frame).or_default().push(s);
    }
    let mut truth_by_frame: BTreeMap<Frame, Vec<&TruthPoint>> = BTreeMap::new();
    for p in points {
        truth_by_frame.entry(p.frame).or_default().push(p);
    }
    let mut previous: BTreeMap<usize, (Frame, TrackId)> = BTreeMap::new();
    let (mut sq_p, mut sq_v, mut matched, mut chances, mut breaks) = (0.0, 0.0, 0, 0, 0);
    for (frame, truths) in &truth_by_frame {
        let tracks = tracks_by_frame.get(frame).map_or(&[][..], Vec::as_slice);
        let pairs = match_frame(trajectories, truths, tracks, config.match_distance_m);
        for (k, p) in truths.iter().enumerate() {
            let now = pairs[k].map(|j| tracks[j].id);
            let turning = trajectories[p.trajectory]
                .turn_rate_at(p.time_s, config.turn_half_window_s)
                .is_some_and(|w| w.abs() > config.turn_rate_rad_s);
            if let Some(&(last_frame, last_id)) = previous.get(&p.trajectory)
                && turning
                && last_frame + 1 == *frame
            {
                chances += 1;
                breaks += usize::from(now != Some(last_id));
            }
            match (now, pairs[k]) {
                (Some(id), Some(j)) => {
                    previous.insert(p.trajectory, (*frame, id));
                    let truth = trajectories[p.trajectory].at(p.time_s);
                    if let Some(t) = truth {
                        let m = tracks[j].estimate.mean();
                        sq_p += (m[0] - t.position[0]).powi(2) + (m[1] - t.position[1]).powi(2);
                        sq_v += (m[2] - t.velocity[0]).powi(2) + (m[3] - t.velocity[1]).powi(2);
                        matched += 1;
                    }
                }
                _ => {
                    previous.remove(&p.trajectory);
                }
            }
        }
    }
    let n = matched.max(1) as f64;
    KinematicScore {
        position_rmse_m: (sq_p / n).sqrt(),
        velocity_rmse_m_s: (sq_v / n).sqrt(),
        matched,
        turning_chances: chances,
        turning_breaks: breaks,
    }
}

/// For each truth point, the index of its matched track: minimum total distance, pairs within
/// `max_distance` only.
fn match_frame<const N: usize>(
    trajectories: &[Trajectory],
    truths: &[&TruthPoint],
    tracks: &[&PlotTrackState<N>],
    max_distance: f64,
) -> Vec<Option<usize>> {
    let (rows, cols) = (truths.len(), tracks.len());
    let mut weights = vec![0.0; rows * cols];
    for (i, p) in truths.iter().enumerate() {
        let Some(t) = trajectories[p.trajectory].at(p.time_s) else {
            continue;
        };
        for (j, s) in tracks.iter().enumerate() {
            let m = s.estimate.mean();
            let d = (m[0] - t.position[0]).hypot(m[1] - t.position[1]);
            if d <= max_distance {
                // Maximising max_distance − d over pairs in reach minimises their distance.
                weights[i * cols + j] = max_distance - d + f64::MIN_POSITIVE;
            }
        }
    }
    let mut out = vec![None; rows];
    if let Ok(pairs) = assignment::maximise(rows, cols, &weights) {
        for (i, j) in pairs {
            if weights[i * cols + j] > 0.0 {
                out[i] = Some(j);
            }
        }
    }
    out
}
