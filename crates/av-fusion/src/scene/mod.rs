//! The road scene of Kushwaha, Oh, Amundson, Koutsoukos & Ledeczi (MFI 2008, Table 1 and
//! Figs. 7–11; reviewed in Oh 2012, §V): a 35 × 20 m region in 0.5 m cells, six acoustic nodes
//! (36 beams) and three cameras (160 angles) either side of a two-lane road, and vehicles
//! passing on it.
//!
//! * [`Params`]: the scene and the six approaches' settings, as deserialised from a
//!   configuration's `[params]` table (unknown fields are rejected);
//! * [`Approach`]: audio, video and audio+video, each fused by the weighted sum or the
//!   floored product, each with its own [`ApproachSettings`] ([`Settings`], a
//!   [`PerApproach`]);
//! * [`simulate_run`]: the vehicles of a [`RunSpec`] through sensors-audio (engine-like
//!   sources, ground reflection, diffuse background noise) and through the sensors-video
//!   renderer and background mixture (cameras at an angle to the road, swaying foliage,
//!   glint, sensor noise), with the truth at every tick ([`Simulated`]);
//! * [`score_with`] / [`score_count_aware`]: one approach tracked on one simulated run, its
//!   mean error per vehicle, MOTA and mean OSPA ([`Score`]).
//!
//! The sensors never read the truth to decide what to report; every random draw comes from
//! the generator passed in.

use std::collections::BTreeMap;
use std::f64::consts::PI;

use mcmcda::{McmcdaConfig, OnlineConfig};
use sensors_audio::{BeamformConfig, MicArray};
use sensors_video::{AngleProfiler, DetectionFilterConfig, MogConfig, PostConfig};
use serde::{Deserialize, Serialize};
use tracker_model::{Region2, Vec2};

use crate::error::invalid;
use crate::tuning::{ScoreFit, Tuning};
use crate::{
    AvConfig, Error, FusionConfig, FusionRule, LobeEqualisation, PeakExtraction, PeakScores,
    RangeFade, Result, SchedulerConfig, SensorNode, SumScaling, TrackerConfig,
};

mod approach;
mod score;
mod sim;
#[cfg(test)]
mod tests;

pub use approach::{Approach, PerApproach};
pub use score::{Score, score_count_aware, score_with};
pub use sim::{RunSpec, Simulated, Vehicle, audio_poses, cameras, clock_offset_s, simulate_run};

/// Table 1: the region, m (x along the road, y across it).
pub const REGION_M: [f64; 2] = [35.0, 20.0];
/// The road's centre line, m, and its two lanes' offsets from it (+x traffic on the lower lane).
const ROAD_Y_M: f64 = 10.0;
const LANE_OFFSET_M: f64 = 1.5;
/// Metres per second in one mile per hour.
pub const MPS_PER_MPH: f64 = 0.44704;

/// One single-vehicle pass: the time it takes to cross the region and its direction.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassSpec {
    /// Seconds from entering to leaving the 35 m region (speed = 35 m / duration).
    pub duration_s: f64,
    /// +1: along +x on the lower lane; −1: along −x on the upper lane.
    pub direction: i8,
}

/// A vehicle of a multi-vehicle run.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleSpec {
    /// Speed, mph.
    pub speed_mph: f64,
    /// +1 or −1 as in [`PassSpec`].
    pub direction: i8,
    /// Seconds after the run's lead-in at which it enters the region.
    pub enter_s: f64,
}

/// The acoustic nodes.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AudioParams {
    /// Background noise SNR, dB (diffuse field).
    pub snr_db: f64,
    /// Plane waves of the diffuse noise.
    pub noise_directions: usize,
    /// Ground reflection coefficient.
    pub ground_reflection: f64,
    /// The beamformer (36 beams).
    pub beamform: BeamformConfig,
    /// The beamformer of the runs with more than one vehicle, if not `beamform` (the same
    /// beams and sample rate; e.g. MVDR in place of delay-and-sum).
    #[serde(default)]
    pub multi_beamform: Option<BeamformConfig>,
}

/// The cameras.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VideoParams {
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Focal length, pixels.
    pub focal_px: f64,
    /// Frames per second.
    pub fps: f64,
    /// Frames rendered before the run for the background model to learn.
    pub warmup_frames: usize,
    /// Angles of the profile (Table 1: 160).
    pub n_angles: usize,
    /// Mast height, m.
    pub mast_m: f64,
    /// Downward tilt, degrees.
    pub tilt_deg: f64,
    /// Swaying clutter patches of the rendered scene.
    pub n_sway_patches: usize,
    /// Mean glints per rendered frame.
    pub glints_per_frame: f64,
    /// Sensor noise of the rendered frames (standard deviation).
    pub noise_sigma: f64,
    /// Background mixture segmentation.
    pub mog: MogConfig,
    /// Post-processing of the foreground masks.
    pub post: PostConfig,
    /// Temporal filter of the detection functions.
    pub filter: DetectionFilterConfig,
}

/// One approach's settings, chosen for that approach alone by a search on tuning seeds
/// ([`crate::tuning::tune_one_config`]). Weights w_s are a multiplier in the weighted sum and an exponent in the
/// product (w < 1 tempers, w > 1 sharpens a sensor's likelihood); a single-modality approach
/// leaves the other modality's entries out (they would be unused; the default is 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ApproachSettings {
    /// Weight of the acoustic nodes.
    #[serde(default = "one")]
    pub audio_weight: f64,
    /// Weight of the cameras.
    #[serde(default = "one")]
    pub video_weight: f64,
    /// Profile exponent γ of the acoustic nodes (see [`SensorNode::exponent`]).
    #[serde(default = "one")]
    pub audio_exponent: f64,
    /// Profile exponent γ of the cameras.
    #[serde(default = "one")]
    pub video_exponent: f64,
    /// Floor ε of the product rule (required by the product approaches, unused by the sum).
    #[serde(default)]
    pub product_floor: Option<f64>,
    /// The peaks' relative threshold κ (the other peak settings are [`Params::peaks`], shared).
    pub relative_threshold: f64,
    /// The peaks' non-maximum suppression radius, m.
    pub suppression_radius_m: f64,
    /// MCMCDA's detection probability (the rest is [`Params::mcmcda`], shared).
    pub p_detect: f64,
    /// MCMCDA's clutter rate per scan.
    pub clutter_per_scan: f64,
    /// Lobe equalisation of the acoustic nodes' profiles (`None`: as reported).
    #[serde(default)]
    pub audio_lobes: Option<LobeEqualisation>,
    /// Lobe equalisation of the cameras' profiles (`None`: as reported).
    #[serde(default)]
    pub video_lobes: Option<LobeEqualisation>,
    /// MCMCDA's birth rate per scan (`None`: [`Params::mcmcda`]'s).
    #[serde(default)]
    pub births_per_scan: Option<f64>,
    /// Peaks by explaining away with this notch width σ, degrees (0: off; see
    /// [`PeakExtraction::explain_away_deg`]).
    #[serde(default)]
    pub explain_away_deg: f64,
    /// At most this many peaks per scan (`None`: [`Params::peaks`]'s).
    #[serde(default)]
    pub max_peaks: Option<usize>,
    /// MCMCDA's speed limit v̄, m/s (`None`: [`Params::mcmcda`]'s). v̄ gates pairs of peaks,
    /// so it has to cover the peaks' jitter as well as the vehicle's speed.
    #[serde(default)]
    pub max_speed: Option<f64>,
    /// MCMCDA's largest gap d̄, scans (`None`: [`Params::mcmcda`]'s): it lets a track bridge
    /// the ticks where another vehicle masks its peak.
    #[serde(default)]
    pub max_gap: Option<u32>,
    /// The peaks' contrasts go to MCMCDA as detection scores, by the approach's table in
    /// [`Params::multi_peak_scores`] (which must then exist; false: every peak counts the same).
    #[serde(default)]
    pub scored: bool,
    /// Each sensor's evidence fades with range (`None`: off).
    #[serde(default)]
    pub range_fade: Option<RangeFade>,
}

fn one() -> f64 {
    1.0
}

/// The settings of the six approaches: one table per approach, keyed by
/// [`Approach::settings_key`].
pub type Settings = PerApproach<ApproachSettings>;

/// The earlier, count-aware configuration, kept as a reference to compare with: one
/// [`Settings`] for runs with one vehicle and another for runs with more, chosen by earlier
/// per-count searches on the tuning seeds (docs/av-fusion.md). Choosing between them reads the
/// true number of vehicles, which a deployment does not know, so the scenario's results use
/// the one configuration of `cargo xtask tune av-fusion-road` instead.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CountAware {
    /// For runs with one vehicle.
    pub single: Settings,
    /// For runs with more than one.
    pub multi: Settings,
}

/// The scene, the approaches' settings and how they were chosen.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The single-vehicle passes (the paper's nine).
    pub passes: Vec<PassSpec>,
    /// Multi-vehicle runs.
    pub multi: Vec<Vec<VehicleSpec>>,
    /// Seconds before the first vehicle enters and after the last leaves.
    pub pad_s: f64,
    /// Grid cell, m (Table 1: 0.5).
    pub cell_size_m: f64,
    /// Scheduler.
    pub scheduler: SchedulerConfig,
    /// Acoustic nodes.
    pub audio: AudioParams,
    /// Cameras.
    pub video: VideoParams,
    /// Camera heading error of the main comparison, degrees (signs alternate by camera).
    pub calibration_error_deg: f64,
    /// Acoustic nodes' heading error of the main comparison, degrees (signs alternate by node).
    pub audio_calibration_error_deg: f64,
    /// Heading errors of the calibration sweep, degrees (applied to cameras and acoustic
    /// nodes alike).
    pub calibration_sweep_deg: Vec<f64>,
    /// The earlier count-aware settings, a reference only (`[params.count_aware]`).
    pub count_aware: CountAware,
    /// Each approach's peak-score table, keyed as the settings are (`audio_sum`, ...,
    /// `audio_video_product`; an approach left out is unscored), learnt on the tuning seeds'
    /// multi-vehicle runs by [`crate::tuning::fit_peak_scores`].
    #[serde(default)]
    pub multi_peak_scores: BTreeMap<String, PeakScores>,
    /// How `multi_peak_scores` are learnt.
    pub score_fit: ScoreFit,
    /// Peak extraction (κ and the NMS radius come from the approach's settings).
    pub peaks: PeakExtraction,
    /// The tracker (p_d and the clutter rate come from the approach's settings; motion
    /// period = 1 / scheduler rate).
    pub mcmcda: McmcdaConfig,
    /// The online tracker's window and sampling.
    pub online: OnlineConfig,
    /// A track is paired with a vehicle within this distance (error, MOTA).
    pub match_distance_m: f64,
    /// OSPA cut-off, m (order 1).
    pub ospa_cutoff_m: f64,
    /// The search behind the one configuration ([`crate::tuning::tune_one_config`]).
    pub tuning: Tuning,
    /// Fresh seeds: generated once after the settings were frozen and never used to choose
    /// anything (disjoint from every other seed list and from the reported seed).
    pub fresh_seeds: Vec<u64>,
}

/// Heading errors of a run: acoustic nodes and cameras, degrees (signs alternate by node).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// The acoustic nodes' heading error, degrees.
    pub audio_deg: f64,
    /// The cameras' heading error, degrees.
    pub video_deg: f64,
}

/// The heading errors of the main comparison.
pub fn nominal(p: &Params) -> Calibration {
    Calibration {
        audio_deg: p.audio_calibration_error_deg,
        video_deg: p.calibration_error_deg,
    }
}

/// The nodes as the fusion centre knows them: acoustic nodes and cameras with heading errors
/// ±`calib` (a wrong believed heading: real nodes are oriented by compass or by hand, and an
/// orientation error turns every bearing by the same angle), weighted by `weights`.
pub fn sensor_nodes(
    p: &Params,
    calib: Calibration,
    weights: &ApproachSettings,
) -> Result<Vec<SensorNode>> {
    let sign = |i: usize| if i.is_multiple_of(2) { 1.0 } else { -1.0 };
    let mut nodes: Vec<SensorNode> = audio_poses()
        .into_iter()
        .enumerate()
        .map(|(i, mut pose)| {
            pose.heading_rad += sign(i) * calib.audio_deg * PI / 180.0;
            let mut n = SensorNode::audio(format!("audio {i}"), pose, p.audio.beamform.n_beams);
            n.clock_offset_s = clock_offset_s(i);
            n.weight = weights.audio_weight;
            n.exponent = weights.audio_exponent;
            n.lobes = weights.audio_lobes;
            n
        })
        .collect();
    for (j, cam) in cameras(&p.video).into_iter().enumerate() {
        let profiler = AngleProfiler::new(cam, p.video.n_angles)?;
        let mut pose = cam.pose();
        pose.heading_rad += sign(j) * calib.video_deg * PI / 180.0;
        let mut n = SensorNode::video(format!("camera {j}"), pose, &profiler, p.video.n_angles);
        n.clock_offset_s = clock_offset_s(6 + j);
        n.weight = weights.video_weight;
        n.exponent = weights.video_exponent;
        n.lobes = weights.video_lobes;
        nodes.push(n);
    }
    Ok(nodes)
}

/// Approach `a`'s count-aware reference settings for a run with one vehicle (`multi` false)
/// or several: the choice reads the true count ([`CountAware`]).
pub fn count_aware_of(p: &Params, a: Approach, multi: bool) -> &ApproachSettings {
    if multi {
        p.count_aware.multi.get(a)
    } else {
        p.count_aware.single.get(a)
    }
}

/// Approach `a`'s peak scores under settings `s` (none unless `s.scored`).
pub fn peak_scores_of<'p>(
    p: &'p Params,
    a: Approach,
    s: &ApproachSettings,
) -> Result<Option<&'p PeakScores>> {
    if !s.scored {
        return Ok(None);
    }
    match p.multi_peak_scores.get(a.settings_key()) {
        Some(table) => Ok(Some(table)),
        None => Err(Error::MissingPeakScores {
            approach: a.settings_key().to_string(),
        }),
    }
}

/// Approach `a`'s configuration with settings `s` and peak scores `scores` over the shared
/// ones.
pub fn av_config(
    p: &Params,
    a: Approach,
    s: &ApproachSettings,
    scores: Option<&PeakScores>,
) -> Result<AvConfig> {
    let rule = if a.is_product() {
        let Some(floor) = s.product_floor else {
            return Err(invalid(
                "product_floor",
                format!("approach {a}: the product rule needs product_floor"),
            ));
        };
        FusionRule::Product { floor }
    } else {
        FusionRule::WeightedSum {
            scaling: SumScaling::Max,
        }
    };
    let mut mcmcda = p.mcmcda.clone();
    mcmcda.p_detect = s.p_detect;
    mcmcda.clutter_per_scan = s.clutter_per_scan;
    if let Some(b) = s.births_per_scan {
        mcmcda.births_per_scan = b;
    }
    if let Some(v) = s.max_speed {
        mcmcda.max_speed = v;
    }
    if let Some(d) = s.max_gap {
        mcmcda.max_gap = d;
    }
    Ok(AvConfig {
        scheduler: p.scheduler,
        fusion: FusionConfig {
            region: region(),
            cell_size_m: p.cell_size_m,
            max_range_m: None,
            min_range_m: 0.5,
            range_fade: s.range_fade,
            rule,
            modalities: a.modalities(),
            peaks: PeakExtraction {
                relative_threshold: s.relative_threshold,
                suppression_radius_m: s.suppression_radius_m,
                explain_away_deg: s.explain_away_deg,
                max_peaks: s.max_peaks.unwrap_or(p.peaks.max_peaks),
                ..p.peaks
            },
        },
        tracker: TrackerConfig {
            mcmcda,
            online: p.online,
            seed: 1,
            peak_scores: scores.cloned(),
        },
    })
}

/// The region, [`REGION_M`] from the origin.
pub fn region() -> Region2 {
    Region2::new(Vec2::zeros(), Vec2::new(REGION_M[0], REGION_M[1]))
        .unwrap_or_else(|_| unreachable!("a fixed valid region"))
}

/// The runs of the parameters: the single-vehicle passes, then the multi-vehicle runs.
pub fn run_specs(p: &Params) -> Result<Vec<RunSpec>> {
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
        if vehicles.is_empty() {
            return Err(invalid("multi", "a multi-vehicle run has no vehicles"));
        }
        let end = vehicles
            .iter()
            .map(|v| v.enter_s + REGION_M[0] / (v.speed_mph * MPS_PER_MPH))
            .fold(0.0, f64::max);
        runs.push(RunSpec {
            vehicles: vehicles
                .iter()
                .map(|v| Vehicle::new(v.speed_mph * MPS_PER_MPH, v.direction, p.pad_s + v.enter_s))
                .collect(),
            duration_s: end + 2.0 * p.pad_s,
        });
    }
    Ok(runs)
}

/// Checks the parameters before any run: passes and sizes, the seed lists (tuning, fitting,
/// reported `seed`, fresh) pairwise disjoint, the multi-vehicle beamformer, the peak-score
/// tables and the count-aware reference settings. The one configuration the results use is
/// checked by [`check_settings`].
pub fn check_params(p: &Params, seed: u64) -> Result<()> {
    check_sizes(p)?;
    check_seeds(p, seed)?;
    p.tuning.check()?;
    check_multi_beamform(&p.audio)?;
    for (k, table) in &p.multi_peak_scores {
        if Approach::from_settings_key(k).is_none() {
            let keys = Approach::ALL.map(Approach::settings_key);
            return Err(Error::UnknownApproach {
                name: k.clone(),
                known: keys.join(", "),
            });
        }
        table.check().map_err(|e| Error::PeakScoreTable {
            approach: k.clone(),
            source: Box::new(e),
        })?;
    }
    for a in Approach::ALL {
        // The count-aware single-vehicle settings were chosen without the tables.
        if p.count_aware.single.get(a).scored {
            return Err(invalid(
                "scored",
                format!(
                    "[params.count_aware.single.{}]: the single-vehicle reference is unscored",
                    a.settings_key()
                ),
            ));
        }
    }
    check_settings(p, &p.count_aware.single)?;
    check_settings(p, &p.count_aware.multi)
}

/// Checks every approach's settings of `settings` against the scene: the fusion, peak and
/// tracker configuration they make, its peak-score table where scored, and every node.
pub fn check_settings(p: &Params, settings: &Settings) -> Result<()> {
    for (a, s) in settings.iter() {
        av_config(p, a, s, peak_scores_of(p, a, s)?)?.check()?;
        for n in sensor_nodes(p, nominal(p), s)? {
            n.check()?;
        }
    }
    Ok(())
}

/// The most seeds a seed list may hold (each seed is a set of simulated runs).
pub const MAX_SEEDS: usize = 64;

/// The seeds that choose (tuning and score fitting), the reported seed and the fresh seeds
/// pairwise disjoint; each list at most [`MAX_SEEDS`], and tuning and fresh seeds not empty.
fn check_seeds(p: &Params, seed: u64) -> Result<()> {
    let choosing: Vec<u64> = p
        .tuning
        .seeds
        .iter()
        .chain(&p.score_fit.seeds)
        .copied()
        .collect();
    for (name, len) in [
        ("[params.tuning] seeds", p.tuning.seeds.len()),
        ("[params.score_fit] seeds", p.score_fit.seeds.len()),
        ("fresh_seeds", p.fresh_seeds.len()),
    ] {
        if len == 0 || len > MAX_SEEDS {
            return Err(invalid(
                "seeds",
                format!("{name}: {len} seeds; 1 to {MAX_SEEDS}"),
            ));
        }
    }
    let reported = [seed];
    let lists: [(&'static str, &[u64]); 3] = [
        ("the tuning and fitting seeds", &choosing),
        ("the reported seed", &reported),
        ("fresh_seeds", &p.fresh_seeds),
    ];
    for (i, (first, a)) in lists.iter().enumerate() {
        for (second, b) in &lists[i + 1..] {
            if let Some(&shared) = a.iter().find(|s| b.contains(s)) {
                return Err(Error::SharedSeed {
                    first,
                    second,
                    seed: shared,
                });
            }
        }
    }
    Ok(())
}

/// The longest run simulated, s: every run's audio is held in memory at the beamformer's
/// sample rate and its video rendered frame by frame, so a typo in a duration (`pad_s = 1e6`)
/// must be an error, not a request for 128 GB.
pub const MAX_RUN_S: f64 = 600.0;

/// The most runs, vehicles in a run and pixels of a camera image.
const MAX_RUNS: usize = 1000;
const MAX_VEHICLES: usize = 50;
const MAX_IMAGE_SIDE: usize = 8192;

/// Every count, size and duration the scenario file sets, before anything is simulated.
fn check_sizes(p: &Params) -> Result<()> {
    if p.passes.is_empty() || p.passes.len() + p.multi.len() > MAX_RUNS {
        return Err(invalid(
            "passes",
            format!(
                "{} passes and {} multi-vehicle runs; 1 to {MAX_RUNS} runs",
                p.passes.len(),
                p.multi.len()
            ),
        ));
    }
    let seconds = |name: &'static str, v: f64, lo_open: bool| {
        let ok = v.is_finite() && v <= MAX_RUN_S && if lo_open { v > 0.0 } else { v >= 0.0 };
        if ok {
            Ok(())
        } else {
            let low = if lo_open { "(0" } else { "[0" };
            Err(invalid(
                name,
                format!("{v} s must be in {low}, {MAX_RUN_S}]"),
            ))
        }
    };
    seconds("pad_s", p.pad_s, false)?;
    for pass in &p.passes {
        seconds("duration_s", pass.duration_s, true)?;
    }
    for run in &p.multi {
        if run.is_empty() || run.len() > MAX_VEHICLES {
            return Err(invalid(
                "multi",
                format!("{} vehicles in a run; 1 to {MAX_VEHICLES}", run.len()),
            ));
        }
        for v in run {
            seconds("enter_s", v.enter_s, false)?;
            if !(v.speed_mph.is_finite() && v.speed_mph > 0.0 && v.speed_mph <= 200.0) {
                return Err(invalid(
                    "speed_mph",
                    format!("{} must be in (0, 200]", v.speed_mph),
                ));
            }
        }
    }
    for spec in run_specs(p)? {
        seconds(
            "a run (pad_s + its vehicles + pad_s)",
            spec.duration_s,
            true,
        )?;
    }
    let v = &p.video;
    let sides_ok = [v.width, v.height]
        .iter()
        .all(|s| (16..=MAX_IMAGE_SIDE).contains(s));
    let fps_ok = v.fps.is_finite() && v.fps > 0.0 && v.fps <= 1000.0;
    if !(sides_ok && fps_ok && v.warmup_frames <= 100_000) {
        return Err(invalid(
            "video",
            format!(
                "{} × {} px at {} fps, {} warm-up frames; sides 16 to {MAX_IMAGE_SIDE} px, fps in (0, 1000], at most 100000 warm-up frames",
                v.width, v.height, v.fps, v.warmup_frames
            ),
        ));
    }
    Ok(())
}

/// A multi-vehicle beamformer keeps the single-vehicle one's beams and sample rate.
fn check_multi_beamform(audio: &AudioParams) -> Result<()> {
    let Some(multi) = &audio.multi_beamform else {
        return Ok(());
    };
    let single = &audio.beamform;
    if (multi.n_beams, multi.sample_rate_hz) != (single.n_beams, single.sample_rate_hz) {
        return Err(invalid(
            "multi_beamform",
            format!(
                "[params.audio.multi_beamform] must keep [params.audio.beamform]'s n_beams ({}) \
                 and sample_rate_hz ({})",
                single.n_beams, single.sample_rate_hz
            ),
        ));
    }
    multi.check(&MicArray::default())?;
    Ok(())
}
