//! `av-fusion`: the audio-video tracker of Kushwaha, Oh, Amundson, Koutsoukos & Ledeczi
//! (MFI 2008, Figs. 7–11; reviewed in Oh 2012, §V) end to end. Table 1's layout: a 35 × 20 m region in
//! 0.5 m cells, six acoustic nodes (36 beams) and three cameras (160 angles) either side of a
//! road. Vehicles are simulated through sensors-audio (engine-like sources, ground reflection,
//! diffuse background noise) and through the sensors-video renderer (cameras at an angle to
//! the road, swaying foliage, glint, sensor noise, background mixture segmentation); the
//! fusion node of the av-fusion crate buffers the reports, fuses them on the grid at 10 Hz and
//! online MCMCDA tracks the peaks. Six approaches (audio, video, audio+video × weighted sum,
//! product) over nine single-vehicle passes of the paper's durations (2.75–4.5 s), error
//! against camera calibration error, and runs with two and three vehicles (OSPA, MOTA).
//!
//! Every run uses one configuration per approach, whatever its number of vehicles:
//! `fixtures/tuned/av-fusion-road.toml`, written by `cargo xtask tune av-fusion-road` from
//! the tuning seeds alone. The earlier count-aware settings, which read the true number of
//! vehicles, are scored beside it as a reference. The claims are made on fresh seeds
//! (`fresh.rs`), each by a paired 95 % interval whose verdict is recorded; the reported seed's
//! runs are shown, not claimed.
//!
//! The scene, its simulator, the scoring of a run and the searches are `av_fusion::scene` and
//! `av_fusion::tuning`; this module runs the experiment and writes its report, and
//! `developer.rs` starts the diagnostic tools on the developer's options.

use std::collections::BTreeMap;

use anyhow::{Context, Result};
use av_fusion::scene::{
    Approach, ApproachSettings, Calibration, MPS_PER_MPH, PerApproach, REGION_M, RunSpec, Settings,
    Simulated, check_params, check_settings, nominal, peak_scores_of, run_specs, score_count_aware,
    score_with, sensor_nodes, simulate_run,
};
use av_fusion::{Modalities, SensorKind};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::{Track, TrackSet};

mod developer;
mod fresh;

use crate::stats::{MeanCi, Verdict, mean_ci};
use crate::tune::{GridRow, Tuned, grid_csv, settings_file};
use crate::{
    BAR_WIDTH, Chart, Claim, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style,
    Table, fill, fmt_num,
};

/// The `av-fusion` pipeline.
pub struct AvFusion;

/// The scenario's parameters: the scene, the settings file of the one configuration and the
/// verdicts recorded from the first fresh run.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The one configuration's settings file (`cargo xtask tune av-fusion-road`).
    tuned: String,
    /// Each fresh comparison's verdict, recorded from its first run.
    #[serde(default)]
    fresh_verdicts: BTreeMap<String, Verdict>,
    /// The scene, the count-aware reference and the searches.
    scene: av_fusion::scene::Params,
}

/// One approach on one run.
struct RunScore {
    /// Mean error of each vehicle's paired track (None: no track formed).
    errors: Vec<Option<f64>>,
    /// MOTA.
    mota: f64,
    /// Mean OSPA, m.
    ospa: f64,
    /// Multi-vehicle runs: MOTA with the count-aware reference (`None` for single-vehicle
    /// runs).
    mota_count_aware: Option<f64>,
}

/// One run's results.
struct RunResult {
    /// Each approach's scores.
    scores: PerApproach<RunScore>,
    /// Per calibration sweep value: each approach's mean error over vehicles (None: no track,
    /// or an approach the sweep does not run).
    sweep: Vec<PerApproach<Option<f64>>>,
    /// For the map: max over ticks of the A+V product grid (per tick scaled to max 1), the
    /// tracks and the truth.
    map: Option<MapData>,
}

/// One grid cell of the map.
struct MapCell {
    /// Centre, m.
    x: f64,
    /// Centre, m.
    y: f64,
    /// Fused likelihood, each tick scaled to max 1, max over the ticks.
    likelihood: f64,
}

/// One sensor of the map.
struct MapSensor {
    /// Position, m.
    x: f64,
    /// Position, m.
    y: f64,
    /// Acoustic node or camera.
    kind: SensorKind,
}

/// The map of the last run: the fused likelihood, the tracks, the truth and the sensors.
struct MapData {
    cells: Vec<MapCell>,
    tracks: Vec<Vec<(f64, f64)>>,
    truth: Vec<Vec<(f64, f64)>>,
    sensors: Vec<MapSensor>,
}

/// One single-vehicle pass.
struct Pass {
    /// Seconds across the region.
    duration_s: f64,
    /// Speed, mph.
    speed_mph: f64,
}

/// The calibration sweep at one heading error.
struct SweepPoint {
    /// The heading error δ of every node, degrees.
    heading_error_deg: f64,
    /// Per approach, per pass: the mean error over the pass's vehicles (None: no track, or
    /// an approach the sweep does not run).
    errors: PerApproach<Vec<Option<f64>>>,
}

/// One approach on one multi-vehicle run.
struct MultiScore {
    /// MOTA.
    mota: f64,
    /// Mean OSPA, m.
    ospa: f64,
    /// MOTA with the count-aware reference.
    mota_count_aware: Option<f64>,
}

/// One multi-vehicle run.
struct MultiRun {
    /// Vehicles in the run.
    vehicles: usize,
    /// Each approach's scores.
    scores: PerApproach<MultiScore>,
}

/// What the pipeline computed.
pub struct Output {
    passes: Vec<Pass>,
    /// Per approach, per pass: the error of the pass's track.
    errors: PerApproach<Vec<Option<f64>>>,
    sweep: Vec<SweepPoint>,
    multi: Vec<MultiRun>,
    map: Option<MapData>,
    calibration_error_deg: f64,
    audio_calibration_error_deg: f64,
    /// The fresh seeds' runs.
    fresh: fresh::Fresh,
}

/// Approach `a` on `sim` with its settings `s` and their peak scores, nodes at `calib`.
fn score_one(
    p: &av_fusion::scene::Params,
    sim: &Simulated,
    calib: Calibration,
    a: Approach,
    s: &ApproachSettings,
) -> Result<av_fusion::scene::Score> {
    Ok(score_with(p, sim, calib, a, s, peak_scores_of(p, a, s)?)?)
}

fn run_one(
    p: &av_fusion::scene::Params,
    one: &Settings,
    run: &RunSpec,
    rng: &mut ChaCha8Rng,
    want_map: bool,
) -> Result<RunResult> {
    let sim = simulate_run(p, run, rng)?;
    let mut map = None;
    let scores = PerApproach::try_from_fn(|a| -> Result<RunScore> {
        let s = score_one(p, &sim, nominal(p), a, one.get(a))?;
        // The reference: the count-aware settings (they read the true count).
        let mota_count_aware = if sim.multi {
            Some(score_count_aware(p, &sim, nominal(p), a)?.mota)
        } else {
            None
        };
        if want_map && a == Approach::AudioVideoProduct {
            map = Some(map_data(p, one, &s.result, &sim.gt)?);
        }
        Ok(RunScore {
            errors: s.errors,
            mota: s.mota,
            ospa: s.ospa,
            mota_count_aware,
        })
    })?;
    let sweep = p
        .calibration_sweep_deg
        .iter()
        .map(|&deg| sweep_errors(p, one, &sim, &scores, deg))
        .collect::<Result<_>>()?;
    Ok(RunResult { scores, sweep, map })
}

/// One run's mean error per approach with every node at heading error ±`deg` (`nominal`: the
/// errors already in `scores`).
fn sweep_errors(
    p: &av_fusion::scene::Params,
    one: &Settings,
    sim: &Simulated,
    scores: &PerApproach<RunScore>,
    deg: f64,
) -> Result<PerApproach<Option<f64>>> {
    let calib = Calibration {
        audio_deg: deg,
        video_deg: deg,
    };
    PerApproach::try_from_fn(|a| {
        // The sweep runs the product rule only, on the single-vehicle passes (time budget;
        // the report averages it over the passes); the nominal setting is done.
        if !a.is_product() || sim.multi {
            return Ok(None);
        }
        let e = if calib == nominal(p) {
            scores.get(a).errors.clone()
        } else {
            score_one(p, sim, calib, a, one.get(a))?.errors
        };
        Ok(average(&e))
    })
}

fn map_data(
    p: &av_fusion::scene::Params,
    one: &Settings,
    run: &av_fusion::AvRun,
    gt: &TrackSet,
) -> Result<MapData> {
    let mut acc: Option<Vec<f64>> = None;
    let mut shape = None;
    for scan in &run.scans {
        let v = scan.grid.values();
        let max = v.iter().copied().fold(0.0, f64::max);
        if max <= 0.0 {
            continue;
        }
        let a = acc.get_or_insert_with(|| vec![0.0; v.len()]);
        for (x, y) in a.iter_mut().zip(v) {
            *x = x.max(y / max);
        }
        shape = Some(&scan.grid);
    }
    let mut cells = Vec::new();
    if let (Some(a), Some(g)) = (acc, shape) {
        let (cols, _) = g.shape();
        for (i, v) in a.iter().enumerate() {
            let c = g.cell_centre(i % cols, i / cols);
            cells.push(MapCell {
                x: c.x,
                y: c.y,
                likelihood: *v,
            });
        }
    }
    let path = |t: &Track| {
        t.points()
            .iter()
            .map(|q| (q.location.position().x, q.location.position().y))
            .collect()
    };
    Ok(MapData {
        cells,
        tracks: run.tracks.tracks().iter().map(path).collect(),
        truth: gt.tracks().iter().map(path).collect(),
        sensors: sensor_nodes(
            p,
            Calibration {
                audio_deg: 0.0,
                video_deg: 0.0,
            },
            one.get(Approach::AudioVideoProduct),
        )?
        .iter()
        .map(|n| MapSensor {
            x: n.pose.position.x,
            y: n.pose.position.y,
            kind: n.kind,
        })
        .collect(),
    })
}

/// The one configuration, read from its settings file and checked against the scene.
fn one_config(p: &Params, env: &Env<'_>) -> Result<Settings> {
    let text = env.inputs.read_to_string(&p.tuned)?;
    let one: Settings =
        toml::from_str(&text).with_context(|| format!("reading the settings file {}", p.tuned))?;
    check_settings(&p.scene, &one).with_context(|| format!("the settings of {}", p.tuned))?;
    Ok(one)
}

/// The reported seed's runs (the generator `rng`, run i on stream i).
fn reported_runs(
    p: &av_fusion::scene::Params,
    one: &Settings,
    runs: &[RunSpec],
    rng: &ChaCha8Rng,
    env: &Env<'_>,
) -> Result<Vec<RunResult>> {
    runs.par_iter()
        .enumerate()
        .map(|(i, run)| {
            let mut rng = rng.clone();
            rng.set_stream(i as u64);
            let r = run_one(p, one, run, &mut rng, i + 1 == runs.len());
            env.progress.advance(1);
            r
        })
        .collect()
}

/// The settings file's header: what wrote it, from which seeds, by which objective.
fn tuned_header(p: &av_fusion::scene::Params) -> String {
    let seeds: Vec<String> = p.tuning.seeds.iter().map(u64::to_string).collect();
    format!(
        "Written by `cargo xtask tune av-fusion-road`: do not edit. The one configuration:\n\
         each approach's settings for every run, one vehicle or several, chosen for it alone\n\
         by the coordinate search of [params.scene.tuning] on every run of seeds {} (never\n\
         the reported or fresh seeds), from the better of its two count-aware settings, by\n\
         J = ½ mean MOTA (passes) + ½ mean MOTA (multi-vehicle runs) − {} × mean pass error\n\
         (m). Every candidate's J is in the grid CSV beside this file.",
        seeds.join(", "),
        p.tuning.error_weight_per_m
    )
}

impl Pipeline for AvFusion {
    type Params = Params;
    type Output = Output;

    fn compute(params: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let p = &params.scene;
        check_params(p, env.seed)?;
        fresh::check_verdicts(&params.fresh_verdicts)?;
        let one = one_config(params, env)?;
        let runs = run_specs(p)?;
        developer::run_tools(env.developer, p, &one, &runs, env.seed)?;
        env.progress
            .set_length((runs.len() + fresh::job_count(params, &runs)) as u64);
        let mut results = reported_runs(p, &one, &runs, rng, env)?;
        let fresh = fresh::run(params, &one, &runs, env)?;
        let map = results.iter_mut().rev().find_map(|r| r.map.take());
        let (singles, multis) = results.split_at(p.passes.len());
        let errors =
            PerApproach::from_fn(|a| singles.iter().map(|r| r.scores.get(a).errors[0]).collect());
        let sweep = p
            .calibration_sweep_deg
            .iter()
            .enumerate()
            .map(|(s, &deg)| SweepPoint {
                heading_error_deg: deg,
                errors: PerApproach::from_fn(|a| {
                    singles.iter().map(|r| *r.sweep[s].get(a)).collect()
                }),
            })
            .collect();
        let multi = multis
            .iter()
            .zip(&p.multi)
            .map(|(r, spec)| MultiRun {
                vehicles: spec.len(),
                scores: r.scores.map(|_, s| MultiScore {
                    mota: s.mota,
                    ospa: s.ospa,
                    mota_count_aware: s.mota_count_aware,
                }),
            })
            .collect();
        Ok(Output {
            passes: p
                .passes
                .iter()
                .map(|s| Pass {
                    duration_s: s.duration_s,
                    speed_mph: REGION_M[0] / s.duration_s / MPS_PER_MPH,
                })
                .collect(),
            errors,
            sweep,
            multi,
            map,
            calibration_error_deg: p.calibration_error_deg,
            audio_calibration_error_deg: p.audio_calibration_error_deg,
            fresh,
        })
    }

    fn tune(params: &Params, env: &Env<'_>) -> Result<Option<Tuned>> {
        let p = &params.scene;
        check_params(p, env.seed)?;
        let seeded: Vec<(u64, ChaCha8Rng)> = p
            .tuning
            .seeds
            .iter()
            .map(|&seed| (seed, ChaCha8Rng::seed_from_u64(seed)))
            .collect();
        let log = |line: &str| env.developer.say(line);
        let (settings, rows) =
            av_fusion::tuning::tune_one_config(p, &run_specs(p)?, &seeded, &log)?;
        let grid: Vec<GridRow> = rows
            .iter()
            .map(|r| GridRow {
                round: r.round,
                key: format!("{}.{}", r.approach.settings_key(), r.coordinate),
                value: fmt_num(r.value),
                score: r.score,
                chosen: r.kept,
            })
            .collect();
        let table = toml::Table::try_from(settings)?;
        Ok(Some(Tuned {
            settings: settings_file(&tuned_header(p), &table)?,
            grid: grid_csv(&grid),
        }))
    }

    fn metrics(out: &Output) -> Metrics {
        let mut m = Metrics::new();
        for a in Approach::ALL {
            let key = metric_key(a);
            let found: Vec<f64> = out.errors.get(a).iter().flatten().copied().collect();
            let (mean, ci) = mean_ci(&found);
            if mean.is_finite() {
                m.insert(format!("error_m_{key}_mean"), mean);
                m.insert(format!("error_m_{key}_ci95"), ci);
            }
            m.insert(format!("passes_tracked_{key}"), found.len() as f64);
            for point in &out.sweep {
                if let Some(e) = average(point.errors.get(a)) {
                    let deg = point.heading_error_deg;
                    m.insert(format!("calibration_{deg}deg_error_m_{key}"), e);
                }
            }
            for (r, run) in out.multi.iter().enumerate() {
                let (n, s) = (run.vehicles, run.scores.get(a));
                m.insert(format!("multi{r}_{n}veh_mota_{key}"), s.mota);
                m.insert(format!("multi{r}_{n}veh_ospa_m_{key}"), s.ospa);
                if let Some(x) = s.mota_count_aware {
                    m.insert(format!("multi{r}_{n}veh_mota_{key}_count_aware"), x);
                }
            }
        }
        fresh::metrics(&out.fresh, &mut m, metric_key);
        m
    }

    fn claims(out: &Output) -> Vec<Claim> {
        fresh::claims(&out.fresh)
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let f = &out.fresh;
        let fmt = |a: Approach| {
            let e = MeanCi::of(f.pass_errors(a, fresh::Config::One));
            format!("{} m", e.show())
        };
        vec![Headline {
            quantity: format!(
                "Average tracking error, audio+video, one configuration, {} fresh \
                 single-vehicle passes (a pass without a track counts 5 m)",
                f.passes()
            ),
            paper: Some("≈ 2 m (Kushwaha et al. 2008, Figs. 10–11)".into()),
            ours: format!(
                "{} (product), {} (weighted sum)",
                fmt(Approach::AudioVideoProduct),
                fmt(Approach::AudioVideoSum)
            ),
            peer: None,
        }]
    }

    fn present(out: &Output) -> Section {
        let mut figures = fresh::figures(&out.fresh);
        figures.extend(reported_figures(out));
        if let Some(map) = &out.map {
            figures.push(map_figure(map));
        }
        Section {
            title: "Audio-video fusion tracked by MCMCDA (Kushwaha et al. 2008)".into(),
            summary: summary(out),
            tables: vec![
                fresh::means_table(&out.fresh),
                fresh::comparisons_table(&out.fresh),
                per_pass_table(out),
                sweep_table(out),
                multi_table(out),
            ],
            figures,
        }
    }
}

/// Each pass's error per approach, their means, and fusion's paired gains.
fn per_pass_table(out: &Output) -> Table {
    let mut header = vec!["pass", "duration (s)", "speed (mph)"];
    header.extend(Approach::ALL.map(Approach::name));
    let mut per_pass = Table::new(
        &format!(
            "Mean tracking error (m) per pass and approach, heading error ±{}° (cameras) and ±{}° (acoustic nodes); — = no track formed",
            fmt_num(out.calibration_error_deg),
            fmt_num(out.audio_calibration_error_deg)
        ),
        &header,
    );
    let cell = |e: Option<f64>| e.map_or("—".to_string(), fmt_num);
    for (i, pass) in out.passes.iter().enumerate() {
        let mut row = vec![
            (i + 1).to_string(),
            fmt_num(pass.duration_s),
            fmt_num(pass.speed_mph),
        ];
        row.extend(out.errors.iter().map(|(_, e)| cell(e[i])));
        per_pass.row(row);
    }
    let mut avg_row = vec!["mean ± 95 % CI".into(), String::new(), String::new()];
    for (_, errors) in out.errors.iter() {
        let found: Vec<f64> = errors.iter().flatten().copied().collect();
        let (m, c) = mean_ci(&found);
        avg_row.push(if found.is_empty() {
            "—".into()
        } else {
            format!(
                "{} ± {} ({}/{})",
                fmt_num(m),
                fmt_num(c),
                found.len(),
                out.passes.len()
            )
        });
    }
    per_pass.row(avg_row);
    for (over, label) in [
        (
            Modalities::Audio,
            "paired gain over audio (audio − audio+video), mean ± 95 % CI",
        ),
        (
            Modalities::Video,
            "paired gain over video (video − audio+video), mean ± 95 % CI",
        ),
    ] {
        let mut gain_row = vec![label.into(), String::new(), String::new()];
        gain_row.extend(
            Approach::ALL.map(|a| fusion_gain(out, a, over).map_or(String::new(), |g| g.show())),
        );
        per_pass.row(gain_row);
    }
    per_pass
}

/// MOTA and mean OSPA of every approach on every multi-vehicle run.
fn multi_table(out: &Output) -> Table {
    let mut multi = Table::new(
        "Reported seed, multi-vehicle runs (not attempted in the paper): MOTA and mean OSPA \
         (order 1) per approach with the one configuration, and MOTA with the count-aware \
         reference",
        &[
            "run",
            "vehicles",
            "approach",
            "MOTA",
            "mean OSPA (m)",
            "MOTA, count-aware",
        ],
    );
    for (r, run) in out.multi.iter().enumerate() {
        for (a, s) in run.scores.iter() {
            multi.row(vec![
                (r + 1).to_string(),
                run.vehicles.to_string(),
                a.name().into(),
                fmt_num(s.mota),
                fmt_num(s.ospa),
                s.mota_count_aware.map_or("—".into(), fmt_num),
            ]);
        }
    }
    multi
}

/// The approaches of the calibration sweep: the product rule's.
fn swept() -> impl Iterator<Item = Approach> {
    Approach::ALL.into_iter().filter(|a| a.is_product())
}

/// The average error against the nodes' heading error, product rule.
fn sweep_table(out: &Output) -> Table {
    let cell = |e: Option<f64>| e.map_or("—".to_string(), fmt_num);
    let mut header = vec!["heading error δ (°)"];
    header.extend(swept().map(Approach::name));
    let mut sweep_table = Table::new(
        "Average error (m) over the passes against the heading error δ of every node (cameras and acoustic nodes alike, signs alternating), product rule",
        &header,
    );
    for point in &out.sweep {
        let mut row = vec![fmt_num(point.heading_error_deg)];
        row.extend(swept().map(|a| cell(average(point.errors.get(a)))));
        sweep_table.row(row);
    }
    sweep_table
}

/// An approach's place within its rule's group of bars and its colour: audio 0, video 1,
/// audio+video 2.
fn modality_slot(a: Approach) -> usize {
    match a.modalities() {
        Modalities::Audio => 0,
        Modalities::Video => 1,
        Modalities::Both => 2,
    }
}

/// Grouped bars per pass index, as the paper's Figs. 10-11 (the product rule's approaches or
/// the weighted sum's); a missing bar is a pass with no track.
fn bar_chart(out: &Output, rule_product: bool) -> Chart {
    let series = Approach::ALL
        .into_iter()
        .filter(|a| a.is_product() == rule_product)
        .map(|a| {
            let m = modality_slot(a);
            let pts = out
                .errors
                .get(a)
                .iter()
                .enumerate()
                .filter_map(|(i, e)| e.map(|e| ((i + 1) as f64 + BAR_WIDTH * (m as f64 - 1.0), e)))
                .collect();
            Series::new(a.name(), pts, Style::Bars, m)
        })
        .collect();
    Chart::new(
        if rule_product {
            "Per-pass error, product fusion (cf. Fig. 11)"
        } else {
            "Per-pass error, weighted-sum fusion (cf. Fig. 10)"
        },
        "pass",
        "mean tracking error (m)",
        series,
    )
}

/// The reported seed's per-pass bars (the paper's Figs. 10-11), the averages and the
/// calibration sweep.
fn reported_figures(out: &Output) -> Vec<Figure> {
    let avg_chart = Chart::new(
        "Average error of the six approaches",
        "approach (1–3: sum, 4–6: product; audio, video, audio+video)",
        "average error (m)",
        out.errors
            .iter()
            .filter_map(|(a, errors)| {
                average(errors).map(|e| {
                    let x = (a.index() + 1) as f64;
                    Series::new(a.name(), vec![(x, e)], Style::Bars, modality_slot(a))
                })
            })
            .collect(),
    );
    let sweep_chart = Chart::new(
        "Error against calibration error",
        "heading error δ of cameras and acoustic nodes (°)",
        "average error (m)",
        swept()
            .map(|a| {
                let pts = out
                    .sweep
                    .iter()
                    .filter_map(|s| average(s.errors.get(a)).map(|e| (s.heading_error_deg, e)))
                    .collect();
                Series::new(a.name(), pts, Style::Line, a.index())
            })
            .collect(),
    );
    vec![
        Figure::new(
            "errors-sum",
            "Mean error of each pass's track, weighted-sum fusion; a missing bar is a pass where no track formed",
            bar_chart(out, false),
        ),
        Figure::new(
            "errors-product",
            "Mean error of each pass's track, product fusion; a missing bar is a pass where no track formed",
            bar_chart(out, true),
        ),
        Figure::new(
            "errors-average",
            "Average over the passes with a track",
            avg_chart,
        ),
        Figure::new(
            "calibration",
            "Average error against the nodes' heading error (the same δ for cameras and acoustic nodes; signs alternate between nodes)",
            sweep_chart,
        ),
    ]
}

/// The fused likelihood of the last multi-vehicle run with the truth, the tracks and the
/// sensors.
fn map_figure(map: &MapData) -> Figure {
    let mut series = Vec::new();
    for (k, (lo, hi)) in [(0.25, 0.5), (0.5, 0.75), (0.75, 1.01)].iter().enumerate() {
        let pts = map
            .cells
            .iter()
            .filter(|c| c.likelihood >= *lo && c.likelihood < *hi)
            .map(|c| (c.x, c.y))
            .collect();
        series.push(Series::new(
            &format!("likelihood {lo}–{}", hi.min(1.0)),
            pts,
            Style::Markers,
            [7, 2, 1][k],
        ));
    }
    // The truth and the tracks over the likelihood dots, which hid the thin grey truth.
    for (i, t) in map.truth.iter().enumerate() {
        let label = if i == 0 { "truth" } else { "" };
        series.push(Series::new(label, t.clone(), Style::Line, 5).in_front());
    }
    for (i, t) in map.tracks.iter().enumerate() {
        let label = if i == 0 { "tracks" } else { "" };
        series.push(Series::new(label, t.clone(), Style::Line, 0).in_front());
    }
    for (kind, label, colour) in [
        (SensorKind::Audio, "acoustic nodes", 3),
        (SensorKind::Video, "cameras", 4),
    ] {
        series.push(Series::new(
            label,
            map.sensors
                .iter()
                .filter(|s| s.kind == kind)
                .map(|s| (s.x, s.y))
                .collect(),
            Style::Markers,
            colour,
        ));
    }
    Figure::new(
        "map",
        "Last multi-vehicle run, audio+video product: the fused likelihood (each tick scaled to maximum 1, maximum over the ticks) with the tracks over it",
        Chart::new("Fused likelihood and tracks", "x (m)", "y (m)", series).with_equal_aspect(),
    )
}

/// Audio alone against audio+video under one rule: (audio, audio+video, the rule's name).
const RULES: [(Approach, Approach, &str); 2] = [
    (Approach::AudioSum, Approach::AudioVideoSum, "sum"),
    (
        Approach::AudioProduct,
        Approach::AudioVideoProduct,
        "product",
    ),
];

/// Per rule, the single-vehicle passes (numbered from 1) where audio alone beats audio+video
/// (a lower error, or a track where fusion formed none).
fn audio_wins(out: &Output) -> Vec<String> {
    RULES
        .iter()
        .map(|&(audio, both, rule)| {
            let passes: Vec<String> = (0..out.passes.len())
                .filter(
                    |&i| match (out.errors.get(audio)[i], out.errors.get(both)[i]) {
                        (Some(ea), Some(eb)) => ea < eb,
                        (Some(_), None) => true,
                        _ => false,
                    },
                )
                .map(|i| (i + 1).to_string())
                .collect();
            if passes.is_empty() {
                format!("under the {rule} rule, on no pass")
            } else {
                format!("under the {rule} rule, on passes {}", passes.join(", "))
            }
        })
        .collect()
}

/// The section's text: the setting, the one configuration and how it was chosen, the fresh
/// seeds' verdicts and means, where the one configuration loses to the count-aware reference,
/// and the reported seed's averages (the prose is `summary.txt`).
fn summary(out: &Output) -> String {
    let f = &out.fresh;
    let av = |a: Approach| average(out.errors.get(a)).map_or("—".into(), fmt_num);
    let [holds, undecided, loses] = fresh::tally(f);
    let losses = fresh::losses_to_count_aware(f);
    let error = |a: Approach| MeanCi::of(f.pass_errors(a, fresh::Config::One)).show();
    let mota = |a: Approach| MeanCi::of(f.multi_motas(a, fresh::Config::One)).show();
    fill(
        include_str!("summary.txt").trim_end(),
        &[
            ("camera_error", fmt_num(out.calibration_error_deg)),
            ("audio_error", fmt_num(out.audio_calibration_error_deg)),
            ("n_fresh", f.seeds.len().to_string()),
            ("fresh_passes", f.passes().to_string()),
            ("fresh_multi", f.multi_runs().to_string()),
            ("n_comparisons", (holds + undecided + loses).to_string()),
            ("holds", holds.to_string()),
            ("undecided", undecided.to_string()),
            ("loses", loses.to_string()),
            (
                "count_aware_losses",
                if losses.is_empty() {
                    "nowhere".into()
                } else {
                    losses.join("; ")
                },
            ),
            ("fresh_av_sum", error(Approach::AudioVideoSum)),
            ("fresh_av_product", error(Approach::AudioVideoProduct)),
            ("fresh_audio_sum", error(Approach::AudioSum)),
            ("fresh_audio_product", error(Approach::AudioProduct)),
            ("fresh_video_sum", error(Approach::VideoSum)),
            ("fresh_video_product", error(Approach::VideoProduct)),
            ("fresh_mota_sum", mota(Approach::AudioVideoSum)),
            ("fresh_mota_product", mota(Approach::AudioVideoProduct)),
            ("fresh_mota_audio_product", mota(Approach::AudioProduct)),
            ("av_sum", av(Approach::AudioVideoSum)),
            ("av_product", av(Approach::AudioVideoProduct)),
            ("audio_wins", audio_wins(out).join("; ")),
            ("n_multi", out.multi.len().to_string()),
        ],
    )
}

/// The approach's part of metric names: its name without punctuation, words joined by `_`
/// (`audio_sum`, ..., `audiovideo_product`).
fn metric_key(a: Approach) -> String {
    a.name()
        .replace([',', '+'], "")
        .replace(' ', "_")
        .to_lowercase()
        .replace("__", "_")
}

/// For an audio+video approach: the paired per-pass gain over one modality alone under the
/// same rule (that modality's error − audio+video's, over the passes where both formed a
/// track), mean and 95 % CI half-width. `None` for the other approaches.
fn fusion_gain(out: &Output, a: Approach, over: Modalities) -> Option<MeanCi> {
    if a.modalities() != Modalities::Both || over == Modalities::Both {
        return None;
    }
    let single = Approach::new(over, a.is_product());
    let gains: Vec<f64> = out
        .errors
        .get(single)
        .iter()
        .zip(out.errors.get(a))
        .filter_map(|(x, y)| Some((*x)? - (*y)?))
        .collect();
    let gain = MeanCi::of(&gains);
    gain.mean.is_finite().then_some(gain)
}

fn average(values: &[Option<f64>]) -> Option<f64> {
    let found: Vec<f64> = values.iter().flatten().copied().collect();
    (!found.is_empty()).then(|| found.iter().sum::<f64>() / found.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metric_keys_are_the_approach_names_without_punctuation() {
        let keys = Approach::ALL.map(metric_key);
        assert_eq!(
            keys,
            [
                "audio_sum",
                "video_sum",
                "audiovideo_sum",
                "audio_product",
                "video_product",
                "audiovideo_product"
            ]
        );
    }
}
