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
mod pipelines;
mod plot;
mod report;
mod scenario;

/// Workspace tasks for the tracking toolkit.
#[derive(Parser)]
#[command(name = "cargo xtask", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run every fixtures/scenarios/*.toml and compare its metrics with fixtures/expected/.
    Scenarios {
        /// Rewrite fixtures/expected/NAME.json with the metrics of this run.
        #[arg(long)]
        bless: bool,
        /// Only scenarios whose name contains this text.
        #[arg(long)]
        filter: Option<String>,
    },
    /// Run all scenarios, print each section's tables, and write target/report/.
    Report {
        /// Output directory.
        #[arg(long, default_value = "target/report")]
        out: PathBuf,
    },
    /// fmt, clippy, tests, docs, bench build and the scenario suite: what CI runs.
    Ci,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let outcome = match cli.command {
        Command::Scenarios { bless, filter } => scenario::run_suite(filter.as_deref(), bless),
        Command::Report { out } => report::run(&out),
        Command::Ci => ci::run(),
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
