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
//! The scene, its simulator, the scoring of a run and the tuning searches are
//! `av_fusion::scene` and `av_fusion::tuning`; this module runs the experiment and writes its
//! report, and `developer.rs` starts the searches on the developer's options.

use anyhow::Result;
use av_fusion::scene::{
    Approach, Calibration, MPS_PER_MPH, Params, PerApproach, REGION_M, RunSpec, Simulated,
    check_params, nominal, run_specs, score, score_with, sensor_nodes, simulate_run,
};
use av_fusion::{Modalities, SensorKind};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use tracker_model::{Track, TrackSet};

mod developer;

use crate::stats::mean_ci;
use crate::{
    BAR_WIDTH, Chart, Claim, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style,
    Table, fill, fmt_num,
};

/// The `av-fusion` pipeline.
pub struct AvFusion;

/// One approach on one run.
struct RunScore {
    /// Mean error of each vehicle's paired track (None: no track formed).
    errors: Vec<Option<f64>>,
    /// MOTA.
    mota: f64,
    /// Mean OSPA, m.
    ospa: f64,
    /// Multi-vehicle runs: MOTA with the single-vehicle settings (audio+video only; `None`
    /// elsewhere and for single-vehicle runs).
    mota_single_settings: Option<f64>,
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
    /// Audio+video's MOTA with its single-vehicle settings (`None` for the others).
    mota_single_settings: Option<f64>,
}

/// One multi-vehicle run.
struct MultiRun {
    /// Vehicles in the run.
    vehicles: usize,
    /// Each approach's scores.
    scores: PerApproach<MultiScore>,
}

/// A mean and the half-width of its 95 % confidence interval.
#[derive(Clone, Copy)]
struct MeanCi {
    mean: f64,
    ci95: f64,
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
}

fn run_one(p: &Params, run: &RunSpec, rng: &mut ChaCha8Rng, want_map: bool) -> Result<RunResult> {
    let sim = simulate_run(p, run, rng)?;
    let mut map = None;
    let scores = PerApproach::try_from_fn(|a| -> Result<RunScore> {
        let s = score(p, &sim, nominal(p), a)?;
        // What the multi-vehicle settings bring: audio+video with its single-vehicle ones.
        let mota_single_settings = if sim.multi && a.modalities() == Modalities::Both {
            Some(score_with(p, &sim, nominal(p), a, p.settings.get(a), None)?.mota)
        } else {
            None
        };
        if want_map && a == Approach::AudioVideoProduct {
            map = Some(map_data(p, &s.result, &sim.gt)?);
        }
        Ok(RunScore {
            errors: s.errors,
            mota: s.mota,
            ospa: s.ospa,
            mota_single_settings,
        })
    })?;
    let sweep = p
        .calibration_sweep_deg
        .iter()
        .map(|&deg| sweep_errors(p, &sim, &scores, deg))
        .collect::<Result<_>>()?;
    Ok(RunResult { scores, sweep, map })
}

/// One run's mean error per approach with every node at heading error ±`deg` (`nominal`: the
/// errors already in `scores`).
fn sweep_errors(
    p: &Params,
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
            score(p, sim, calib, a)?.errors
        };
        Ok(average(&e))
    })
}

fn map_data(p: &Params, run: &av_fusion::AvRun, gt: &TrackSet) -> Result<MapData> {
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
            p.settings.get(Approach::AudioVideoProduct),
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

impl Pipeline for AvFusion {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        check_params(p, env.seed)?;
        let runs = run_specs(p)?;
        developer::run_tools(env.developer, p, &runs, env.seed)?;
        env.progress.set_length(runs.len() as u64);
        let base = rng.clone();
        let n_passes = p.passes.len();
        let mut results: Vec<RunResult> = runs
            .par_iter()
            .enumerate()
            .map(|(i, run)| {
                let mut rng = base.clone();
                rng.set_stream(i as u64);
                let r = run_one(p, run, &mut rng, i + 1 == runs.len());
                env.progress.advance(1);
                r
            })
            .collect::<Result<_>>()?;
        let map = results.iter_mut().rev().find_map(|r| r.map.take());
        let (singles, multis) = results.split_at(n_passes);
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
                    mota_single_settings: s.mota_single_settings,
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
        })
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
            if let Some(gain) = fusion_gain(out, a, Modalities::Audio) {
                m.insert(format!("fusion_gain_m_{key}_mean"), gain.mean);
                m.insert(format!("fusion_gain_m_{key}_ci95"), gain.ci95);
            }
            if let Some(gain) = fusion_gain(out, a, Modalities::Video) {
                m.insert(format!("fusion_gain_over_video_m_{key}_mean"), gain.mean);
                m.insert(format!("fusion_gain_over_video_m_{key}_ci95"), gain.ci95);
            }
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
                if let Some(x) = s.mota_single_settings {
                    m.insert(
                        format!("multi{r}_{n}veh_mota_{key}_single_vehicle_settings"),
                        x,
                    );
                }
            }
        }
        m
    }

    fn claims(out: &Output) -> Vec<Claim> {
        let mut claims = single_vehicle_claims(out);
        claims.extend(multi_vehicle_claims(out));
        claims.extend(sweep_claims(out));
        claims
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let fmt = |a: Approach| {
            let found: Vec<f64> = out.errors.get(a).iter().flatten().copied().collect();
            let (m, c) = mean_ci(&found);
            format!("{} ± {} m", fmt_num(m), fmt_num(c))
        };
        vec![Headline {
            quantity: format!(
                "Average tracking error, audio+video, {} single-vehicle passes",
                out.passes.len()
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
        let mut figures = figures(out);
        if let Some(map) = &out.map {
            figures.push(map_figure(map));
        }
        Section {
            title: "Audio-video fusion tracked by MCMCDA (Kushwaha et al. 2008)".into(),
            summary: summary(out),
            tables: vec![per_pass_table(out), sweep_table(out), multi_table(out)],
            figures,
        }
    }
}

/// The claims on the single-vehicle passes at the nominal heading errors.
fn single_vehicle_claims(out: &Output) -> Vec<Claim> {
    let avg = |a: Approach| average(out.errors.get(a)).unwrap_or(f64::INFINITY);
    let gain_over = |over: Modalities, a: Approach| significant(fusion_gain(out, a, over));
    vec![
        // The averages below skip passes without a track; this keeps them comparable.
        Claim::new(
            "every approach forms a track on every single-vehicle pass",
            out.errors
                .iter()
                .all(|(_, per_pass)| per_pass.iter().all(Option::is_some)),
        ),
        Claim::new(
            "audio+video's average error over the passes is at most 2 m (the paper's ≈ 2 m) under both rules",
            avg(Approach::AudioVideoSum) <= 2.0 && avg(Approach::AudioVideoProduct) <= 2.0,
        ),
        Claim::new(
            "audio+video is better than video alone under both rules: the paired per-pass \
             gain over video (video − audio+video) has its 95 % CI above 0",
            gain_over(Modalities::Video, Approach::AudioVideoSum)
                && gain_over(Modalities::Video, Approach::AudioVideoProduct),
        ),
        Claim::new(
            "under the product rule audio+video is better than each single modality: the \
             paired per-pass gains over audio and over video have their 95 % CIs above 0 \
             (the issue's target; each approach with its own settings tuned on seeds 1–3)",
            gain_over(Modalities::Audio, Approach::AudioVideoProduct)
                && gain_over(Modalities::Video, Approach::AudioVideoProduct),
        ),
    ]
}

/// The claims on the multi-vehicle runs.
fn multi_vehicle_claims(out: &Output) -> Vec<Claim> {
    let mota = |run: &MultiRun, a: Approach| run.scores.get(a).mota;
    vec![
        Claim::new(
            "under the product rule audio+video reaches the issue's MOTA 0.8 on every \
             multi-vehicle run of this seed (this seed only: other seeds have runs below \
             0.8, see docs/av-fusion.md)",
            !out.multi.is_empty()
                && out
                    .multi
                    .iter()
                    .all(|run| mota(run, Approach::AudioVideoProduct) >= 0.8),
        ),
        Claim::new(
            "under the weighted sum audio+video does not reach MOTA 0.8 on every \
             multi-vehicle run",
            out.multi
                .iter()
                .any(|run| mota(run, Approach::AudioVideoSum) < 0.8),
        ),
    ]
}

/// The claims on the calibration sweep (none with fewer than two heading errors).
fn sweep_claims(out: &Output) -> Vec<Claim> {
    let (Some(first), Some(last)) = (out.sweep.first(), out.sweep.last()) else {
        return Vec::new();
    };
    if out.sweep.len() < 2 {
        return Vec::new();
    }
    let grows = |a: Approach| {
        average(last.errors.get(a)).unwrap_or(f64::INFINITY)
            > average(first.errors.get(a)).unwrap_or(0.0)
    };
    vec![
        Claim::new(
            format!(
                "video-only (product) error grows with camera calibration error: higher at {}° than at {}°",
                fmt_num(last.heading_error_deg),
                fmt_num(first.heading_error_deg)
            ),
            grows(Approach::VideoProduct),
        ),
        Claim::new(
            format!(
                "audio-only (product) error grows with the acoustic nodes' heading error: higher at {}° than at {}°",
                fmt_num(last.heading_error_deg),
                fmt_num(first.heading_error_deg)
            ),
            grows(Approach::AudioProduct),
        ),
    ]
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
        gain_row.extend(Approach::ALL.map(|a| {
            fusion_gain(out, a, over).map_or(String::new(), |g| {
                format!("{} ± {}", fmt_num(g.mean), fmt_num(g.ci95))
            })
        }));
        per_pass.row(gain_row);
    }
    per_pass
}

/// MOTA and mean OSPA of every approach on every multi-vehicle run.
fn multi_table(out: &Output) -> Table {
    let mut multi = Table::new(
        "Multi-vehicle runs (not attempted in the paper): MOTA and mean OSPA (order 1) per approach",
        &["run", "vehicles", "approach", "MOTA", "mean OSPA (m)"],
    );
    for (r, run) in out.multi.iter().enumerate() {
        for (a, s) in run.scores.iter() {
            multi.row(vec![
                (r + 1).to_string(),
                run.vehicles.to_string(),
                a.name().into(),
                fmt_num(s.mota),
                fmt_num(s.ospa),
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

/// The per-pass bars (the paper's Figs. 10-11), the averages and the calibration sweep.
fn figures(out: &Output) -> Vec<Figure> {
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

/// The multi-vehicle runs (numbered from 1) whose MOTAs of approaches `a` and `b` satisfy
/// `pick`, as a phrase for the rule `rule`.
fn runs_where(
    out: &Output,
    a: Approach,
    b: Approach,
    rule: &str,
    pick: fn(f64, f64) -> bool,
) -> String {
    let runs: Vec<String> = out
        .multi
        .iter()
        .enumerate()
        .filter(|(_, run)| pick(run.scores.get(a).mota, run.scores.get(b).mota))
        .map(|(r, _)| (r + 1).to_string())
        .collect();
    match runs.len() {
        0 => format!("under the {rule} rule, on no run"),
        1 => format!("under the {rule} rule, on run {}", runs[0]),
        _ => format!("under the {rule} rule, on runs {}", runs.join(", ")),
    }
}

/// The section's text: the setting, the averages against the paper's, where fusion gains
/// and where it loses (the prose is `summary.txt`).
fn summary(out: &Output) -> String {
    // Audio+video below the MOTA 0.8, and audio alone ahead of it.
    let short_of_target =
        RULES.map(|(_, both, rule)| runs_where(out, both, both, rule, |m, _| m < 0.8));
    let audio_wins_multi = RULES
        .map(|(audio, both, rule)| runs_where(out, audio, both, rule, |audio, both| audio > both));
    let av = |a: Approach| average(out.errors.get(a)).map_or("—".into(), fmt_num);
    let gain = |a: Approach| {
        fusion_gain(out, a, Modalities::Audio).map_or("—".into(), |g| {
            format!("{} ± {}", fmt_num(g.mean), fmt_num(g.ci95))
        })
    };
    let motas = |a: Approach| {
        out.multi
            .iter()
            .map(|run| fmt_num(run.scores.get(a).mota))
            .collect::<Vec<_>>()
            .join(", ")
    };
    fill(
        include_str!("summary.txt").trim_end(),
        &[
            ("camera_error", fmt_num(out.calibration_error_deg)),
            ("audio_error", fmt_num(out.audio_calibration_error_deg)),
            ("av_sum", av(Approach::AudioVideoSum)),
            ("av_product", av(Approach::AudioVideoProduct)),
            ("audio_sum", av(Approach::AudioSum)),
            ("audio_product", av(Approach::AudioProduct)),
            ("video_sum", av(Approach::VideoSum)),
            ("video_product", av(Approach::VideoProduct)),
            ("gain_sum", gain(Approach::AudioVideoSum)),
            ("gain_product", gain(Approach::AudioVideoProduct)),
            ("audio_wins", audio_wins(out).join("; ")),
            ("mota_sum", motas(Approach::AudioVideoSum)),
            ("mota_product", motas(Approach::AudioVideoProduct)),
            ("n_multi", out.multi.len().to_string()),
            ("short_of_target", short_of_target.join("; ")),
            ("audio_wins_multi", audio_wins_multi.join("; ")),
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
    let (mean, ci95) = mean_ci(&gains);
    mean.is_finite().then_some(MeanCi { mean, ci95 })
}

/// Whether a paired gain's 95 % CI lies above 0.
fn significant(gain: Option<MeanCi>) -> bool {
    gain.is_some_and(|g| g.mean - g.ci95 > 0.0)
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
