//! `cargo xtask track --tracker mcmcda|gnn|phd --input DETS.txt --out TRACKS.txt`: reads
//! MOTChallenge detections and an optional configuration, runs `scenarios::track` and writes
//! MOTChallenge tracks.

use std::fs;
use std::path::Path;

use anyhow::{Context, Result};
use scenarios::mot::parse_detections;
use scenarios::track::{TrackConfig, Tracker, track_detections};
use tracker_model::format_mot;

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

/// Runs the command.
#[expect(clippy::print_stdout, reason = "a one-line summary on the terminal")]
pub fn run(
    tracker: Tracker,
    input: &Path,
    out: &Path,
    config: Option<&Path>,
    seed: u64,
) -> Outcome {
    let rows = parse_detections(&read_file(input)?, &input.display().to_string())?;
    let set = track_detections(tracker, &rows, &read_config(config)?, seed)?;
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
