//! # xtask
//!
//! The project's command runner (`cargo xtask ...`): the scenario regression suite, the report
//! that reproduces the papers' tables on bundled scenarios, and the CI entry point. Only xtask
//! touches files, the clock and the terminal; the library crates stay pure.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};

mod appendix;
mod ci;
mod data;
#[cfg(test)]
mod doc_numbers;
mod eval;
mod fuzz;
mod junit;
mod plot;
mod plot_track;
mod real_video;
mod report;
mod scenario;
mod screenshot;
mod track;
mod tune;

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
    Track(track::TrackArgs),
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
    /// Re-run the tuning search of a scenario on its tuning seeds and write the settings file
    /// it reads (fixtures/tuned/NAME.toml) with every candidate's score (NAME-grid.csv).
    Tune {
        /// The scenario (file stem), e.g. mot-realistic.
        name: String,
        /// Compare with the committed files instead of writing them (exit 1 on a difference).
        #[arg(long)]
        check: bool,
    },
    /// Score a tracker's MOTChallenge output against MOTChallenge ground truth.
    /// Writes the adsb-radar scenario's radar runs (the tuning run and each reported seed) as
    /// plot and truth files to a folder: the real collection when fetched, else the stand-in.
    /// For peers run outside the suite (docs/comparisons/stonesoup_adsb.py).
    ExportPlots {
        /// The folder.
        #[arg(long)]
        out: PathBuf,
    },
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
        /// Score point tracks instead of boxes: both files are CSVs with a header (time_s,
        /// id or track_id, x, y; what `track --plots` writes), matched within this distance,
        /// with OSPA and GOSPA at this cut-off (docs/aircraft.md).
        #[arg(long, conflicts_with = "iou")]
        distance: Option<f64>,
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
        Command::Track(args) => match &args.plots {
            Some(plots) => plot_track::run(plots, &args),
            None => track::run(&args.request()),
        },
        Command::FetchData { name } => data::run(&name),
        Command::Tune { name, check } => tune::run(&name, check),
        Command::Walkers {
            seed,
            fps,
            seconds,
            out,
        } => track::write_walkers(seed, fps, seconds, &out),
        Command::ExportPlots { out } => plot_track::export(&out),
        Command::Eval {
            gt,
            pred,
            iou,
            distance,
            json,
            require,
        } => {
            let matching = match distance {
                Some(distance) => eval::Matching::Points { distance },
                None => eval::Matching::Boxes { iou },
            };
            eval::run(&gt, &pred, matching, json, require.as_deref())
        }
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
