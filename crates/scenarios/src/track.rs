//! Trackers for detection files: what `cargo xtask track` and the `mot-track` and
//! `mot-realistic` pipelines run. MCMCDA (offline batch, or online with a sliding window) and
//! GNN associate the box centres as point measurements; the SMC-PHD filter tracks the boxes
//! themselves. Without a configuration each tracker uses its model scaled to the boxes
//! ([`McmcdaConfig::for_boxes`], [`PhdConfig::for_boxes`]) and then fitted to the file
//! ([`fit_model`]: p_d, clutter and birth rates, R and q from the confident tracks of a first
//! GNN pass, iterated).
//!
//! Output boxes follow the detections a track holds ([`smooth_boxes`]): each box edge is a
//! local-linear kernel fit over the track's detections (σ = `[boxes] smoothing_frames`), so a
//! box shrinks with the detections where a person is cut by the image border, missed frames are
//! bridged, and nothing is extrapolated beyond a track's first and last detection unless
//! `[boxes] extrapolate_frames` asks for it. Online MCMCDA outputs, at each frame, the tracks
//! its window's MAP reports then, with a box fitted to their detections up to that frame only.
//!
//! No tracker's cost grows with gaps in the frame numbers: MCMCDA's and GNN's `Problem` stores
//! only non-empty scans, and the PHD path steps only the frames with detections, jumping each
//! gap in one prediction with the motion model's exact multi-frame transition
//! (`phd_filter::SmcPhd::step_after`); a frame number with no row is a frame in which the
//! detector found nothing.

use std::fmt;
use std::str::FromStr;

use anyhow::{Context, Result, bail};
use mcmcda::{
    McmcdaConfig, MeasId, NearestNeighbourConfig, OnlineConfig, OnlineTracker, Partition, Problem,
    TrackInit, nearest_neighbour_tracks, run_chains,
};
use phd_filter::{PhdConfig, SmcPhd};
use serde::{Deserialize, Serialize};
use tracker_model::{
    BoundingBox, ConstantVelocity2, Frame, MotRow, Track, TrackId, TrackPoint, TrackSet, Vec2,
};

/// Which tracker runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Tracker {
    /// Offline (batch) MCMCDA over the whole file.
    Mcmcda,
    /// Online sliding-window MCMCDA, output frame by frame.
    #[serde(rename = "mcmcda-online")]
    McmcdaOnline,
    /// Global nearest neighbour with M-of-N confirmation.
    Gnn,
    /// GNN output frame by frame: each box fitted to the track's detections up to that
    /// frame, coasted on the prediction through misses (up to `[boxes] online_coast_frames`).
    #[serde(rename = "gnn-online")]
    GnnOnline,
    /// SMC-PHD on boxes (global detections only: no images, so no local detectors).
    Phd,
}

impl Tracker {
    /// Every tracker, in the order the command line lists them.
    pub const ALL: [Tracker; 5] = [
        Tracker::Mcmcda,
        Tracker::McmcdaOnline,
        Tracker::Gnn,
        Tracker::GnnOnline,
        Tracker::Phd,
    ];

    /// The name on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Tracker::Mcmcda => "mcmcda",
            Tracker::McmcdaOnline => "mcmcda-online",
            Tracker::Gnn => "gnn",
            Tracker::GnnOnline => "gnn-online",
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
            .with_context(|| {
                format!("unknown tracker {s:?}; known: mcmcda, mcmcda-online, gnn, gnn-online, phd")
            })
    }
}

/// Offline MCMCDA's chain.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OfflineConfig {
    /// MCMC samples per detection in the file (the chain's length grows with the problem).
    pub samples_per_detection: u64,
    /// The fewest samples, whatever the file's size.
    pub min_samples: u64,
    /// Tracklet linking after the chain (min-cost, by the motion model; docs/mot-realistic.md):
    /// a track may continue one that ended at most this many times d̄ frames before (0: no
    /// linking).
    pub link_gap_factor: f64,
}

impl Default for OfflineConfig {
    fn default() -> Self {
        Self {
            samples_per_detection: 20,
            min_samples: 20_000,
            // Chosen on the tuning sequences of `mot-realistic` (0.5: little linked; 1, 1.5
            // and 2 alike, 1.5 best; 3 links passers-by).
            link_gap_factor: 1.5,
        }
    }
}

/// How the model is fitted to the file ([`fit_model`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FitConfig {
    /// Rounds of fitting (0: keep the box-scaled model).
    pub iterations: usize,
    /// Detections a GNN track needs to count as confident.
    pub min_track_detections: usize,
}

impl Default for FitConfig {
    fn default() -> Self {
        Self {
            iterations: 2,
            min_track_detections: 6,
        }
    }
}

/// How output boxes are made from a track's detections ([`smooth_boxes`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BoxConfig {
    /// σ, in frames, of the Gaussian kernel of the local-linear fit of each box edge.
    pub smoothing_frames: f64,
    /// Frames output before a track's first and after its last detection.
    pub extrapolate_frames: u32,
    /// Online GNN (`gnn-online`): frames a track is output from its prediction after a miss
    /// (at most GNN's deletion gap; the track stays open to detections until that gap).
    pub online_coast_frames: u32,
}

impl Default for BoxConfig {
    fn default() -> Self {
        Self {
            smoothing_frames: 1.5,
            extrapolate_frames: 0,
            // On the tuning sequences of `mot-realistic` (mean MOTA): 1 → 0.829, 3 → 0.851,
            // 5 → 0.842, the whole deletion gap (7-12 frames) → 0.818.
            online_coast_frames: 3,
        }
    }
}

/// Whether and how the detection scores (the confidence column) enter MCMCDA's and GNN's
/// likelihoods ([`fit_scores`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScoreConfig {
    /// Use the confidence column when it varies over the file.
    pub enabled: bool,
    /// The largest |ln f₁(s)/f₀(s)| a score contributes.
    pub max_log_ratio: f64,
}

impl Default for ScoreConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            max_log_ratio: 3.0,
        }
    }
}

impl ScoreConfig {
    /// Checks the bound (finite, ≥ 0).
    pub fn check(&self) -> Result<()> {
        if !(self.max_log_ratio.is_finite() && self.max_log_ratio >= 0.0) {
            bail!(
                "max_log_ratio = {}; it must be finite and ≥ 0",
                self.max_log_ratio
            );
        }
        Ok(())
    }
}

/// The score densities fitted to a file ([`fit_scores`]): f₁ of the scores of detections in
/// confident tracks, f₀ of those in no track, as ln f₁/f₀ tabulated over the file's score
/// range.
#[derive(Debug, Clone, PartialEq)]
pub struct ScoreModel {
    lo: f64,
    hi: f64,
    /// ln f₁/f₀ at `SCORE_GRID` evenly spaced scores from `lo` to `hi`, clamped.
    log_ratio: Vec<f64>,
    /// (count, mean, standard deviation) of the track and the clutter scores.
    track: (usize, f64, f64),
    clutter: (usize, f64, f64),
}

/// The online MCMCDA tracker's settings for detection files: the crate's defaults, except
/// that a track is output from the prediction for up to 5 frames after its last detection
/// (2, the crate's default, drops people through short occlusions; 5 and 8 did alike, 12
/// worse, on the tuning sequences of `mot-realistic`).
fn online_base() -> OnlineConfig {
    OnlineConfig {
        coast_scans: 5,
        ..OnlineConfig::default()
    }
}

/// Points of the tabulated score ratio.
const SCORE_GRID: usize = 64;

impl ScoreModel {
    /// ln f₁(s)/f₀(s), linear between the grid points (constant beyond the file's range).
    pub fn log_ratio(&self, s: f64) -> f64 {
        let n = self.log_ratio.len();
        if n < 2 || !s.is_finite() {
            return 0.0;
        }
        let u = ((s - self.lo) / (self.hi - self.lo)).clamp(0.0, 1.0) * (n - 1) as f64;
        let i = (u.floor() as usize).min(n - 2);
        let t = u - i as f64;
        self.log_ratio[i] + t * (self.log_ratio[i + 1] - self.log_ratio[i])
    }

    /// One line: the two samples and where the ratio crosses 1.
    pub fn summary(&self) -> String {
        let crossing = (1..self.log_ratio.len())
            .find(|&i| self.log_ratio[i - 1] < 0.0 && self.log_ratio[i] >= 0.0)
            .map(|i| {
                let (a, b) = (self.log_ratio[i - 1], self.log_ratio[i]);
                let step = (self.hi - self.lo) / (self.log_ratio.len() - 1) as f64;
                format!("{:.3}", self.lo + step * (i as f64 - 1.0 + a / (a - b)))
            })
            .unwrap_or_else(|| "none".into());
        format!(
            "scores: tracks {:.3} ± {:.3} (n {}), clutter {:.3} ± {:.3} (n {}), f₁/f₀ = 1 at {}, \
             ln f₁/f₀ {:.2} to {:.2}",
            self.track.1,
            self.track.2,
            self.track.0,
            self.clutter.1,
            self.clutter.2,
            self.clutter.0,
            crossing,
            self.log_ratio.iter().copied().fold(f64::INFINITY, f64::min),
            self.log_ratio
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max),
        )
    }
}

/// The optional configuration (TOML): any of the tables, each field optional. Fields of
/// `[model]` and `[phd]` override the configurations scaled and fitted to the detections.
/// Every table present is checked, whichever tracker runs ([`TrackConfig::resolve`]).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackConfig {
    model: Option<toml::Table>,
    #[serde(default)]
    fit: FitConfig,
    #[serde(default)]
    offline: OfflineConfig,
    /// Fields of `mcmcda::OnlineConfig`, overriding [`online_base`].
    online: Option<toml::Table>,
    #[serde(default)]
    gnn: NearestNeighbourConfig,
    #[serde(default)]
    boxes: BoxConfig,
    #[serde(default)]
    scores: ScoreConfig,
    /// Fields of `phd_filter::PhdConfig`, overriding a configuration scaled to the boxes.
    phd: Option<toml::Table>,
    #[serde(default)]
    phd_labels: PhdLabelConfig,
}

/// The effective configuration of every tracker: what runs, with every field set.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EffectiveConfig {
    /// MCMCDA's and GNN's model (`[model]`).
    pub model: McmcdaConfig,
    /// How the model was fitted (`[fit]`).
    pub fit: FitConfig,
    /// Offline MCMCDA (`[offline]`).
    pub offline: OfflineConfig,
    /// Output boxes (`[boxes]`).
    pub boxes: BoxConfig,
    /// Detection scores (`[scores]`).
    pub scores: ScoreConfig,
    /// The score densities fitted to the file (none when `[scores]` is off or the file's
    /// scores do not vary or are too few); not a key of the configuration.
    #[serde(skip)]
    pub score_model: Option<ScoreModel>,
    /// The online MCMCDA tracker (`[online]`).
    pub online: OnlineConfig,
    /// GNN (`[gnn]`).
    pub gnn: NearestNeighbourConfig,
    /// The SMC-PHD filter (`[phd]`).
    pub phd: PhdConfig,
    /// The PHD tracker's track management (`[phd_labels]`).
    pub phd_labels: PhdLabelConfig,
}

impl TrackConfig {
    /// Builds and checks every table against the detections `rows` (the models are scaled to
    /// their boxes; with no rows, the defaults of the papers are the base). A table for a
    /// tracker that does not run is checked too: a mistake in it is a mistake in the file.
    pub fn resolve(&self, rows: &[MotRow]) -> Result<EffectiveConfig> {
        let boxes = boxes(rows);
        let (model_base, mut phd_base) = if boxes.is_empty() {
            (McmcdaConfig::default(), PhdConfig::default())
        } else {
            (
                McmcdaConfig::for_boxes(&boxes)?,
                PhdConfig::for_boxes(&boxes)?,
            )
        };
        if self.fit.min_track_detections < 3 {
            bail!(
                "in the [fit] table of the configuration: min_track_detections = {}; the \
                 moment estimates need at least 3",
                self.fit.min_track_detections
            );
        }
        self.offline
            .check()
            .context("in the [offline] table of the configuration")?;
        self.boxes
            .check()
            .context("in the [boxes] table of the configuration")?;
        self.scores
            .check()
            .context("in the [scores] table of the configuration")?;
        let model_base = if boxes.is_empty() {
            model_base
        } else {
            fit_model(&model_base, rows, &self.fit)?
        };
        if self.fit.iterations > 0 && !boxes.is_empty() {
            // The PHD filter's rates, noise and motion come from the same fit: constant
            // velocity with MCMCDA's q, newborn velocity σ from the fitted velocity variance,
            // the centre's R and twice its σ for the size.
            phd_base.p_detect = model_base.p_detect;
            phd_base.clutter_rate = model_base.clutter_per_scan;
            phd_base.birth_rate = model_base.births_per_scan;
            // Floors at half the box-scaled σ: a particle filter needs likelihoods wider than
            // the spacing of its particles (near-noiseless files would starve it).
            let r = model_base.measurement_noise;
            let floor = phd_base.measurement_std;
            let (sx, sy) = (r[(0, 0)].sqrt(), r[(1, 1)].sqrt());
            phd_base.measurement_std = [
                sx.max(0.5 * floor[0]),
                sy.max(0.5 * floor[1]),
                (2.0 * sx).max(0.5 * floor[2]),
                (2.0 * sy).max(0.5 * floor[3]),
            ];
            let size_std = match phd_base.motion {
                phd_filter::Motion::RandomWalk { size_std, .. }
                | phd_filter::Motion::ConstantVelocity { size_std, .. } => size_std,
            };
            let q = match model_base.motion.noise() {
                tracker_model::CvNoise::Discrete {
                    acceleration_covariance,
                } => acceleration_covariance[(0, 0)],
                tracker_model::CvNoise::WhiteAcceleration { q } => q,
            };
            phd_base.motion = phd_filter::Motion::ConstantVelocity {
                acceleration_std: q.sqrt().max(0.1 * floor[0]),
                size_std,
            };
            if let TrackInit::FirstMeasurement {
                velocity_variance: Some(v),
            } = model_base.track_init
            {
                phd_base.birth_velocity_std = v.sqrt();
            }
        }
        let model = overridden(&model_base, self.model.as_ref(), "model")?;
        model
            .check()
            .context("in the [model] table of the configuration")?;
        let online = overridden(&online_base(), self.online.as_ref(), "online")?;
        online
            .check()
            .context("in the [online] table of the configuration")?;
        if online.samples_per_scan == 0 {
            bail!(
                "in the [online] table of the configuration: samples_per_scan = 0; MCMCDA \
                 needs at least 1 sample per scan to find any track"
            );
        }
        self.gnn
            .check()
            .context("in the [gnn] table of the configuration")?;
        let phd = overridden(&phd_base, self.phd.as_ref(), "phd")?;
        phd.check()
            .context("in the [phd] table of the configuration")?;
        self.phd_labels
            .check()
            .context("in the [phd_labels] table of the configuration")?;
        let mut gnn = self.gnn;
        if gnn.max_gap.is_none() && self.fit.iterations > 0 && !boxes.is_empty() {
            // GNN deletes after one box width of travel, half of MCMCDA's d̄ (the fitted one,
            // or the user's `[model] max_gap`).
            gnn.max_gap = Some(((f64::from(model.max_gap) / GAP_BOX_WIDTHS).round() as u32).max(1));
        }
        let score_model = fit_scores(&model, rows, &self.fit, &gnn, &self.scores)?;
        Ok(EffectiveConfig {
            model,
            fit: self.fit,
            offline: self.offline,
            boxes: self.boxes,
            scores: self.scores,
            score_model,
            online,
            gnn,
            phd,
            phd_labels: self.phd_labels,
        })
    }
}

/// Tracks `rows` and returns boxed tracks with ids from 1. The configuration is resolved and
/// checked first, every table of it.
pub fn track_detections(
    tracker: Tracker,
    rows: &[MotRow],
    settings: &TrackConfig,
    seed: u64,
) -> Result<TrackSet> {
    if rows.is_empty() {
        bail!("no detections");
    }
    let config = settings.resolve(rows)?;
    match tracker {
        Tracker::Phd => track_boxes_phd(rows, &config, seed),
        Tracker::Mcmcda | Tracker::McmcdaOnline | Tracker::Gnn | Tracker::GnnOnline => {
            track_points(tracker, rows, &config, seed)
        }
    }
}

/// [`track_detections`], or, given a folder of `frames`, the PHD tracker fused with image local
/// detectors on those pictures ([`crate::track_frames`]; `--tracker phd` only).
pub fn track_detections_with_frames(
    tracker: Tracker,
    rows: &[MotRow],
    settings: &TrackConfig,
    seed: u64,
    frames: Option<&std::path::Path>,
) -> Result<TrackSet> {
    match (frames, tracker) {
        (None, _) => track_detections(tracker, rows, settings, seed),
        (Some(dir), Tracker::Phd) => crate::track_frames::track_frames(
            dir,
            rows,
            settings,
            &crate::track_frames::FusedSettings::default(),
            seed,
        ),
        (Some(_), _) => bail!("--frames runs the fused PHD tracker: use it with --tracker phd"),
    }
}

/// Why a tracker that was given detections returned no track, or nothing when it returned
/// some: a warning for the user that names the parameters that decide it.
pub fn empty_output_warning(
    tracker: Tracker,
    rows: &[MotRow],
    config: &EffectiveConfig,
    tracks: &TrackSet,
) -> Option<String> {
    if !tracks.is_empty() || rows.is_empty() {
        return None;
    }
    let frames: std::collections::BTreeSet<Frame> = rows.iter().map(|r| r.frame).collect();
    let seen = format!(
        "{tracker} found no track in {} detections over {} frames",
        rows.len(),
        frames.len()
    );
    let m = &config.model;
    let why = match tracker {
        Tracker::Mcmcda | Tracker::McmcdaOnline | Tracker::Gnn | Tracker::GnnOnline => format!(
            "a track needs detections in at least two frames at most max_gap = {} frames \
             apart, moving at most max_speed = {} per frame, and it must explain them better \
             than clutter_per_scan = {} false alarms per frame over volume = {}",
            m.max_gap, m.max_speed, m.clutter_per_scan, m.volume
        ),
        Tracker::Phd => format!(
            "a track is reported where the filter's weight passes extraction_threshold = {} \
             with p_detect = {}, birth_rate = {} and clutter_rate = {} per frame",
            config.phd.extraction_threshold,
            config.phd.p_detect,
            config.phd.birth_rate,
            config.phd.clutter_rate
        ),
    };
    Some(format!(
        "{seen}: {why}. See the effective configuration with `cargo xtask track \
         --print-config --tracker {tracker} --input FILE`"
    ))
}

/// One line of explanation per key of each table, in the order `--print-config` writes them.
const KEY_COMMENTS: [(&str, &[(&str, &str)]); 9] = [
    (
        "model",
        &[
            (
                "volume",
                "volume V of the surveillance region (area, pixels²)",
            ),
            ("births_per_scan", "expected new targets per frame, λ_b·V"),
            (
                "clutter_per_scan",
                "expected false detections per frame, λ_f·V",
            ),
            (
                "p_disappear",
                "probability p_z that a target disappears between frames",
            ),
            ("p_detect", "detection probability p_d"),
            (
                "motion",
                "constant-velocity motion: frame period dt_s and the acceleration noise",
            ),
            (
                "measurement_noise",
                "covariance R of a detection's centre, as rows [[xx, xy], [yx, yy]]",
            ),
            (
                "max_gap",
                "d̄: the most frames between two detections of one track (1-64)",
            ),
            (
                "max_speed",
                "v̄: the largest speed, pixels per frame (gates associations)",
            ),
            (
                "stop_probability",
                "γ: the chance that growing a track stops before each further detection",
            ),
            (
                "gap_distribution",
                "ζ, the gap distribution: \"geometric\" or \"uniform\"",
            ),
            (
                "head_probability",
                "probability that extension/reduction/update acts on a track's head",
            ),
            (
                "move_weights",
                "ξ: weights of birth, death, split, merge, extension, reduction, update, switch",
            ),
            (
                "track_init",
                "how a track's filter starts (first_measurement {velocity_variance} or two_point)",
            ),
            (
                "track_end",
                "how a track's end is scored: \"disappeared\" or \"undetected\"",
            ),
        ],
    ),
    (
        "fit",
        &[
            (
                "iterations",
                "rounds of fitting p_d, clutter, births, R and q to the file (0 = off)",
            ),
            (
                "min_track_detections",
                "detections a GNN track needs to enter the fit",
            ),
        ],
    ),
    (
        "offline",
        &[
            (
                "samples_per_detection",
                "MCMC samples per detection of the file",
            ),
            ("min_samples", "the fewest MCMC samples"),
            (
                "link_gap_factor",
                "tracklet linking: a track may continue one that ended up to this many d̄ frames before (0 = off)",
            ),
        ],
    ),
    (
        "online",
        &[
            ("window", "t_win: frames in the sliding window (≥ 2)"),
            ("samples_per_scan", "MCMC samples per window (≥ 1)"),
            (
                "extension_gate",
                "χ² gate of the greedy extension of live tracks into a new frame",
            ),
            (
                "coast_scans",
                "a track is reported while its last detection is at most this many frames old",
            ),
        ],
    ),
    (
        "gnn",
        &[
            (
                "assignment",
                "\"optimal\" (minimum total cost) or \"greedy\"",
            ),
            (
                "cost",
                "\"log_likelihood_ratio\" (a track may go unassigned) or \"forced\"",
            ),
            (
                "gate",
                "χ² gate on the innovation's squared Mahalanobis distance",
            ),
            ("confirm_hits", "M of M-of-N confirmation"),
            ("confirm_window", "N of M-of-N confirmation"),
            (
                "max_gap",
                "the largest gap in frames within a track; unset = the model's max_gap",
            ),
        ],
    ),
    (
        "boxes",
        &[
            (
                "smoothing_frames",
                "σ (frames) of the kernel fitting each output box edge to the track's detections",
            ),
            (
                "extrapolate_frames",
                "frames output before the first and after the last detection of a track",
            ),
            (
                "online_coast_frames",
                "gnn-online: frames a track is output from its prediction after a miss (≤ the deletion gap)",
            ),
        ],
    ),
    (
        "scores",
        &[
            (
                "enabled",
                "use the confidence column: ln f₁(s)/f₀(s), fitted to the file, in each detection's likelihood",
            ),
            (
                "max_log_ratio",
                "the largest |ln f₁(s)/f₀(s)| one detection's score contributes",
            ),
        ],
    ),
    (
        "phd",
        &[
            ("p_survive", "survival probability p_S"),
            ("p_detect", "detection probability p_D"),
            ("clutter_rate", "expected false detections per frame, λ_c"),
            (
                "measurement_volume",
                "volume of measurement space (centre x range · y range · width range · height range)",
            ),
            ("birth_rate", "expected births per frame"),
            (
                "measurement_std",
                "σ of the measured [c_x, c_y, w, h], pixels",
            ),
            (
                "motion",
                "random_walk {position_std, size_std} or constant_velocity {acceleration_std, size_std}",
            ),
            (
                "birth_velocity_std",
                "σ of a newborn's velocity (constant_velocity only)",
            ),
            ("particles_per_target", "SMC particles per expected target"),
            (
                "birth_particles",
                "SMC particles for each detection's newborn group",
            ),
            ("max_particles", "the most SMC particles after resampling"),
            (
                "extraction_threshold",
                "a box is reported where the filter's weight exceeds this",
            ),
            (
                "label_min_share",
                "an estimate keeps the oldest identity holding at least this share of its weight",
            ),
        ],
    ),
    (
        "phd_labels",
        &[
            (
                "confirm_hits",
                "estimates a tentative PHD track needs to get an id",
            ),
            ("confirm_window", "frames within which it needs them"),
            (
                "min_iou",
                "overlap an estimate needs with a track's last box to continue it",
            ),
            (
                "min_mass",
                "share of a missed target's expected PHD mass its label must hold to keep its id",
            ),
            (
                "max_misses",
                "the most frames a confirmed track is output from the prediction",
            ),
        ],
    ),
];

/// The tables a tracker reads.
fn tables_of(tracker: Tracker) -> &'static [&'static str] {
    match tracker {
        Tracker::Mcmcda => &["model", "fit", "offline", "boxes", "scores"],
        Tracker::McmcdaOnline => &["model", "fit", "online", "boxes", "scores"],
        Tracker::Gnn | Tracker::GnnOnline => &["model", "fit", "gnn", "boxes", "scores"],
        Tracker::Phd => &["fit", "phd", "phd_labels"],
    }
}

/// The effective configuration as commented TOML: every key of the tables `tracker` reads
/// (all of them without one) with its value and a one-line comment. Loading the text back as a
/// [`TrackConfig`] gives the same effective configuration. Unset optional keys are written
/// as comments.
pub fn render_config(config: &EffectiveConfig, tracker: Option<Tracker>) -> Result<String> {
    let all = toml::Table::try_from(config)?;
    let mut out = String::from(
        "# Effective configuration of `cargo xtask track` (load it with --config FILE).\n\
         # Every key is optional: a missing key of [model] or [phd] keeps the value scaled and\n\
         # fitted to the detections, of the other tables its default.\n",
    );
    for (name, keys) in KEY_COMMENTS {
        if tracker.is_some_and(|t| !tables_of(t).contains(&name)) {
            continue;
        }
        let table = all
            .get(name)
            .and_then(toml::Value::as_table)
            .with_context(|| format!("the configuration has no [{name}] table"))?;
        if let Some(key) = table.keys().find(|k| !keys.iter().any(|(c, _)| c == k)) {
            bail!("[{name}] {key} has no comment in KEY_COMMENTS");
        }
        out.push_str(&format!("\n[{name}]\n"));
        for (key, comment) in keys {
            out.push_str(&format!("# {comment}\n"));
            match table.get(*key) {
                Some(value) => out.push_str(&format!("{key} = {value}\n")),
                None => out.push_str(&format!("# {key} is unset\n")),
            }
        }
    }
    Ok(out)
}

/// Track management on top of the SMC-PHD filter's per-frame estimates (the labelled-PHD
/// practice of track-before-confirm, then a persistent id):
/// - an estimate continues the track that holds its PHD label, else the unmatched live track
///   whose last box it overlaps most (IoU ≥ `[phd_labels] min_iou`), else it starts a
///   tentative track;
/// - a tentative track is confirmed, and gets its id, at `confirm_hits` estimates within its
///   first `confirm_window` frames (its earlier boxes are output too), or is dropped;
/// - a confirmed track without an estimate keeps its id while the PHD mass of its label stays
///   at or above `min_mass` times what a missed target keeps ((p_S (1 − p_D)) per missed frame)
///   and for at most `max_misses` frames, and is output from the prediction (the weighted
///   mean of its label's particles, or, once resampling has left the label none, the track's
///   own constant-velocity prediction);
/// - frame numbers that no row names are frames without detections: the filter jumps them in
///   one prediction and the labeller coasts through them in closed form (`coast_through_gap`);
/// - a track that ends drops the coasted frames after its last estimate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PhdLabelConfig {
    /// Estimates a tentative track needs to be confirmed.
    pub confirm_hits: u32,
    /// Frames within which it needs them.
    pub confirm_window: u32,
    /// Overlap an estimate needs with a track's last box to continue it.
    pub min_iou: f64,
    /// Share of the mass a missed target keeps, (p_S (1 − p_D))^misses, that its label's PHD
    /// mass must hold for the track to keep its id.
    pub min_mass: f64,
    /// The most frames a confirmed track is output from the prediction (at most 10 000: a gap
    /// in the frame numbers costs at most this many boxes per track).
    pub max_misses: u32,
}

impl Default for PhdLabelConfig {
    fn default() -> Self {
        // Chosen on the tuning sequences of `mot-realistic` (mean MOTA / IDF1 there), where
        // the PHD path lost to online MCMCDA mainly by misses (FN), not false boxes: from
        // 3 hits, IoU 0.3, mass 0.1 and 8 frames (0.800 / 0.622), coasting 15 frames gave
        // 0.825 / 0.683, 40 with 2 hits and mass 0.02 0.842 / 0.771 (80 the same: tracks end
        // by their label's mass before), IoU 0.2 then 0.843 / 0.808 (0.1, tried with an
        // extraction threshold of 0.3 only: MOTA alike, IDF1 higher).
        Self {
            confirm_hits: 2,
            confirm_window: 5,
            min_iou: 0.2,
            min_mass: 0.02,
            max_misses: 40,
        }
    }
}

/// A track of the PHD labeller.
struct PhdTrack {
    id: Option<u64>,
    phd_label: u64,
    first: Frame,
    hits: u32,
    misses: u32,
    /// Output points; the last `coasted` of them are predictions.
    points: Vec<TrackPoint>,
    coasted: usize,
    last_box: BoundingBox,
    velocity: Vec2,
    last_seen: Frame,
}

/// SMC-PHD on the boxes themselves, with [`PhdLabelConfig`]'s track management.
fn track_boxes_phd(rows: &[MotRow], settings: &EffectiveConfig, seed: u64) -> Result<TrackSet> {
    let config = settings.phd;
    let labels = settings.phd_labels;
    let mut phd = SmcPhd::new(config, seed)?;
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<BoundingBox>> = Default::default();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(r.bbox);
    }
    if by_frame.is_empty() {
        bail!("no detections");
    }
    // Only frames with detections are stepped. A frame number with no row is a frame in
    // which the detector found nothing (a MOTChallenge file has no way to say "no detector
    // ran"): the filter jumps such a gap of k frames in one prediction with the exact k-frame
    // transition and weights p_Sᵏ (1 − p_D)ᵏ⁻¹ (`SmcPhd::step_after`), and the labeller
    // coasts through it in closed form (`coast_through_gap`). The cost is bounded by the
    // detection frames, not by the span of frame numbers.
    let mut live: Vec<PhdTrack> = Vec::new();
    let mut done: Vec<PhdTrack> = Vec::new();
    let mut next_id = 1u64;
    let mut previous: Option<Frame> = None;
    let mut step_frame = |frame: Frame,
                          frames: u64,
                          boxes: &[BoundingBox],
                          phd: &mut SmcPhd,
                          live: &mut Vec<PhdTrack>,
                          done: &mut Vec<PhdTrack>|
     -> Result<()> {
        let step = phd.step_after(frames, boxes)?;
        let mass = label_masses(phd);
        let mut updated = vec![false; live.len()];
        let mut unmatched = Vec::new();
        for e in &step.estimates {
            match live
                .iter()
                .enumerate()
                .position(|(i, t)| !updated[i] && t.phd_label == e.label)
            {
                Some(i) => {
                    updated[i] = true;
                    observe(&mut live[i], frame, e.bbox, e.label);
                }
                None => unmatched.push(*e),
            }
        }
        for e in unmatched {
            let best = live
                .iter()
                .enumerate()
                .filter(|(i, _)| !updated[*i])
                .map(|(i, t)| (i, predicted(t, frame).iou(&e.bbox)))
                .filter(|&(_, iou)| iou >= labels.min_iou)
                .max_by(|a, b| a.1.total_cmp(&b.1));
            match best {
                Some((i, _)) => {
                    updated[i] = true;
                    observe(&mut live[i], frame, e.bbox, e.label);
                }
                None => {
                    live.push(PhdTrack {
                        id: None,
                        phd_label: e.label,
                        first: frame,
                        hits: 1,
                        misses: 0,
                        points: vec![TrackPoint::boxed(frame, e.bbox)],
                        coasted: 0,
                        last_box: e.bbox,
                        velocity: Vec2::zeros(),
                        last_seen: frame,
                    });
                    updated.push(true);
                }
            }
        }
        let mut kept = Vec::with_capacity(live.len());
        for (mut t, up) in live.drain(..).zip(updated) {
            if t.id.is_none() {
                if t.hits >= labels.confirm_hits {
                    t.id = Some(next_id);
                    next_id += 1;
                } else if frame - t.first + 1 >= labels.confirm_window {
                    continue;
                }
            }
            if up {
                kept.push(t);
                continue;
            }
            t.misses += 1;
            let label_mass = mass.get(&t.phd_label);
            // A missed target's PHD mass shrinks by p_S (1 − p_D) per frame; the label keeps
            // its track while it holds at least `min_mass` of that.
            let expected = (config.p_survive * (1.0 - config.p_detect)).powi(t.misses as i32);
            // Resampling gives a label about particles_per_target × its mass particles, so a
            // label missed for a few frames can lose them all: then the track coasts on its
            // own constant-velocity prediction, still at most `max_misses` frames.
            let alive = t.id.is_some()
                && t.misses <= labels.max_misses
                && label_mass.is_none_or(|m| m.0 >= labels.min_mass * expected);
            if !alive {
                if t.id.is_some() {
                    done.push(t);
                }
                continue;
            }
            // The prediction: the label's particles' mean centre, the track's last size.
            let bbox = match label_mass {
                Some(&(m, x)) if m > 0.0 => BoundingBox::from_centre(
                    Vec2::new(x[0] / m, x[1] / m),
                    t.last_box.width,
                    t.last_box.height,
                )?,
                _ => predicted(&t, frame),
            };
            t.points.push(TrackPoint::boxed(frame, bbox));
            t.coasted += 1;
            kept.push(t);
        }
        *live = kept;
        Ok(())
    };
    for (&frame, boxes) in &by_frame {
        let frames = match previous {
            Some(prev) => {
                let frames = u64::from(frame) - u64::from(prev);
                if frames > 1 {
                    coast_through_gap(prev, frames - 1, &phd, &mut live, &mut done, settings)?;
                }
                frames
            }
            None => 1,
        };
        step_frame(frame, frames, boxes, &mut phd, &mut live, &mut done)?;
        previous = Some(frame);
    }
    done.extend(live.into_iter().filter(|t| t.id.is_some()));
    let mut tracks = Vec::with_capacity(done.len());
    for mut t in done {
        let n = t.points.len() - t.coasted;
        t.points.truncate(n);
        if let Some(id) = t.id {
            tracks.push(Track::from_points(TrackId(id), t.points)?);
        }
    }
    Ok(TrackSet::from_tracks(tracks)?)
}

/// A PHD track takes an estimate: coasted points stay (they were output), velocity from the
/// last two estimates.
fn observe(t: &mut PhdTrack, frame: Frame, bbox: BoundingBox, label: u64) {
    let gap = f64::from(frame - t.last_seen).max(1.0);
    t.velocity = (bbox.centre() - t.last_box.centre()) / gap;
    t.points.push(TrackPoint::boxed(frame, bbox));
    t.coasted = 0;
    t.hits += 1;
    t.misses = 0;
    t.last_box = bbox;
    t.last_seen = frame;
    t.phd_label = label;
}

/// A PHD track's box moved on at its last velocity to `frame`.
fn predicted(t: &PhdTrack, frame: Frame) -> BoundingBox {
    let dt = f64::from(frame.saturating_sub(t.last_seen));
    let c = t.last_box.centre() + t.velocity * dt;
    BoundingBox::from_centre(c, t.last_box.width, t.last_box.height).unwrap_or(t.last_box)
}

/// Mass and weighted mean state of every PHD label's particles.
fn label_masses(phd: &SmcPhd) -> std::collections::HashMap<u64, (f64, [f64; 6])> {
    let mut mass: std::collections::HashMap<u64, (f64, [f64; 6])> = Default::default();
    for p in phd.particles() {
        let e = mass.entry(p.label).or_insert((0.0, [0.0; 6]));
        e.0 += p.w;
        for k in 0..6 {
            e.1[k] += p.w * p.x[k];
        }
    }
    mass
}

/// The labeller through the `gap` frames after `prev` that hold no detection, in closed form
/// and in one pass over the live tracks, while the filter jumps them in one prediction.
/// Stepping each empty frame would give no estimate, so:
/// - a tentative track ends at the gap's first frame (it missed a frame before confirmation);
/// - a confirmed track keeps its id through the gap iff it would at every frame of it: at most
///   `max_misses` misses in all, and its label's mass at `prev`, m, at least `min_mass`
///   (p_S (1 − p_D))^misses (through the gap the label's mass and the bound shrink by the same
///   p_S (1 − p_D) per frame, so the check at each frame is this one). It is output at each
///   frame prev + j from its label's mean state moved j frames by the motion model, F(j) x̄
///   (the mean of what stepping would give; or its own constant-velocity prediction when the
///   label has no particle left), with its last size;
/// - a track that ends in the gap keeps no coasted frame (they would be dropped at its end).
///
/// At most `max_misses` (≤ 10 000) boxes per track per gap, whatever the gap's length.
fn coast_through_gap(
    prev: Frame,
    gap: u64,
    phd: &SmcPhd,
    live: &mut Vec<PhdTrack>,
    done: &mut Vec<PhdTrack>,
    settings: &EffectiveConfig,
) -> Result<()> {
    let (config, labels) = (settings.phd, settings.phd_labels);
    let per_frame = config.p_survive * (1.0 - config.p_detect);
    let mass = label_masses(phd);
    let mut kept = Vec::with_capacity(live.len());
    for mut t in live.drain(..) {
        if t.id.is_none() {
            continue;
        }
        let label = mass.get(&t.phd_label);
        let holds = label.is_none_or(|m| {
            // misses ≤ max_misses ≤ 10 000 fits an i32.
            m.0 >= labels.min_mass * per_frame.powi(t.misses as i32)
        });
        if u64::from(t.misses) + gap > u64::from(labels.max_misses) || !holds {
            done.push(t);
            continue;
        }
        for j in 1..=gap {
            // j ≤ gap = frame − prev − 1 ≤ max_misses, so prev + j fits a Frame.
            let frame = prev + j as Frame;
            let bbox = match label {
                Some(&(m, x)) if m > 0.0 => {
                    let c = config.motion.predict_mean(&x.map(|v| v / m), j);
                    BoundingBox::from_centre(
                        Vec2::new(c[0], c[1]),
                        t.last_box.width,
                        t.last_box.height,
                    )?
                }
                _ => predicted(&t, frame),
            };
            t.points.push(TrackPoint::boxed(frame, bbox));
        }
        t.coasted += gap as usize;
        t.misses += gap as u32;
        kept.push(t);
    }
    *live = kept;
    Ok(())
}

/// The most frames a PHD track may coast (`[phd_labels] max_misses`): a gap in the frame
/// numbers costs at most this many boxes per live track.
const MAX_COAST_FRAMES: u32 = 10_000;

impl PhdLabelConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        if !(0.0..=1.0).contains(&self.min_iou) {
            bail!("min_iou = {} must be in [0, 1]", self.min_iou);
        }
        if !(self.min_mass.is_finite() && self.min_mass >= 0.0) {
            bail!("min_mass = {} must be finite and ≥ 0", self.min_mass);
        }
        if self.max_misses > MAX_COAST_FRAMES {
            bail!(
                "max_misses = {} is over {MAX_COAST_FRAMES}: a track coasts at most that many \
                 frames, so that a gap in the frame numbers costs a bounded number of boxes",
                self.max_misses
            );
        }
        Ok(())
    }
}

impl OfflineConfig {
    /// Checks that the chain runs at all.
    pub fn check(&self) -> Result<()> {
        if self.min_samples == 0 && self.samples_per_detection == 0 {
            bail!("min_samples = samples_per_detection = 0: the chain would never move");
        }
        // At most 100 × d̄ (d̄ ≤ 64 frames): a link's bridged frames are output boxes, so the
        // factor bounds what one gap in the frame numbers can cost.
        if !(self.link_gap_factor.is_finite() && (0.0..=100.0).contains(&self.link_gap_factor)) {
            bail!(
                "link_gap_factor = {}; it must be in [0, 100]",
                self.link_gap_factor
            );
        }
        Ok(())
    }

    fn samples(&self, n_detections: usize) -> u64 {
        (self
            .samples_per_detection
            .saturating_mul(n_detections as u64))
        .max(self.min_samples)
    }
}

impl BoxConfig {
    /// Checks the kernel width (finite, > 0) and bounds the frames output without a detection
    /// (as `[phd_labels] max_misses`: each is a box per track, so an unbounded value would let
    /// a configuration ask for billions of boxes).
    pub fn check(&self) -> Result<()> {
        if !(self.smoothing_frames.is_finite() && self.smoothing_frames > 0.0) {
            bail!(
                "smoothing_frames = {}; it must be finite and > 0",
                self.smoothing_frames
            );
        }
        for (name, frames) in [
            ("extrapolate_frames", self.extrapolate_frames),
            ("online_coast_frames", self.online_coast_frames),
        ] {
            if frames > MAX_COAST_FRAMES {
                bail!(
                    "{name} = {frames} is over {MAX_COAST_FRAMES}: each frame is one output box \
                     per track"
                );
            }
        }
        Ok(())
    }
}

/// Detections by frame.
type ByFrame = std::collections::BTreeMap<Frame, Vec<MotRow>>;

/// Detections in measurement-id order, by frame (file order within a frame; MCMCDA's
/// measurement ids follow this order), and the problem of their centres, with each
/// detection's score ratio when `scores` is given.
fn problem_of(
    model: &mcmcda::Model,
    rows: &[MotRow],
    scores: Option<&ScoreModel>,
) -> Result<(Vec<MotRow>, ByFrame, Problem)> {
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<MotRow>> = Default::default();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(*r);
    }
    let detections: Vec<MotRow> = by_frame.values().flatten().copied().collect();
    let first = by_frame.keys().next().copied().unwrap_or(0);
    let mut problem = Problem::empty(model, first);
    for (frame, dets) in &by_frame {
        problem.push_scan_scored(*frame, &centres(dets), &score_ratios(scores, dets))?;
    }
    Ok((detections, by_frame, problem))
}

/// ln f₁(s)/f₀(s) of each detection's score (all 0 without a score model).
fn score_ratios(scores: Option<&ScoreModel>, dets: &[MotRow]) -> Vec<f64> {
    dets.iter()
        .map(|d| scores.map_or(0.0, |m| m.log_ratio(d.confidence)))
        .collect()
}

fn centres(dets: &[MotRow]) -> Vec<Vec2> {
    dets.iter().map(|d| d.bbox.centre()).collect()
}

/// The model fitted to the detections: starting from `base`, GNN tracks the file and its
/// confident tracks (at least `min_track_detections` detections) give moment estimates, which
/// become the next round's model:
/// - p_d = detections / frames spanned, over the confident tracks;
/// - clutter per frame = detections in no track of three or more / frames of the file;
/// - births per frame = confident tracks / frames, p_z = confident tracks / frames they span;
/// - R and q per axis from the second differences of consecutive detections: with the
///   discrete white-noise-acceleration model (Q = q G Gᵀ), Var(z₊₁ − 2z + z₋₁) = 6R + q/2 and
///   Var(z₊₂ − 2z + z₋₂) = 6R + 5q, solved for R and q;
/// - the newborn velocity variance from the central differences (minus their R/2);
/// - v̄ at least 1.5 times the 99th percentile of the speeds between detections.
///
/// Estimates are clamped to sane ranges, and a round without confident tracks keeps the
/// model it had. `[model]` keys of `--config` override the result.
pub fn fit_model(base: &McmcdaConfig, rows: &[MotRow], fit: &FitConfig) -> Result<McmcdaConfig> {
    let mut config = base.clone();
    for _ in 0..fit.iterations {
        let model = config.check()?;
        let (detections, by_frame, problem) = problem_of(&model, rows, None)?;
        let (Some(first), Some(last)) = (
            by_frame.keys().next().copied(),
            by_frame.keys().next_back().copied(),
        ) else {
            break;
        };
        let n_frames = f64::from(last - first) + 1.0;
        let gnn = NearestNeighbourConfig::default();
        let tracks = nearest_neighbour_tracks(&model, &problem, problem.all_scans()?, &gnn)?;
        let confident: Vec<&Vec<MeasId>> = tracks
            .iter()
            .filter(|t| t.len() >= fit.min_track_detections)
            .collect();
        if confident.is_empty() {
            break;
        }
        let size = |m: MeasId| {
            let b = detections[m as usize].bbox;
            [b.width, b.height]
        };
        let (mut n_det, mut n_span) = (0.0, 0.0);
        // Sums of squares per axis, in box widths (x) and heights (y): lag-1 second
        // differences, lag-2, central velocities.
        let (mut v1, mut v2, mut vel) = ([0.0f64; 2], [0.0f64; 2], [0.0f64; 2]);
        let (mut n1, mut n2) = (0.0f64, 0.0f64);
        let (mut speeds, mut widths, mut heights) = (Vec::new(), Vec::new(), Vec::new());
        for t in &confident {
            n_det += t.len() as f64;
            let scans: Vec<usize> = t.iter().map(|&m| problem.scan_of(m)).collect();
            n_span += (scans[scans.len() - 1] - scans[0] + 1) as f64;
            // Ordered, so that the sums (and the fitted model) do not depend on hashing.
            let at: std::collections::BTreeMap<usize, MeasId> =
                t.iter().map(|&m| (problem.scan_of(m), m)).collect();
            for pair in t.windows(2) {
                let gap = (problem.scan_of(pair[1]) - problem.scan_of(pair[0])) as f64;
                let d = (problem.position(pair[1]) - problem.position(pair[0])).norm() / gap;
                speeds.push(d / size(pair[1])[0]);
            }
            for (&s, &m) in &at {
                let z = problem.position(m);
                let wh = size(m);
                widths.push(wh[0]);
                heights.push(wh[1]);
                if let (Some(&a), Some(&b)) = (at.get(&(s.wrapping_sub(1))), at.get(&(s + 1))) {
                    let (a, b) = (problem.position(a), problem.position(b));
                    let d = b - 2.0 * z + a;
                    let v = (b - a) / 2.0;
                    for k in 0..2 {
                        v1[k] += (d[k] / wh[k]).powi(2);
                        vel[k] += (v[k] / wh[k]).powi(2);
                    }
                    n1 += 1.0;
                }
                if let (Some(&a), Some(&b)) = (at.get(&(s.wrapping_sub(2))), at.get(&(s + 2))) {
                    let d = problem.position(b) - 2.0 * z + problem.position(a);
                    for k in 0..2 {
                        v2[k] += (d[k] / wh[k]).powi(2);
                    }
                    n2 += 1.0;
                }
            }
        }
        let assigned: usize = tracks.iter().filter(|t| t.len() >= 3).map(Vec::len).sum();
        let clutter = (rows.len() as f64 - assigned as f64).max(0.0) / n_frames;
        config.p_detect = (n_det / n_span).clamp(0.3, 0.99);
        config.clutter_per_scan = clutter.clamp(0.01, 1e3);
        config.births_per_scan = (confident.len() as f64 / n_frames).clamp(1e-3, 1e2);
        config.p_disappear = (confident.len() as f64 / n_span).clamp(1e-4, 0.5);
        // The noise grows with the box: the relative moments are turned into pixels at a
        // large box (the 90th percentile of widths and heights), so that gates hold for the
        // nearest people.
        let percentile = |v: &mut Vec<f64>, p: usize| {
            v.sort_by(f64::total_cmp);
            v.get(v.len() * p / 100).copied()
        };
        let (Some(w90), Some(h90), Some(w50)) = (
            percentile(&mut widths, 90),
            percentile(&mut heights, 90),
            percentile(&mut widths.clone(), 50),
        ) else {
            break;
        };
        let scale = [w90 * w90, h90 * h90];
        if n1 >= 10.0 && n2 >= 10.0 {
            let (mut r, mut q) = ([0.0; 2], [0.0; 2]);
            for k in 0..2 {
                let (a, b) = (v1[k] / n1, v2[k] / n2);
                q[k] = ((b - a) / 4.5).max(1e-3 * a.max(1e-9));
                r[k] = ((a - 0.5 * q[k]) / 6.0).max(1e-2 * a.max(1e-9));
            }
            let q_px = (q[0] * scale[0] + q[1] * scale[1]) / 2.0 * NOISE_INFLATION;
            config.motion = ConstantVelocity2::mcmcda(config.motion.dt_s(), q_px)?;
            config.measurement_noise = nalgebra::Matrix2::new(
                r[0] * scale[0] * NOISE_INFLATION,
                0.0,
                0.0,
                r[1] * scale[1] * NOISE_INFLATION,
            );
            let vv = (0..2)
                .map(|k| (vel[k] / n1 - r[k] / 2.0).max(r[k]) * scale[k])
                .fold(0.0, f64::max);
            if let TrackInit::FirstMeasurement { .. } = config.track_init {
                config.track_init = TrackInit::FirstMeasurement {
                    velocity_variance: Some(vv),
                };
            }
        }
        if let Some(p99) = percentile(&mut speeds.clone(), 99) {
            config.max_speed = config.max_speed.max(1.5 * p99 * w90);
        }
        // A track may bridge the frames in which its target moves about `GAP_BOX_WIDTHS` box
        // widths (an occlusion by a passer-by lasts about that long).
        if let Some(p50) = percentile(&mut speeds, 50) {
            let frames = (GAP_BOX_WIDTHS / p50.max(1e-3)).round().clamp(3.0, 30.0);
            config.max_gap = frames as u32;
        }
        let _ = w50;
    }
    Ok(config)
}

/// How much the fitted R and q are widened over the moment estimates: the detections' errors
/// are heavier-tailed than Gaussian (turns, stops, boxes cut at the border), and a gate sized
/// to the mean square splits tracks. Chosen on the tuning sequences of `mot-realistic`.
const NOISE_INFLATION: f64 = 2.0;

/// MCMCDA's d̄ is the frames in which a walker moves this many box widths: occlusions by a
/// passer-by last about that long, and MCMCDA, which weighs every association against the
/// whole window, bridges them (1 and 1.5 fragmented tracks, 2.5 gained nothing on the tuning
/// sequences of `mot-realistic`). GNN, which commits scan by scan, deletes a track after half
/// of it (one box width) unless `[gnn] max_gap` is set.
const GAP_BOX_WIDTHS: f64 = 2.0;

/// The score densities of the file (the amplitude-feature likelihood of Lerro & Bar-Shalom
/// 1993, IEEE AES 29(2), with the detector's confidence as the feature): GNN (`gnn`) tracks
/// the file with `model` (kinematics only); f₁ is the density of the scores of detections in its
/// confident tracks (≥ `min_track_detections`), f₀ of those in no track of three or more
/// (clutter, with some missed true detections in it, which only makes the ratio milder). Each
/// is a Gaussian kernel density (Silverman's bandwidth, 0.9 min(sd, IQR/1.34) n^(−1/5)) with
/// one pseudo-observation spread uniformly over the file's score range, so that a score where
/// one sample is thin does not give an extreme ratio; ln f₁/f₀ is tabulated on 64 points and
/// clamped to ±`max_log_ratio`. None when scores are off, do not vary over the file, or
/// either sample has fewer than 10 scores.
pub fn fit_scores(
    model: &McmcdaConfig,
    rows: &[MotRow],
    fit: &FitConfig,
    gnn: &NearestNeighbourConfig,
    config: &ScoreConfig,
) -> Result<Option<ScoreModel>> {
    if !config.enabled || rows.is_empty() {
        return Ok(None);
    }
    let (lo, hi) = rows
        .iter()
        .map(|r| r.confidence)
        .filter(|s| s.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
            (a.min(s), b.max(s))
        });
    // Also false for NaN bounds (no finite score at all) and for a span beyond f64 (scores
    // near ±1.8e308: the grid's step would be infinite and every density NaN).
    let varies = (hi - lo).is_finite() && hi - lo > 1e-9 * hi.abs().max(1.0);
    if !varies {
        return Ok(None);
    }
    let checked = model.check()?;
    let (detections, _, problem) = problem_of(&checked, rows, None)?;
    let window = problem.all_scans()?;
    let tracks = nearest_neighbour_tracks(&checked, &problem, window, gnn)?;
    let mut in_track = vec![0usize; detections.len()];
    for t in &tracks {
        for &m in t {
            in_track[m as usize] = t.len();
        }
    }
    let sample = |keep: &dyn Fn(usize) -> bool| -> Vec<f64> {
        detections
            .iter()
            .zip(&in_track)
            .filter(|(d, n)| keep(**n) && d.confidence.is_finite())
            .map(|(d, _)| d.confidence)
            .collect()
    };
    let min_len = fit.min_track_detections;
    let track = sample(&|n| n >= min_len);
    let clutter = sample(&|n| n < 3);
    if track.len() < 10 || clutter.len() < 10 {
        return Ok(None);
    }
    let step = (hi - lo) / (SCORE_GRID - 1) as f64;
    let grid: Vec<f64> = (0..SCORE_GRID).map(|i| lo + step * i as f64).collect();
    // Size, mean and sample standard deviation.
    let moments = |v: &[f64]| {
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        (v.len(), mean, sd)
    };
    let density = |v: &[f64]| -> Vec<f64> {
        let (_, _, sd) = moments(v);
        let n = v.len() as f64;
        let mut sorted = v.to_vec();
        sorted.sort_by(f64::total_cmp);
        let iqr = sorted[sorted.len() * 3 / 4] - sorted[sorted.len() / 4];
        let spread = if iqr > 0.0 { sd.min(iqr / 1.34) } else { sd };
        // Never narrower than the grid's step (a constant sample would be a spike).
        let h = (0.9 * spread * n.powf(-0.2)).max(step);
        grid.iter()
            .map(|&x| {
                let kde = v
                    .iter()
                    .map(|s| (-0.5 * ((x - s) / h).powi(2)).exp())
                    .sum::<f64>()
                    / (n * h * (2.0 * std::f64::consts::PI).sqrt());
                (n * kde + 1.0 / (hi - lo)) / (n + 1.0)
            })
            .collect()
    };
    let (f1, f0) = (density(&track), density(&clutter));
    let bound = config.max_log_ratio;
    let log_ratio = f1
        .iter()
        .zip(&f0)
        .map(|(a, b)| (a.ln() - b.ln()).clamp(-bound, bound))
        .collect();
    Ok(Some(ScoreModel {
        lo,
        hi,
        log_ratio,
        track: moments(&track),
        clutter: moments(&clutter),
    }))
}

/// MCMCDA (offline or online) or GNN on the box centres; boxes from [`smooth_boxes`].
fn track_points(
    tracker: Tracker,
    rows: &[MotRow],
    settings: &EffectiveConfig,
    seed: u64,
) -> Result<TrackSet> {
    let model = settings.model.check()?;
    let (detections, by_frame, problem) = problem_of(&model, rows, settings.score_model.as_ref())?;
    let associations: Vec<Vec<MeasId>> = match tracker {
        Tracker::McmcdaOnline => return track_online(&model, &by_frame, settings, seed),
        Tracker::Mcmcda => {
            // The chain starts from GNN's tracks (feasible in Ω by construction), so the MAP
            // is at least as probable as GNN's answer under the fitted model.
            let window = problem.all_scans()?;
            let start = nearest_neighbour_tracks(&model, &problem, window.clone(), &settings.gnn)?;
            let start = Partition::from_tracks(&model, &problem, window, &start)?;
            let map = run_chains(&start, 1, settings.offline.samples(detections.len()), seed)?;
            let max_gap = (settings.offline.link_gap_factor * f64::from(model.config().max_gap))
                .round() as u32;
            link_tracklets(map.tracks, &detections, model.config(), max_gap)
        }
        Tracker::Gnn | Tracker::Phd => {
            let window = problem.all_scans()?;
            nearest_neighbour_tracks(&model, &problem, window, &settings.gnn)?
        }
        Tracker::GnnOnline => {
            let window = problem.all_scans()?;
            let tracks = nearest_neighbour_tracks(&model, &problem, window, &settings.gnn)?;
            let last = by_frame.keys().next_back().copied().unwrap_or(0);
            let coast = settings
                .gnn
                .max_gap
                .unwrap_or(model.config().max_gap)
                .min(settings.boxes.online_coast_frames);
            return gnn_online_output(&detections, &tracks, &settings.boxes, coast, last);
        }
    };
    let mut tracks = Vec::with_capacity(associations.len());
    for (i, meas) in associations.iter().enumerate() {
        let dets = detection_boxes(&detections, meas);
        let points = smooth_boxes(&dets, &settings.boxes, None)?;
        if !points.is_empty() {
            tracks.push(Track::from_points(TrackId(i as u64 + 1), points)?);
        }
    }
    Ok(TrackSet::from_tracks(tracks)?)
}

/// Min-cost tracklet linking after offline MCMCDA (the hierarchical association of Huang,
/// Wu & Nevatia 2008, ECCV, with its motion affinity alone): a track A that ends at frame ℓ
/// may be continued by a track B that starts at s, ℓ < s ≤ ℓ + `max_gap`, when each end's
/// constant-velocity prediction over the gap g = s − ℓ reaches the other's end: with A's
/// last centre c_A and velocity v_A (least squares over its last 8 detections) and B's first
/// c_B, v_B, the squared Mahalanobis distances of c_A + g v_A − c_B and c_B − g v_B − c_A
/// under the fitted model's spread over the gap (per axis 2R + q g³/3) must both pass the
/// 99 % χ² gate, and the heights must agree within 30 %. A one-to-one assignment of ends to
/// starts minimises the sum of the two distances. This bridges occlusions longer than the
/// posterior's d̄ (whose (1 − p_d)^g term treats the misses of an occlusion as independent).
fn link_tracklets(
    tracks: Vec<Vec<MeasId>>,
    detections: &[MotRow],
    model: &McmcdaConfig,
    max_gap: u32,
) -> Vec<Vec<MeasId>> {
    if max_gap == 0 || tracks.len() < 2 {
        return tracks;
    }
    const GATE: f64 = 9.21;
    let r = [
        model.measurement_noise[(0, 0)],
        model.measurement_noise[(1, 1)],
    ];
    let q = match model.motion.noise() {
        tracker_model::CvNoise::Discrete {
            acceleration_covariance,
        } => acceleration_covariance[(0, 0)],
        tracker_model::CvNoise::WhiteAcceleration { q } => q,
    };
    // Centre and velocity at one end of a track (its first or last 8 detections).
    let end_state = |meas: &[MeasId], at_end: bool| -> (Frame, Vec2, Vec2, f64) {
        let k = meas.len().min(8);
        let part = if at_end {
            &meas[meas.len() - k..]
        } else {
            &meas[..k]
        };
        let pts: Vec<(f64, Vec2)> = part
            .iter()
            .map(|&m| {
                let d = &detections[m as usize];
                (f64::from(d.frame), d.bbox.centre())
            })
            .collect();
        let n = pts.len() as f64;
        let tm = pts.iter().map(|p| p.0).sum::<f64>() / n;
        let cm = pts.iter().fold(Vec2::zeros(), |a, p| a + p.1) / n;
        let stt = pts.iter().map(|p| (p.0 - tm).powi(2)).sum::<f64>();
        let v = if stt > 0.0 {
            pts.iter()
                .fold(Vec2::zeros(), |a, p| a + (p.1 - cm) * (p.0 - tm))
                / stt
        } else {
            Vec2::zeros()
        };
        let m = if at_end {
            meas[meas.len() - 1]
        } else {
            meas[0]
        };
        let d = &detections[m as usize];
        // The fitted line's value at the end frame.
        let c = cm + v * (f64::from(d.frame) - tm);
        (d.frame, c, v, d.bbox.height)
    };
    let ends: Vec<_> = tracks.iter().map(|t| end_state(t, true)).collect();
    let starts: Vec<_> = tracks.iter().map(|t| end_state(t, false)).collect();
    let n = tracks.len();
    let mut pairs = Vec::new();
    for (a, &(la, ca, va, ha)) in ends.iter().enumerate() {
        for (b, &(sb, cb, vb, hb)) in starts.iter().enumerate() {
            if a == b || sb <= la || sb - la > max_gap || (hb / ha).ln().abs() > 0.3_f64.ln_1p() {
                continue;
            }
            let g = f64::from(sb - la);
            let var = [0, 1].map(|k| 2.0 * r[k] + q * g.powi(3) / 3.0);
            let d2 = |e: Vec2| e.x * e.x / var[0] + e.y * e.y / var[1];
            let (df, db) = (d2(ca + va * g - cb), d2(cb - vb * g - ca));
            if df <= GATE && db <= GATE {
                pairs.push((a, b, df + db));
            }
        }
    }
    if pairs.is_empty() {
        return tracks;
    }
    // Rows: ends; columns: starts, then one "no link" column per end at the gate's cost.
    let n_cols = 2 * n;
    let forbidden = 1e6;
    let mut costs = vec![forbidden; n * n_cols];
    for &(a, b, c) in &pairs {
        costs[a * n_cols + b] = c;
    }
    for a in 0..n {
        costs[a * n_cols + n + a] = 2.0 * GATE;
    }
    let Ok(chosen) = tracker_model::assignment::minimise(n, n_cols, &costs) else {
        return tracks;
    };
    let mut next: Vec<Option<usize>> = vec![None; n];
    let mut has_prev = vec![false; n];
    for (a, b) in chosen {
        if b < n && costs[a * n_cols + b] < forbidden {
            next[a] = Some(b);
            has_prev[b] = true;
        }
    }
    let mut out = Vec::with_capacity(n);
    for start in (0..n).filter(|&i| !has_prev[i]) {
        let mut chain = Vec::new();
        let mut at = Some(start);
        // Links go forward in time, so a chain cannot cycle; n bounds it anyway.
        for _ in 0..n {
            let Some(i) = at else { break };
            chain.extend_from_slice(&tracks[i]);
            at = next[i];
        }
        out.push(chain);
    }
    out
}

/// GNN's tracks output as a frame-by-frame tracker would have output them. GNN's
/// associations are causal (scan by scan), so at every frame f from a track's first detection
/// on the output is what was known at f: with a detection at f, the box fitted to the track's
/// detections up to f ([`smooth_boxes`] with `until`); without one, the box fitted at its last
/// detection ℓ moved on at the velocity of the fitted boxes between its last two detections,
/// for at most `coast` frames after ℓ (`[boxes] online_coast_frames`, at most GNN's deletion
/// gap, after which GNN deletes the track) and not beyond the
/// file's last frame `end`. The first box of a track is its first detection (a track holds its
/// initiating detections, as the peer's trackers do): causal up to confirmation, since whether
/// a track is output at all is decided by its M-of-N confirmation, which may come after f.
fn gnn_online_output(
    detections: &[MotRow],
    tracks: &[Vec<MeasId>],
    boxes: &BoxConfig,
    coast: u32,
    end: Frame,
) -> Result<TrackSet> {
    let mut out = Vec::with_capacity(tracks.len());
    for (i, meas) in tracks.iter().enumerate() {
        let dets = detection_boxes(detections, meas);
        // The causal fit at each detection's frame, from the detections within the kernel's
        // reach before it (all the fit reads: the track's detection at f is the slice's last),
        // so a track costs O(length · reach), not O(length²).
        let reach = kernel_reach(boxes.smoothing_frames);
        let mut fitted: Vec<(Frame, BoundingBox)> = Vec::with_capacity(dets.len());
        let mut start = 0;
        for (k, &(f, _)) in dets.iter().enumerate() {
            while i64::from(dets[start].0) < i64::from(f).saturating_sub(reach) {
                start += 1;
            }
            if let Some(tracker_model::Location::Box(b)) =
                smooth_boxes(&dets[start..=k], boxes, Some(f))?
                    .last()
                    .map(|p| p.location)
            {
                fitted.push((f, b));
            }
        }
        let mut points = Vec::new();
        for (k, &(f, b)) in fitted.iter().enumerate() {
            points.push(TrackPoint::boxed(f, b));
            let velocity = match k.checked_sub(1).map(|j| fitted[j]) {
                Some((g, a)) => (b.centre() - a.centre()) / f64::from(f - g),
                None => Vec2::zeros(),
            };
            let next = fitted.get(k + 1).map_or(Frame::MAX, |n| n.0);
            let until = u64::from(f) + u64::from(coast);
            let stop = until
                .min(u64::from(end))
                .min(u64::from(next).saturating_sub(1));
            for g in u64::from(f) + 1..=stop {
                let dt = (g - u64::from(f)) as f64;
                let c = b.centre() + velocity * dt;
                // g ≤ end, a Frame.
                let frame = Frame::try_from(g).context("a coasted frame beyond u32")?;
                points.push(TrackPoint::boxed(
                    frame,
                    BoundingBox::from_centre(c, b.width, b.height)?,
                ));
            }
        }
        if !points.is_empty() {
            out.push(Track::from_points(TrackId(i as u64 + 1), points)?);
        }
    }
    Ok(TrackSet::from_tracks(out)?)
}

/// Online MCMCDA, output frame by frame: after each frame, every track the window's MAP
/// reports at that frame (its last detection at most `coast_scans` frames old) gets a box fitted
/// to its detections up to that frame only; a coasting track keeps the size of that fit and
/// moves with the tracker's prediction.
fn track_online(
    model: &mcmcda::Model,
    by_frame: &std::collections::BTreeMap<Frame, Vec<MotRow>>,
    settings: &EffectiveConfig,
    seed: u64,
) -> Result<TrackSet> {
    let first = by_frame.keys().next().copied().unwrap_or(0);
    let mut online = OnlineTracker::new(model.clone(), first, settings.online, seed)?;
    let mut detections: Vec<MotRow> = Vec::new();
    let mut out: std::collections::BTreeMap<u64, Vec<TrackPoint>> = Default::default();
    for (&frame, dets) in by_frame {
        detections.extend_from_slice(dets);
        let step = online.push_scan_scored(
            frame,
            &centres(dets),
            &score_ratios(settings.score_model.as_ref(), dets),
        )?;
        let map: std::collections::HashMap<u64, &Vec<MeasId>> =
            online.map_tracks().iter().map(|(l, t)| (*l, t)).collect();
        for (label, position) in &step.estimates {
            let Some(meas) = map.get(label) else {
                continue;
            };
            let dets: Vec<(Frame, BoundingBox)> = meas
                .iter()
                .map(|&m| {
                    let d = &detections[m as usize];
                    (d.frame, d.bbox)
                })
                .collect();
            let Some(&(last_frame, _)) = dets.last() else {
                continue;
            };
            let fitted = smooth_boxes(&dets, &settings.boxes, Some(last_frame))?;
            let Some(tracker_model::Location::Box(at_last)) = fitted.last().map(|p| p.location)
            else {
                continue;
            };
            let bbox = if last_frame == frame {
                at_last
            } else {
                BoundingBox::from_centre(*position, at_last.width, at_last.height)?
            };
            out.entry(*label)
                .or_default()
                .push(TrackPoint::boxed(frame, bbox));
        }
    }
    let tracks = out
        .into_iter()
        .map(|(label, points)| Track::from_points(TrackId(label + 1), points))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    Ok(TrackSet::from_tracks(tracks)?)
}

/// A track's (frame, box) pairs from its measurement ids (indices into `detections`, which
/// `problem_of` orders by id).
fn detection_boxes(detections: &[MotRow], meas: &[MeasId]) -> Vec<(Frame, BoundingBox)> {
    meas.iter()
        .map(|&m| {
            let d = &detections[m as usize];
            (d.frame, d.bbox)
        })
        .collect()
}

/// Frames on either side whose detections the box kernel of width σ reads: 3σ, rounded up
/// (saturating, so a huge σ reads the whole track instead of overflowing).
fn kernel_reach(sigma: f64) -> i64 {
    (3.0 * sigma).ceil() as i64
}

/// Boxes of a track from its detections `dets` (frame, box; frames strictly increasing): at
/// every frame from the first detection to the last (or to `until`, when given: the fit then
/// uses only the detections up to it and outputs that one frame), each edge is a local-linear
/// fit with Gaussian kernel weights of σ = `smoothing_frames` over the detections within 3σ;
/// where fewer than two distinct frames are in reach, the edges are interpolated linearly
/// between the nearest detections. `extrapolate_frames` frames are added at both ends.
pub fn smooth_boxes(
    dets: &[(Frame, BoundingBox)],
    config: &BoxConfig,
    until: Option<Frame>,
) -> Result<Vec<TrackPoint>> {
    let dets: Vec<(Frame, BoundingBox)> = match until {
        Some(u) => dets.iter().copied().filter(|d| d.0 <= u).collect(),
        None => dets.to_vec(),
    };
    let (Some(&(f0, _)), Some(&(f1, _))) = (dets.first(), dets.last()) else {
        return Ok(Vec::new());
    };
    let sigma = config.smoothing_frames;
    let reach = kernel_reach(sigma);
    let e = i64::from(config.extrapolate_frames);
    let frames: Vec<i64> = match until {
        Some(u) => vec![i64::from(u)],
        None => {
            ((i64::from(f0) - e).max(0)..=(i64::from(f1) + e).min(i64::from(Frame::MAX))).collect()
        }
    };
    let edges = |b: &BoundingBox| [b.left, b.top, b.right(), b.bottom()];
    let mut out = Vec::with_capacity(frames.len());
    let mut lo = 0usize;
    for f in frames {
        while lo < dets.len() && i64::from(dets[lo].0) < f.saturating_sub(reach) {
            lo += 1;
        }
        // Weighted sums for the local-linear fit of each edge: Σw, Σw·x, Σw·x², Σw·y, Σw·x·y.
        let (mut sw, mut sx, mut sxx) = (0.0, 0.0, 0.0);
        let (mut sy, mut sxy) = ([0.0f64; 4], [0.0f64; 4]);
        let mut n = 0usize;
        for &(g, b) in dets[lo..]
            .iter()
            .take_while(|d| i64::from(d.0) <= f.saturating_add(reach))
        {
            let x = (i64::from(g) - f) as f64;
            let w = (-0.5 * (x / sigma).powi(2)).exp();
            let y = edges(&b);
            sw += w;
            sx += w * x;
            sxx += w * x * x;
            for k in 0..4 {
                sy[k] += w * y[k];
                sxy[k] += w * x * y[k];
            }
            n += 1;
        }
        let det = sw * sxx - sx * sx;
        let e4: [f64; 4] = if n >= 2 && det > 1e-9 * sw * sw {
            // The fit's value at x = 0.
            std::array::from_fn(|k| (sxx * sy[k] - sx * sxy[k]) / det)
        } else {
            // Linear interpolation between the nearest detections (constant beyond the ends).
            let after = dets.partition_point(|d| i64::from(d.0) < f);
            let (a, b) = match (after.checked_sub(1).map(|i| dets[i]), dets.get(after)) {
                (Some(a), Some(b)) => (a, *b),
                (Some(a), None) => (a, a),
                (None, Some(b)) => (*b, *b),
                (None, None) => continue,
            };
            let (ya, yb) = (edges(&a.1), edges(&b.1));
            let span = f64::from(b.0) - f64::from(a.0);
            let t = if span > 0.0 {
                ((f - i64::from(a.0)) as f64 / span).clamp(0.0, 1.0)
            } else {
                0.0
            };
            std::array::from_fn(|k| ya[k] + t * (yb[k] - ya[k]))
        };
        let (w, h) = ((e4[2] - e4[0]).max(1.0), (e4[3] - e4[1]).max(1.0));
        // f is within [0, Frame::MAX] by construction.
        let frame = Frame::try_from(f).context("an output frame beyond u32")?;
        out.push(TrackPoint::boxed(
            frame,
            BoundingBox::new(e4[0], e4[1], w, h)?,
        ));
    }
    Ok(out)
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

    /// The walkers' detections (the fixture `cargo xtask track` is demonstrated on).
    fn walkers() -> Vec<MotRow> {
        crate::mot::parse_detections(
            include_str!("../../../fixtures/mot/walkers-dets.txt"),
            "walkers-dets.txt",
        )
        .unwrap()
    }

    fn config(text: &str) -> TrackConfig {
        toml::from_str(text).unwrap()
    }

    fn error_of(text: &str, tracker: Tracker) -> String {
        let rows = rows_with_a_jump();
        format!(
            "{:#}",
            track_detections(tracker, &rows[..4], &config(text), 1).unwrap_err()
        )
    }

    #[test]
    fn printed_configs_load_back_unchanged() {
        for rows in [walkers(), Vec::new()] {
            let effective = TrackConfig::default().resolve(&rows).unwrap();
            for tracker in [
                None,
                Some(Tracker::Mcmcda),
                Some(Tracker::Gnn),
                Some(Tracker::Phd),
            ] {
                let text = render_config(&effective, tracker).unwrap();
                let back = config(&text).resolve(&rows).unwrap();
                // What the printed tables hold comes back exactly; the tables left out are the
                // (identical) defaults.
                assert_eq!(back, effective, "{tracker:?}:\n{text}");
                assert_eq!(render_config(&back, tracker).unwrap(), text);
                // Every key is there with a comment above it.
                let n_keys = text
                    .lines()
                    .filter(|l| !l.starts_with('#') && l.contains(" = "))
                    .count();
                let n_unset = text.lines().filter(|l| l.ends_with(" is unset")).count();
                let n_comments = text.lines().filter(|l| l.starts_with("# ")).count();
                assert_eq!(n_comments - 3, n_keys + 2 * n_unset, "{text}");
            }
            // Against a configuration that differs from the defaults (the loaded values, not
            // the base, must come back).
            let text = "[model]\nmeasurement_noise = [[9.0, 1.0], [1.0, 4.0]]\nmax_gap = 3\n\
                        [gnn]\nmax_gap = 2\n[phd]\nmotion = { constant_velocity = \
                        { acceleration_std = 0.5, size_std = 0.25 } }\n";
            let effective = config(text).resolve(&rows).unwrap();
            assert_eq!(
                effective.model.measurement_noise,
                nalgebra::Matrix2::new(9.0, 1.0, 1.0, 4.0)
            );
            let printed = render_config(&effective, None).unwrap();
            assert!(
                printed.contains("measurement_noise = [[9.0, 1.0], [1.0, 4.0]]"),
                "{printed}"
            );
            assert_eq!(config(&printed).resolve(&rows).unwrap(), effective);
        }
    }

    #[test]
    fn the_example_configs_load_and_differ_from_nothing_they_do_not_mention() {
        let rows = walkers();
        for (name, text) in [
            (
                "mcmcda",
                include_str!("../../../fixtures/configs/mcmcda.toml"),
            ),
            ("gnn", include_str!("../../../fixtures/configs/gnn.toml")),
            ("phd", include_str!("../../../fixtures/configs/phd.toml")),
        ] {
            let tracker: Tracker = name.parse().unwrap();
            let effective = config(text)
                .resolve(&rows)
                .unwrap_or_else(|e| panic!("{name}: {e:#}"));
            let tracks = track_detections(tracker, &rows, &config(text), 1).unwrap();
            assert!(!tracks.is_empty(), "{name}");
            assert!(empty_output_warning(tracker, &rows, &effective, &tracks).is_none());
        }
    }

    #[test]
    fn matrices_take_rows_and_the_old_flat_form() {
        let rows = walkers();
        let nested = config("[model]\nmeasurement_noise = [[16.0, 2.0], [2.0, 25.0]]\n");
        let flat = config("[model]\nmeasurement_noise = [16.0, 2.0, 2.0, 25.0]\n");
        let a = nested.resolve(&rows).unwrap();
        assert_eq!(a, flat.resolve(&rows).unwrap());
        assert_eq!(
            a.model.measurement_noise,
            nalgebra::Matrix2::new(16.0, 2.0, 2.0, 25.0)
        );
        let err = format!(
            "{:#}",
            config("[model]\nmeasurement_noise = [[16.0], [2.0, 25.0]]\n")
                .resolve(&rows)
                .unwrap_err()
        );
        assert!(err.contains("2×2") && err.contains("[model]"), "{err}");
    }

    #[test]
    fn every_table_is_checked_whichever_tracker_runs() {
        // A bad [phd] table with MCMCDA, a bad [model] or [online] with PHD.
        let err = error_of("[phd]\np_detect = 2.0\n", Tracker::Mcmcda);
        assert!(err.contains("[phd]") && err.contains("p_detect"), "{err}");
        let err = error_of("[model]\nmax_speed = -1.0\n", Tracker::Phd);
        assert!(
            err.contains("[model]") && err.contains("max_speed"),
            "{err}"
        );
        let err = error_of("[gnn]\nconfirm_hits = 0\n", Tracker::Mcmcda);
        assert!(
            err.contains("[gnn]") && err.contains("confirm_hits"),
            "{err}"
        );
    }

    #[test]
    fn zero_samples_are_an_error() {
        for tracker in Tracker::ALL {
            let err = error_of("[online]\nsamples_per_scan = 0\n", tracker);
            assert!(err.contains("samples_per_scan = 0"), "{err}");
        }
    }

    #[test]
    fn no_track_from_detections_says_why() {
        // Three detections 100 frames apart: more than max_gap, so no track can form.
        let rows: Vec<MotRow> = [1, 101, 201]
            .map(|f| MotRow {
                frame: f,
                id: -1,
                bbox: BoundingBox::new(10.0, 10.0, 40.0, 90.0).unwrap(),
                confidence: 1.0,
                world: [-1.0; 3],
            })
            .to_vec();
        let effective = TrackConfig::default().resolve(&rows).unwrap();
        for tracker in [Tracker::Mcmcda, Tracker::Gnn] {
            let tracks = track_detections(tracker, &rows, &TrackConfig::default(), 1).unwrap();
            assert!(tracks.is_empty(), "{tracker}");
            let warning = empty_output_warning(tracker, &rows, &effective, &tracks).unwrap();
            assert!(
                warning.contains("no track in 3 detections over 3 frames")
                    && warning.contains("max_gap = 5"),
                "{warning}"
            );
        }
        let warning =
            empty_output_warning(Tracker::Phd, &rows, &effective, &TrackSet::new()).unwrap();
        assert!(warning.contains("extraction_threshold = 0.5"), "{warning}");
    }

    fn det(frame: Frame, left: f64, top: f64, w: f64, h: f64) -> MotRow {
        MotRow {
            frame,
            id: -1,
            bbox: BoundingBox::new(left, top, w, h).unwrap(),
            confidence: 0.9,
            world: [-1.0; 3],
        }
    }

    #[test]
    fn one_row_at_frame_1_and_one_at_the_last_frame_cost_nothing() {
        // A tracker that stepped or stored the frames in between would not finish.
        let rows = vec![
            det(1, 10.0, 10.0, 40.0, 90.0),
            det(Frame::MAX - 1, 10.0, 10.0, 41.0, 92.0),
        ];
        for tracker in Tracker::ALL {
            let tracks = track_detections(tracker, &rows, &TrackConfig::default(), 1).unwrap();
            assert!(tracks.n_points() <= 2, "{tracker}: {}", tracks.n_points());
        }
    }

    /// A walker leaving the image on the right: its box is cut by the border and shrinks over
    /// the last frames; a second walker keeps the model's scale sensible. Deterministic jitter
    /// of ±1 px on the edges.
    fn leaving_walker() -> (Vec<MotRow>, Vec<(Frame, BoundingBox)>) {
        let mut rows = Vec::new();
        let mut truth = Vec::new();
        for f in 1..=32u32 {
            let x = 400.0 + 12.0 * f64::from(f);
            let right = (x + 80.0).min(800.0);
            let b = BoundingBox::new(x, 100.0, right - x, 120.0).unwrap();
            let j = if f % 2 == 0 { 1.0 } else { -1.0 };
            truth.push((f, b));
            rows.push(det(f, x + j, 100.0 - j, right - x - j, 120.0 + j));
            rows.push(det(
                f,
                100.0 + 2.0 * f64::from(f) - j,
                300.0,
                50.0 + j,
                120.0,
            ));
        }
        (rows, truth)
    }

    #[test]
    fn output_boxes_follow_the_detections_to_the_track_ends() {
        let (rows, truth) = leaving_walker();
        for tracker in [Tracker::Mcmcda, Tracker::Gnn] {
            let tracks = track_detections(tracker, &rows, &TrackConfig::default(), 1).unwrap();
            // The leaving walker's track: the one that reaches x > 600.
            let track = tracks
                .tracks()
                .iter()
                .find(|t| t.points().iter().any(|p| p.location.position().x > 600.0))
                .unwrap_or_else(|| panic!("{tracker}: no track of the leaving walker"));
            let points = track.points();
            // No box before the first or after the last detection.
            assert!(
                points.iter().all(|p| (1..=32).contains(&p.frame)),
                "{tracker}"
            );
            for p in points {
                let tracker_model::Location::Box(b) = p.location else {
                    panic!("{tracker}: a point without a box");
                };
                let t = truth[(p.frame - 1) as usize].1;
                // The last boxes shrink from 80 to 16 px by 12 px a frame: a box of the
                // track's mean size or one lagging a frame behind has IoU < 0.5 there; the
                // fitted box follows within the jitter (and a few pixels at the kink where the
                // border starts to cut).
                assert!(
                    b.iou(&t) >= 0.8,
                    "{tracker} frame {}: {b:?} vs {t:?}",
                    p.frame
                );
            }
            let last = points[points.len() - 1].frame;
            // The centre slows from 12 to 6 px a frame as the border cuts the box; with the
            // near-noiseless fit of this file both trackers leave the last four detections to
            // clutter (a known loss, docs/mot-realistic.md), but no more.
            assert!(last >= 28, "{tracker}: ends at {last}");
        }
    }

    #[test]
    fn phd_ids_persist_through_a_three_frame_miss() {
        let mut rows = Vec::new();
        for f in 1..=30u32 {
            let t = f64::from(f);
            if !(10..=12).contains(&f) {
                rows.push(det(f, 100.0 + 3.0 * t, 100.0, 40.0 + t % 3.0, 100.0));
            }
            rows.push(det(f, 500.0 - 2.0 * t, 250.0, 42.0, 104.0 - t % 2.0));
        }
        let tracks = track_detections(Tracker::Phd, &rows, &TrackConfig::default(), 3).unwrap();
        let a: Vec<&Track> = tracks
            .tracks()
            .iter()
            .filter(|t| t.points().iter().any(|p| p.location.position().x < 300.0))
            .collect();
        assert_eq!(a.len(), 1, "the first walker has {} ids", a.len());
        let frames: Vec<Frame> = a[0].points().iter().map(|p| p.frame).collect();
        // Output from the prediction through the miss, and the same id after it.
        for f in 9..=20 {
            assert!(frames.contains(&f), "frame {f} missing: {frames:?}");
        }
    }

    /// Two walkers scored 0.8-0.95 over 60 frames, one or two false boxes per frame scored
    /// 0.2-0.45 at scattered places, and an isolated pair of detections in frames 30 and 31
    /// (far from everything, 4 px apart) scored `pair_score`.
    fn scored_file(pair_score: f64) -> Vec<MotRow> {
        let mut rows = Vec::new();
        let mut lcg = 7u64;
        let mut next = || {
            lcg = lcg
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (lcg >> 11) as f64 / (1u64 << 53) as f64
        };
        for f in 1..=60u32 {
            let t = f64::from(f);
            for (k, (x, y)) in [(100.0 + 4.0 * t, 100.0), (900.0 - 3.0 * t, 500.0)]
                .into_iter()
                .enumerate()
            {
                let mut r = det(f, x, y, 40.0 + (t % 3.0), 100.0 + (t % 2.0));
                r.confidence = 0.8 + 0.15 * next();
                if !(f + k as u32).is_multiple_of(7) {
                    rows.push(r);
                }
            }
            for _ in 0..1 + (f % 2) {
                let mut r = det(f, 1000.0 * next(), 700.0 * next(), 40.0, 100.0);
                r.confidence = 0.2 + 0.25 * next();
                rows.push(r);
            }
            if f == 30 || f == 31 {
                let mut r = det(f, 1500.0 + 4.0 * (t - 30.0), 1200.0, 40.0, 100.0);
                r.confidence = pair_score;
                rows.push(r);
            }
        }
        rows
    }

    #[test]
    fn the_score_densities_are_fitted_from_tracks_and_clutter() {
        let rows = scored_file(0.9);
        let effective = TrackConfig::default().resolve(&rows).unwrap();
        let m = effective
            .score_model
            .as_ref()
            .expect("scores vary: a model");
        // Track scores 0.8-0.95 (mean ≈ 0.875), clutter 0.2-0.45 (mean ≈ 0.325): the ratio
        // favours a track at 0.9 and clutter at 0.3, within the bound 3.
        assert!(m.log_ratio(0.9) > 1.0 && m.log_ratio(0.3) < -1.0, "{m:?}");
        assert!(m.log_ratio(0.9) <= 3.0 && m.log_ratio(0.3) >= -3.0);
        let summary = m.summary();
        assert!(
            summary.contains("tracks 0.8") && summary.contains("clutter 0."),
            "{summary}"
        );
        // Off by configuration, or a constant column: no score model.
        let off = config("[scores]\nenabled = false\n")
            .resolve(&rows)
            .unwrap();
        assert!(off.score_model.is_none());
        let constant: Vec<MotRow> = rows
            .iter()
            .map(|r| MotRow {
                confidence: 1.0,
                ..*r
            })
            .collect();
        assert!(
            TrackConfig::default()
                .resolve(&constant)
                .unwrap()
                .score_model
                .is_none()
        );
        let err = error_of("[scores]\nmax_log_ratio = -1.0\n", Tracker::Gnn);
        assert!(
            err.contains("[scores]") && err.contains("max_log_ratio"),
            "{err}"
        );
    }

    #[test]
    fn a_high_score_isolated_pair_is_a_track_and_a_low_score_one_is_not() {
        let pair_track = |rows: &[MotRow], settings: &TrackConfig, tracker: Tracker| {
            track_detections(tracker, rows, settings, 1)
                .unwrap()
                .tracks()
                .iter()
                .any(|t| t.points().iter().any(|p| p.location.position().x > 1400.0))
        };
        // MCMCDA weighs both detections' scores against clutter (GNN's cost holds only the
        // second's: a pair 4 px apart links on its kinematics; the mcmcda crate's tests check
        // GNN's score-shifted boundary by hand).
        for tracker in [Tracker::Mcmcda, Tracker::McmcdaOnline] {
            let default = TrackConfig::default();
            assert!(
                pair_track(&scored_file(0.9), &default, tracker),
                "{tracker}"
            );
            assert!(
                !pair_track(&scored_file(0.3), &default, tracker),
                "{tracker}"
            );
            // Without scores the pair is a track whatever it is scored: the decision above is
            // the scores'.
            let off = config("[scores]\nenabled = false\n");
            assert!(pair_track(&scored_file(0.3), &off, tracker), "{tracker}");
        }
    }

    #[test]
    fn offline_mcmcda_links_a_walker_across_an_occlusion_longer_than_its_max_gap() {
        // Walker 1 at 4 px a frame (0.1 box widths: d̄ ≈ 2 / 0.1 = 20 frames), hidden in
        // frames 31-51 (a gap of 22 frames > d̄, ≤ 1.5 d̄); walker 2, visible throughout, and
        // walker 3, who appears at frame 52 far from where walker 1 would be.
        let mut rows = Vec::new();
        for f in 1..=90u32 {
            let t = f64::from(f);
            let j = if f % 2 == 0 { 0.5 } else { -0.5 };
            if !(31..=51).contains(&f) {
                rows.push(det(f, 100.0 + 4.0 * t + j, 100.0, 40.0, 100.0 + j));
            }
            rows.push(det(f, 900.0 - 4.0 * t - j, 400.0, 40.0 + j, 100.0));
            if f >= 52 {
                rows.push(det(f, 300.0 + 4.0 * t, 700.0 + j, 40.0, 100.0));
            }
        }
        let ids_of = |settings: &TrackConfig, y: f64| {
            let tracks = track_detections(Tracker::Mcmcda, &rows, settings, 1).unwrap();
            tracks
                .tracks()
                .iter()
                .filter(|t| {
                    t.points()
                        .iter()
                        .any(|p| (p.location.position().y - y).abs() < 20.0)
                })
                .map(|t| (t.points()[0].frame, t.points()[t.points().len() - 1].frame))
                .collect::<Vec<_>>()
        };
        let effective = TrackConfig::default().resolve(&rows).unwrap();
        let d_bar = effective.model.max_gap;
        assert!((18..=21).contains(&d_bar), "d̄ = {d_bar}");
        // Linked: one track from frame 1 to 90, the occlusion bridged.
        assert_eq!(ids_of(&TrackConfig::default(), 150.0), vec![(1, 90)]);
        // Walker 3 keeps his own track (out of the motion gate of walker 1's end).
        assert_eq!(ids_of(&TrackConfig::default(), 750.0), vec![(52, 90)]);
        // Without linking the occlusion splits walker 1.
        let off = config("[offline]\nlink_gap_factor = 0.0\n");
        assert_eq!(ids_of(&off, 150.0), vec![(1, 30), (52, 90)]);
    }

    #[test]
    fn online_gnn_output_is_causal_and_coasts_a_bounded_time() {
        // One walker at 5 px a frame, missed in frames 10-11, last seen at frame 20; a second
        // one seen to frame 40 keeps the file going.
        let mut rows = Vec::new();
        for f in 1..=40u32 {
            let t = f64::from(f);
            if f <= 20 && !(10..=11).contains(&f) {
                rows.push(det(f, 100.0 + 5.0 * t, 100.0, 40.0, 100.0));
            }
            rows.push(det(f, 600.0, 100.0 + 3.0 * t, 40.0, 100.0));
        }
        let settings = config("[gnn]\nmax_gap = 6\n[boxes]\nonline_coast_frames = 8\n");
        let tracks = track_detections(Tracker::GnnOnline, &rows, &settings, 1).unwrap();
        let walker = tracks
            .tracks()
            .iter()
            .find(|t| t.points().iter().any(|p| p.location.position().x < 500.0))
            .unwrap();
        let frames: Vec<Frame> = walker.points().iter().map(|p| p.frame).collect();
        // From the first detection, through the miss, and 6 coasted frames after frame 20.
        assert_eq!(frames, (1..=26).collect::<Vec<_>>());
        let at = |f: Frame| {
            walker
                .points()
                .iter()
                .find(|p| p.frame == f)
                .unwrap()
                .location
                .position()
        };
        // The first box is the first detection; coasted frames move on at 5 px a frame.
        assert!((at(1).x - 125.0).abs() < 1e-9, "{:?}", at(1));
        for f in [10, 11, 21, 26] {
            let expected = 120.0 + 5.0 * f64::from(f);
            assert!((at(f).x - expected).abs() < 1e-6, "frame {f}: {:?}", at(f));
        }
        // With the default 3 coasted frames: the two-frame miss is bridged, the end coasts 3.
        let short = track_detections(
            Tracker::GnnOnline,
            &rows,
            &config("[gnn]\nmax_gap = 6\n"),
            1,
        )
        .unwrap();
        let short_walker = short
            .tracks()
            .iter()
            .find(|t| t.points().iter().any(|p| p.location.position().x < 500.0))
            .unwrap();
        let frames: Vec<Frame> = short_walker.points().iter().map(|p| p.frame).collect();
        assert_eq!(frames, (1..=23).collect::<Vec<_>>());
        // Causal: the output up to frame 15 is the same when the file ends at frame 15.
        let cut: Vec<MotRow> = rows.iter().filter(|r| r.frame <= 15).copied().collect();
        let early = track_detections(Tracker::GnnOnline, &cut, &settings, 1).unwrap();
        let early_walker = early
            .tracks()
            .iter()
            .find(|t| t.points().iter().any(|p| p.location.position().x < 500.0))
            .unwrap();
        for p in early_walker.points() {
            let q = at(p.frame);
            assert!(
                (p.location.position() - q).norm() < 1e-9,
                "frame {}",
                p.frame
            );
        }
    }

    #[test]
    fn the_fit_recovers_the_simulated_model() {
        use rand::{RngExt, SeedableRng};
        use rand_distr::{Distribution, Normal};
        // Six targets, constant box size 40 × 100 (so relative and pixel noise agree),
        // p_d = 0.8, R = 1 px² per axis, acceleration variance q = 0.25 px²/frame⁴, one false
        // alarm every other frame.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (sr, sq) = (1.0, 0.5);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let mut rows = Vec::new();
        let mut states: Vec<[f64; 4]> = (0..6)
            .map(|i| [500.0 * f64::from(i), 1000.0 * f64::from(i % 2), 1.0, 0.5])
            .collect();
        for f in 1..=200u32 {
            for s in &mut states {
                for k in 0..2 {
                    let a = sq * noise.sample(&mut rng);
                    s[k] += s[k + 2] + 0.5 * a;
                    s[k + 2] += a;
                }
                if rng.random::<f64>() < 0.8 {
                    let (cx, cy) = (
                        s[0] + sr * noise.sample(&mut rng),
                        s[1] + sr * noise.sample(&mut rng),
                    );
                    rows.push(det(f, cx - 20.0, cy - 50.0, 40.0, 100.0));
                }
            }
            if rng.random::<f64>() < 0.5 {
                let x = 2000.0 * rng.random::<f64>();
                rows.push(det(f, x, 1000.0 * rng.random::<f64>(), 40.0, 100.0));
            }
        }
        let base = McmcdaConfig::for_boxes(&boxes(&rows)).unwrap();
        let fitted = fit_model(&base, &rows, &FitConfig::default()).unwrap();
        assert!((fitted.p_detect - 0.8).abs() < 0.05, "{}", fitted.p_detect);
        assert!(
            (fitted.clutter_per_scan - 0.5).abs() < 0.25,
            "{}",
            fitted.clutter_per_scan
        );
        // R and q are widened by NOISE_INFLATION.
        for k in 0..2 {
            let r = fitted.measurement_noise[(k, k)] / NOISE_INFLATION;
            assert!((r - sr * sr).abs() < 0.3 * sr * sr, "R[{k}] = {r}");
        }
        let tracker_model::CvNoise::Discrete {
            acceleration_covariance,
        } = fitted.motion.noise()
        else {
            panic!("not the discrete noise");
        };
        let q = acceleration_covariance[(0, 0)] / NOISE_INFLATION;
        assert!((q - sq * sq).abs() < 0.6 * sq * sq, "q = {q}");
    }

    /// Two walkers, at (+3, +1) and (−2, 0) px a frame, seen in frames 1-30 except `gap`,
    /// whose frame numbers no row names.
    fn walker_with_a_gap(gap: std::ops::RangeInclusive<Frame>) -> Vec<MotRow> {
        let mut rows = Vec::new();
        for f in (1..=30u32).filter(|f| !gap.contains(f)) {
            let t = f64::from(f);
            rows.push(det(f, 100.0 + 3.0 * t, 100.0 + t, 40.0 + t % 3.0, 100.0));
            rows.push(det(f, 500.0 - 2.0 * t, 250.0, 42.0, 104.0 - t % 2.0));
        }
        rows
    }

    #[test]
    fn phd_tracks_coast_through_empty_frames_in_closed_form() {
        // Frames 13-16 hold no row: the filter jumps them in one prediction, and a confirmed
        // track whose label holds its mass is output there from the label's mean moved by the
        // motion model. (The slow walker's track, whose estimates took a label holding 7 % of
        // their mass, may end at the gap, as stepping the empty frames would.)
        let rows = walker_with_a_gap(13..=16);
        let tracks = track_detections(Tracker::Phd, &rows, &TrackConfig::default(), 3).unwrap();
        let truth = |f: Frame| {
            let t = f64::from(f);
            BoundingBox::new(100.0 + 3.0 * t, 100.0 + t, 41.0, 100.0).unwrap()
        };
        let fast: Vec<&Track> = tracks
            .tracks()
            .iter()
            .filter(|t| t.points().iter().any(|p| p.location.position().x < 300.0))
            .collect();
        assert_eq!(fast.len(), 1, "the fast walker has {} ids", fast.len());
        let frames: Vec<Frame> = fast[0].points().iter().map(|p| p.frame).collect();
        for f in 5..=30 {
            assert!(frames.contains(&f), "frame {f} missing: {frames:?}");
        }
        for p in fast[0]
            .points()
            .iter()
            .filter(|p| (13..=16).contains(&p.frame))
        {
            let tracker_model::Location::Box(b) = p.location else {
                panic!("a point without a box");
            };
            assert!(b.iou(&truth(p.frame)) >= 0.7, "frame {}: {b:?}", p.frame);
        }
        // A gap longer than max_misses (8 here) ends every track: no box inside it, and no id
        // on both sides.
        let rows = walker_with_a_gap(11..=20);
        let short = config("[phd_labels]\nmax_misses = 8\n");
        let tracks = track_detections(Tracker::Phd, &rows, &short, 3).unwrap();
        assert!(tracks.len() >= 2);
        for t in tracks.tracks() {
            let frames: Vec<Frame> = t.points().iter().map(|p| p.frame).collect();
            assert!(frames.iter().all(|f| *f <= 10) || frames.iter().all(|f| *f >= 21));
        }
    }

    #[test]
    fn coasting_is_bounded_by_the_configuration() {
        let err = error_of("[phd_labels]\nmax_misses = 4000000000\n", Tracker::Phd);
        assert!(
            err.contains("[phd_labels]") && err.contains("max_misses"),
            "{err}"
        );
        let err = error_of("[phd_labels]\nmin_iou = nan\n", Tracker::Mcmcda);
        assert!(err.contains("min_iou"), "{err}");
        let err = error_of("[offline]\nlink_gap_factor = 1e9\n", Tracker::Mcmcda);
        assert!(
            err.contains("[offline]") && err.contains("link_gap_factor"),
            "{err}"
        );
        for key in ["extrapolate_frames", "online_coast_frames"] {
            let err = error_of(&format!("[boxes]\n{key} = 4000000000\n"), Tracker::Gnn);
            assert!(err.contains("[boxes]") && err.contains(key), "{err}");
        }
        // The most coasting allowed, over a gap of four billion frames: at most that many
        // boxes, in milliseconds.
        let rows = [1, 2, 3, 4, 5, 4_000_000_000, 4_000_000_001]
            .map(|f| det(f, 10.0 + f64::from(f % 7), 10.0, 40.0, 90.0));
        let start = std::time::Instant::now();
        let tracks = track_detections(
            Tracker::Phd,
            &rows,
            &config("[phd_labels]\nmax_misses = 10000\n"),
            1,
        )
        .unwrap();
        assert!(tracks.n_points() <= 7, "{}", tracks.n_points());
        assert!(start.elapsed().as_secs() < 5);
        // A gap of 10 frames within max_misses: both walkers' confirmed tracks coast through
        // it with one box a frame (kept, since each walker is found again after it); with
        // max_misses = 8 (the default) they end at the gap instead.
        let rows = walker_with_a_gap(11..=20);
        let coasted = |max_misses: u32| {
            let text = format!("[phd_labels]\nmax_misses = {max_misses}\nmin_mass = 0.0\n");
            let tracks = track_detections(Tracker::Phd, &rows, &config(&text), 3).unwrap();
            tracks
                .tracks()
                .iter()
                .flat_map(|t| t.points())
                .filter(|p| (11..=20).contains(&p.frame))
                .count()
        };
        assert_eq!(coasted(12), 20);
        assert_eq!(coasted(8), 0);
    }
}
