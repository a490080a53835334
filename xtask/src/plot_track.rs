//! `cargo xtask track --plots PLOTS.csv --filter kf|ekf|ukf|imm --out TRACKS.csv`: users' own
//! radar plots tracked by GNN with the chosen filter (air_traffic::track_plots), the tracks
//! written as CSV. `--print-config` prints the effective `PlotTrackConfig`.

use std::fs;
use std::path::Path;

use air_traffic::{PlotFilter, PlotTrackConfig, format_tracks, parse_plots, track_plots};
use anyhow::{Context, Result};

use crate::track::TrackArgs;
use crate::{Outcome, read_file};

fn config(path: Option<&Path>) -> Result<PlotTrackConfig> {
    match path {
        Some(p) => toml::from_str(&read_file(p)?).with_context(|| format!("in {}", p.display())),
        None => Ok(PlotTrackConfig::default()),
    }
}

/// Runs the command.
#[expect(clippy::print_stdout, reason = "the summary goes to the terminal")]
pub fn run(plots: &Path, args: &TrackArgs) -> Outcome {
    let settings = config(args.config.as_deref())?;
    if args.print_config {
        print!("{}", toml::to_string(&settings)?);
        return Ok(true);
    }
    let out = args.out.as_deref().context("track --plots needs --out")?;
    let filter: PlotFilter = args.filter.parse()?;
    let rows =
        parse_plots(&read_file(plots)?).with_context(|| format!("in {}", plots.display()))?;
    let start = std::time::Instant::now();
    let tracks = track_plots(&rows, filter, &settings)?;
    let elapsed = start.elapsed().as_secs_f64();
    fs::write(out, format_tracks(&tracks)).with_context(|| format!("writing {}", out.display()))?;
    let ids: std::collections::BTreeSet<u64> = tracks.iter().map(|t| t.id).collect();
    println!(
        "{}: {} tracks ({} estimates) from {} plots written to {}; {:.1} ms",
        args.filter,
        ids.len(),
        tracks.len(),
        rows.len(),
        out.display(),
        elapsed * 1e3
    );
    Ok(true)
}

/// `cargo xtask export-plots --out DIR`.
#[expect(clippy::print_stdout, reason = "where the files went")]
pub fn export(out: &Path) -> Outcome {
    let scenario = crate::scenario::load_all(Some("adsb-radar"))?
        .into_iter()
        .find(|s| s.name == "adsb-radar")
        .context("no fixtures/scenarios/adsb-radar.toml")?;
    let env = scenarios::Env::new(
        &scenarios::NoProgress,
        &crate::scenario::WorkspaceFiles,
        &scenarios::NoClock,
    );
    let (data, files) =
        scenarios::export_adsb_radar_plots(&scenario.file.params, scenario.file.seed, &env)?;
    fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    for (name, text) in &files {
        fs::write(out.join(name), text).with_context(|| format!("writing {name}"))?;
    }
    println!(
        "{} files from {} in {}",
        files.len(),
        data.as_deref().unwrap_or("the stand-in"),
        out.display()
    );
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The numbers docs/aircraft.md gives for fixtures/plots: MOTA 0.972, IDF1 0.986 and no
    /// identity switch at 500 m for the three filters, and their mean OSPA.
    #[test]
    fn the_example_plot_file_scores_as_documented() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/plots");
        let plots = parse_plots(&read_file(&root.join("two-aircraft-plots.csv")).unwrap()).unwrap();
        let truth = read_file(&root.join("two-aircraft-truth.csv")).unwrap();
        for (filter, ospa) in [
            (PlotFilter::Ekf, 73.0),
            (PlotFilter::Ukf, 71.9),
            (PlotFilter::Imm, 65.3),
        ] {
            let tracks = track_plots(&plots, filter, &PlotTrackConfig::default()).unwrap();
            let (gt, pred) =
                air_traffic::point_track_sets(&truth, &format_tracks(&tracks)).unwrap();
            let config = eval_metrics::EvalConfig {
                matching: eval_metrics::MatchConfig::within_distance(500.0),
            };
            let m = eval_metrics::evaluate(&gt, &pred, &config).unwrap();
            assert!(
                (m.clear.mota - 0.972).abs() < 5e-4,
                "{filter:?}: {}",
                m.clear.mota
            );
            assert!(
                (m.identity.idf1 - 0.986).abs() < 5e-4,
                "{filter:?}: {}",
                m.identity.idf1
            );
            assert_eq!(m.clear.id_switches, 0);
            let cfg = eval_metrics::OspaConfig {
                cutoff: 500.0,
                order: 2.0,
            };
            let per_frame = eval_metrics::ospa_over_time(&gt, &pred, &cfg).unwrap();
            let mean =
                per_frame.iter().map(|(_, o)| o.distance).sum::<f64>() / per_frame.len() as f64;
            assert!((mean - ospa).abs() < 0.05, "{filter:?}: OSPA {mean}");
        }
    }
}
