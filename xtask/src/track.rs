//! `cargo xtask track --tracker mcmcda|gnn|phd --input DETS.txt --out TRACKS.txt`: reads
//! MOTChallenge detections and an optional configuration, runs `scenarios::track` and writes
//! MOTChallenge tracks. `--print-config` prints the effective configuration instead.

use std::fs;
use std::path::Path;

use anyhow::{Context, Result, bail};
use scenarios::mot::read_detections;
use scenarios::track::{
    TrackConfig, Tracker, empty_output_warning, render_config, track_detections,
};
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

/// What `cargo xtask track` was asked.
pub struct Request<'a> {
    /// The tracker (needed unless printing the configuration).
    pub tracker: Option<Tracker>,
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
        let rows = req.input.map(read_input).transpose()?.unwrap_or_default();
        print!("{}", render_config(&settings.resolve(&rows)?, req.tracker)?);
        return Ok(true);
    }
    let (Some(tracker), Some(input), Some(out)) = (req.tracker, req.input, req.out) else {
        bail!("track needs --tracker, --input and --out (or --print-config)");
    };
    let rows = read_input(input)?;
    let set = track_detections(tracker, &rows, &settings, req.seed)?;
    if let Some(warning) = empty_output_warning(tracker, &rows, &settings.resolve(&rows)?, &set) {
        eprintln!("warning: {warning}");
    }
    let mut boxes = set.to_mot_rows(0.0);
    for row in &mut boxes {
        // Smoothing leaves float noise in the last digits (28.359999999999978); a thousandth
        // of a pixel is far below any detector's precision.
        for v in [
            &mut row.bbox.left,
            &mut row.bbox.top,
            &mut row.bbox.width,
            &mut row.bbox.height,
        ] {
            *v = (*v * 1e3).round() / 1e3;
        }
    }
    fs::write(out, format_mot(&boxes))
        .with_context(|| format!("cannot write {}", out.display()))?;
    println!(
        "{} tracks ({} boxes) from {} detections written to {}",
        set.len(),
        set.n_points(),
        rows.len(),
        out.display()
    );
    Ok(true)
}
