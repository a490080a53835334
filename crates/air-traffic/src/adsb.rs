//! ADS-B collections as the `traffic` package stores them (`traffic.core.Traffic` written as
//! JSON records: one object per report with `icao24`, `timestamp` in ms, `latitude`,
//! `longitude`, `groundspeed` in knots, `track` in degrees clockwise from north, `onground`
//! and more, any of them null) read into [`Trajectory`]s in a local east-north frame.
//!
//! Reports on the ground or without a position are dropped; an aircraft's reports are sorted
//! by time, repeated time stamps keep the first, and a gap longer than `max_gap_s` splits it
//! into separate trajectories with the same label. Velocities come from ground speed and
//! track where reported, else from the neighbouring positions. Positions are taken at the
//! ellipsoid's surface (height 0): what a 2-D radar that corrects slant range with the
//! reported altitude sees.

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::geodesy::EnuFrame;
use crate::trajectory::{Sample, Trajectory};

/// Knots to metres per second.
const KNOT_M_S: f64 = 1852.0 / 3600.0;

/// One report: seconds from the start, east-north position, reported velocity.
type Raw = (f64, [f64; 2], Option<[f64; 2]>);

/// The most reports a collection may hold (the `traffic` quickstart has 284,505).
pub const MAX_REPORTS: usize = 20_000_000;

#[derive(Debug, Deserialize)]
struct Report {
    icao24: String,
    timestamp: f64,
    latitude: Option<f64>,
    longitude: Option<f64>,
    groundspeed: Option<f64>,
    track: Option<f64>,
    #[serde(default)]
    onground: Option<bool>,
}

/// How a collection becomes trajectories.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReadConfig {
    /// The local frame.
    pub frame: EnuFrame,
    /// A longer gap between reports splits a trajectory.
    pub max_gap_s: f64,
    /// Trajectories shorter than this are dropped.
    pub min_duration_s: f64,
}

/// The collection's reports as trajectories, with times in seconds from its first report.
pub fn read_collection(json: &str, config: &ReadConfig) -> Result<Vec<Trajectory>> {
    tracker_model::ensure_positive(config.max_gap_s, "max_gap_s")?;
    tracker_model::ensure_non_negative(config.min_duration_s, "min_duration_s")?;
    let reports: Vec<Report> = serde_json::from_str(json)
        .map_err(|e| Error::Collection(format!("not a list of ADS-B records: {e}")))?;
    if reports.len() > MAX_REPORTS {
        return Err(Error::Collection(format!(
            "{} reports; at most {MAX_REPORTS}",
            reports.len()
        )));
    }
    let start_ms = reports
        .iter()
        .map(|r| r.timestamp)
        .fold(f64::INFINITY, f64::min);
    let mut by_aircraft: BTreeMap<&str, Vec<Raw>> = BTreeMap::new();
    for r in &reports {
        let (Some(lat), Some(lon)) = (r.latitude, r.longitude) else {
            continue;
        };
        if r.onground == Some(true) {
            continue;
        }
        let [e, n, _] = config.frame.to_enu(lat, lon, 0.0)?;
        let velocity = match (r.groundspeed, r.track) {
            (Some(gs), Some(track)) if gs.is_finite() && track.is_finite() => {
                let (s, c) = track.to_radians().sin_cos();
                Some([gs * KNOT_M_S * s, gs * KNOT_M_S * c])
            }
            _ => None,
        };
        let t = (r.timestamp - start_ms) / 1000.0;
        by_aircraft
            .entry(&r.icao24)
            .or_default()
            .push((t, [e, n], velocity));
    }
    let mut out = Vec::new();
    for (label, mut reports) in by_aircraft {
        reports.sort_by(|a, b| a.0.total_cmp(&b.0));
        reports.dedup_by(|b, a| b.0.to_bits() == a.0.to_bits());
        for piece in split_at_gaps(&reports, config.max_gap_s) {
            let samples = with_velocities(piece);
            let duration = samples.last().map_or(0.0, |s| s.time_s) - samples[0].time_s;
            if samples.len() >= 2 && duration >= config.min_duration_s {
                out.push(Trajectory::new(label.to_string(), samples)?);
            }
        }
    }
    Ok(out)
}

/// The runs of reports with no gap longer than `max_gap_s` between neighbours.
fn split_at_gaps(reports: &[Raw], max_gap_s: f64) -> Vec<&[Raw]> {
    let mut pieces = Vec::new();
    let mut start = 0;
    for i in 1..reports.len() {
        if reports[i].0 - reports[i - 1].0 > max_gap_s {
            pieces.push(&reports[start..i]);
            start = i;
        }
    }
    pieces.push(&reports[start..]);
    pieces
}

/// Samples with the reported velocity, or the central difference of the positions where none
/// was reported.
fn with_velocities(piece: &[Raw]) -> Vec<Sample> {
    (0..piece.len())
        .map(|i| {
            let (t, p, v) = piece[i];
            let velocity = v.unwrap_or_else(|| {
                let (a, b) = (
                    piece[i.saturating_sub(1)],
                    piece[(i + 1).min(piece.len() - 1)],
                );
                let dt = b.0 - a.0;
                if dt > 0.0 {
                    [(b.1[0] - a.1[0]) / dt, (b.1[1] - a.1[1]) / dt]
                } else {
                    [0.0, 0.0]
                }
            });
            Sample {
                time_s: t,
                position: p,
                velocity,
            }
        })
        .collect()
}
