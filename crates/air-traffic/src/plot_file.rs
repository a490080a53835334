//! Users' own radar plots: a CSV file in, tracks as CSV out, and point truth for scoring.
//!
//! Plots: one row per plot, with a header naming the columns (any order, extra columns
//! ignored):
//! - `time_s`, `sensor` (an integer id), `sensor_x`, `sensor_y` (metres);
//! - either `x`, `y` (a position, metres) or `range`, `bearing` (metres; radians
//!   counter-clockwise from the x axis);
//! - optionally the plot's noise: `sigma_x`, `sigma_y` or `sigma_range`, `sigma_bearing`;
//!   without them, the configuration's;
//! - optionally the sector the sensor looked at, `beam_rad` and `beam_width_rad` (a rotating
//!   radar's dwell): a track outside it is neither predicted nor missed there. Without them
//!   a dwell sees everything within `max_range_m`, so a sector-by-sector radar needs them.
//!
//! Plots with the same time, sensor and noise form one dwell. Every sensor is taken to see
//! everything within `max_range_m`. Tracks (`time_s,track_id,x,y,vx,vy,hit`) are written at
//! every dwell that saw them, `hit` 1 when a plot updated them. Truth for `eval` is `time_s,id,x,y`, and a track file reads as
//! the same; frames are the distinct times of both files.

use std::collections::BTreeMap;

use mcmcda::{Dwell, PlotGnn, PlotGnnConfig, View};
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};
use tracker_model::{
    Error as ModelError, Gaussian, LinearObservation, MeasurementModel, RadarSite, RangeBearing,
    SigmaPoints, StateEstimator, TrackId, TrackPoint, TrackSet, Vec2,
};

use crate::error::{Error, Result};
use crate::trackers::MotionSettings;
use mcmcda::BirthPrior;

/// The most rows a plot or point file may have.
pub const MAX_PLOT_ROWS: usize = 50_000_000;

/// What a plot measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlotValue {
    /// A position, metres.
    Position([f64; 2]),
    /// Range (m) and bearing (rad).
    RangeBearing([f64; 2]),
}

/// One row of a plot file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlotRow {
    /// Seconds.
    pub time_s: f64,
    /// The sensor's id.
    pub sensor: u32,
    /// The sensor's position, metres.
    pub sensor_position: [f64; 2],
    /// The measurement.
    pub value: PlotValue,
    /// Its standard deviations (σ_x, σ_y or σ_range, σ_bearing), if given.
    pub sigma: Option<[f64; 2]>,
    /// The sector looked at: its centre bearing and its width, radians, if given.
    pub beam: Option<[f64; 2]>,
}

/// Column positions found in a header.
struct Columns(BTreeMap<String, usize>);

impl Columns {
    fn of(header: &str) -> Self {
        Self(
            header
                .split(',')
                .enumerate()
                .map(|(i, name)| (name.trim().to_ascii_lowercase(), i))
                .collect(),
        )
    }

    fn has(&self, name: &str) -> bool {
        self.0.contains_key(name)
    }

    fn number(&self, fields: &[&str], name: &str, line: usize) -> Result<f64> {
        let i = self
            .0
            .get(name)
            .ok_or_else(|| parse(line, format!("no column {name}")))?;
        let text = fields.get(*i).map(|f| f.trim()).unwrap_or("");
        let v: f64 = text
            .parse()
            .map_err(|_| parse(line, format!("{name} = {text:?} is not a number")))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(parse(line, format!("{name} = {text} is not finite")))
        }
    }
}

fn parse(line: usize, reason: String) -> Error {
    ModelError::Parse { line, reason }.into()
}

/// A data row: its 1-based line and its fields.
type Row<'a> = (usize, Vec<&'a str>);

/// The data rows of a CSV with a header; blank lines skipped.
fn data_rows(text: &str) -> Result<(Columns, Vec<Row<'_>>)> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines
        .next()
        .ok_or_else(|| parse(1, "the file is empty; a header line is needed".into()))?;
    let rows: Vec<Row<'_>> = lines
        .map(|(i, l)| (i + 1, l.split(',').collect()))
        .collect();
    if rows.len() > MAX_PLOT_ROWS {
        return Err(parse(
            1,
            format!("{} rows; at most {MAX_PLOT_ROWS}", rows.len()),
        ));
    }
    Ok((Columns::of(header), rows))
}

/// The plots of a plot file, sorted by time (stable: a file's order within a time is kept).
pub fn parse_plots(text: &str) -> Result<Vec<PlotRow>> {
    let (cols, rows) = data_rows(text)?;
    let polar = cols.has("range") && cols.has("bearing");
    if !(polar || cols.has("x") && cols.has("y")) {
        return Err(parse(1, "the header needs x,y or range,bearing".into()));
    }
    let (sx, sy) = if polar {
        ("sigma_range", "sigma_bearing")
    } else {
        ("sigma_x", "sigma_y")
    };
    let mut out = Vec::with_capacity(rows.len());
    for (line, f) in &rows {
        let n = |name: &str| cols.number(f, name, *line);
        let sensor = n("sensor")?;
        if sensor < 0.0 || sensor.fract() != 0.0 || sensor > f64::from(u32::MAX) {
            return Err(parse(
                *line,
                format!("sensor = {sensor} is not a sensor id"),
            ));
        }
        let pair = if polar {
            PlotValue::RangeBearing([n("range")?, n("bearing")?])
        } else {
            PlotValue::Position([n("x")?, n("y")?])
        };
        let sigma = if cols.has(sx) && cols.has(sy) {
            let s = [n(sx)?, n(sy)?];
            if s.iter().any(|v| *v <= 0.0) {
                return Err(parse(*line, format!("{sx}, {sy} must be positive")));
            }
            Some(s)
        } else {
            None
        };
        let beam = if cols.has("beam_rad") && cols.has("beam_width_rad") {
            Some([n("beam_rad")?, n("beam_width_rad")?])
        } else {
            None
        };
        out.push(PlotRow {
            time_s: n("time_s")?,
            sensor: sensor as u32,
            sensor_position: [n("sensor_x")?, n("sensor_y")?],
            value: pair,
            sigma,
            beam,
        });
    }
    out.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    Ok(out)
}

/// Which filter `track_plots` runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlotFilter {
    /// Constant velocity through the Kalman filter; position plots only.
    Kf,
    /// The coordinated turn with its rate in the state, EKF.
    Ekf,
    /// The same through the UKF.
    Ukf,
    /// The IMM of CV and turns at ±ω₀, EKF.
    Imm,
}

impl std::str::FromStr for PlotFilter {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "kf" => Ok(PlotFilter::Kf),
            "ekf" => Ok(PlotFilter::Ekf),
            "ukf" => Ok(PlotFilter::Ukf),
            "imm" => Ok(PlotFilter::Imm),
            other => Err(ModelError::InvalidParameter {
                name: "filter",
                reason: format!("{other:?}; one of kf, ekf, ukf, imm"),
            }
            .into()),
        }
    }
}

/// How a plot file is tracked; every key has a default (`PlotTrackConfig::default`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlotTrackConfig {
    /// White-acceleration spectral density per axis, (m/s²)²·s.
    pub q_accel: f64,
    /// The turn rate's random-walk density, (rad/s)²/s.
    pub q_turn: f64,
    /// The IMM's turn rate ω₀, degrees per second.
    pub imm_turn_rate_deg_s: f64,
    /// Noise of plots that give none: σ of a position, metres …
    pub sigma_position_m: f64,
    /// … or of range (m) and bearing (rad).
    pub sigma_range_m: f64,
    /// See `sigma_range_m`.
    pub sigma_bearing_rad: f64,
    /// A sensor sees every target within this range, metres.
    pub max_range_m: f64,
    /// With sector columns: a track predicted within this many radians of a sector's border
    /// may take a plot there but is not missed there (`mcmcda::View::Edge`); 0 by default.
    pub edge_margin_rad: f64,
    /// ln λ, false alarms per unit measurement volume (m² for positions, m·rad for
    /// range-bearing).
    pub clutter_log_density: f64,
    /// χ² gate.
    pub gate_chi2: f64,
    /// M of N confirmation and K misses to delete.
    pub confirm_hits: u32,
    /// See `confirm_hits`.
    pub confirm_window: u32,
    /// See `confirm_hits`.
    pub max_misses: u32,
    /// The most tracks held.
    pub max_tracks: usize,
    /// σ of a new track's velocity components, m/s.
    pub birth_sigma_speed_m_s: f64,
    /// σ of a new track's turn rate, degrees per second.
    pub birth_sigma_turn_deg_s: f64,
}

impl Default for PlotTrackConfig {
    /// Air-traffic defaults: the `adsb-radar` scenario's settings, with q = 3.
    fn default() -> Self {
        Self {
            q_accel: 3.0,
            q_turn: 1e-5,
            imm_turn_rate_deg_s: 3.0,
            sigma_position_m: 50.0,
            sigma_range_m: 50.0,
            sigma_bearing_rad: 0.0015,
            max_range_m: 150_000.0,
            edge_margin_rad: 0.0,
            clutter_log_density: (50.0f64 / (150_000.0 * std::f64::consts::TAU)).ln(),
            gate_chi2: 16.0,
            confirm_hits: 3,
            confirm_window: 4,
            max_misses: 3,
            max_tracks: 2000,
            birth_sigma_speed_m_s: 250.0,
            birth_sigma_turn_deg_s: 2.0,
        }
    }
}

/// One confirmed track's estimate at one dwell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackRow {
    /// Seconds.
    pub time_s: f64,
    /// The track.
    pub id: u64,
    /// Position, metres.
    pub position: [f64; 2],
    /// Velocity, m/s.
    pub velocity: [f64; 2],
    /// Whether a plot updated it at this dwell (else it coasted).
    pub hit: bool,
}

/// The sensor model of a dwell: positions or range-bearing, with its noise.
enum Sensor<const N: usize> {
    Position(LinearObservation<N, 2>),
    Polar(RangeBearing<N>),
}

impl<const N: usize> Sensor<N> {
    fn of(row: &PlotRow, config: &PlotTrackConfig) -> Result<Self> {
        Ok(match row.value {
            PlotValue::Position(_) => {
                let s = row.sigma.unwrap_or([config.sigma_position_m; 2]);
                let r = SMatrix::<f64, 2, 2>::from_diagonal(&SVector::<f64, 2>::new(
                    s[0] * s[0],
                    s[1] * s[1],
                ));
                Sensor::Position(LinearObservation::leading_components(r)?)
            }
            PlotValue::RangeBearing(_) => {
                let s = row
                    .sigma
                    .unwrap_or([config.sigma_range_m, config.sigma_bearing_rad]);
                let site = RadarSite {
                    position: SVector::<f64, 2>::from(row.sensor_position),
                    state_indices: SVector::<usize, 2>::new(0, 1),
                };
                Sensor::Polar(RangeBearing::new(site, s[0], s[1])?)
            }
        })
    }
}

fn value(row: &PlotRow) -> SVector<f64, 2> {
    match row.value {
        PlotValue::Position(p) | PlotValue::RangeBearing(p) => SVector::<f64, 2>::from(p),
    }
}

/// A dwell's key: time, sensor, kind, noise and sector, compared by their bits.
fn dwell_key(row: &PlotRow) -> (u64, u32, bool, [u64; 2], [u64; 2]) {
    let bits = |v: Option<[f64; 2]>| v.map_or([0, 0], |s| s.map(f64::to_bits));
    (
        row.time_s.to_bits(),
        row.sensor,
        matches!(row.value, PlotValue::Position(_)),
        bits(row.sigma),
        bits(row.beam),
    )
}

/// How a track predicted at `bearing` and `range` sees the row's dwell: beyond `max_range`,
/// out; in the sector (every bearing when the row names none), in; within `margin` of its
/// border, at the edge (`mcmcda::View`).
fn view_of(row: &PlotRow, range: f64, bearing: f64, max_range: f64, margin: f64) -> View {
    match row.beam {
        _ if range > max_range => View::Out,
        None => View::In,
        Some([centre, width]) => crate::radar::sector_view(bearing, centre, width, margin),
    }
}

/// One dwell through `gnn`.
fn step_dwell<E: StateEstimator<N>, const N: usize>(
    gnn: &mut PlotGnn<E, N>,
    rows: &[PlotRow],
    config: &PlotTrackConfig,
    out: &mut Vec<TrackRow>,
) -> Result<()> {
    let first = &rows[0];
    let plots: Vec<SVector<f64, 2>> = rows.iter().map(value).collect();
    let birth = BirthPrior {
        sigma_speed_m_s: config.birth_sigma_speed_m_s,
        sigma_turn_rad_s: config.birth_sigma_turn_deg_s.to_radians(),
    };
    let centre = first.sensor_position;
    let states = match Sensor::<N>::of(first, config)? {
        Sensor::Position(sensor) => {
            let r = MeasurementModel::<N, 2>::noise(&sensor);
            let margin = 5.0 * (r[(0, 0)].max(r[(1, 1)])).sqrt();
            let in_view = |z: &SVector<f64, 2>| {
                let (dx, dy) = (z[0] - centre[0], z[1] - centre[1]);
                let range = dx.hypot(dy);
                view_of(
                    first,
                    range,
                    dy.atan2(dx),
                    config.max_range_m,
                    margin / range.max(1.0),
                )
            };
            let start = |z: &SVector<f64, 2>| birth.around::<N>(z, &r);
            step_with(gnn, first.time_s, &sensor, &plots, &in_view, &start)?
        }
        Sensor::Polar(sensor) => {
            let in_view = |z: &SVector<f64, 2>| {
                view_of(
                    first,
                    z[0],
                    z[1],
                    config.max_range_m,
                    config.edge_margin_rad,
                )
            };
            let start = |z: &SVector<f64, 2>| birth.at(&sensor, z);
            step_with(gnn, first.time_s, &sensor, &plots, &in_view, &start)?
        }
    };
    out.extend(states.into_iter().map(|s| {
        let m = s.estimate.mean();
        TrackRow {
            time_s: s.time_s,
            id: s.id.0,
            position: [m[0], m[1]],
            velocity: [m[2], m[3]],
            hit: s.hit,
        }
    }));
    Ok(())
}

/// One [`Dwell`] of `sensor`'s plots at `time_s`.
fn step_with<E: StateEstimator<N>, O: MeasurementModel<N, 2>, const N: usize>(
    gnn: &mut PlotGnn<E, N>,
    time_s: f64,
    sensor: &O,
    plots: &[SVector<f64, 2>],
    in_view: &dyn Fn(&SVector<f64, 2>) -> View,
    birth: &dyn Fn(&SVector<f64, 2>) -> tracker_model::Result<Gaussian<N>>,
) -> Result<Vec<mcmcda::PlotTrackState<N>>> {
    Ok(gnn.step(&Dwell {
        time_s,
        sensor,
        plots,
        in_view,
        birth,
    })?)
}

fn run_all<E: StateEstimator<N>, const N: usize>(
    estimator: E,
    rows: &[PlotRow],
    config: &PlotTrackConfig,
) -> Result<Vec<TrackRow>> {
    let gnn_config = PlotGnnConfig {
        gate_chi2: config.gate_chi2,
        clutter_log_density: config.clutter_log_density,
        confirm_hits: config.confirm_hits,
        confirm_window: config.confirm_window,
        max_misses: config.max_misses,
        max_tracks: config.max_tracks,
    };
    let mut gnn = PlotGnn::new(estimator, gnn_config)?;
    let mut out = Vec::new();
    let mut start = 0;
    while start < rows.len() {
        let key = dwell_key(&rows[start]);
        let len = rows[start..]
            .iter()
            .take_while(|r| dwell_key(r) == key)
            .count();
        step_dwell(&mut gnn, &rows[start..start + len], config, &mut out)?;
        start += len;
    }
    Ok(out)
}

/// Tracks `rows` (sorted by time, as [`parse_plots`] returns them) with `filter`.
pub fn track_plots(
    rows: &[PlotRow],
    filter: PlotFilter,
    config: &PlotTrackConfig,
) -> Result<Vec<TrackRow>> {
    ensure_positive_config(config)?;
    let motion = MotionSettings {
        q_accel: config.q_accel,
        q_turn: config.q_turn,
        imm_turn_rate_rad_s: config.imm_turn_rate_deg_s.to_radians(),
        switching_cv_turns: [[0.90, 0.05, 0.05], [0.10, 0.85, 0.05], [0.10, 0.05, 0.85]],
        switching_turn_rate: [[0.95, 0.05], [0.10, 0.90]],
        sigma_points: SigmaPoints::new(0.5, 2.0, -2.0)?,
    };
    match filter {
        PlotFilter::Kf => {
            if rows
                .iter()
                .any(|r| matches!(r.value, PlotValue::RangeBearing(_)))
            {
                return Err(ModelError::InvalidParameter {
                    name: "filter",
                    reason: "kf tracks position plots; range-bearing plots need ekf, ukf or imm"
                        .into(),
                }
                .into());
            }
            run_all(crate::trackers::cv_estimator(&motion)?, rows, config)
        }
        PlotFilter::Ekf => run_all(crate::trackers::ct_estimator(&motion, false)?, rows, config),
        PlotFilter::Ukf => run_all(crate::trackers::ct_estimator(&motion, true)?, rows, config),
        PlotFilter::Imm => run_all(crate::trackers::imm_cv_turns(&motion)?, rows, config),
    }
}

fn ensure_positive_config(c: &PlotTrackConfig) -> Result<()> {
    use tracker_model::{ensure_in_range, ensure_non_negative, ensure_positive};
    ensure_non_negative(c.q_accel, "q_accel")?;
    ensure_non_negative(c.q_turn, "q_turn")?;
    ensure_non_negative(c.edge_margin_rad, "edge_margin_rad")?;
    ensure_in_range(
        c.imm_turn_rate_deg_s,
        0.0,
        tracker_model::MAX_TURN_RATE_RAD_S.to_degrees(),
        "imm_turn_rate_deg_s",
    )?;
    for (v, name) in [
        (c.sigma_position_m, "sigma_position_m"),
        (c.sigma_range_m, "sigma_range_m"),
        (c.sigma_bearing_rad, "sigma_bearing_rad"),
        (c.max_range_m, "max_range_m"),
        (c.birth_sigma_speed_m_s, "birth_sigma_speed_m_s"),
        (c.birth_sigma_turn_deg_s, "birth_sigma_turn_deg_s"),
    ] {
        ensure_positive(v, name)?;
    }
    Ok(())
}

/// Tracks as CSV: `time_s,track_id,x,y,vx,vy,hit` (hit 1 when a plot updated the track at
/// that dwell, 0 when it coasted), shortest round-trip numbers.
pub fn format_tracks(rows: &[TrackRow]) -> String {
    let mut out = String::from("time_s,track_id,x,y,vx,vy,hit\n");
    for r in rows {
        out.push_str(&format!(
            "{},{},{},{},{},{},{}\n",
            r.time_s,
            r.id,
            r.position[0],
            r.position[1],
            r.velocity[0],
            r.velocity[1],
            u8::from(r.hit)
        ));
    }
    out
}

/// A rotating radar's dwells as a plot file (range-bearing with each dwell's sector, sensor 1
/// at the radar; σ left to the configuration; a dwell without plots is not written) and the aircraft in view as a point truth file at the same times.
pub fn format_radar_run(
    radar: &crate::RotatingRadar,
    dwells: &[crate::RadarDwell],
    trajectories: &[crate::Trajectory],
    truth: &[crate::TruthPoint],
) -> (String, String) {
    let mut plots =
        String::from("time_s,sensor,sensor_x,sensor_y,range,bearing,beam_rad,beam_width_rad\n");
    let width = radar.beam_width_rad();
    for d in dwells {
        for z in &d.plots {
            plots.push_str(&format!(
                "{},1,{},{},{},{},{},{width}\n",
                d.time_s, radar.position[0], radar.position[1], z[0], z[1], d.beam_rad
            ));
        }
    }
    let mut points = String::from("time_s,id,x,y\n");
    for p in truth {
        if let Some(k) = trajectories[p.trajectory].at(p.time_s) {
            points.push_str(&format!(
                "{},{},{},{}\n",
                p.time_s,
                p.trajectory + 1,
                k.position[0],
                k.position[1]
            ));
        }
    }
    (plots, points)
}

/// Points of two files (`time_s`, an id column `id` or `track_id`, `x`, `y`) as track sets
/// on one shared frame numbering: the distinct times of both, in order.
pub fn point_track_sets(truth: &str, estimates: &str) -> Result<(TrackSet, TrackSet)> {
    let a = parse_points(truth)?;
    let b = parse_points(estimates)?;
    let mut times: Vec<u64> = a.iter().chain(&b).map(|p| p.0.to_bits()).collect();
    times.sort_by(|x, y| f64::from_bits(*x).total_cmp(&f64::from_bits(*y)));
    times.dedup();
    let frame_of = |t: f64| {
        times
            .binary_search_by(|x| f64::from_bits(*x).total_cmp(&t))
            .unwrap_or(0) as u32
    };
    let build = |points: &[(f64, u64, [f64; 2])]| -> Result<TrackSet> {
        let mut by_id: BTreeMap<u64, Vec<TrackPoint>> = BTreeMap::new();
        for (t, id, p) in points {
            by_id
                .entry(*id)
                .or_default()
                .push(TrackPoint::at(frame_of(*t), Vec2::new(p[0], p[1])));
        }
        let lists = by_id.into_iter().map(|(id, mut pts)| {
            pts.sort_by_key(|p| p.frame);
            (TrackId(id), pts)
        });
        Ok(TrackSet::from_point_lists(lists)?)
    };
    Ok((build(&a)?, build(&b)?))
}

fn parse_points(text: &str) -> Result<Vec<(f64, u64, [f64; 2])>> {
    let (cols, rows) = data_rows(text)?;
    let id = if cols.has("id") { "id" } else { "track_id" };
    let mut out = Vec::with_capacity(rows.len());
    for (line, f) in &rows {
        let n = |name: &str| cols.number(f, name, *line);
        let raw = n(id)?;
        if raw < 0.0 || raw.fract() != 0.0 || raw > 9.0e15 {
            return Err(parse(*line, format!("{id} = {raw} is not a track id")));
        }
        out.push((n("time_s")?, raw as u64, [n("x")?, n("y")?]));
    }
    Ok(out)
}
