//! `av-fusion`: the audio-video tracker of Kushwaha, Oh, Amundson, Koutsoukos & Ledeczi
//! (MFI 2008; seed 000 §V, Figs. 7–11) end to end. Table 1's layout: a 35 × 20 m region in
//! 0.5 m cells, six acoustic nodes (36 beams) and three cameras (160 angles) either side of a
//! road. Vehicles are simulated through sensors-audio (engine-like sources, ground reflection,
//! diffuse background noise) and through the sensors-video renderer (cameras at an angle to
//! the road, swaying foliage, glint, sensor noise, background mixture segmentation); the
//! fusion node of the av-fusion crate buffers the reports, fuses them on the grid at 10 Hz and
//! online MCMCDA tracks the peaks. Six approaches (audio, video, audio+video × weighted sum,
//! product) over nine single-vehicle passes of the paper's durations (2.75–4.5 s), error
//! against camera calibration error, and runs with two and three vehicles (OSPA, MOTA).

use std::f64::consts::PI;

use anyhow::{Result, ensure};
use av_fusion::{
    AvConfig, FusionConfig, FusionRule, Modalities, PeakExtraction, Report, SchedulerConfig,
    SensorKind, SensorNode, SumScaling, TrackerConfig, track_reports,
};
use eval_metrics::{EvalConfig, MatchConfig, OspaConfig, evaluate, mean_error_per_track};
use mcmcda::{McmcdaConfig, OnlineConfig};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use sensors_audio::{
    BackgroundNoise, BeamformConfig, EnergyScaling, MicArray, NoiseField, SimulationConfig, Source,
    SourcePath, SourceSignal, simulate,
};
use sensors_video::{
    AngleProfiler, BackgroundModel, DetectionFilter, DetectionFilterConfig, MogConfig, ObjectKind,
    PinholeCamera, PixelFormat, PostConfig, Scene, SceneConfig, SceneObject, clean,
};
use serde::Deserialize;
use tracker_model::{Frame, Region2, SensorPose, Track, TrackId, TrackPoint, TrackSet, Vec2};

use crate::stats::mean_ci;
use crate::{
    Chart, Claim, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style, Table, fmt_num,
};

/// The `av-fusion` pipeline.
pub struct AvFusion;

/// Table 1: the region.
const REGION_M: [f64; 2] = [35.0, 20.0];
/// The road's centre line and its two lanes (+x traffic on the lower lane).
const ROAD_Y_M: f64 = 10.0;
const LANE_OFFSET_M: f64 = 1.5;
const MPS_PER_MPH: f64 = 0.44704;

/// One single-vehicle pass: the time it takes to cross the region and its direction.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassSpec {
    /// Seconds from entering to leaving the 35 m region (speed = 35 m / duration).
    duration_s: f64,
    /// +1: along +x on the lower lane; −1: along −x on the upper lane.
    direction: i8,
}

/// A vehicle of a multi-vehicle run.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleSpec {
    /// Speed, mph.
    speed_mph: f64,
    /// +1 or −1 as in [`PassSpec`].
    direction: i8,
    /// Seconds after the run's lead-in at which it enters the region.
    enter_s: f64,
}

/// The acoustic nodes.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AudioParams {
    /// Background noise SNR, dB (diffuse field).
    snr_db: f64,
    /// Plane waves of the diffuse noise.
    noise_directions: usize,
    /// Ground reflection coefficient.
    ground_reflection: f64,
    /// The beamformer (36 beams).
    beamform: BeamformConfig,
}

/// The cameras.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VideoParams {
    /// Image width and height, pixels.
    width: usize,
    height: usize,
    /// Focal length, pixels.
    focal_px: f64,
    /// Frames per second.
    fps: f64,
    /// Frames rendered before the run for the background model to learn.
    warmup_frames: usize,
    /// Angles of the profile (Table 1: 160).
    n_angles: usize,
    /// Mast height, m, and downward tilt, degrees.
    mast_m: f64,
    tilt_deg: f64,
    /// Clutter of the rendered scene.
    n_sway_patches: usize,
    glints_per_frame: f64,
    noise_sigma: f64,
    /// Segmentation and its post-processing.
    mog: MogConfig,
    post: PostConfig,
    filter: DetectionFilterConfig,
}

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The nine single-vehicle passes.
    passes: Vec<PassSpec>,
    /// Multi-vehicle runs.
    multi: Vec<Vec<VehicleSpec>>,
    /// Seconds before the first vehicle enters and after the last leaves.
    pad_s: f64,
    /// Grid cell, m (Table 1: 0.5).
    cell_size_m: f64,
    /// Scheduler.
    scheduler: SchedulerConfig,
    /// Sensors.
    audio: AudioParams,
    video: VideoParams,
    /// Camera heading error of the main comparison, degrees (signs alternate by camera).
    calibration_error_deg: f64,
    /// Heading errors of the calibration sweep, degrees.
    calibration_sweep_deg: Vec<f64>,
    /// Floor ε of the product rule.
    product_floor: f64,
    /// Peak extraction under each rule.
    peaks_sum: PeakExtraction,
    peaks_product: PeakExtraction,
    /// The tracker (motion period = 1 / scheduler rate).
    mcmcda: McmcdaConfig,
    online: OnlineConfig,
    /// A track is paired with a vehicle within this distance (error, MOTA).
    match_distance_m: f64,
    /// OSPA cut-off, m (order 1).
    ospa_cutoff_m: f64,
}

/// The six approaches: modality × rule.
const APPROACHES: [(&str, Modalities, bool); 6] = [
    ("audio, sum", Modalities::Audio, false),
    ("video, sum", Modalities::Video, false),
    ("audio+video, sum", Modalities::Both, false),
    ("audio, product", Modalities::Audio, true),
    ("video, product", Modalities::Video, true),
    ("audio+video, product", Modalities::Both, true),
];

/// A vehicle's straight path: position at run time t.
#[derive(Debug, Clone, Copy)]
struct Vehicle {
    start: Vec2,
    velocity: Vec2,
}

impl Vehicle {
    fn at(&self, t: f64) -> Vec2 {
        self.start + self.velocity * t
    }

    /// Enters the region at `enter_s` going `direction` at `speed` m/s.
    fn new(speed_mps: f64, direction: i8, enter_s: f64) -> Self {
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
struct RunSpec {
    vehicles: Vec<Vehicle>,
    duration_s: f64,
}

/// One run's results.
struct RunResult {
    /// Per approach: mean error of each vehicle's paired track (None: no track formed).
    errors: Vec<Vec<Option<f64>>>,
    /// Per approach: MOTA and mean OSPA.
    mota: Vec<f64>,
    ospa: Vec<f64>,
    /// Per calibration sweep value, per approach: mean error over vehicles (None: no track).
    sweep: Vec<Vec<Option<f64>>>,
    /// For the map: max over ticks of the A+V product grid (per tick scaled to max 1), the
    /// tracks and the truth.
    map: Option<MapData>,
}

struct MapData {
    cells: Vec<(f64, f64, f64)>,
    tracks: Vec<Vec<(f64, f64)>>,
    truth: Vec<Vec<(f64, f64)>>,
    sensors: Vec<(f64, f64, SensorKind)>,
}

/// What the pipeline computed.
pub struct Output {
    passes: Vec<(f64, f64)>,
    /// errors[approach][pass].
    errors: Vec<Vec<Option<f64>>>,
    sweep_deg: Vec<f64>,
    /// sweep[value][approach][pass].
    sweep: Vec<Vec<Vec<Option<f64>>>>,
    /// Multi-vehicle runs: (vehicles, MOTA per approach, OSPA per approach).
    multi: Vec<(usize, Vec<f64>, Vec<f64>)>,
    map: Option<MapData>,
    calibration_error_deg: f64,
}

fn audio_poses() -> Vec<SensorPose> {
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
fn cameras(v: &VideoParams) -> Vec<PinholeCamera> {
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
fn clock_offset_s(i: usize) -> f64 {
    0.37 * i as f64 - 1.1
}

/// The nodes as the fusion centre knows them, cameras with heading errors ±`calib_deg`.
fn sensor_nodes(p: &Params, calib_deg: f64) -> Result<Vec<SensorNode>> {
    let mut nodes: Vec<SensorNode> = audio_poses()
        .into_iter()
        .enumerate()
        .map(|(i, pose)| {
            let mut n = SensorNode::audio(format!("audio {i}"), pose, p.audio.beamform.n_beams);
            n.clock_offset_s = clock_offset_s(i);
            n
        })
        .collect();
    for (j, cam) in cameras(&p.video).into_iter().enumerate() {
        let profiler = AngleProfiler::new(cam, p.video.n_angles)?;
        let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
        let mut pose = cam.pose();
        pose.heading_rad += sign * calib_deg * PI / 180.0;
        let mut n = SensorNode::video(format!("camera {j}"), pose, &profiler, p.video.n_angles);
        n.clock_offset_s = clock_offset_s(6 + j);
        nodes.push(n);
    }
    Ok(nodes)
}

fn audio_reports(p: &Params, run: &RunSpec, rng: &mut ChaCha8Rng) -> Result<Vec<Report>> {
    let array = MicArray::default();
    let sim = SimulationConfig {
        sample_rate_hz: p.audio.beamform.sample_rate_hz,
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
    let mut beamformer = p.audio.beamform.check(&array)?;
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

fn av_config(p: &Params, modalities: Modalities, product: bool) -> AvConfig {
    AvConfig {
        scheduler: p.scheduler,
        fusion: FusionConfig {
            region: region(),
            cell_size_m: p.cell_size_m,
            max_range_m: None,
            min_range_m: 0.5,
            rule: if product {
                FusionRule::Product {
                    floor: p.product_floor,
                }
            } else {
                FusionRule::WeightedSum {
                    scaling: SumScaling::Max,
                }
            },
            modalities,
            peaks: if product {
                p.peaks_product
            } else {
                p.peaks_sum
            },
        },
        tracker: TrackerConfig {
            mcmcda: p.mcmcda.clone(),
            online: p.online,
            seed: 1,
        },
    }
}

fn region() -> Region2 {
    Region2::new(Vec2::zeros(), Vec2::new(REGION_M[0], REGION_M[1]))
        .unwrap_or_else(|_| unreachable!("a fixed valid region"))
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

fn run_one(p: &Params, run: &RunSpec, rng: &mut ChaCha8Rng, want_map: bool) -> Result<RunResult> {
    let mut reports = audio_reports(p, run, rng)?;
    reports.extend(video_reports(p, run, rng)?);
    let n_ticks = (run.duration_s * p.scheduler.rate_hz).floor() as u64;
    let gt = truth(run, p, n_ticks)?;
    let score = |calib: f64, modalities, product| -> Result<(Vec<Option<f64>>, f64, f64, _)> {
        let nodes = sensor_nodes(p, calib)?;
        let result = track_reports(
            nodes,
            reports.clone(),
            n_ticks,
            &av_config(p, modalities, product),
        )?;
        let pairs = mean_error_per_track(&gt, &result.tracks, p.match_distance_m)?;
        let errors = gt
            .tracks()
            .iter()
            .map(|g| {
                pairs
                    .iter()
                    .find(|e| e.gt_id == g.id())
                    .map(|e| e.mean_error)
            })
            .collect();
        let eval = evaluate(
            &gt,
            &result.tracks,
            &EvalConfig {
                matching: MatchConfig::within_distance(p.match_distance_m),
            },
        )?;
        let ospa = eval_metrics::ospa_over_time(
            &gt,
            &result.tracks,
            &OspaConfig {
                cutoff: p.ospa_cutoff_m,
                order: 1.0,
            },
        )?;
        let mean_ospa =
            ospa.iter().map(|(_, o)| o.distance).sum::<f64>() / ospa.len().max(1) as f64;
        Ok((errors, eval.clear.mota, mean_ospa, result))
    };
    let mut errors = Vec::new();
    let mut mota = Vec::new();
    let mut ospa = Vec::new();
    let mut map = None;
    for (a, (_, modalities, product)) in APPROACHES.iter().enumerate() {
        let (e, m, o, result) = score(p.calibration_error_deg, *modalities, *product)?;
        errors.push(e);
        mota.push(m);
        ospa.push(o);
        if want_map && a == APPROACHES.len() - 1 {
            map = Some(map_data(p, &result, &gt)?);
        }
    }
    let mean_of = |e: &[Option<f64>]| {
        let found: Vec<f64> = e.iter().flatten().copied().collect();
        (!found.is_empty()).then(|| found.iter().sum::<f64>() / found.len() as f64)
    };
    let mut sweep = Vec::new();
    for &calib in &p.calibration_sweep_deg {
        let mut row = Vec::new();
        for (a, (_, modalities, product)) in APPROACHES.iter().enumerate() {
            // The sweep runs the product rule only (time budget); audio-only does not depend
            // on the cameras, and the nominal error is done.
            if !*product {
                row.push(None);
                continue;
            }
            let e = if *modalities == Modalities::Audio
                || calib.to_bits() == p.calibration_error_deg.to_bits()
            {
                errors[a].clone()
            } else {
                score(calib, *modalities, *product)?.0
            };
            row.push(mean_of(&e));
        }
        sweep.push(row);
    }
    Ok(RunResult {
        errors,
        mota,
        ospa,
        sweep,
        map,
    })
}

fn map_data(p: &Params, run: &av_fusion::AvRun, gt: &TrackSet) -> Result<MapData> {
    let mut acc: Option<Vec<f64>> = None;
    let mut shape = None;
    for scan in &run.scans {
        let v = scan.grid.values();
        let max = v.iter().copied().fold(0.0, f64::max);
        if max <= 0.0 {
            continue;
        }
        let a = acc.get_or_insert_with(|| vec![0.0; v.len()]);
        for (x, y) in a.iter_mut().zip(v) {
            *x = x.max(y / max);
        }
        shape = Some(&scan.grid);
    }
    let mut cells = Vec::new();
    if let (Some(a), Some(g)) = (acc, shape) {
        let (cols, _) = g.shape();
        for (i, v) in a.iter().enumerate() {
            let c = g.cell_centre(i % cols, i / cols);
            cells.push((c.x, c.y, *v));
        }
    }
    let path = |t: &Track| {
        t.points()
            .iter()
            .map(|q| (q.location.position().x, q.location.position().y))
            .collect()
    };
    Ok(MapData {
        cells,
        tracks: run.tracks.tracks().iter().map(path).collect(),
        truth: gt.tracks().iter().map(path).collect(),
        sensors: sensor_nodes(p, 0.0)?
            .iter()
            .map(|n| (n.pose.position.x, n.pose.position.y, n.kind))
            .collect(),
    })
}

impl Pipeline for AvFusion {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        ensure!(!p.passes.is_empty(), "no passes");
        ensure!(p.pad_s >= 0.0, "pad_s must be >= 0");
        ensure!(
            p.passes.iter().all(|s| s.duration_s > 0.0),
            "pass durations must be > 0"
        );
        av_config(p, Modalities::Both, true).check()?;
        av_config(p, Modalities::Both, false).check()?;
        let mut runs: Vec<RunSpec> = p
            .passes
            .iter()
            .map(|s| RunSpec {
                vehicles: vec![Vehicle::new(
                    REGION_M[0] / s.duration_s,
                    s.direction,
                    p.pad_s,
                )],
                duration_s: s.duration_s + 2.0 * p.pad_s,
            })
            .collect();
        for vehicles in &p.multi {
            ensure!(!vehicles.is_empty(), "a multi-vehicle run has no vehicles");
            let end = vehicles
                .iter()
                .map(|v| v.enter_s + REGION_M[0] / (v.speed_mph * MPS_PER_MPH))
                .fold(0.0, f64::max);
            runs.push(RunSpec {
                vehicles: vehicles
                    .iter()
                    .map(|v| {
                        Vehicle::new(v.speed_mph * MPS_PER_MPH, v.direction, p.pad_s + v.enter_s)
                    })
                    .collect(),
                duration_s: end + 2.0 * p.pad_s,
            });
        }
        env.progress.set_length(runs.len() as u64);
        let base = rng.clone();
        let n_passes = p.passes.len();
        let results: Vec<RunResult> = runs
            .par_iter()
            .enumerate()
            .map(|(i, run)| {
                let mut rng = base.clone();
                rng.set_stream(i as u64);
                let r = run_one(p, run, &mut rng, i + 1 == runs.len());
                env.progress.advance(1);
                r
            })
            .collect::<Result<_>>()?;
        let errors = (0..APPROACHES.len())
            .map(|a| results[..n_passes].iter().map(|r| r.errors[a][0]).collect())
            .collect();
        let sweep = (0..p.calibration_sweep_deg.len())
            .map(|s| {
                (0..APPROACHES.len())
                    .map(|a| results[..n_passes].iter().map(|r| r.sweep[s][a]).collect())
                    .collect()
            })
            .collect();
        let multi = results[n_passes..]
            .iter()
            .zip(&p.multi)
            .map(|(r, spec)| (spec.len(), r.mota.clone(), r.ospa.clone()))
            .collect();
        let map = results.into_iter().rev().find_map(|r| r.map);
        Ok(Output {
            passes: p
                .passes
                .iter()
                .map(|s| (s.duration_s, REGION_M[0] / s.duration_s / MPS_PER_MPH))
                .collect(),
            errors,
            sweep_deg: p.calibration_sweep_deg.clone(),
            sweep,
            multi,
            map,
            calibration_error_deg: p.calibration_error_deg,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut m = Metrics::new();
        for (a, (name, _, _)) in APPROACHES.iter().enumerate() {
            let key = key(name);
            let found: Vec<f64> = out.errors[a].iter().flatten().copied().collect();
            let (mean, ci) = mean_ci(&found);
            if mean.is_finite() {
                m.insert(format!("error_m_{key}_mean"), mean);
                m.insert(format!("error_m_{key}_ci95"), ci);
            }
            m.insert(format!("passes_tracked_{key}"), found.len() as f64);
            for (s, deg) in out.sweep_deg.iter().enumerate() {
                if let Some(e) = average(&out.sweep[s][a]) {
                    m.insert(format!("calibration_{deg}deg_error_m_{key}"), e);
                }
            }
            for (r, (n, mota, ospa)) in out.multi.iter().enumerate() {
                m.insert(format!("multi{r}_{n}veh_mota_{key}"), mota[a]);
                m.insert(format!("multi{r}_{n}veh_ospa_m_{key}"), ospa[a]);
            }
        }
        m
    }

    fn claims(out: &Output) -> Vec<Claim> {
        let avg = |a: usize| average(&out.errors[a]).unwrap_or(f64::INFINITY);
        let mut claims = vec![
            // The averages below skip passes without a track; this keeps them comparable.
            Claim::new(
                "every approach forms a track on every single-vehicle pass",
                out.errors
                    .iter()
                    .all(|per_pass| per_pass.iter().all(Option::is_some)),
            ),
            Claim::new(
                "audio+video's average error over the passes is at most 2 m (the paper's ≈ 2 m) under both rules",
                avg(2) <= 2.0 && avg(5) <= 2.0,
            ),
            Claim::new(
                "audio+video's average error is below video-only's under both rules",
                avg(2) < avg(1) && avg(5) < avg(4),
            ),
            Claim::new(
                "audio-only's average error is below audio+video's under both rules: here fusion does \
                 not beat the better single modality (the issue's target is not met)",
                avg(0) < avg(2) && avg(3) < avg(5),
            ),
        ];
        if let (Some(first), Some(last)) = (out.sweep.first(), out.sweep.last())
            && out.sweep.len() >= 2
        {
            claims.push(Claim::new(
                format!(
                    "video-only (product) error grows with camera calibration error: higher at {}° than at {}°",
                    fmt_num(out.sweep_deg[out.sweep_deg.len() - 1]),
                    fmt_num(out.sweep_deg[0])
                ),
                average(&last[4]).unwrap_or(f64::INFINITY) > average(&first[4]).unwrap_or(0.0),
            ));
        }
        claims
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let fmt = |a: usize| {
            let found: Vec<f64> = out.errors[a].iter().flatten().copied().collect();
            let (m, c) = mean_ci(&found);
            format!("{} ± {} m", fmt_num(m), fmt_num(c))
        };
        vec![Headline {
            quantity: format!(
                "Average tracking error, audio+video, {} single-vehicle passes",
                out.passes.len()
            ),
            paper: Some("≈ 2 m (Kushwaha et al. 2008, Figs. 10–11)".into()),
            ours: format!("{} (product), {} (weighted sum)", fmt(5), fmt(2)),
            peer: None,
        }]
    }

    fn present(out: &Output) -> Section {
        let mut per_pass = Table::new(
            &format!(
                "Mean tracking error (m) per pass and approach, camera heading error ±{}°; — = no track formed",
                fmt_num(out.calibration_error_deg)
            ),
            &[
                "pass",
                "duration (s)",
                "speed (mph)",
                APPROACHES[0].0,
                APPROACHES[1].0,
                APPROACHES[2].0,
                APPROACHES[3].0,
                APPROACHES[4].0,
                APPROACHES[5].0,
            ],
        );
        let cell = |e: Option<f64>| e.map_or("—".to_string(), fmt_num);
        for (i, (d, mph)) in out.passes.iter().enumerate() {
            let mut row = vec![(i + 1).to_string(), fmt_num(*d), fmt_num(*mph)];
            row.extend((0..APPROACHES.len()).map(|a| cell(out.errors[a][i])));
            per_pass.row(row);
        }
        let mut avg_row = vec!["mean ± 95 % CI".into(), String::new(), String::new()];
        for a in 0..APPROACHES.len() {
            let found: Vec<f64> = out.errors[a].iter().flatten().copied().collect();
            let (m, c) = mean_ci(&found);
            avg_row.push(if found.is_empty() {
                "—".into()
            } else {
                format!(
                    "{} ± {} ({}/{})",
                    fmt_num(m),
                    fmt_num(c),
                    found.len(),
                    out.passes.len()
                )
            });
        }
        per_pass.row(avg_row);
        let mut multi = Table::new(
            "Multi-vehicle runs (not attempted in the paper): MOTA and mean OSPA (order 1) per approach",
            &["run", "vehicles", "approach", "MOTA", "mean OSPA (m)"],
        );
        for (r, (n, mota, ospa)) in out.multi.iter().enumerate() {
            for (a, (name, _, _)) in APPROACHES.iter().enumerate() {
                multi.row(vec![
                    (r + 1).to_string(),
                    n.to_string(),
                    (*name).into(),
                    fmt_num(mota[a]),
                    fmt_num(ospa[a]),
                ]);
            }
        }
        let mut sweep_table = Table::new(
            "Average error (m) over the passes against camera heading error, product rule (audio-only is unaffected)",
            &["heading error (°)", APPROACHES[4].0, APPROACHES[5].0],
        );
        for (s, deg) in out.sweep_deg.iter().enumerate() {
            sweep_table.row(vec![
                fmt_num(*deg),
                cell(average(&out.sweep[s][4])),
                cell(average(&out.sweep[s][5])),
            ]);
        }
        // Bars as markers per pass index (the report's charts have no bar style); a missing
        // marker is a pass with no track.
        let bar_chart = |rule_product: bool| {
            let offset = if rule_product { 3 } else { 0 };
            let series = (0..3)
                .map(|m| {
                    let a = offset + m;
                    let pts = out.errors[a]
                        .iter()
                        .enumerate()
                        .filter_map(|(i, e)| {
                            e.map(|e| ((i + 1) as f64 + 0.15 * (m as f64 - 1.0), e))
                        })
                        .collect();
                    Series::new(APPROACHES[a].0, pts, Style::Markers, m)
                })
                .collect();
            Chart::new(
                if rule_product {
                    "Per-pass error, product fusion (cf. Fig. 11)"
                } else {
                    "Per-pass error, weighted-sum fusion (cf. Fig. 10)"
                },
                "pass",
                "mean tracking error (m)",
                series,
            )
        };
        let avg_chart = Chart::new(
            "Average error of the six approaches",
            "approach (1–3: sum, 4–6: product; audio, video, audio+video)",
            "average error (m)",
            (0..APPROACHES.len())
                .filter_map(|a| {
                    average(&out.errors[a]).map(|e| {
                        Series::new(
                            APPROACHES[a].0,
                            vec![((a + 1) as f64, e)],
                            Style::Markers,
                            a % 3,
                        )
                    })
                })
                .collect(),
        );
        let sweep_chart = Chart::new(
            "Error against camera calibration error",
            "camera heading error (°)",
            "average error (m)",
            [4usize, 5]
                .iter()
                .map(|&a| {
                    let pts = out
                        .sweep_deg
                        .iter()
                        .enumerate()
                        .filter_map(|(s, d)| average(&out.sweep[s][a]).map(|e| (*d, e)))
                        .collect();
                    Series::new(APPROACHES[a].0, pts, Style::Line, a)
                })
                .collect(),
        );
        let mut figures = vec![
            Figure::new(
                "errors-sum",
                "Mean error of each pass's track, weighted-sum fusion; a missing marker is a pass where no track formed",
                bar_chart(false),
            ),
            Figure::new(
                "errors-product",
                "Mean error of each pass's track, product fusion; a missing marker is a pass where no track formed",
                bar_chart(true),
            ),
            Figure::new(
                "errors-average",
                "Average over the passes with a track",
                avg_chart,
            ),
            Figure::new(
                "calibration",
                "Average error against the cameras' heading error (signs alternate between cameras)",
                sweep_chart,
            ),
        ];
        if let Some(map) = &out.map {
            let mut series = Vec::new();
            for (k, (lo, hi)) in [(0.25, 0.5), (0.5, 0.75), (0.75, 1.01)].iter().enumerate() {
                let pts = map
                    .cells
                    .iter()
                    .filter(|(_, _, v)| v >= lo && v < hi)
                    .map(|(x, y, _)| (*x, *y))
                    .collect();
                series.push(Series::new(
                    &format!("likelihood {lo}–{}", hi.min(1.0)),
                    pts,
                    Style::Markers,
                    [7, 2, 1][k],
                ));
            }
            for (i, t) in map.truth.iter().enumerate() {
                series.push(Series::new(
                    if i == 0 { "truth" } else { "" },
                    t.clone(),
                    Style::ThinLine,
                    7,
                ));
            }
            for (i, t) in map.tracks.iter().enumerate() {
                series.push(Series::new(
                    if i == 0 { "tracks" } else { "" },
                    t.clone(),
                    Style::Line,
                    0,
                ));
            }
            for (kind, label, colour) in [
                (SensorKind::Audio, "acoustic nodes", 3),
                (SensorKind::Video, "cameras", 4),
            ] {
                series.push(Series::new(
                    label,
                    map.sensors
                        .iter()
                        .filter(|s| s.2 == kind)
                        .map(|s| (s.0, s.1))
                        .collect(),
                    Style::Markers,
                    colour,
                ));
            }
            figures.push(Figure::new(
                "map",
                "Last multi-vehicle run, audio+video product: the fused likelihood (each tick scaled to maximum 1, maximum over the ticks) with the tracks over it",
                Chart::new("Fused likelihood and tracks", "x (m)", "y (m)", series),
            ));
        }
        // Where audio alone beats fusion, per rule.
        let audio_wins: Vec<String> = [(0usize, 2usize, "sum"), (3, 5, "product")]
            .iter()
            .map(|&(a, b, rule)| {
                let passes: Vec<String> = (0..out.passes.len())
                    .filter(|&i| match (out.errors[a][i], out.errors[b][i]) {
                        (Some(ea), Some(eb)) => ea < eb,
                        (Some(_), None) => true,
                        _ => false,
                    })
                    .map(|i| (i + 1).to_string())
                    .collect();
                if passes.is_empty() {
                    format!("under the {rule} rule, on no pass")
                } else {
                    format!("under the {rule} rule, on passes {}", passes.join(", "))
                }
            })
            .collect();
        let av = |a: usize| average(&out.errors[a]).map_or("—".into(), fmt_num);
        Section {
            title: "Audio-video fusion tracked by MCMCDA (Kushwaha et al. 2008)".into(),
            summary: format!(
                "Table 1's layout: 35 × 20 m in 0.5 m cells, six acoustic nodes (the 10 cm × 6 cm \
                 four-microphone array, 36 beams, frequency-domain delay-and-sum) and three cameras \
                 (160 angles) either side of a two-lane road, all at an angle to it; nodes keep their \
                 own clocks (known offsets). Each pass is simulated end to end: engine-like sources with \
                 a ground reflection in diffuse noise through the beamformer, and the rendered scene \
                 (swaying foliage, glint, noise) through the background mixture and the angle profile. \
                 The fusion node takes each sensor's nearest report within the staleness limit at \
                 10 Hz, fuses the bearing grids by weighted sum or by a floored product, and online \
                 MCMCDA tracks the peaks. Errors are the mean distance between a vehicle and its \
                 paired track (pairing within the match distance). The paper reports about 2 m on \
                 average; our audio+video averages are {} m (sum) and {} m (product), against {} m \
                 and {} m for audio alone and {} m and {} m for video alone. Where it loses: audio \
                 alone beats fusion {}. Our simulated acoustic nodes hear a single vehicle in diffuse \
                 noise with no reverberation or wind, so their bearings are better than the cameras', \
                 which suffer from the oblique view, the 2° heading errors (table and figure below) and \
                 clutter; fusing the worse modality in pulls the estimate away. With two and three \
                 vehicles the broad audio beams merge and the weaker vehicle's peak often falls \
                 below the threshold: tracks fragment and MOTA stays far below 0.8 for every \
                 approach (table below).",
                av(2),
                av(5),
                av(0),
                av(3),
                av(1),
                av(4),
                audio_wins.join("; ")
            ),
            tables: vec![per_pass, sweep_table, multi],
            figures,
        }
    }
}

fn key(name: &str) -> String {
    name.replace([',', '+'], "")
        .replace(' ', "_")
        .to_lowercase()
        .replace("__", "_")
}

fn average(values: &[Option<f64>]) -> Option<f64> {
    let found: Vec<f64> = values.iter().flatten().copied().collect();
    (!found.is_empty()).then(|| found.iter().sum::<f64>() / found.len() as f64)
}
