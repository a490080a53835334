//! # xtask
//!
//! The project's command runner (`cargo xtask ...`): the scenario regression suite, the report
//! that reproduces the papers' tables on bundled scenarios, and the CI entry point. Only xtask
//! touches files, the clock and the terminal; the library crates stay pure.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};

mod ci;
mod data;
mod eval;
mod fuzz;
mod junit;
mod plot;
mod report;
mod scenario;
mod screenshot;
mod track;

/// Workspace tasks for the tracking toolkit.
#[derive(Parser)]
#[command(name = "cargo xtask", bin_name = "cargo xtask", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run every fixtures/scenarios/*.toml, compare its metrics with fixtures/expected/ and
    /// check its claims.
    Scenarios {
        /// Rewrite fixtures/expected/NAME.json with the metrics of this run.
        #[arg(long)]
        bless: bool,
        /// Only scenarios whose name contains this text.
        #[arg(long)]
        filter: Option<String>,
        /// Also write the verdicts as JUnit XML to this file, for CI dashboards.
        #[arg(long)]
        junit: Option<PathBuf>,
        /// Also write every scenario's metrics as JSON to this file (the CI determinism step
        /// compares it across thread counts).
        #[arg(long, hide = true)]
        metrics_out: Option<PathBuf>,
    },
    /// Run the scenarios, print each section's tables, and write the HTML and Markdown report.
    Report {
        /// Output directory [default: target/report in the workspace].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Only scenarios whose name contains this text.
        #[arg(long)]
        filter: Option<String>,
        /// Also take a PNG screenshot of every page with headless Chromium (skipped with a
        /// note when no `chromium` is on the PATH; Debian: `apt-get install chromium`).
        #[arg(long)]
        screenshots: bool,
    },
    /// fmt, clippy, tests, docs, bench build, the determinism check and the scenario suite:
    /// what CI runs.
    Ci {
        /// Only the determinism step (the tracker CLIs and a few scenarios at 1 and 2
        /// threads, outputs compared byte for byte).
        #[arg(long)]
        determinism_only: bool,
    },
    /// Run the cargo-fuzz targets under fuzz/ (needs the nightly toolchain; installs
    /// cargo-fuzz when missing) and print the executions of each.
    Fuzz {
        /// Seconds per target.
        #[arg(long, default_value_t = 60)]
        seconds: u64,
        /// Only the targets whose name contains this text.
        #[arg(long)]
        filter: Option<String>,
    },
    /// Track MOTChallenge detections and write MOTChallenge tracks. Each tracker's model is
    /// fitted to the detections (p_d, clutter, births, noise; printed); --config overrides any key.
    Track {
        /// mcmcda: offline (batch) MCMCDA on the box centres; mcmcda-online: the sliding-window
        /// tracker, output frame by frame; gnn: global nearest neighbour with M-of-N
        /// confirmation on the box centres (all three output boxes fitted to each track's
        /// detections); gnn-online: GNN output frame by frame, coasting through misses; phd:
        /// SMC-PHD on the boxes themselves.
        #[arg(long, required_unless_present = "print_config")]
        tracker: Option<mot::track::TrackerKind>,
        /// Detections (frame,id,left,top,width,height,conf,...).
        #[arg(long, required_unless_present_any = ["print_config", "video"])]
        input: Option<PathBuf>,
        /// Where to write the tracks.
        #[arg(long, required_unless_present = "print_config")]
        out: Option<PathBuf>,
        /// TOML with optional `[model]` (MCMCDA's and GNN's model, overriding a model scaled
        /// to the median box width), `[online]`, `[gnn]` and `[phd]` (overriding a PHD model
        /// scaled to the boxes) tables; every table present is checked. See --print-config
        /// and fixtures/configs/.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Seed of the tracker's random generator (MCMCDA's chains, the PHD filter's
        /// particles; GNN draws nothing).
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Print the effective configuration (every key, its value and a comment) as TOML
        /// that --config loads, and exit: the tables of --tracker (all without it), scaled to
        /// --input's boxes when given, with --config applied.
        #[arg(long)]
        print_config: bool,
        /// With --tracker mcmcda: run the online sliding-window tracker (mcmcda-online); with
        /// --tracker gnn: output frame by frame (gnn-online).
        #[arg(long)]
        online: bool,
        /// A folder of the video's frames (PNG/PGM/PPM, frame number in the file name, e.g.
        /// img1/000001.png). With --tracker phd, SMC-PHD is fused with an image local detector
        /// per target (image-detector), as in the phd-images scenarios; with any tracker,
        /// --overlay draws on them.
        #[arg(long)]
        frames: Option<PathBuf>,
        /// A folder of the video's frames to detect in: the review's camera pipeline
        /// (background mixture with shadow removal, cleaned mask, blobs) makes the detections
        /// instead of --input, and any tracker follows them; with --tracker phd the image
        /// local detectors are fused on the same frames.
        #[arg(long, conflicts_with = "input")]
        video: Option<PathBuf>,
        /// The frame number of the first image of --video or --frames (default: the numbers in
        /// the file names). MOTChallenge frames start at 1.
        #[arg(long)]
        first_frame: Option<u32>,
        /// Write the frames of --video or --frames with the tracks drawn (boxes and ids) as PNG
        /// files to this folder.
        #[arg(long)]
        overlay: Option<PathBuf>,
        /// With --video: also write the detections made as MOTChallenge text to this file.
        #[arg(long, requires = "video")]
        detections_out: Option<PathBuf>,
        /// With --video: TOML of the detector (warmup_frames, [mog] the background mixture,
        /// [post] opening, closing and the smallest blob; mot::video::VideoDetectorConfig).
        #[arg(long, requires = "video")]
        video_config: Option<PathBuf>,
        /// With --tracker phd and --video or --frames: track the detections alone, without the
        /// image local detectors (the frames are then only drawn on by --overlay).
        #[arg(long)]
        no_fusion: bool,
    },
    /// Write a realistic pedestrian sequence (mot::walkers): OUT-det.txt (detections
    /// with scores) and OUT-gt.txt (ground truth), MOTChallenge text.
    Walkers {
        /// Seed of the generator.
        #[arg(long)]
        seed: u64,
        /// Frames per second.
        #[arg(long, default_value_t = 25.0)]
        fps: f64,
        /// Length in seconds.
        #[arg(long, default_value_t = 16.0)]
        seconds: f64,
        /// Path prefix of the two files.
        #[arg(long)]
        out: PathBuf,
    },
    /// Fetch real data that is not committed into a cache outside the repository
    /// ($TRACKING_DATA_DIR, else ~/.cache/tracking-toolkit). vtest: OpenCV's pedestrian video
    /// from Debian's opencv-doc package, frames 300-794 decoded to PNG by ffmpeg.
    FetchData {
        /// The data set: vtest.
        name: String,
    },
    /// Score a tracker's MOTChallenge output against MOTChallenge ground truth.
    Eval {
        /// Ground truth (frame,id,left,top,width,height,conf,...); rows with conf 0 are ignored.
        #[arg(long)]
        gt: PathBuf,
        /// Tracker output in the same format.
        #[arg(long)]
        pred: PathBuf,
        /// IoU a box pair needs to match.
        #[arg(long, default_value_t = 0.5)]
        iou: f64,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Thresholds that must hold, e.g. "MOTA>=0.9,IDF1>=0.8" (any metric of the table;
        /// >=, >, <=, <); the command exits with status 1 when one fails.
        #[arg(long)]
        require: Option<String>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let outcome = match cli.command {
        Command::Scenarios {
            bless,
            filter,
            junit,
            metrics_out,
        } => scenario::run_suite(
            filter.as_deref(),
            bless,
            junit.as_deref(),
            metrics_out.as_deref(),
        ),
        Command::Report {
            out,
            filter,
            screenshots,
        } => report::run(
            &out.unwrap_or_else(|| workspace_root().join("target/report")),
            filter.as_deref(),
            screenshots,
        ),
        Command::Ci { determinism_only } => ci::run(determinism_only),
        Command::Fuzz { seconds, filter } => fuzz::run(seconds, filter.as_deref()),
        Command::Track {
            tracker,
            input,
            out,
            config,
            seed,
            print_config,
            online,
            frames,
            video,
            first_frame,
            overlay,
            detections_out,
            video_config,
            no_fusion,
        } => track::run(&track::Request {
            tracker: match (tracker, online) {
                (Some(mot::track::TrackerKind::Mcmcda), true) => {
                    Some(mot::track::TrackerKind::McmcdaOnline)
                }
                (Some(mot::track::TrackerKind::Gnn), true) => {
                    Some(mot::track::TrackerKind::GnnOnline)
                }
                (t, _) => t,
            },
            input: input.as_deref(),
            out: out.as_deref(),
            config: config.as_deref(),
            seed,
            print_config,
            frames: frames.as_deref(),
            video: video.as_deref(),
            first_frame,
            overlay: overlay.as_deref(),
            detections_out: detections_out.as_deref(),
            video_config: video_config.as_deref(),
            no_fusion,
        }),
        Command::FetchData { name } => data::run(&name),
        Command::Walkers {
            seed,
            fps,
            seconds,
            out,
        } => track::write_walkers(seed, fps, seconds, &out),
        Command::Eval {
            gt,
            pred,
            iou,
            json,
            require,
        } => eval::run(&gt, &pred, iou, json, require.as_deref()),
    };
    match outcome {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(err) => {
            report_error(&err);
            ExitCode::FAILURE
        }
    }
}

#[expect(clippy::print_stderr, reason = "xtask reports errors on the terminal")]
fn report_error(err: &anyhow::Error) {
    eprintln!("error: {err:#}");
}

/// The workspace root (xtask lives one level below it).
fn workspace_root() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().map(PathBuf::from).unwrap_or(manifest)
}

/// Result of a task: `Ok(true)` when everything passed.
type Outcome = Result<bool>;

/// A file's text; the error names the file.
fn read_file(path: &std::path::Path) -> Result<String> {
    use anyhow::Context;
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}
