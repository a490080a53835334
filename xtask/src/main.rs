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
mod eval;
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
    /// fmt, clippy, tests, docs, bench build and the scenario suite: what CI runs.
    Ci,
    /// Track MOTChallenge detections and write MOTChallenge tracks. Without --config each
    /// tracker's model is scaled to the detections' median box size.
    Track {
        /// mcmcda: online sliding-window MCMCDA on the box centres; gnn: global nearest
        /// neighbour with M-of-N confirmation on the box centres (both output smoothed centres
        /// with each track's mean detection size); phd: SMC-PHD on the boxes themselves.
        #[arg(long)]
        tracker: scenarios::track::Tracker,
        /// Detections (frame,id,left,top,width,height,conf,...).
        #[arg(long)]
        input: PathBuf,
        /// Where to write the tracks.
        #[arg(long)]
        out: PathBuf,
        /// TOML with optional `[model]` (fields of `mcmcda::McmcdaConfig`, overriding a model
        /// scaled to the median box width), `[online]`, `[gnn]` and `[phd]` (fields of
        /// `phd_filter::PhdConfig`) tables.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Seed of the tracker's random generator (MCMCDA's chains, the PHD filter's
        /// particles; GNN draws nothing).
        #[arg(long, default_value_t = 0)]
        seed: u64,
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
        } => scenario::run_suite(filter.as_deref(), bless, junit.as_deref()),
        Command::Report {
            out,
            filter,
            screenshots,
        } => report::run(
            &out.unwrap_or_else(|| workspace_root().join("target/report")),
            filter.as_deref(),
            screenshots,
        ),
        Command::Ci => ci::run(),
        Command::Track {
            tracker,
            input,
            out,
            config,
            seed,
        } => track::run(tracker, &input, &out, config.as_deref(), seed),
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
