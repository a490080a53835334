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
//! only non-empty scans, and the PHD path steps the frames with detections plus at most the
//! first few empty frames of a gap (until the filter has forgotten what came before; see
//! `coast_frames`).

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
    /// SMC-PHD on boxes (global detections only: no images, so no local detectors).
    Phd,
}

impl Tracker {
    /// Every tracker, in the order the command line lists them.
    pub const ALL: [Tracker; 4] = [
        Tracker::Mcmcda,
        Tracker::McmcdaOnline,
        Tracker::Gnn,
        Tracker::Phd,
    ];

    /// The name on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Tracker::Mcmcda => "mcmcda",
            Tracker::McmcdaOnline => "mcmcda-online",
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
            .with_context(|| {
                format!("unknown tracker {s:?}; known: mcmcda, mcmcda-online, gnn, phd")
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
}

impl Default for OfflineConfig {
    fn default() -> Self {
        Self {
            samples_per_detection: 20,
            min_samples: 20_000,
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
}

impl Default for BoxConfig {
    fn default() -> Self {
        Self {
            smoothing_frames: 1.5,
            extrapolate_frames: 0,
        }
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
    #[serde(default)]
    online: OnlineConfig,
    #[serde(default)]
    gnn: NearestNeighbourConfig,
    #[serde(default)]
    boxes: BoxConfig,
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
        self.online
            .check()
            .context("in the [online] table of the configuration")?;
        if self.online.samples_per_scan == 0 {
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
        Ok(EffectiveConfig {
            model,
            fit: self.fit,
            offline: self.offline,
            boxes: self.boxes,
            online: self.online,
            gnn: self.gnn,
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
        Tracker::Mcmcda | Tracker::McmcdaOnline | Tracker::Gnn => {
            track_points(tracker, rows, &config, seed)
        }
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
        Tracker::Mcmcda | Tracker::McmcdaOnline | Tracker::Gnn => format!(
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
const KEY_COMMENTS: [(&str, &[(&str, &str)]); 8] = [
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
        Tracker::Mcmcda => &["model", "fit", "offline", "boxes"],
        Tracker::McmcdaOnline => &["model", "fit", "online", "boxes"],
        Tracker::Gnn => &["model", "fit", "gnn", "boxes"],
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
    /// The most frames a confirmed track is output from the prediction.
    pub max_misses: u32,
}

impl Default for PhdLabelConfig {
    fn default() -> Self {
        Self {
            confirm_hits: 3,
            confirm_window: 5,
            min_iou: 0.3,
            min_mass: 0.1,
            max_misses: 8,
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
    let cap = coast_frames(config.p_survive, config.p_detect);
    let mut phd = SmcPhd::new(config, seed)?;
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
    let mut live: Vec<PhdTrack> = Vec::new();
    let mut done: Vec<PhdTrack> = Vec::new();
    let mut next_id = 1u64;
    let mut previous: Option<Frame> = None;
    let mut step_frame = |frame: Frame,
                          boxes: &[BoundingBox],
                          phd: &mut SmcPhd,
                          live: &mut Vec<PhdTrack>,
                          done: &mut Vec<PhdTrack>|
     -> Result<()> {
        let step = phd.step(boxes)?;
        // Mass and weighted mean state of every PHD label.
        let mut mass: std::collections::HashMap<u64, (f64, [f64; 6])> = Default::default();
        for p in phd.particles() {
            let e = mass.entry(p.label).or_insert((0.0, [0.0; 6]));
            e.0 += p.w;
            for k in 0..6 {
                e.1[k] += p.w * p.x[k];
            }
        }
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
        if let Some(prev) = previous {
            let empty = u64::from(frame) - u64::from(prev) - 1;
            for k in 1..=empty.min(cap) {
                // k ≤ frame − prev − 1, so prev + k < frame fits a Frame.
                step_frame(prev + k as Frame, &[], &mut phd, &mut live, &mut done)?;
            }
        }
        step_frame(frame, boxes, &mut phd, &mut live, &mut done)?;
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

impl OfflineConfig {
    /// Checks that the chain runs at all.
    pub fn check(&self) -> Result<()> {
        if self.min_samples == 0 && self.samples_per_detection == 0 {
            bail!("min_samples = samples_per_detection = 0: the chain would never move");
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
    /// Checks the kernel width (finite, > 0).
    pub fn check(&self) -> Result<()> {
        if !(self.smoothing_frames.is_finite() && self.smoothing_frames > 0.0) {
            bail!(
                "smoothing_frames = {}; it must be finite and > 0",
                self.smoothing_frames
            );
        }
        Ok(())
    }
}

/// Detections by frame.
type ByFrame = std::collections::BTreeMap<Frame, Vec<MotRow>>;

/// Detections in measurement-id order, by frame (file order within a frame; MCMCDA's
/// measurement ids follow this order), and the problem of their centres.
fn problem_of(model: &mcmcda::Model, rows: &[MotRow]) -> Result<(Vec<MotRow>, ByFrame, Problem)> {
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<MotRow>> = Default::default();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(*r);
    }
    let detections: Vec<MotRow> = by_frame.values().flatten().copied().collect();
    let first = by_frame.keys().next().copied().unwrap_or(0);
    let mut problem = Problem::empty(model, first);
    for (frame, dets) in &by_frame {
        problem.push_scan(*frame, &centres(dets))?;
    }
    Ok((detections, by_frame, problem))
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
        let (detections, by_frame, problem) = problem_of(&model, rows)?;
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
        // A track may bridge the frames in which its target moves about one box width.
        if let Some(p50) = percentile(&mut speeds, 50) {
            let frames = (1.0 / p50.max(1e-3)).round().clamp(3.0, 20.0);
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

/// MCMCDA (offline or online) or GNN on the box centres; boxes from [`smooth_boxes`].
fn track_points(
    tracker: Tracker,
    rows: &[MotRow],
    settings: &EffectiveConfig,
    seed: u64,
) -> Result<TrackSet> {
    let model = settings.model.check()?;
    let (detections, by_frame, problem) = problem_of(&model, rows)?;
    let associations: Vec<Vec<MeasId>> = match tracker {
        Tracker::McmcdaOnline => return track_online(&model, &by_frame, settings, seed),
        Tracker::Mcmcda => {
            // The chain starts from GNN's tracks (feasible in Ω by construction), so the MAP
            // is at least as probable as GNN's answer under the fitted model.
            let window = problem.all_scans()?;
            let start = nearest_neighbour_tracks(&model, &problem, window.clone(), &settings.gnn)?;
            let start = Partition::from_tracks(&model, &problem, window, &start)?;
            run_chains(&start, 1, settings.offline.samples(detections.len()), seed)?.tracks
        }
        Tracker::Gnn | Tracker::Phd => {
            let window = problem.all_scans()?;
            nearest_neighbour_tracks(&model, &problem, window, &settings.gnn)?
        }
    };
    let mut tracks = Vec::with_capacity(associations.len());
    for (i, meas) in associations.iter().enumerate() {
        let dets: Vec<(Frame, BoundingBox)> = meas
            .iter()
            .map(|&m| {
                let d = &detections[m as usize];
                (d.frame, d.bbox)
            })
            .collect();
        let points = smooth_boxes(&dets, &settings.boxes, None)?;
        if !points.is_empty() {
            tracks.push(Track::from_points(TrackId(i as u64 + 1), points)?);
        }
    }
    Ok(TrackSet::from_tracks(tracks)?)
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
        let step = online.push_scan(frame, &centres(dets))?;
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
    let reach = (3.0 * sigma).ceil() as i64;
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
        while lo < dets.len() && i64::from(dets[lo].0) < f - reach {
            lo += 1;
        }
        // Weighted sums for the local-linear fit of each edge: Σw, Σw·x, Σw·x², Σw·y, Σw·x·y.
        let (mut sw, mut sx, mut sxx) = (0.0, 0.0, 0.0);
        let (mut sy, mut sxy) = ([0.0f64; 4], [0.0f64; 4]);
        let mut n = 0usize;
        for &(g, b) in dets[lo..]
            .iter()
            .take_while(|d| i64::from(d.0) <= f + reach)
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

    #[test]
    fn the_phd_path_coasts_until_the_filter_has_forgotten() {
        // p_S (1 − p_D) = 0.99 · 0.2: 0.198^k < 1e-12 from k = 18 (by hand: ln 1e-12 / ln 0.198
        // = 27.63 / 1.619 = 17.06).
        assert_eq!(coast_frames(0.99, 0.8), 18);
        // Nearly no forgetting: bounded.
        assert_eq!(coast_frames(0.999_999, 1e-9), MAX_COAST_FRAMES);
    }
}
