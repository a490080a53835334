//! The simulated road: vehicles on straight paths, the acoustic nodes' beamforms through
//! sensors-audio and the cameras' angle profiles through the sensors-video renderer and
//! background mixture, and the truth. The sensors never read the truth to decide what to
//! report: they see only the simulated signals and images.

use std::f64::consts::PI;

use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use sensors_audio::{
    BackgroundNoise, EnergyScaling, MicArray, NoiseField, SimulationConfig, Source, SourcePath,
    SourceSignal, simulate,
};
use sensors_video::{
    AngleProfiler, BackgroundModel, DetectionFilter, ObjectKind, PinholeCamera, PixelFormat, Scene,
    SceneConfig, SceneObject, clean,
};
use tracker_model::{Frame, SensorPose, Track, TrackId, TrackPoint, TrackSet, Vec2};

use super::{LANE_OFFSET_M, Params, REGION_M, ROAD_Y_M, VideoParams, region};
use crate::{Report, Result};

/// A vehicle's straight path: position at run time t.
#[derive(Debug, Clone, Copy)]
pub struct Vehicle {
    /// Position at run time 0, m (outside the region until it enters).
    pub start: Vec2,
    /// Velocity, m/s.
    pub velocity: Vec2,
}

impl Vehicle {
    /// Position at run time `t`, s.
    pub fn at(&self, t: f64) -> Vec2 {
        self.start + self.velocity * t
    }

    /// Enters the region at `enter_s` going `direction` (+1: along +x on the lower lane; −1:
    /// along −x on the upper lane) at `speed_mps` m/s.
    pub fn new(speed_mps: f64, direction: i8, enter_s: f64) -> Self {
        let dir = if direction >= 0 { 1.0 } else { -1.0 };
        let y = ROAD_Y_M - dir * LANE_OFFSET_M;
        let x_enter = if dir > 0.0 { 0.0 } else { REGION_M[0] };
        let velocity = Vec2::new(dir * speed_mps, 0.0);
        Self {
            start: Vec2::new(x_enter, y) - velocity * enter_s,
            velocity,
        }
    }
}

/// One run's inputs: the vehicles and how long it lasts.
pub struct RunSpec {
    /// The vehicles.
    pub vehicles: Vec<Vehicle>,
    /// Seconds from the start of the run to its end.
    pub duration_s: f64,
}

/// The six acoustic nodes' true poses, three either side of the road.
pub fn audio_poses() -> Vec<SensorPose> {
    [
        (5.0, 4.0),
        (17.5, 4.0),
        (30.0, 4.0),
        (5.0, 16.0),
        (17.5, 16.0),
        (30.0, 16.0),
    ]
    .iter()
    .enumerate()
    .map(|(i, &(x, y))| SensorPose {
        position: Vec2::new(x, y),
        heading_rad: 0.4 * i as f64,
    })
    .collect()
}

/// Three cameras at an angle to the road: two at the near corners looking along it, one on
/// the far side looking across and down the road.
pub fn cameras(v: &VideoParams) -> Vec<PinholeCamera> {
    [(1.0, 1.0, 35.0), (34.0, 1.0, 145.0), (8.0, 19.5, -55.0)]
        .iter()
        .map(|&(x, y, h)| PinholeCamera {
            width: v.width,
            height: v.height,
            fx: v.focal_px,
            fy: v.focal_px,
            cx: (v.width as f64 - 1.0) / 2.0,
            cy: (v.height as f64 - 1.0) / 2.0,
            position_m: [x, y, v.mast_m],
            heading_rad: h * PI / 180.0,
            tilt_rad: v.tilt_deg * PI / 180.0,
        })
        .collect()
}

/// Known clock offsets of the nodes (each node's clock runs ahead by this much; the fusion
/// node knows it from synchronisation).
pub fn clock_offset_s(i: usize) -> f64 {
    0.37 * i as f64 - 1.1
}

/// The acoustic nodes' reports of a run: each node's beamforms of its simulated recording.
fn audio_reports(p: &Params, run: &RunSpec, rng: &mut ChaCha8Rng) -> Result<Vec<Report>> {
    let array = MicArray::default();
    // `check_params` checks that a multi-vehicle beamformer keeps the beams and sample rate.
    let beamform = match &p.audio.multi_beamform {
        Some(multi) if run.vehicles.len() > 1 => multi,
        _ => &p.audio.beamform,
    };
    let sim = SimulationConfig {
        sample_rate_hz: beamform.sample_rate_hz,
        ground_reflection: Some(p.audio.ground_reflection),
        noise: Some(BackgroundNoise {
            snr_db: p.audio.snr_db,
            field: NoiseField::Diffuse {
                n_directions: p.audio.noise_directions,
            },
        }),
        ..SimulationConfig::default()
    };
    let sources: Vec<Source> = run
        .vehicles
        .iter()
        .map(|v| {
            let (t0, t1) = (-1.0, run.duration_s + 1.0);
            Source {
                path: SourcePath::Waypoints {
                    times_s: vec![t0, t1],
                    positions: vec![v.at(t0), v.at(t1)],
                },
                height_m: 0.5,
                level: 1.0,
                signal: SourceSignal::Vehicle {
                    fundamental_hz: rng.random_range(30.0..60.0),
                    n_harmonics: 40,
                    rolloff: 0.7,
                    noise_fraction: 0.3,
                },
            }
        })
        .collect();
    let mut reports = Vec::new();
    let mut beamformer = beamform.check(&array)?;
    for (i, pose) in audio_poses().iter().enumerate() {
        let rec = simulate(&array, pose, &sources, run.duration_s, &sim, rng)?;
        for bf in beamformer.beamform(&rec)? {
            let mut r = Report::from_beamform(i, &bf, EnergyScaling::MinSubtracted);
            r.local_time_s += clock_offset_s(i);
            reports.push(r);
        }
    }
    Ok(reports)
}

/// The cameras' reports of a run: each camera's filtered angle profiles of the foreground of
/// its rendered frames, after a warm-up for the background model.
fn video_reports(p: &Params, run: &RunSpec, rng: &mut ChaCha8Rng) -> Result<Vec<Report>> {
    let v = &p.video;
    let period = 1.0 / v.fps;
    let warm_s = v.warmup_frames as f64 * period;
    let n_frames = v.warmup_frames + (run.duration_s / period).floor() as usize + 1;
    let mut reports = Vec::new();
    for (j, cam) in cameras(v).into_iter().enumerate() {
        let config = SceneConfig {
            camera: cam,
            format: PixelFormat::Rgb,
            frame_period_s: period,
            drift_amplitude: 0.05,
            drift_period_s: 60.0,
            n_sway_patches: v.n_sway_patches,
            sway_amplitude_px: 2.0,
            sway_period_s: 2.0,
            glints_per_frame: v.glints_per_frame,
            noise_sigma: v.noise_sigma,
            sun_azimuth_rad: 2.4,
            sun_elevation_rad: 0.7,
            shadow_factor: 0.55,
        };
        // Scene time = run time + warm-up; vehicles appear when the run starts.
        let objects = run
            .vehicles
            .iter()
            .map(|veh| {
                let s = veh.at(-warm_s);
                SceneObject {
                    kind: ObjectKind::Vehicle,
                    start_m: [s.x, s.y],
                    velocity_mps: [veh.velocity.x, veh.velocity.y],
                    colour: [rng.random(), rng.random(), rng.random()],
                    appear_s: warm_s,
                    vanish_s: 1e9,
                }
            })
            .collect();
        let scene = Scene::new(config, objects, rng)?;
        let profiler = AngleProfiler::new(cam, v.n_angles)?;
        let mut model = BackgroundModel::new(&v.mog, cam.width, cam.height, PixelFormat::Rgb)?;
        let mut filter = DetectionFilter::new(v.filter);
        for k in 0..n_frames {
            let frame = scene.render(k, rng)?;
            let mask = model.apply(&frame.frame)?;
            let cleaned = clean(&mask, &v.post)?;
            let counts = profiler.counts(&cleaned.foreground)?;
            let values = filter.apply(&counts);
            if k >= v.warmup_frames {
                let t = (k - v.warmup_frames) as f64 * period;
                reports.push(Report {
                    sensor: 6 + j,
                    local_time_s: t + clock_offset_s(6 + j),
                    values,
                });
            }
        }
    }
    Ok(reports)
}

/// Each vehicle's positions at the ticks it is inside the region.
fn truth(run: &RunSpec, p: &Params, n_ticks: u64) -> Result<TrackSet> {
    let mut set = TrackSet::new();
    for (i, v) in run.vehicles.iter().enumerate() {
        let points: Vec<TrackPoint> = (0..n_ticks)
            .filter_map(|k| {
                let pos = v.at(p.scheduler.tick_time_s(k));
                let frame = Frame::try_from(k).ok()?;
                region().contains(&pos).then(|| TrackPoint::at(frame, pos))
            })
            .collect();
        set.push(Track::from_points(TrackId(i as u64), points)?)?;
    }
    Ok(set)
}

/// Every report of a run: the acoustic nodes' beamforms and the cameras' angle profiles.
fn simulate_reports(p: &Params, run: &RunSpec, rng: &mut ChaCha8Rng) -> Result<Vec<Report>> {
    let mut reports = audio_reports(p, run, rng)?;
    reports.extend(video_reports(p, run, rng)?);
    Ok(reports)
}

/// A run's simulated inputs: its reports, its length in ticks and the truth.
pub struct Simulated {
    /// More than one vehicle (the run takes the multi-vehicle settings).
    pub multi: bool,
    /// Every report: the acoustic nodes' beamforms, then the cameras' angle profiles, each
    /// stamped with its node's clock.
    pub reports: Vec<Report>,
    /// Ticks of the scheduler over the run.
    pub n_ticks: u64,
    /// Each vehicle's positions at the ticks it is inside the region, one track per vehicle.
    pub gt: TrackSet,
}

/// Simulates run `run`: the reports of every node (drawing from `rng`: the vehicles' engine
/// notes and colours, the noise and the scenes' clutter) and the truth.
pub fn simulate_run(p: &Params, run: &RunSpec, rng: &mut ChaCha8Rng) -> Result<Simulated> {
    let reports = simulate_reports(p, run, rng)?;
    let n_ticks = (run.duration_s * p.scheduler.rate_hz).floor() as u64;
    let gt = truth(run, p, n_ticks)?;
    Ok(Simulated {
        multi: run.vehicles.len() > 1,
        reports,
        n_ticks,
        gt,
    })
}
