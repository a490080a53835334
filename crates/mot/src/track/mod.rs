//! Trackers for detection files: what `cargo xtask track` and the `mot-track` and
//! `mot-realistic` pipelines run. MCMCDA (offline batch, or online with a sliding window) and
//! GNN associate the box centres as point measurements; the SMC-PHD filter tracks the boxes
//! themselves; SORT, ByteTrack and OC-SORT (the `box-trackers` crate, with the defaults of
//! roboflow `trackers`) track the boxes frame by frame. Without a configuration each tracker
//! uses its model scaled to the boxes ([`McmcdaConfig::for_boxes`], [`PhdConfig::for_boxes`])
//! and then fitted to the file
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

use std::borrow::Cow;
use std::fmt;
use std::str::FromStr;

use crate::error::{Error, InTable, Result, invalid};
use box_trackers::{ByteTrackConfig, OcSortConfig, SortConfig};
use mcmcda::{
    McmcdaConfig, MeasId, NearestNeighbourConfig, OnlineConfig, OnlineTracker, Problem, TrackInit,
    chain::{Partition, run_chains},
    nearest_neighbour_tracks,
};
use phd_filter::{PhdConfig, SmcPhd};
use serde::{Deserialize, Serialize};
use tracker_model::{
    BoundingBox, ConstantVelocity2, Frame, MotRow, Track, TrackId, TrackPoint, TrackSet, Vec2,
};

mod association;
mod boxes;
mod fit;
mod phd;
mod sort_family;

use association::track_points;
use boxes::{detection_boxes, kernel_reach};
use fit::{Detections, centres, detections_by_frame, problem_of, score_ratios};
pub(crate) use phd::Labeller;
use phd::{MAX_COAST_FRAMES, track_boxes_phd};
use sort_family::track_sort_family;

pub use boxes::smooth_boxes;
pub use fit::{fit_model, fit_scores};
pub use phd::PhdLabelConfig;

/// Which tracker runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrackerKind {
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
    /// SORT (Bewley et al. 2016), `[sort]`.
    Sort,
    /// ByteTrack (Zhang et al. 2022), `[bytetrack]`.
    #[serde(rename = "bytetrack")]
    ByteTrack,
    /// OC-SORT (Cao et al. 2023), `[ocsort]`.
    #[serde(rename = "ocsort")]
    OcSort,
}

impl TrackerKind {
    /// Every tracker, in the order the command line lists them.
    pub const ALL: [TrackerKind; 8] = [
        TrackerKind::Mcmcda,
        TrackerKind::McmcdaOnline,
        TrackerKind::Gnn,
        TrackerKind::GnnOnline,
        TrackerKind::Phd,
        TrackerKind::Sort,
        TrackerKind::ByteTrack,
        TrackerKind::OcSort,
    ];

    /// The name on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            TrackerKind::Mcmcda => "mcmcda",
            TrackerKind::McmcdaOnline => "mcmcda-online",
            TrackerKind::Gnn => "gnn",
            TrackerKind::GnnOnline => "gnn-online",
            TrackerKind::Phd => "phd",
            TrackerKind::Sort => "sort",
            TrackerKind::ByteTrack => "bytetrack",
            TrackerKind::OcSort => "ocsort",
        }
    }

    /// Whether this is one of the box trackers (SORT, ByteTrack, OC-SORT), which read their
    /// own table only and follow the detections frame by frame.
    pub fn is_sort_family(self) -> bool {
        matches!(
            self,
            TrackerKind::Sort | TrackerKind::ByteTrack | TrackerKind::OcSort
        )
    }
}

impl fmt::Display for TrackerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for TrackerKind {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        TrackerKind::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| Error::UnknownTracker { name: s.into() })
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
    /// Independent chains from the same start, run in parallel, each with its share of the
    /// samples above (the total, rounded up to a multiple of the chain count); the best MAP
    /// among them is the answer. Two (the default) halve the chain's time on two cores, and on
    /// the tuning sequences of `mot-realistic` two half-length chains tracked as well as one
    /// full-length chain (docs/mot-realistic.md).
    pub chains: usize,
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
            chains: 2,
            // 0.5 links little and 3 links passers-by; the tuned value for pedestrian files is
            // in fixtures/tuned/mot-realistic.toml.
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
    /// How much the fitted R and q are widened over the moment estimates: the detections'
    /// errors are heavier-tailed than Gaussian (turns, stops, boxes cut at the border), and a
    /// gate sized to the mean square splits tracks.
    pub noise_inflation: f64,
    /// MCMCDA's d̄ is the frames in which a walker moves this many box widths: occlusions by a
    /// passer-by last about that long, and MCMCDA, which weighs every association against the
    /// whole window, bridges them. GNN, which commits scan by scan, deletes a track after half
    /// of it (one box width at the default) unless `[gnn] max_gap` is set.
    pub gap_box_widths: f64,
}

impl Default for FitConfig {
    /// General defaults. The values `cargo xtask tune mot-realistic` chose for realistic
    /// pedestrian files, with every candidate's score, are `fixtures/tuned/mot-realistic.toml`
    /// and its grid (a `--config` file).
    fn default() -> Self {
        Self {
            iterations: 2,
            min_track_detections: 6,
            noise_inflation: 2.0,
            gap_box_widths: 2.0,
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
            // A few frames bridge a missed detection; the whole deletion gap outputs people
            // who left (fixtures/tuned/mot-realistic.toml has the tuned value).
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
    /// GNN and online GNN drop the detections whose fitted ln f₁(s)/f₀(s) (clamped to
    /// ±`max_log_ratio`; 0 for a detection without a finite score) is below this, and fit
    /// the model again to the rest, where the file's scores give a [`ScoreModel`]. GNN
    /// decides every association at once and starts a track from any two detections, so a
    /// false box it takes costs a false positive or a switch that its cost cannot weigh by
    /// score; MCMCDA weighs each detection's score in the posterior and drops none. −∞ keeps
    /// every detection; above `max_log_ratio` it would drop all, and is refused. A
    /// configuration printed for GNN holds the refitted model, which loading it pins; the
    /// drop is then made with the score densities fitted under that model.
    pub gnn_min_log_ratio: f64,
}

impl Default for ScoreConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            max_log_ratio: 3.0,
            gnn_min_log_ratio: GNN_MIN_LOG_RATIO,
        }
    }
}

impl ScoreConfig {
    /// Checks the bound (finite, ≥ 0) and GNN's threshold (at most the bound, −∞ allowed).
    pub fn check(&self) -> Result<()> {
        tracker_model::ensure_non_negative(self.max_log_ratio, "max_log_ratio")?;
        if self.gnn_min_log_ratio.is_nan() || self.gnn_min_log_ratio > self.max_log_ratio {
            return Err(invalid(
                "gnn_min_log_ratio",
                format!(
                    "{} must be at most max_log_ratio = {} (every clamped ratio would be below \
                     it; -inf keeps every detection)",
                    self.gnn_min_log_ratio, self.max_log_ratio
                ),
            ));
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
/// that
/// - a track is output from the prediction for up to 5 frames after its last detection (2,
///   the crate's default, drops people through short occlusions);
/// - each window runs two chains of 1,000 samples in parallel instead of one of 2,000, and
///   no sample is drawn at a frame whose every detection extends the only track gating it;
/// - a frame counts as ambiguous only for a rival at least e⁻⁴ as likely as the best
///   association (`rival_log_ratio` = 4) or for an ungated detection with a free one in its
///   neighbourhood in the last two frames (`birth_lookback` = 2). With the sampler's bounded
///   rejection it takes 0.11-0.19 ms per frame on the realistic pedestrian files.
///
/// The values `cargo xtask tune mot-realistic` chose for those files, with every candidate's
/// score, are `fixtures/tuned/mot-realistic.toml` and its grid.
fn online_base() -> OnlineConfig {
    OnlineConfig {
        coast_scans: 5,
        chains: 2,
        samples_per_scan: 1000,
        skip_unambiguous: true,
        rival_log_ratio: 4.0,
        birth_lookback: 2,
        ..OnlineConfig::default()
    }
}

/// Points of the tabulated score ratio.
const SCORE_GRID: usize = 64;

/// GNN's default `[scores] gnn_min_log_ratio`.
const GNN_MIN_LOG_RATIO: f64 = -2.0;

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
#[derive(Debug, Clone, Default, Deserialize)]
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
    #[serde(default)]
    sort: SortConfig,
    #[serde(default)]
    bytetrack: ByteTrackConfig,
    #[serde(default)]
    ocsort: OcSortConfig,
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
    /// The detections GNN and online GNN dropped below `[scores] gnn_min_log_ratio` (the
    /// model above was fitted to the rest); not a key of the configuration.
    #[serde(skip)]
    pub gnn_dropped: usize,
    /// The online MCMCDA tracker (`[online]`).
    pub online: OnlineConfig,
    /// GNN (`[gnn]`).
    pub gnn: NearestNeighbourConfig,
    /// The SMC-PHD filter (`[phd]`).
    pub phd: PhdConfig,
    /// The PHD tracker's track management (`[phd_labels]`).
    pub phd_labels: PhdLabelConfig,
    /// SORT (`[sort]`).
    pub sort: SortConfig,
    /// ByteTrack (`[bytetrack]`).
    pub bytetrack: ByteTrackConfig,
    /// OC-SORT (`[ocsort]`).
    pub ocsort: OcSortConfig,
}

impl TrackConfig {
    /// Builds and checks every table against the detections `rows` (the models are scaled to
    /// their boxes; with no rows, the defaults of the papers are the base). A table for a
    /// tracker that does not run is checked too: a mistake in it is a mistake in the file.
    pub fn resolve(&self, rows: &[MotRow]) -> Result<EffectiveConfig> {
        self.resolve_scores(rows, true)
    }

    /// Whether the configuration file sets `key` in its `[phd]` table.
    pub(crate) fn sets_phd_key(&self, key: &str) -> bool {
        self.phd.as_ref().is_some_and(|t| t.contains_key(key))
    }

    /// [`TrackConfig::resolve`] for one tracker: the detection-score densities (a GNN pass of
    /// their own) are fitted only for the trackers whose likelihood has a score term, so not
    /// for the PHD or the box trackers, which read the scores as they are (their
    /// `score_model` stays `None`, as `--print-config` shows no `[scores]` table for them).
    pub fn resolve_for(&self, rows: &[MotRow], tracker: TrackerKind) -> Result<EffectiveConfig> {
        self.resolve_scores(
            rows,
            tracker != TrackerKind::Phd && !tracker.is_sort_family(),
        )
    }

    /// The configuration `tracker` runs with on `rows`, and the detections it tracks: GNN and
    /// online GNN drop those whose fitted score ratio is below `[scores] gnn_min_log_ratio`
    /// and are fitted again to the rest (when the file's scores give a score model and the
    /// threshold drops some of them); the other trackers take [`TrackConfig::resolve_for`]
    /// and every row. `--print-config` prints this configuration.
    pub fn resolve_tracked<'a>(
        &self,
        rows: &'a [MotRow],
        tracker: TrackerKind,
    ) -> Result<(EffectiveConfig, Cow<'a, [MotRow]>)> {
        let config = self.resolve_for(rows, tracker)?;
        let Some(scores) = config.score_model.as_ref() else {
            return Ok((config, Cow::Borrowed(rows)));
        };
        if !matches!(tracker, TrackerKind::Gnn | TrackerKind::GnnOnline) {
            return Ok((config, Cow::Borrowed(rows)));
        }
        let min = config.scores.gnn_min_log_ratio;
        let kept: Vec<MotRow> = rows
            .iter()
            .filter(|r| scores.log_ratio(r.confidence) >= min)
            .cloned()
            .collect();
        if kept.is_empty() {
            let best = rows
                .iter()
                .map(|r| scores.log_ratio(r.confidence))
                .fold(f64::NEG_INFINITY, f64::max);
            return Err(Error::DropsEveryDetection { min, best });
        }
        if kept.len() == rows.len() {
            return Ok((config, Cow::Borrowed(rows)));
        }
        let mut refitted = self.resolve_for(&kept, tracker)?;
        refitted.gnn_dropped = rows.len() - kept.len();
        Ok((refitted, Cow::Owned(kept)))
    }

    fn resolve_scores(&self, rows: &[MotRow], with_scores: bool) -> Result<EffectiveConfig> {
        let boxes = boxes(rows);
        let (model_base, mut phd_base) = if boxes.is_empty() {
            (McmcdaConfig::default(), PhdConfig::default())
        } else {
            (
                McmcdaConfig::for_boxes(&boxes)?,
                PhdConfig::for_boxes(&boxes)?,
            )
        };
        self.check_tables()?;
        let model_base = if boxes.is_empty() {
            model_base
        } else {
            fit_model(&model_base, rows, &self.fit)?
        };
        if self.fit.iterations > 0 && !boxes.is_empty() {
            phd_base = phd_fitted(&model_base, phd_base);
        }
        let model = overridden(&model_base, self.model.as_ref(), "model")?;
        model.check().in_table("model")?;
        let online = overridden(&online_base(), self.online.as_ref(), "online")?;
        online.check().in_table("online")?;
        if online.samples_per_scan == 0 {
            return Err(invalid(
                "samples_per_scan",
                "0; MCMCDA needs at least 1 sample per scan to find any track".into(),
            ))
            .in_table("online");
        }
        self.gnn.check().in_table("gnn")?;
        let phd = overridden(&phd_base, self.phd.as_ref(), "phd")?;
        phd.check().in_table("phd")?;
        self.phd_labels.check().in_table("phd_labels")?;
        self.sort.build().in_table("sort")?;
        self.bytetrack.build().in_table("bytetrack")?;
        self.ocsort.build().in_table("ocsort")?;
        let mut gnn = self.gnn;
        if gnn.max_gap.is_none() && self.fit.iterations > 0 && !boxes.is_empty() {
            // GNN deletes after one box width of travel, half of MCMCDA's d̄ (the fitted one,
            // or the user's `[model] max_gap`).
            gnn.max_gap =
                Some(((f64::from(model.max_gap) / self.fit.gap_box_widths).round() as u32).max(1));
        }
        let score_model = if with_scores {
            fit_scores(&model, rows, &self.fit, &gnn, &self.scores)?
        } else {
            None
        };
        Ok(EffectiveConfig {
            model,
            fit: self.fit,
            offline: self.offline,
            boxes: self.boxes,
            scores: self.scores,
            score_model,
            gnn_dropped: 0,
            online,
            gnn,
            phd,
            phd_labels: self.phd_labels,
            sort: self.sort,
            bytetrack: self.bytetrack,
            ocsort: self.ocsort,
        })
    }
}

/// Tracks `rows` and returns boxed tracks with ids from 1. The configuration is resolved and
/// checked first, every table of it.
pub fn track_detections(
    tracker: TrackerKind,
    rows: &[MotRow],
    settings: &TrackConfig,
    seed: u64,
) -> Result<TrackSet> {
    if rows.is_empty() {
        return Err(Error::NoDetections {
            what: "the input".into(),
        });
    }
    let (config, rows) = settings.resolve_tracked(rows, tracker)?;
    match tracker {
        TrackerKind::Phd => track_boxes_phd(&rows, &config, seed),
        TrackerKind::Sort | TrackerKind::ByteTrack | TrackerKind::OcSort => {
            track_sort_family(tracker, &rows, &config)
        }
        TrackerKind::Mcmcda
        | TrackerKind::McmcdaOnline
        | TrackerKind::Gnn
        | TrackerKind::GnnOnline => track_points(tracker, &rows, &config, seed),
    }
}

/// A detection-file tracker behind tracker-model's
/// [`BatchTracker`](tracker_model::BatchTracker): [`track_detections`] on the scans' boxes
/// (their scores as the confidence column), its configuration fitted to them.
#[derive(Debug, Clone)]
pub struct FileTracker {
    /// Which tracker.
    pub kind: TrackerKind,
    /// The configuration file's tables.
    pub config: TrackConfig,
    /// The seed of every random draw.
    pub seed: u64,
}

impl tracker_model::BatchTracker for FileTracker {
    type Error = Error;

    /// No scan, no track (as every tracker of the interface); the file trackers' own entry
    /// point, [`track_detections`], calls an empty file an error.
    fn track(&mut self, scans: &[tracker_model::FrameDetections]) -> Result<TrackSet> {
        if scans.is_empty() {
            return Ok(TrackSet::new());
        }
        let rows = crate::driver::rows_of(scans)?;
        track_detections(self.kind, &rows, &self.config, self.seed)
    }
}

/// [`track_detections`], or, given a folder of `frames`, the PHD tracker fused with image local
/// detectors on those pictures ([`crate::frames`]; `--tracker phd` only). Also returns
/// the configuration the tracker ran with, resolved once: resolving fits the model to the file,
/// which costs as much as a GNN pass, so the caller must not resolve it again to report it.
pub fn track_detections_with_frames(
    tracker: TrackerKind,
    rows: &[MotRow],
    settings: &TrackConfig,
    seed: u64,
    frames: Option<(&std::path::Path, &crate::frames::FusedSettings)>,
) -> Result<(TrackSet, EffectiveConfig)> {
    if rows.is_empty() {
        return Err(Error::NoDetections {
            what: "the input".into(),
        });
    }
    let (config, rows) = effective_config(tracker, rows, settings, frames.map(|f| f.1))?;
    let tracks = match (frames, tracker) {
        (Some((dir, fused)), _) => {
            crate::frames::track_frames_resolved(dir, &rows, &config, fused, seed)?
        }
        (None, TrackerKind::Phd) => track_boxes_phd(&rows, &config, seed)?,
        (None, t) if t.is_sort_family() => track_sort_family(t, &rows, &config)?,
        (None, _) => track_points(tracker, &rows, &config, seed)?,
    };
    Ok((tracks, config))
}

/// The configuration a run of `tracker` on `rows` uses, and the rows it tracks (GNN may drop
/// those its scores call clutter): with `fused` settings (a frame folder), the fused PHD's (its own detection
/// probability and threshold, [`crate::frames`]; `--tracker phd` only), else the one fitted to
/// the file. `--print-config` shows exactly this.
pub fn effective_config<'r>(
    tracker: TrackerKind,
    rows: &'r [MotRow],
    settings: &TrackConfig,
    fused: Option<&crate::frames::FusedSettings>,
) -> Result<(EffectiveConfig, Cow<'r, [MotRow]>)> {
    let Some(fused) = fused else {
        return settings.resolve_tracked(rows, tracker);
    };
    if tracker != TrackerKind::Phd {
        return Err(Error::FramesNeedPhd {
            tracker: tracker.name(),
        });
    }
    Ok((
        crate::frames::fused_config(settings, rows, fused)?,
        Cow::Borrowed(rows),
    ))
}

impl TrackConfig {
    /// Checks the tables that need no detections: `[fit]`, `[offline]`, `[boxes]`, `[scores]`.
    fn check_tables(&self) -> Result<()> {
        self.fit.check().in_table("fit")?;
        self.offline.check().in_table("offline")?;
        self.boxes.check().in_table("boxes")?;
        self.scores.check().in_table("scores")?;
        Ok(())
    }
}

/// The PHD filter's rates, noise and motion from the MCMCDA model fitted to the file:
/// constant velocity with MCMCDA's q, newborn velocity σ from the fitted velocity variance,
/// the centre's R and twice its σ for the size.
fn phd_fitted(model_base: &McmcdaConfig, mut phd_base: PhdConfig) -> PhdConfig {
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
    phd_base
}

/// Why a tracker that was given detections returned no track, or nothing when it returned
/// some: a warning for the user that names the parameters that decide it.
pub fn empty_output_warning(
    tracker: TrackerKind,
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
        TrackerKind::Mcmcda
        | TrackerKind::McmcdaOnline
        | TrackerKind::Gnn
        | TrackerKind::GnnOnline => format!(
            "a track needs detections in at least two frames at most max_gap = {} frames \
             apart, moving at most max_speed = {} per frame, and it must explain them better \
             than clutter_per_scan = {} false alarms per frame over volume = {}",
            m.max_gap, m.max_speed, m.clutter_per_scan, m.volume
        ),
        TrackerKind::Phd => format!(
            "a track is reported where the filter's weight passes extraction_threshold = {} \
             with p_detect = {}, birth_rate = {} and clutter_rate = {} per frame",
            config.phd.extraction_threshold,
            config.phd.p_detect,
            config.phd.birth_rate,
            config.phd.clutter_rate
        ),
        TrackerKind::Sort | TrackerKind::ByteTrack | TrackerKind::OcSort => {
            sort_family::why_empty(tracker, config)
        }
    };
    Some(format!(
        "{seen}: {why}. See the effective configuration with `cargo xtask track \
         --print-config --tracker {tracker} --input FILE`"
    ))
}

/// One line of explanation per key of each table, in the order `--print-config` writes them.
const KEY_COMMENTS: [(&str, &[(&str, &str)]); 12] = [
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
            (
                "noise_inflation",
                "factor on the fitted R and q (the detections' errors are heavier-tailed than \
                 Gaussian)",
            ),
            (
                "gap_box_widths",
                "MCMCDA's largest gap d̄ = the frames a walker takes to move this many box \
                 widths (GNN's: half of it)",
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
                "chains",
                "independent chains in parallel, sharing the samples; the best MAP is kept",
            ),
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
            (
                "patience",
                "stop a window's chain after this many samples without a better MAP (0 = run all samples_per_scan)",
            ),
            (
                "skip_unambiguous",
                "draw no sample at a frame whose every detection extends the only track gating it",
            ),
            (
                "rival_log_ratio",
                "with skip_unambiguous: a second gated association makes a frame ambiguous only if its log likelihood is within this of the best (inf = any)",
            ),
            (
                "birth_lookback",
                "with skip_unambiguous: a detection no track gates makes a frame ambiguous only if a free detection lies in its neighbourhood in the last this many frames (0 = always)",
            ),
            (
                "chains",
                "independent chains per window in parallel, samples_per_scan each; the best MAP is kept",
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
            (
                "gnn_min_log_ratio",
                "gnn, gnn-online: drop detections whose fitted ln f₁(s)/f₀(s) is below this, then fit again (-inf = keep all)",
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
            (
                "duplicate_cover",
                "a tentative track is dropped when a confirmed track's box covers this share of its box (unset: never)",
            ),
        ],
    ),
    (
        "sort",
        &[
            (
                "lost_track_buffer",
                "frames at 30 fps a track lives without a match (scaled by frame_rate)",
            ),
            ("frame_rate", "the video's frame rate, frames per second"),
            (
                "track_activation_threshold",
                "the least score that starts a track",
            ),
            (
                "minimum_consecutive_frames",
                "matches (the first detection included) before a track is output",
            ),
            ("minimum_iou_threshold", "the least IoU of a match"),
            (
                "coast_frames",
                "frames a confirmed track is output at its prediction after a miss (0: only its detections, as the reference)",
            ),
            (
                "state",
                "the Kalman state: corners, or centre-area-aspect (the paper's)",
            ),
        ],
    ),
    (
        "bytetrack",
        &[
            (
                "lost_track_buffer",
                "frames at 30 fps a track lives without a match (scaled by frame_rate)",
            ),
            ("frame_rate", "the video's frame rate, frames per second"),
            (
                "track_activation_threshold",
                "the least score that starts a track (from a high-score box)",
            ),
            (
                "minimum_consecutive_frames",
                "consecutive matches (the first detection included) before a track is confirmed",
            ),
            (
                "minimum_iou_threshold",
                "the least IoU of a match in the first stage (and the second unless second_iou_threshold is set)",
            ),
            (
                "high_conf_det_threshold",
                "boxes scoring at least this are matched first; the others only to the tracks left",
            ),
            (
                "low_conf_det_threshold",
                "boxes scoring below this are dropped (the paper: 0.1)",
            ),
            (
                "second_iou_threshold",
                "the least IoU of a second-stage match (unset: minimum_iou_threshold; the paper: 0.5)",
            ),
            (
                "coast_frames",
                "frames a confirmed track is output at its prediction after a miss (0: only its detections, as the reference)",
            ),
            ("state", "the Kalman state: corners, or centre-area-aspect"),
        ],
    ),
    (
        "ocsort",
        &[
            (
                "lost_track_buffer",
                "frames at 30 fps a track lives without a match (scaled by frame_rate)",
            ),
            ("frame_rate", "the video's frame rate, frames per second"),
            (
                "minimum_consecutive_frames",
                "consecutive matches before a track is output (any match in the first frames)",
            ),
            ("minimum_iou_threshold", "the least IoU of a match"),
            (
                "direction_consistency_weight",
                "the weight of the direction term in the cost (OCM)",
            ),
            (
                "high_conf_det_threshold",
                "boxes scoring below this are not used",
            ),
            (
                "delta_t",
                "frames back to the observation a direction is measured from",
            ),
            (
                "coast_frames",
                "frames a confirmed track is output at its prediction after a miss (0: only its detections, as the reference)",
            ),
            (
                "state",
                "the Kalman state: centre-area-aspect (the paper's), or corners",
            ),
        ],
    ),
];

/// The tables a tracker reads.
fn tables_of(tracker: TrackerKind) -> &'static [&'static str] {
    match tracker {
        TrackerKind::Mcmcda => &["model", "fit", "offline", "boxes", "scores"],
        TrackerKind::McmcdaOnline => &["model", "fit", "online", "boxes", "scores"],
        TrackerKind::Gnn | TrackerKind::GnnOnline => &["model", "fit", "gnn", "boxes", "scores"],
        TrackerKind::Phd => &["fit", "phd", "phd_labels"],
        TrackerKind::Sort => &["sort"],
        TrackerKind::ByteTrack => &["bytetrack"],
        TrackerKind::OcSort => &["ocsort"],
    }
}

/// The effective configuration as commented TOML: every key of the tables `tracker` reads
/// (all of them without one) with its value and a one-line comment. Loading the text back as a
/// [`TrackConfig`] gives the same effective configuration. Unset optional keys are written
/// as comments.
pub fn render_config(config: &EffectiveConfig, tracker: Option<TrackerKind>) -> Result<String> {
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
            .ok_or_else(|| invalid("configuration", format!("it has no [{name}] table")))?;
        if let Some(key) = table.keys().find(|k| !keys.iter().any(|(c, _)| c == k)) {
            return Err(invalid(
                "configuration",
                format!("[{name}] {key} has no comment in KEY_COMMENTS"),
            ));
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
/// The most rounds of model fitting: each runs GNN over the whole file, and the fit settles
/// in two or three.
pub const MAX_FIT_ITERATIONS: usize = 20;

/// `[fit] noise_inflation` range: below 1/10 the gates would hold no detection, above 100 every
/// detection of the frame would fall in every gate.
const MIN_NOISE_INFLATION: f64 = 0.1;
const MAX_NOISE_INFLATION: f64 = 100.0;

/// `[fit] gap_box_widths` range (d̄ is clamped to 3–30 frames whatever it is).
const MIN_GAP_BOX_WIDTHS: f64 = 0.1;
const MAX_GAP_BOX_WIDTHS: f64 = 100.0;

impl FitConfig {
    /// Checks the rounds (at most [`MAX_FIT_ITERATIONS`]) and the confident-track length (≥ 3,
    /// the fewest detections the moment estimates can use).
    pub fn check(&self) -> Result<()> {
        if self.iterations > MAX_FIT_ITERATIONS {
            return Err(invalid(
                "iterations",
                format!("{}; at most {MAX_FIT_ITERATIONS}", self.iterations),
            ));
        }
        if self.min_track_detections < 3 {
            return Err(invalid(
                "min_track_detections",
                format!(
                    "{}; the moment estimates need at least 3",
                    self.min_track_detections
                ),
            ));
        }
        tracker_model::ensure_in_range(
            self.noise_inflation,
            MIN_NOISE_INFLATION,
            MAX_NOISE_INFLATION,
            "noise_inflation",
        )?;
        tracker_model::ensure_in_range(
            self.gap_box_widths,
            MIN_GAP_BOX_WIDTHS,
            MAX_GAP_BOX_WIDTHS,
            "gap_box_widths",
        )?;
        Ok(())
    }
}

impl OfflineConfig {
    /// Checks that the chain runs at all, with at most [`mcmcda::MAX_SAMPLES`] steps.
    pub fn check(&self) -> Result<()> {
        if self.min_samples == 0 && self.samples_per_detection == 0 {
            return Err(invalid(
                "min_samples",
                "min_samples = samples_per_detection = 0: the chain would never move".into(),
            ));
        }
        if !(1..=mcmcda::MAX_CHAINS).contains(&self.chains) {
            return Err(invalid(
                "chains",
                format!("{}; it must be in 1..={}", self.chains, mcmcda::MAX_CHAINS),
            ));
        }
        for (name, samples) in [
            ("samples_per_detection", self.samples_per_detection),
            ("min_samples", self.min_samples),
        ] {
            if samples > mcmcda::MAX_SAMPLES {
                return Err(invalid(
                    name,
                    format!(
                        "{samples}; at most {} samples per chain",
                        mcmcda::MAX_SAMPLES
                    ),
                ));
            }
        }
        // At most 100 × d̄ (d̄ ≤ 64 frames): a link's bridged frames are output boxes, so the
        // factor bounds what one gap in the frame numbers can cost.
        if !(self.link_gap_factor.is_finite() && (0.0..=100.0).contains(&self.link_gap_factor)) {
            return Err(invalid(
                "link_gap_factor",
                format!("{}; it must be in [0, 100]", self.link_gap_factor),
            ));
        }
        Ok(())
    }

    /// Samples per chain for a file of `n_detections`, at most [`mcmcda::MAX_SAMPLES`].
    pub(crate) fn samples_for(&self, n_detections: usize) -> Result<u64> {
        let samples = self.samples(n_detections);
        if samples > mcmcda::MAX_SAMPLES {
            return Err(invalid(
                "samples_per_detection",
                format!(
                    "{} × {n_detections} detections asks {samples} samples per chain; at most {}",
                    self.samples_per_detection,
                    mcmcda::MAX_SAMPLES
                ),
            ))
            .in_table("offline");
        }
        Ok(samples)
    }

    /// Samples per chain: the total shared by the chains, rounded up (so no chain is left
    /// without a sample).
    fn samples(&self, n_detections: usize) -> u64 {
        (self
            .samples_per_detection
            .saturating_mul(n_detections as u64))
        .max(self.min_samples)
        .div_ceil(self.chains as u64)
    }
}

impl BoxConfig {
    /// Checks the kernel width (finite, > 0) and bounds the frames output without a detection
    /// (as `[phd_labels] max_misses`: each is a box per track, so an unbounded value would let
    /// a configuration ask for billions of boxes).
    pub fn check(&self) -> Result<()> {
        if !(self.smoothing_frames.is_finite() && self.smoothing_frames > 0.0) {
            return Err(invalid(
                "smoothing_frames",
                format!("{}; it must be finite and > 0", self.smoothing_frames),
            ));
        }
        for (name, frames) in [
            ("extrapolate_frames", self.extrapolate_frames),
            ("online_coast_frames", self.online_coast_frames),
        ] {
            if frames > MAX_COAST_FRAMES {
                return Err(invalid(
                    name,
                    format!(
                        "{frames} is over {MAX_COAST_FRAMES}: each frame is one output box per track"
                    ),
                ));
            }
        }
        Ok(())
    }
}

fn boxes(rows: &[MotRow]) -> Vec<BoundingBox> {
    rows.iter().map(|r| r.bbox).collect()
}

/// Merges the fields of `overrides` into `base` (both serde structs) and checks the result.
fn overridden<T: Clone + serde::Serialize + serde::de::DeserializeOwned>(
    base: &T,
    overrides: Option<&toml::Table>,
    what: &'static str,
) -> Result<T> {
    let Some(overrides) = overrides else {
        return Ok(base.clone());
    };
    let mut table = toml::Table::try_from(base)?;
    table.extend(overrides.clone());
    table
        .try_into()
        .map_err(|error| Error::TableSyntax { table: what, error })
}

#[cfg(test)]
mod tests;
