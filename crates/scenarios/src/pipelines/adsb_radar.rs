//! `adsb-radar`: a rotating radar over real aircraft (the `traffic` package's ADS-B quickstart
//! collection, from `cargo xtask fetch-data adsb`; without it, a synthetic stand-in), tracked
//! by GNN with constant velocity, coordinated turns (EKF, UKF) and two IMMs. Each tracker's
//! acceleration noise is chosen from one grid on the first window (a radar seed of its own);
//! the others are scored on the later window over the reported radar seeds, with paired
//! intervals whose verdicts are recorded in the scenario file.

use std::collections::BTreeMap;

use air_traffic::{
    BirthPrior, EnuFrame, MotionSettings, RadarScene, RadarTracker, ReadConfig, RotatingRadar,
    ScoreConfig, StandinConfig, TrackerOutcome, Trajectory, read_collection, run_tracker,
    truth_points, truth_set,
};
use anyhow::{Context, Result, ensure};
use eval_metrics::{
    EvalConfig, MatchConfig, OspaConfig, evaluate, gospa_over_time, ospa_over_time,
};
use mcmcda::PlotGnnConfig;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::TrackSet;

use crate::fresh::{self, Comparison, negated};
use crate::stats::{MeanCi, Verdict};
use crate::{Chart, Claim, Env, Figure, Metrics, Pipeline, Section, Series, Style, Table, fmt_num};

/// The `adsb-radar` pipeline.
pub struct AdsbRadar;

/// A time window: tuning before `split_s`, reporting from it to `end_s`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Windows {
    /// Seconds from the start where tuning ends and reporting begins.
    split_s: f64,
    /// The end of the reported window, seconds.
    end_s: f64,
}

/// GNN settings; the clutter density comes from the radar.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GnnParams {
    gate_chi2: f64,
    confirm_hits: u32,
    confirm_window: u32,
    max_misses: u32,
    max_tracks: usize,
}

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The local frame (its origin is the radar's site unless `radar.position` says otherwise).
    frame: EnuFrame,
    /// How the ADS-B collection becomes trajectories.
    max_gap_s: f64,
    min_duration_s: f64,
    /// Windows on the real collection and on the stand-in.
    real_windows: Windows,
    standin_windows: Windows,
    standin: StandinConfig,
    radar: RotatingRadar,
    gnn: GnnParams,
    birth_sigma_speed_m_s: f64,
    birth_sigma_turn_deg_s: f64,
    /// The grid every tracker's q_accel is chosen from.
    q_accel_grid: Vec<f64>,
    q_turn: f64,
    imm_turn_rate_deg_s: f64,
    switching_cv_turns: [[f64; 3]; 3],
    switching_turn_rate: [[f64; 2]; 2],
    ukf_alpha: f64,
    ukf_beta: f64,
    ukf_kappa: f64,
    match_distance_m: f64,
    turn_threshold_deg_s: f64,
    ospa_cutoff_m: f64,
    tune_seed: u64,
    report_seeds: Vec<u64>,
    /// The recorded verdicts on the stand-in and on the real collection.
    #[serde(default)]
    fresh_verdicts: BTreeMap<String, Verdict>,
    #[serde(default)]
    real_fresh_verdicts: BTreeMap<String, Verdict>,
}

/// One tracker on one radar seed.
#[derive(Debug, Clone)]
pub struct Scores {
    position_rmse_m: f64,
    velocity_rmse_m_s: f64,
    break_rate: f64,
    turning_chances: usize,
    ospa_m: f64,
    gospa_m: f64,
    mota: f64,
    idf1: f64,
}

/// One tracker over the reported seeds, with its tuned q.
#[derive(Debug, Clone)]
pub struct TrackerResult {
    tracker: RadarTracker,
    q_accel: f64,
    /// (q, tuning OSPA) over the grid.
    grid: Vec<(f64, f64)>,
    seeds: Vec<Scores>,
    /// OSPA per revolution on the first reported seed.
    ospa_series: Vec<(f64, f64)>,
}

/// What the run measured.
pub struct Output {
    data: Option<String>,
    aircraft: usize,
    trajectories: Vec<Trajectory>,
    windows: Windows,
    radar: RotatingRadar,
    results: Vec<TrackerResult>,
    fresh: Vec<Comparison>,
    seeds: Vec<u64>,
    fresh_verdicts: BTreeMap<String, Verdict>,
}

fn traffic(
    p: &Params,
    env: &Env<'_>,
    rng: &mut ChaCha8Rng,
) -> Result<(Option<String>, Vec<Trajectory>, Windows)> {
    if let Some(json) = env.inputs.fetched("adsb", "quickstart.json")? {
        let config = ReadConfig {
            frame: p.frame,
            max_gap_s: p.max_gap_s,
            min_duration_s: p.min_duration_s,
        };
        let t = read_collection(&json, &config).context("reading the ADS-B collection")?;
        return Ok((Some("adsb".into()), t, p.real_windows));
    }
    Ok((None, p.standin.generate(rng)?, p.standin_windows))
}

fn motion(p: &Params, q_accel: f64) -> Result<MotionSettings> {
    Ok(MotionSettings {
        q_accel,
        q_turn: p.q_turn,
        imm_turn_rate_rad_s: p.imm_turn_rate_deg_s.to_radians(),
        switching_cv_turns: p.switching_cv_turns,
        switching_turn_rate: p.switching_turn_rate,
        sigma_points: tracker_model::SigmaPoints::new(p.ukf_alpha, p.ukf_beta, p.ukf_kappa)?,
    })
}

fn gnn(p: &Params) -> PlotGnnConfig {
    PlotGnnConfig {
        gate_chi2: p.gnn.gate_chi2,
        clutter_log_density: p.radar.clutter_log_density(),
        confirm_hits: p.gnn.confirm_hits,
        confirm_window: p.gnn.confirm_window,
        max_misses: p.gnn.max_misses,
        max_tracks: p.gnn.max_tracks,
    }
}

/// A radar run's dwells and truth over [start, end).
struct RadarRunData {
    dwells: Vec<air_traffic::RadarDwell>,
    truth: Vec<air_traffic::TruthPoint>,
    truth_set: TrackSet,
}

fn simulate(
    p: &Params,
    trajectories: &[Trajectory],
    seed: u64,
    span: (f64, f64),
) -> Result<RadarRunData> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let dwells = p.radar.simulate(trajectories, span.0, span.1, &mut rng)?;
    let truth = truth_points(&p.radar, trajectories, &dwells)?;
    let truth_set = truth_set(trajectories, &truth)?;
    Ok(RadarRunData {
        dwells,
        truth,
        truth_set,
    })
}

fn scene<'a>(
    p: &Params,
    trajectories: &'a [Trajectory],
    data: &'a RadarRunData,
    radar: &'a RotatingRadar,
) -> RadarScene<'a> {
    RadarScene {
        radar,
        dwells: &data.dwells,
        trajectories,
        truth: &data.truth,
        birth: BirthPrior {
            sigma_speed_m_s: p.birth_sigma_speed_m_s,
            sigma_turn_rad_s: p.birth_sigma_turn_deg_s.to_radians(),
        },
        score: ScoreConfig {
            match_distance_m: p.match_distance_m,
            turn_rate_rad_s: p.turn_threshold_deg_s.to_radians(),
            turn_half_window_s: 5.0,
        },
    }
}

/// OSPA per revolution, (revolution, metres).
fn ospa_series(p: &Params, truth: &TrackSet, tracks: &TrackSet) -> Result<Vec<(f64, f64)>> {
    let cfg = OspaConfig {
        cutoff: p.ospa_cutoff_m,
        order: 2.0,
    };
    Ok(ospa_over_time(truth, tracks, &cfg)?
        .into_iter()
        .map(|(f, o)| (f64::from(f), o.distance))
        .collect())
}

/// The run's scores, and its OSPA per revolution (what the mean is taken over).
fn scores(
    p: &Params,
    data: &RadarRunData,
    outcome: &TrackerOutcome,
) -> Result<(Scores, Vec<(f64, f64)>)> {
    let cfg = OspaConfig {
        cutoff: p.ospa_cutoff_m,
        order: 2.0,
    };
    let mean = |v: Vec<f64>| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let series = ospa_series(p, &data.truth_set, &outcome.tracks)?;
    let ospa = mean(series.iter().map(|(_, d)| *d).collect());
    let gospa = mean(
        gospa_over_time(&data.truth_set, &outcome.tracks, &cfg)?
            .into_iter()
            .map(|(_, g)| g.distance)
            .collect(),
    );
    let eval = EvalConfig {
        matching: MatchConfig::within_distance(p.match_distance_m),
    };
    let m = evaluate(&data.truth_set, &outcome.tracks, &eval)?;
    let scores = Scores {
        position_rmse_m: outcome.score.position_rmse_m,
        velocity_rmse_m_s: outcome.score.velocity_rmse_m_s,
        break_rate: outcome.score.break_rate(),
        turning_chances: outcome.score.turning_chances,
        ospa_m: ospa,
        gospa_m: gospa,
        mota: m.clear.mota,
        idf1: m.identity.idf1,
    };
    Ok((scores, series))
}

/// The q of the grid with the lowest mean OSPA on the tuning window (the first on a tie).
fn tune(
    p: &Params,
    tracker: RadarTracker,
    trajectories: &[Trajectory],
    data: &RadarRunData,
) -> Result<(f64, Vec<(f64, f64)>)> {
    let mut grid = Vec::new();
    for &q in &p.q_accel_grid {
        let outcome = run_tracker(
            tracker,
            &motion(p, q)?,
            gnn(p),
            &scene(p, trajectories, data, &p.radar),
        )?;
        grid.push((q, scores(p, data, &outcome)?.0.ospa_m));
    }
    let best = grid
        .iter()
        .fold(None::<(f64, f64)>, |b, &(q, o)| match b {
            Some((_, bo)) if bo <= o => b,
            _ => Some((q, o)),
        })
        .context("an empty q_accel_grid")?;
    Ok((best.0, grid))
}

fn comparisons(results: &[TrackerResult]) -> Vec<Comparison> {
    let get = |t: RadarTracker| results.iter().find(|r| r.tracker == t);
    let (Some(cv), Some(ct), Some(imm)) = (
        get(RadarTracker::Cv),
        get(RadarTracker::Ct),
        get(RadarTracker::ImmCvTurns),
    ) else {
        return Vec::new();
    };
    let of = |r: &TrackerResult, f: fn(&Scores) -> f64| r.seeds.iter().map(f).collect::<Vec<_>>();
    let lower = |key: &str,
                 statement: &str,
                 ours: &TrackerResult,
                 theirs: &TrackerResult,
                 f: fn(&Scores) -> f64| Comparison {
        key: key.into(),
        statement: statement.into(),
        units: "radar seeds",
        ours: negated(&of(ours, f)),
        theirs: negated(&of(theirs, f)),
    };
    vec![
        lower(
            "imm_rmse_below_cv",
            "IMM CV/CT± position RMSE below CV's",
            imm,
            cv,
            |s| s.position_rmse_m,
        ),
        lower(
            "imm_breaks_below_cv",
            "IMM CV/CT± track breaks during turns below CV's",
            imm,
            cv,
            |s| s.break_rate,
        ),
        lower(
            "imm_ospa_below_cv",
            "IMM CV/CT± OSPA below CV's",
            imm,
            cv,
            |s| s.ospa_m,
        ),
        lower(
            "imm_rmse_below_ct",
            "IMM CV/CT± position RMSE below CT-only's",
            imm,
            ct,
            |s| s.position_rmse_m,
        ),
        lower(
            "imm_breaks_below_ct",
            "IMM CV/CT± track breaks during turns below CT-only's",
            imm,
            ct,
            |s| s.break_rate,
        ),
    ]
}

/// Files by name, with the data set they came from.
pub type ExportedFiles = (Option<String>, Vec<(String, String)>);

/// The scenario's radar runs as plot and truth files, for peers run outside
/// (`docs/comparisons/stonesoup_adsb.py`): `(name, contents)` of `tune-plots.csv`,
/// `tune-truth.csv` and `report-SEED-plots.csv`, `report-SEED-truth.csv` for each reported
/// seed, with the data set they came from (`None`: the stand-in).
pub fn export_plot_files(params: &toml::Table, seed: u64, env: &Env<'_>) -> Result<ExportedFiles> {
    let p = crate::typed_params::<AdsbRadar>(params)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (data, trajectories, windows) = traffic(&p, env, &mut rng)?;
    let mut files = Vec::new();
    let runs = std::iter::once(("tune".to_string(), p.tune_seed, (0.0, windows.split_s))).chain(
        p.report_seeds
            .iter()
            .map(|&s| (format!("report-{s}"), s, (windows.split_s, windows.end_s))),
    );
    for (name, radar_seed, span) in runs {
        let run = simulate(&p, &trajectories, radar_seed, span)?;
        let (plots, truth) =
            air_traffic::format_radar_run(&p.radar, &run.dwells, &trajectories, &run.truth);
        files.push((format!("{name}-plots.csv"), plots));
        files.push((format!("{name}-truth.csv"), truth));
    }
    Ok((data, files))
}

impl Pipeline for AdsbRadar {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        ensure!(!p.report_seeds.is_empty(), "report_seeds is empty");
        crate::seeds::check_disjoint(&[("tuning", &[p.tune_seed]), ("reported", &p.report_seeds)])?;
        let (data, trajectories, windows) = traffic(p, env, rng)?;
        ensure!(
            windows.split_s < windows.end_s,
            "the tuning window must end before the reported one does"
        );
        let tune_data = simulate(p, &trajectories, p.tune_seed, (0.0, windows.split_s))?;
        let reported: Vec<RadarRunData> = p
            .report_seeds
            .par_iter()
            .map(|&s| simulate(p, &trajectories, s, (windows.split_s, windows.end_s)))
            .collect::<Result<_>>()?;
        env.progress.set_length(
            (RadarTracker::ALL.len() * (p.q_accel_grid.len() + p.report_seeds.len())) as u64,
        );
        let results = RadarTracker::ALL
            .par_iter()
            .map(|&tracker| -> Result<TrackerResult> {
                let (q, grid) = tune(p, tracker, &trajectories, &tune_data)?;
                env.progress.advance(p.q_accel_grid.len() as u64);
                let mut seeds = Vec::new();
                let mut series = Vec::new();
                for (k, data) in reported.iter().enumerate() {
                    let outcome = run_tracker(
                        tracker,
                        &motion(p, q)?,
                        gnn(p),
                        &scene(p, &trajectories, data, &p.radar),
                    )?;
                    let (scored, ospa) = scores(p, data, &outcome)?;
                    if k == 0 {
                        series = ospa;
                    }
                    seeds.push(scored);
                    env.progress.advance(1);
                }
                Ok(TrackerResult {
                    tracker,
                    q_accel: q,
                    grid,
                    seeds,
                    ospa_series: series,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let fresh = comparisons(&results);
        let verdicts = if data.is_some() {
            &p.real_fresh_verdicts
        } else {
            &p.fresh_verdicts
        };
        fresh::check_verdicts(&fresh, verdicts)?;
        Ok(Output {
            data,
            aircraft: trajectories
                .iter()
                .map(Trajectory::label)
                .collect::<std::collections::BTreeSet<_>>()
                .len(),
            trajectories,
            windows,
            radar: p.radar,
            results,
            fresh,
            seeds: p.report_seeds.clone(),
            fresh_verdicts: verdicts.clone(),
        })
    }

    fn data_set(out: &Output) -> Option<String> {
        out.data.clone()
    }

    fn metrics(out: &Output) -> Metrics {
        let mut m = Metrics::new();
        for r in &out.results {
            let key = r.tracker.key();
            m.insert(format!("{key}_q_accel"), r.q_accel);
            for (name, f) in score_fields() {
                let v = MeanCi::of(r.seeds.iter().map(f));
                m.insert(format!("{key}_{name}"), v.mean);
                m.insert(format!("{key}_{name}_ci95"), v.ci);
            }
        }
        fresh::metrics(&out.fresh, &mut m);
        m
    }

    fn claims(out: &Output) -> Vec<Claim> {
        fresh::claims(&out.fresh, &out.fresh_verdicts, &seeds_text(&out.seeds))
    }

    fn present(out: &Output) -> Section {
        Section {
            title: "Real aircraft under a rotating radar: GNN with CV, coordinated turns and IMMs"
                .into(),
            summary: summary(out),
            tables: vec![
                fresh::table(
                    &format!(
                        "Reported radar seeds ({}), never used to choose anything: per seed, ours − theirs (lower-is-better quantities negated)",
                        seeds_text(&out.seeds)
                    ),
                    &out.fresh,
                    &out.fresh_verdicts,
                ),
                results_table(out),
                grid_table(out),
            ],
            figures: vec![
                Figure::new(
                    "map",
                    "The aircraft (east, north; km) and the radar's range",
                    map_chart(out),
                ),
                Figure::new(
                    "ospa",
                    "OSPA (c = 2 km, p = 2) per revolution on the first reported radar seed, as a moving mean over 30 revolutions (5 minutes)",
                    ospa_chart(out),
                ),
            ],
        }
    }
}

fn seeds_text(seeds: &[u64]) -> String {
    let list: Vec<String> = seeds.iter().map(u64::to_string).collect();
    format!("radar seeds {}", list.join(", "))
}

type Field = (&'static str, fn(&Scores) -> f64);

fn score_fields() -> [Field; 8] {
    [
        ("position_rmse_m", |s| s.position_rmse_m),
        ("velocity_rmse_m_s", |s| s.velocity_rmse_m_s),
        ("turn_break_rate", |s| s.break_rate),
        ("turning_chances", |s| s.turning_chances as f64),
        ("ospa_m", |s| s.ospa_m),
        ("gospa_m", |s| s.gospa_m),
        ("mota", |s| s.mota),
        ("idf1", |s| s.idf1),
    ]
}

fn summary(out: &Output) -> String {
    let source = match &out.data {
        Some(_) => format!(
            "Data: the `traffic` package's ADS-B quickstart collection (OpenSky; {} aircraft, from `cargo xtask fetch-data adsb`).",
            out.aircraft
        ),
        None => format!(
            "Data: a synthetic stand-in of {} aircraft (straight legs and coordinated turns), because the real collection is not in the cache here; run `cargo xtask fetch-data adsb` for the real aircraft.",
            out.aircraft
        ),
    };
    let r = &out.radar;
    format!(
        "{source} A rotating radar at ({} km, {} km) turns every {} s in {} dwells, ranges {}-{} km, σ_r {} m, σ_θ {} mrad, p_D {}, {} false alarms per revolution. Each tracker's acceleration noise q is chosen from one grid by mean OSPA on the first {} s (radar seed of its own); the results are from {} s to {} s over the reported radar seeds. A break is a revolution in which an aircraft turning faster than the threshold loses the track that held it the revolution before.",
        fmt_num(r.position[0] / 1e3),
        fmt_num(r.position[1] / 1e3),
        fmt_num(r.period_s),
        r.dwells,
        fmt_num(r.min_range_m / 1e3),
        fmt_num(r.max_range_m / 1e3),
        fmt_num(r.sigma_range_m),
        fmt_num(r.sigma_bearing_rad * 1e3),
        fmt_num(r.p_detect),
        fmt_num(r.clutter_per_revolution),
        fmt_num(out.windows.split_s),
        fmt_num(out.windows.split_s),
        fmt_num(out.windows.end_s),
    )
}

fn results_table(out: &Output) -> Table {
    let mut t = Table::new(
        "Each tracker over the reported radar seeds: mean ± 95 % CI",
        &[
            "tracker",
            "q",
            "position RMSE (m)",
            "velocity RMSE (m/s)",
            "breaks per turning revolution",
            "OSPA (m)",
            "GOSPA (m)",
            "MOTA",
            "IDF1",
        ],
    );
    for r in &out.results {
        let cell = |f: fn(&Scores) -> f64| MeanCi::of(r.seeds.iter().map(f)).show();
        t.row(vec![
            r.tracker.name().into(),
            fmt_num(r.q_accel),
            cell(|s| s.position_rmse_m),
            cell(|s| s.velocity_rmse_m_s),
            cell(|s| s.break_rate),
            cell(|s| s.ospa_m),
            cell(|s| s.gospa_m),
            cell(|s| s.mota),
            cell(|s| s.idf1),
        ]);
    }
    t
}

fn grid_table(out: &Output) -> Table {
    let mut header = vec!["tracker".to_string()];
    if let Some(r) = out.results.first() {
        header.extend(
            r.grid
                .iter()
                .map(|(q, _)| format!("OSPA at q = {}", fmt_num(*q))),
        );
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    let mut t = Table::new(
        "The tuning grid: mean OSPA (m) on the tuning window",
        &header,
    );
    for r in &out.results {
        let mut row = vec![r.tracker.name().to_string()];
        row.extend(r.grid.iter().map(|(_, o)| fmt_num(*o)));
        t.row(row);
    }
    t
}

fn map_chart(out: &Output) -> Chart {
    let mut series: Vec<Series> = out
        .trajectories
        .iter()
        .take(60)
        .enumerate()
        .map(|(i, t)| {
            let points = t
                .samples()
                .iter()
                .step_by(10)
                .map(|s| (s.position[0] / 1e3, s.position[1] / 1e3))
                .collect();
            Series::new(
                if i == 0 { "aircraft" } else { "" },
                points,
                Style::ThinLine,
                0,
            )
        })
        .collect();
    let r = &out.radar;
    let ring = (0..=72)
        .map(|k| {
            let a = f64::from(k) * std::f64::consts::TAU / 72.0;
            (
                (r.position[0] + r.max_range_m * a.cos()) / 1e3,
                (r.position[1] + r.max_range_m * a.sin()) / 1e3,
            )
        })
        .collect();
    series.push(Series::new("radar range", ring, Style::Line, 1));
    series.push(
        Series::new(
            "radar",
            vec![(r.position[0] / 1e3, r.position[1] / 1e3)],
            Style::Markers,
            1,
        )
        .in_front(),
    );
    Chart::new("Aircraft and radar", "east (km)", "north (km)", series).with_equal_aspect()
}

fn ospa_chart(out: &Output) -> Chart {
    let series = out
        .results
        .iter()
        .enumerate()
        .filter(|(_, r)| {
            matches!(
                r.tracker,
                RadarTracker::Cv | RadarTracker::Ct | RadarTracker::ImmCvTurns
            )
        })
        .map(|(i, r)| {
            Series::new(
                r.tracker.name(),
                moving_mean(&r.ospa_series, 30),
                Style::Line,
                i,
            )
        })
        .collect();
    Chart::new(
        "OSPA, mean over 30 revolutions",
        "revolution",
        "OSPA (m)",
        series,
    )
}

/// The mean of each run of `width` consecutive points, at the run's last x.
fn moving_mean(points: &[(f64, f64)], width: usize) -> Vec<(f64, f64)> {
    points
        .windows(width.max(1))
        .map(|w| {
            (
                w[w.len() - 1].0,
                w.iter().map(|p| p.1).sum::<f64>() / w.len() as f64,
            )
        })
        .collect()
}
