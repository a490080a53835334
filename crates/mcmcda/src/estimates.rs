//! From a partition to what users want: smoothed trajectories, and per-scan labels of the
//! measurements for association scoring.

use tracker_model::{
    Gaussian, LinearObservation, Track, TrackId, TrackPoint, TrackSet, filter, smooth,
};

use crate::config::Model;
use crate::error::{Error, Result};
use crate::problem::{MeasId, Problem};

/// Checks that every id of track `k` exists in `problem` and that the ids lie in strictly
/// increasing scans.
fn check_ids(problem: &Problem, k: usize, track: &[MeasId]) -> Result<()> {
    if let Some(&id) = track.iter().find(|&&m| !problem.contains(m)) {
        return Err(Error::UnknownMeasurement { track: k, id });
    }
    match track
        .windows(2)
        .find(|p| problem.scan_of(p[1]) <= problem.scan_of(p[0]))
    {
        Some(p) => Err(Error::ScansNotIncreasing {
            track: k,
            first: p[0],
            second: p[1],
        }),
        None => Ok(()),
    }
}

/// Kalman-smoothed states of each track at every frame from its first to its last
/// measurement (missed scans filled by the smoother), one scan period per step. Track i gets
/// id `first_id + i`. The filter starts at the first measurement with position covariance R
/// and the configured initial velocity variance per axis (v̄²/3 for the two-point start).
///
/// Each track's ids must exist in `problem` ([`Error::UnknownMeasurement`]) and lie in
/// strictly increasing scans ([`Error::ScansNotIncreasing`]); empty tracks are skipped. The
/// output has a point per frame of each track's span, so its size grows with the span.
pub fn smoothed_tracks(
    model: &Model,
    problem: &Problem,
    tracks: &[Vec<MeasId>],
    first_id: u64,
) -> Result<TrackSet> {
    let cfg = model.config();
    let sensor = LinearObservation::leading_components(cfg.measurement_noise)?;
    let v = match cfg.track_init {
        crate::TrackInit::FirstMeasurement { .. } => model.initial_velocity_variance,
        crate::TrackInit::TwoPoint { .. } => cfg.max_speed * cfg.max_speed / 3.0,
    };
    for (k, track) in tracks.iter().enumerate() {
        check_ids(problem, k, track)?;
    }
    let mut out = Vec::with_capacity(tracks.len());
    for (i, track) in tracks.iter().enumerate() {
        let (Some(&first), Some(&last)) = (track.first(), track.last()) else {
            continue;
        };
        let (t0, t1) = (problem.scan_of(first), problem.scan_of(last));
        let mut zs = vec![None; t1 - t0 + 1];
        for &m in &track[1..] {
            zs[problem.scan_of(m) - t0] = Some(problem.position(m));
        }
        // The first step has no measurement: its filtered state is this start.
        let (mean, cov) = model.start_at(problem.position(first), v);
        let start = Gaussian::new(mean, cov)?;
        let run = filter(&cfg.motion, &sensor, &start, &zs)?;
        let states = smooth(&cfg.motion, &run)?;
        let points = states
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let m = s.mean();
                TrackPoint {
                    velocity: Some(nalgebra::Vector2::new(m[2], m[3])),
                    covariance: Some(s.covariance().fixed_view::<2, 2>(0, 0).into_owned()),
                    ..TrackPoint::at(
                        problem.first_frame() + (t0 + k) as u32,
                        nalgebra::Vector2::new(m[0], m[1]),
                    )
                }
            })
            .collect();
        out.push(Track::from_points(TrackId(first_id + i as u64), points)?);
    }
    Ok(TrackSet::from_tracks(out)?)
}

/// For each scan, the label (track index) of each of its measurements in the order the
/// problem holds them, `None` for false alarms: the input of
/// `eval_metrics::association_scores`. One list per scan index, empty scans included, so
/// the output grows with the frame span (as the scans it is scored against do).
///
/// Fails with [`Error::UnknownMeasurement`] for an id the problem does not have and
/// [`Error::MeasurementTaken`] for an id in two tracks.
pub fn measurement_labels(
    problem: &Problem,
    tracks: &[Vec<MeasId>],
) -> Result<Vec<Vec<Option<u64>>>> {
    let mut label = vec![None; problem.n_measurements()];
    for (k, track) in tracks.iter().enumerate() {
        for &id in track {
            match label.get_mut(id as usize) {
                None => return Err(Error::UnknownMeasurement { track: k, id }),
                Some(Some(_)) => return Err(Error::MeasurementTaken { track: k, id }),
                Some(slot) => *slot = Some(k as u64),
            }
        }
    }
    let mut out = vec![Vec::new(); problem.n_scans()];
    for (s, scan) in problem.nonempty_scans(0..=problem.n_scans().saturating_sub(1)) {
        out[s] = scan.iter().map(|&m| label[m as usize]).collect();
    }
    Ok(out)
}

/// The true partition of simulated scans (each target's detections, in scan order), with
/// measurement ids as [`Problem::from_scans`] gives them (scan by scan, in order). Targets
/// detected fewer than twice are not tracks.
pub fn tracks_by_origin(scans: &[tracker_model::Scan]) -> Vec<Vec<MeasId>> {
    let mut by_target: std::collections::BTreeMap<TrackId, Vec<MeasId>> = Default::default();
    let mut id: MeasId = 0;
    for scan in scans {
        for m in &scan.measurements {
            if let tracker_model::Origin::Target(t) = m.origin {
                by_target.entry(t).or_default().push(id);
            }
            id += 1;
        }
    }
    by_target.into_values().filter(|t| t.len() >= 2).collect()
}
