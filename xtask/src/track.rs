//! `cargo xtask track --tracker mcmcda|gnn|phd|sort|bytetrack|ocsort --input DETS.txt --out TRACKS.txt`: reads
//! MOTChallenge detections and an optional configuration, runs `mot::track` and writes
//! MOTChallenge tracks. `--print-config` prints the effective configuration instead.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use mot::frames::FusedSettings;
use mot::text::read_detections;
use mot::track::{
    TrackConfig, TrackerKind, effective_config, empty_output_warning, render_config,
    track_detections_with_frames,
};
use mot::video::{self, VideoDetectorConfig};
use sensors_video::io::FrameFolder;
use tracker_model::{MotRow, format_mot};

use crate::{Outcome, read_file};

/// Reads the optional configuration file.
fn read_config(config: Option<&Path>) -> Result<TrackConfig> {
    match config {
        Some(path) => {
            toml::from_str(&read_file(path)?).with_context(|| format!("in {}", path.display()))
        }
        None => Ok(TrackConfig::default()),
    }
}

/// The detections of `input` (notes printed on stderr).
#[expect(clippy::print_stderr, reason = "notes on the input go to the terminal")]
fn read_input(input: &Path) -> Result<Vec<MotRow>> {
    let (rows, notes) = read_detections(&read_file(input)?, &input.display().to_string())?;
    for note in notes {
        eprintln!("note: {note}");
    }
    Ok(rows)
}

/// `cargo xtask track`'s command line.
#[derive(clap::Args)]
pub struct TrackArgs {
    /// mcmcda: offline (batch) MCMCDA on the box centres; mcmcda-online: the sliding-window
    /// tracker, output frame by frame; gnn: global nearest neighbour with M-of-N
    /// confirmation on the box centres (all three output boxes fitted to each track's
    /// detections); gnn-online: GNN output frame by frame, coasting through misses; phd:
    /// SMC-PHD on the boxes themselves; sort, bytetrack, ocsort: SORT, ByteTrack and OC-SORT
    /// with roboflow trackers 2.6.1's defaults (the detections' own boxes, `[sort]`,
    /// `[bytetrack]`, `[ocsort]`).
    #[arg(long, required_unless_present_any = ["print_config", "plots"])]
    pub tracker: Option<mot::track::TrackerKind>,
    /// Detections (frame,id,left,top,width,height,conf,...).
    #[arg(long, required_unless_present_any = ["print_config", "video", "plots"])]
    pub input: Option<PathBuf>,
    /// Where to write the tracks.
    #[arg(long, required_unless_present = "print_config")]
    pub out: Option<PathBuf>,
    /// TOML with optional `[model]` (MCMCDA's and GNN's model, overriding a model scaled
    /// to the median box width), `[online]`, `[gnn]` and `[phd]` (overriding a PHD model
    /// scaled to the boxes), `[sort]`, `[bytetrack]` and `[ocsort]` tables; every table
    /// present is checked. See --print-config
    /// and fixtures/configs/.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Seed of the tracker's random generator (MCMCDA's chains, the PHD filter's
    /// particles; GNN draws nothing).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print the effective configuration (every key, its value and a comment) as TOML
    /// that --config loads, and exit: the tables of --tracker (all without it), scaled to
    /// --input's boxes when given, with --config applied.
    #[arg(long)]
    pub print_config: bool,
    /// With --tracker mcmcda: run the online sliding-window tracker (mcmcda-online); with
    /// --tracker gnn: output frame by frame (gnn-online).
    #[arg(long)]
    pub online: bool,
    /// A folder of the video's frames (PNG/PGM/PPM, frame number in the file name, e.g.
    /// img1/000001.png). With --tracker phd, SMC-PHD is fused with an image local detector
    /// per target (image-detector), as in the phd-images scenarios; with any tracker,
    /// --overlay draws on them.
    #[arg(long)]
    pub frames: Option<PathBuf>,
    /// A folder of the video's frames to detect in: the review's camera pipeline
    /// (background mixture with shadow removal, cleaned mask, blobs) makes the detections
    /// instead of --input, and any tracker follows them; with --tracker phd the image
    /// local detectors are fused on the same frames.
    #[arg(long, conflicts_with = "input")]
    pub video: Option<PathBuf>,
    /// The frame number of the first image of --video or --frames (default: the numbers in
    /// the file names). MOTChallenge frames start at 1.
    #[arg(long)]
    pub first_frame: Option<u32>,
    /// Write the frames of --video or --frames with the tracks drawn (boxes and ids) as PNG
    /// files to this folder.
    #[arg(long)]
    pub overlay: Option<PathBuf>,
    /// With --video: also write the detections made as MOTChallenge text to this file.
    #[arg(long, requires = "video")]
    pub detections_out: Option<PathBuf>,
    /// With --video: TOML of the detector (warmup_frames, [mog] the background mixture,
    /// [post] opening, closing and the smallest blob; mot::video::VideoDetectorConfig).
    #[arg(long, requires = "video")]
    pub video_config: Option<PathBuf>,
    /// With --tracker phd and --video or --frames: track the detections alone, without the
    /// image local detectors (the frames are then only drawn on by --overlay).
    #[arg(long)]
    pub no_fusion: bool,
    /// A radar plot file (CSV with a header: time_s, sensor, sensor_x, sensor_y, then x, y
    /// or range, bearing, optionally their sigmas; docs/aircraft.md), tracked by GNN with
    /// --filter instead of --tracker; the tracks are written as CSV
    /// (time_s,track_id,x,y,vx,vy,hit). --config then holds air_traffic::PlotTrackConfig's keys.
    #[arg(long, conflicts_with_all = ["input", "video", "frames", "tracker", "online"])]
    pub plots: Option<PathBuf>,
    /// With --plots: kf (constant velocity, position plots), ekf or ukf (coordinated turn
    /// with the rate in the state) or imm (CV and turns at ±3°/s).
    #[arg(long, requires = "plots", default_value = "imm")]
    pub filter: String,
}

impl TrackArgs {
    /// The request these arguments make (`--online` turns mcmcda and gnn into their online
    /// variants).
    pub fn request(&self) -> Request<'_> {
        Request {
            tracker: match (self.tracker, self.online) {
                (Some(TrackerKind::Mcmcda), true) => Some(TrackerKind::McmcdaOnline),
                (Some(TrackerKind::Gnn), true) => Some(TrackerKind::GnnOnline),
                (t, _) => t,
            },
            input: self.input.as_deref(),
            out: self.out.as_deref(),
            config: self.config.as_deref(),
            seed: self.seed,
            print_config: self.print_config,
            frames: self.frames.as_deref(),
            video: self.video.as_deref(),
            first_frame: self.first_frame,
            overlay: self.overlay.as_deref(),
            detections_out: self.detections_out.as_deref(),
            video_config: self.video_config.as_deref(),
            no_fusion: self.no_fusion,
        }
    }
}

/// What `cargo xtask track` was asked.
pub struct Request<'a> {
    /// The tracker (needed unless printing the configuration).
    pub tracker: Option<TrackerKind>,
    /// Detections.
    pub input: Option<&'a Path>,
    /// Where the tracks go.
    pub out: Option<&'a Path>,
    /// The configuration file.
    pub config: Option<&'a Path>,
    /// The tracker's seed.
    pub seed: u64,
    /// Print the effective configuration instead of tracking.
    pub print_config: bool,
    /// A folder of frames: run the PHD tracker fused with image local detectors on them.
    pub frames: Option<&'a Path>,
    /// A folder of frames to detect in by background subtraction (instead of `input`); with
    /// the PHD tracker, also the frames its local detectors search.
    pub video: Option<&'a Path>,
    /// The frame number of the first image of `frames` or `video`.
    pub first_frame: Option<u32>,
    /// Where to write the frames with the tracks drawn (PNG).
    pub overlay: Option<&'a Path>,
    /// Where to write the detections made from `video`.
    pub detections_out: Option<&'a Path>,
    /// TOML of the video detector ([`VideoDetectorConfig`]), defaults where unset.
    pub video_config: Option<&'a Path>,
    /// Run the PHD tracker on the detections alone even with frames (they are drawn on only).
    pub no_fusion: bool,
}

impl Request<'_> {
    /// The frame folder given, `--video` or `--frames`.
    fn folder(&self) -> Option<&Path> {
        self.video.or(self.frames)
    }

    /// The fused tracker's settings when a folder is given to the PHD tracker (named, or
    /// implied by `--frames` alone with `--print-config`), unless `no_fusion`.
    fn fused(&self) -> Option<FusedSettings> {
        let phd = match self.tracker {
            Some(tracker) => tracker == TrackerKind::Phd,
            None => self.frames.is_some(),
        };
        let fused = phd && self.folder().is_some() && !self.no_fusion;
        fused.then(|| FusedSettings {
            first_frame: self.first_frame,
            ..FusedSettings::default()
        })
    }

    /// The folder, opened and renumbered as asked.
    fn open_folder(&self) -> Result<Option<FrameFolder>> {
        let Some(dir) = self.folder() else {
            return Ok(None);
        };
        Ok(Some(FrameFolder::open_numbered(dir, self.first_frame)?))
    }
}

/// Runs the command.
#[expect(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "a summary (or the configuration) on the terminal"
)]
pub fn run(req: &Request<'_>) -> Outcome {
    let settings = read_config(req.config)?;
    if req.print_config {
        print!("{}", config_text(req, &settings)?);
        return Ok(true);
    }
    let (Some(tracker), Some(out)) = (req.tracker, req.out) else {
        bail!("track needs --tracker, --input (or --video) and --out (or --print-config)");
    };
    if req.frames.is_some() && req.fused().is_none() && req.overlay.is_none() {
        bail!(
            "--frames with --tracker {tracker}{}: the frames would only be drawn on, so give \
             --overlay (the image-fused tracker is --tracker phd)",
            if req.no_fusion { " --no-fusion" } else { "" }
        );
    }
    let rows = detections(req)?;
    let start = std::time::Instant::now();
    let fused = req.fused();
    let frames = req.folder().zip(fused.as_ref());
    let (set, effective) =
        track_detections_with_frames(tracker, &rows, &settings, req.seed, frames)?;
    let elapsed = start.elapsed().as_secs_f64();
    if let Some(warning) = empty_output_warning(tracker, &rows, &effective, &set) {
        eprintln!("warning: {warning}");
    }
    write_tracks(&set, out)?;
    let frames: std::collections::BTreeSet<u32> = rows.iter().map(|r| r.frame).collect();
    println!(
        "{tracker}: {} tracks ({} boxes) from {} detections in {} frames written to {}; {}; \
         {:.3} ms per frame",
        set.len(),
        set.n_points(),
        rows.len(),
        frames.len(),
        out.display(),
        fitted_summary(tracker, &effective),
        1e3 * elapsed / frames.len().max(1) as f64
    );
    if let Some(overlay) = req.overlay {
        let Some(folder) = req.open_folder()? else {
            bail!("--overlay draws on the frames of --video or --frames; give one");
        };
        let written = video::write_overlay(&folder, &set, overlay, &mut every_50th("overlay"))?;
        println!(
            "{written} frames with the tracks drawn written to {}",
            overlay.display()
        );
    }
    Ok(true)
}

/// The detections: `--input`'s, or those made from `--video`'s frames (written to
/// `--detections-out` when asked).
#[expect(clippy::print_stderr, reason = "progress of the detector")]
fn detections(req: &Request<'_>) -> Result<Vec<MotRow>> {
    match (req.input, req.video) {
        (Some(input), None) => read_input(input),
        (None, Some(dir)) => {
            let folder = req.open_folder()?.context("--video needs a folder")?;
            let config: VideoDetectorConfig = match req.video_config {
                Some(path) => toml::from_str(&read_file(path)?)
                    .with_context(|| format!("in {}", path.display()))?,
                None => VideoDetectorConfig::default(),
            };
            eprintln!(
                "detecting in {} frames of {} (background mixture, {} warm-up frames)",
                folder.len(),
                dir.display(),
                config.warmup_frames
            );
            let rows = video::detect_folder(&folder, &config, &mut every_50th("detected"))?;
            if let Some(path) = req.detections_out {
                fs::write(path, format_mot(&rows))
                    .with_context(|| format!("cannot write {}", path.display()))?;
            }
            Ok(rows)
        }
        (Some(_), Some(_)) => bail!("give --input or --video, not both"),
        (None, None) => bail!("track needs --input (a detection file) or --video (frames)"),
    }
}

/// A progress callback that prints a line every 50 frames (a pipe shows it too).
#[expect(clippy::print_stderr, reason = "progress on the terminal")]
fn every_50th(what: &'static str) -> impl FnMut(u32) {
    let mut n = 0u64;
    move |frame| {
        n += 1;
        if n.is_multiple_of(50) {
            eprintln!("  {what} {n} frames (frame {frame})");
        }
    }
}

/// Writes the tracks as MOTChallenge text, boxes rounded to a thousandth of a pixel
/// ([`mot::text::format_tracks`]).
fn write_tracks(set: &tracker_model::TrackSet, out: &Path) -> Result<()> {
    fs::write(out, mot::text::format_tracks(set))
        .with_context(|| format!("cannot write {}", out.display()))
}

/// The configuration `--print-config` prints: what the run would use, `--frames` included
/// (which implies the PHD tracker when none is named).
fn config_text(req: &Request<'_>, settings: &TrackConfig) -> Result<String> {
    let rows = if req.input.is_some() || req.video.is_some() {
        detections(req)?
    } else {
        Vec::new()
    };
    let tracker = match (req.tracker, req.frames) {
        (None, Some(_)) => Some(TrackerKind::Phd),
        (tracker, _) => tracker,
    };
    let fused = req.fused();
    let effective = match tracker {
        Some(tracker) => effective_config(tracker, &rows, settings, fused.as_ref())?.0,
        None => settings.resolve(&rows)?,
    };
    Ok(render_config(&effective, tracker)?)
}

/// The fitted parameters the tracker used, on one line.
fn fitted_summary(tracker: TrackerKind, c: &mot::track::EffectiveConfig) -> String {
    let m = &c.model;
    let q = match m.motion.noise() {
        tracker_model::CvNoise::Discrete {
            acceleration_covariance,
        } => acceleration_covariance[(0, 0)],
        tracker_model::CvNoise::WhiteAcceleration { q } => q,
    };
    match tracker {
        TrackerKind::Phd => format!(
            "p_d {:.3}, clutter {:.3}/frame, births {:.4}/frame",
            c.phd.p_detect, c.phd.clutter_rate, c.phd.birth_rate
        ),
        TrackerKind::Sort | TrackerKind::ByteTrack | TrackerKind::OcSort => format!(
            "the [{tracker}] settings (roboflow trackers 2.6.1's defaults unless --config sets \
             them); scores read as they are"
        ),
        _ => {
            format!(
                "fitted p_d {:.3}, clutter {:.3}/frame, births {:.4}/frame, R diag [{:.2}, {:.2}] px², \
             q {:.3} px²/frame⁴, v̄ {:.1} px/frame, d̄ {} frames; {}",
                m.p_detect,
                m.clutter_per_scan,
                m.births_per_scan,
                m.measurement_noise[(0, 0)],
                m.measurement_noise[(1, 1)],
                q,
                m.max_speed,
                m.max_gap,
                c.score_model
                    .as_ref()
                    .map_or_else(|| "scores unused".to_string(), |s| s.summary())
            ) + &dropped(c)
        }
    }
}

/// GNN's detections dropped below `[scores] gnn_min_log_ratio`, if any.
fn dropped(c: &mot::track::EffectiveConfig) -> String {
    if c.gnn_dropped == 0 {
        return String::new();
    }
    format!(
        "; {} detections with ln f₁/f₀ < {} dropped and the model fitted to the rest",
        c.gnn_dropped, c.scores.gnn_min_log_ratio
    )
}

/// `cargo xtask walkers`: writes `OUT-det.txt` and `OUT-gt.txt`.
#[expect(clippy::print_stdout, reason = "what was written goes to the terminal")]
pub fn write_walkers(seed: u64, fps: f64, seconds: f64, out: &Path) -> Outcome {
    let config = mot::walkers::WalkersConfig {
        fps,
        duration_s: seconds,
        ..Default::default()
    };
    let seq = config.generate_seeded(seed)?;
    for (suffix, rows) in [("det", &seq.detections), ("gt", &seq.gt)] {
        let path = format!("{}-{suffix}.txt", out.display());
        fs::write(&path, format_mot(rows)).with_context(|| format!("cannot write {path}"))?;
    }
    println!(
        "{} frames, {} truth boxes, {} detections: {}-det.txt, {}-gt.txt",
        seq.n_frames,
        seq.gt.len(),
        seq.detections.len(),
        out.display(),
        out.display()
    );
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn print_config_shows_what_frames_change() {
        let dir = std::env::temp_dir().join(format!("xtask-track-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let seq = mot::walkers::WalkersConfig::default()
            .generate_seeded(3)
            .unwrap();
        let input = dir.join("det.txt");
        fs::write(&input, format_mot(&seq.detections)).unwrap();
        let request = |frames| Request {
            tracker: Some(TrackerKind::Phd),
            input: Some(&input),
            out: None,
            config: None,
            seed: 1,
            print_config: true,
            frames,
            video: None,
            first_frame: None,
            overlay: None,
            detections_out: None,
            video_config: None,
            no_fusion: false,
        };
        let settings = TrackConfig::default();
        let plain = config_text(&request(None), &settings).unwrap();
        let fused = config_text(&request(Some(&dir)), &settings).unwrap();
        let fused_p = mot::frames::FusedSettings::default().p_detect;
        // The run with --frames uses the fused detection probability; the printed
        // configuration must say so (it printed the plain one before).
        assert!(fused.contains(&format!("p_detect = {fused_p}")), "{fused}");
        assert_ne!(plain, fused);
        fs::remove_dir_all(&dir).unwrap();
    }
}
