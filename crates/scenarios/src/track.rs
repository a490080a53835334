//! Trackers for detection files: what `cargo xtask track` and the `mot-track` pipeline run.
//! MCMCDA and GNN track the box centres as point measurements and output smoothed centres with
//! each track's mean detection size; the SMC-PHD filter tracks the boxes themselves. Without a
//! configuration each tracker uses its model scaled to the boxes
//! ([`McmcdaConfig::for_boxes`], [`PhdConfig::for_boxes`]).
//!
//! No tracker's cost grows with gaps in the frame numbers: MCMCDA's and GNN's `Problem` stores
//! only non-empty scans, and the PHD path steps the frames with detections plus at most the
//! first few empty frames of a gap (until the filter has forgotten what came before; see
//! `coast_frames`).

use std::fmt;
use std::str::FromStr;

use anyhow::{Context, Result, bail};
use mcmcda::{
    McmcdaConfig, MeasId, NearestNeighbourConfig, OnlineConfig, OnlineTracker, Problem,
    nearest_neighbour_tracks, smoothed_tracks,
};
use phd_filter::{PhdConfig, PhdTracker, SmcPhd};
use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, Frame, MotRow, Track, TrackPoint, TrackSet, Vec2};

/// Which tracker runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Tracker {
    /// Online sliding-window MCMCDA.
    Mcmcda,
    /// Global nearest neighbour with M-of-N confirmation.
    Gnn,
    /// SMC-PHD on boxes (global detections only: no images, so no local detectors).
    Phd,
}

impl Tracker {
    /// Every tracker, in the order the command line lists them.
    pub const ALL: [Tracker; 3] = [Tracker::Mcmcda, Tracker::Gnn, Tracker::Phd];

    /// The name on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Tracker::Mcmcda => "mcmcda",
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
            .with_context(|| format!("unknown tracker {s:?}; known: mcmcda, gnn, phd"))
    }
}

/// The optional configuration (TOML): any of the four tables, each field optional. Fields of
/// `[model]` and `[phd]` override the configurations scaled to the detections. Every table
/// present is checked, whichever tracker runs ([`TrackConfig::resolve`]).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackConfig {
    model: Option<toml::Table>,
    #[serde(default)]
    online: OnlineConfig,
    #[serde(default)]
    gnn: NearestNeighbourConfig,
    /// Fields of `phd_filter::PhdConfig`, overriding a configuration scaled to the boxes.
    phd: Option<toml::Table>,
}

/// The effective configuration of every tracker: what runs, with every field set.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EffectiveConfig {
    /// MCMCDA's and GNN's model (`[model]`).
    pub model: McmcdaConfig,
    /// The online MCMCDA tracker (`[online]`).
    pub online: OnlineConfig,
    /// GNN (`[gnn]`).
    pub gnn: NearestNeighbourConfig,
    /// The SMC-PHD filter (`[phd]`).
    pub phd: PhdConfig,
}

impl TrackConfig {
    /// Builds and checks every table against the detections `rows` (the models are scaled to
    /// their boxes; with no rows, the defaults of the papers are the base). A table for a
    /// tracker that does not run is checked too: a mistake in it is a mistake in the file.
    pub fn resolve(&self, rows: &[MotRow]) -> Result<EffectiveConfig> {
        let boxes = boxes(rows);
        let (model_base, phd_base) = if boxes.is_empty() {
            (McmcdaConfig::default(), PhdConfig::default())
        } else {
            (
                McmcdaConfig::for_boxes(&boxes)?,
                PhdConfig::for_boxes(&boxes)?,
            )
        };
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
            online: self.online,
            gnn: self.gnn,
            phd,
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
        Tracker::Mcmcda | Tracker::Gnn => track_points(tracker, rows, &config, seed),
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
        Tracker::Mcmcda | Tracker::Gnn => format!(
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
const KEY_COMMENTS: [(&str, &[(&str, &str)]); 4] = [
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
];

/// The tables a tracker reads.
fn tables_of(tracker: Tracker) -> &'static [&'static str] {
    match tracker {
        Tracker::Mcmcda => &["model", "online"],
        Tracker::Gnn => &["model", "gnn"],
        Tracker::Phd => &["phd"],
    }
}

/// The effective configuration as commented TOML: every key of the tables `tracker` reads
/// (all four without one) with its value and a one-line comment. Loading the text back as a
/// [`TrackConfig`] gives the same effective configuration. Unset optional keys are written
/// as comments.
pub fn render_config(config: &EffectiveConfig, tracker: Option<Tracker>) -> Result<String> {
    let all = toml::Table::try_from(config)?;
    let mut out = String::from(
        "# Effective configuration of `cargo xtask track` (load it with --config FILE).\n\
         # Every key is optional: a missing key of [model] or [phd] keeps the value scaled to\n\
         # the detections, of [online] or [gnn] its default.\n",
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

/// SMC-PHD on the boxes themselves.
fn track_boxes_phd(rows: &[MotRow], settings: &EffectiveConfig, seed: u64) -> Result<TrackSet> {
    let config = settings.phd;
    let cap = coast_frames(config.p_survive, config.p_detect);
    let mut phd = PhdTracker::global_only(SmcPhd::new(config, seed)?);
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
    let mut previous: Option<Frame> = None;
    for (&frame, boxes) in &by_frame {
        if let Some(prev) = previous {
            let empty = u64::from(frame) - u64::from(prev) - 1;
            for k in 1..=empty.min(cap) {
                // k ≤ frame − prev − 1, so prev + k < frame fits a Frame.
                phd.step(prev + k as Frame, &[])?;
            }
        }
        phd.step(frame, boxes)?;
        previous = Some(frame);
    }
    Ok(phd.tracks()?)
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

/// Online MCMCDA or GNN on the box centres; boxes get each track's mean detection size.
fn track_points(
    tracker: Tracker,
    rows: &[MotRow],
    settings: &EffectiveConfig,
    seed: u64,
) -> Result<TrackSet> {
    let model = settings.model.check()?;
    // Detections by frame, in file order within a frame; ids follow that order.
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<MotRow>> = Default::default();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(*r);
    }
    let detections: Vec<MotRow> = by_frame.values().flatten().copied().collect();
    let first = by_frame.keys().next().copied().unwrap_or(0);
    let centres = |dets: &[MotRow]| dets.iter().map(|d| d.bbox.centre()).collect::<Vec<Vec2>>();
    let (associations, problem): (Vec<(u64, Vec<MeasId>)>, Problem) = if tracker == Tracker::Mcmcda
    {
        let mut online = OnlineTracker::new(model.clone(), first, settings.online, seed)?;
        for (frame, dets) in &by_frame {
            online.push_scan(*frame, &centres(dets))?;
        }
        let result = online.finish()?;
        (result.associations, result.problem)
    } else {
        let mut problem = Problem::empty(&model, first);
        for (frame, dets) in &by_frame {
            problem.push_scan(*frame, &centres(dets))?;
        }
        let window = problem.all_scans()?;
        let tracks = nearest_neighbour_tracks(&model, &problem, window, &settings.gnn)?;
        let labelled = tracks.into_iter().zip(0..).map(|(t, i)| (i, t)).collect();
        (labelled, problem)
    };
    let mut tracks = Vec::with_capacity(associations.len());
    for (label, meas) in &associations {
        let smoothed = smoothed_tracks(&model, &problem, std::slice::from_ref(meas), label + 1)?;
        let n = meas.len() as f64;
        let width = meas
            .iter()
            .map(|&m| detections[m as usize].bbox.width)
            .sum::<f64>()
            / n;
        let height = meas
            .iter()
            .map(|&m| detections[m as usize].bbox.height)
            .sum::<f64>()
            / n;
        for t in smoothed.tracks() {
            let points = t
                .points()
                .iter()
                .map(|p| {
                    Ok(TrackPoint::boxed(
                        p.frame,
                        BoundingBox::from_centre(p.location.position(), width, height)?,
                    ))
                })
                .collect::<Result<Vec<_>>>()?;
            tracks.push(Track::from_points(t.id(), points)?);
        }
    }
    Ok(TrackSet::from_tracks(tracks)?)
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

    #[test]
    fn the_phd_path_coasts_until_the_filter_has_forgotten() {
        // p_S (1 − p_D) = 0.99 · 0.2: 0.198^k < 1e-12 from k = 18 (by hand: ln 1e-12 / ln 0.198
        // = 27.63 / 1.619 = 17.06).
        assert_eq!(coast_frames(0.99, 0.8), 18);
        // Nearly no forgetting: bounded.
        assert_eq!(coast_frames(0.999_999, 1e-9), MAX_COAST_FRAMES);
    }
}
