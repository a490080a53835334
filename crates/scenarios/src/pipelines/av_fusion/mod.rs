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
    APPROACHES, Calibration, MPS_PER_MPH, Params, REGION_M, RunSpec, check_params, nominal,
    run_specs, score, score_with, sensor_nodes, simulate_run,
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

/// One run's results.
struct RunResult {
    /// Per approach: mean error of each vehicle's paired track (None: no track formed).
    errors: Vec<Vec<Option<f64>>>,
    /// Per approach: MOTA and mean OSPA.
    mota: Vec<f64>,
    ospa: Vec<f64>,
    /// Multi-vehicle runs, per approach: MOTA with the single-vehicle settings (audio+video
    /// only; `None` elsewhere and for single-vehicle runs).
    mota_single_settings: Vec<Option<f64>>,
    /// Per calibration sweep value, per approach: mean error over vehicles (None: no track).
    sweep: Vec<Vec<Option<f64>>>,
    /// For the map: max over ticks of the A+V product grid (per tick scaled to max 1), the
    /// tracks and the truth.
    map: Option<MapData>,
}

struct MapData {
    cells: Vec<(f64, f64, f64)>,
    tracks: Vec<Vec<(f64, f64)>>,
    truth: Vec<Vec<(f64, f64)>>,
    sensors: Vec<(f64, f64, SensorKind)>,
}

/// What the pipeline computed.
pub struct Output {
    passes: Vec<(f64, f64)>,
    /// errors[approach][pass].
    errors: Vec<Vec<Option<f64>>>,
    sweep_deg: Vec<f64>,
    /// sweep[value][approach][pass].
    sweep: Vec<Vec<Vec<Option<f64>>>>,
    /// Multi-vehicle runs: (vehicles, MOTA per approach, OSPA per approach).
    multi: Vec<(usize, Vec<f64>, Vec<f64>)>,
    /// Multi-vehicle runs, per approach: audio+video's MOTA with its single-vehicle settings.
    multi_single_settings: Vec<Vec<Option<f64>>>,
    map: Option<MapData>,
    calibration_error_deg: f64,
    audio_calibration_error_deg: f64,
}

fn run_one(p: &Params, run: &RunSpec, rng: &mut ChaCha8Rng, want_map: bool) -> Result<RunResult> {
    let sim = simulate_run(p, run, rng)?;
    let mut errors = Vec::new();
    let mut mota = Vec::new();
    let mut ospa = Vec::new();
    let mut map = None;
    let mut mota_single_settings = Vec::new();
    for (a, (_, modalities, _)) in APPROACHES.iter().enumerate() {
        let s = score(p, &sim, nominal(p), a)?;
        errors.push(s.errors);
        mota.push(s.mota);
        ospa.push(s.ospa);
        // What the multi-vehicle settings bring: audio+video with its single-vehicle ones.
        mota_single_settings.push(if sim.multi && *modalities == Modalities::Both {
            Some(score_with(p, &sim, nominal(p), a, p.settings.get(a), None)?.mota)
        } else {
            None
        });
        if want_map && a == APPROACHES.len() - 1 {
            map = Some(map_data(p, &s.result, &sim.gt)?);
        }
    }
    let mut sweep = Vec::new();
    for &deg in &p.calibration_sweep_deg {
        let calib = Calibration {
            audio_deg: deg,
            video_deg: deg,
        };
        let mut row = Vec::new();
        for (a, (_, _, product)) in APPROACHES.iter().enumerate() {
            // The sweep runs the product rule only, on the single-vehicle passes (time budget;
            // the report averages it over the passes); the nominal setting is done.
            if !*product || sim.multi {
                row.push(None);
                continue;
            }
            let e = if calib == nominal(p) {
                errors[a].clone()
            } else {
                score(p, &sim, calib, a)?.errors
            };
            row.push(average(&e));
        }
        sweep.push(row);
    }
    Ok(RunResult {
        errors,
        mota,
        ospa,
        mota_single_settings,
        sweep,
        map,
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
            cells.push((c.x, c.y, *v));
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
            p.settings.get(5),
        )?
        .iter()
        .map(|n| (n.pose.position.x, n.pose.position.y, n.kind))
        .collect(),
    })
}

impl Pipeline for AvFusion {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        check_params(p, env.seed)?;
        let runs = run_specs(p)?;
        developer::run_tools(env.developer, p, &runs)?;
        env.progress.set_length(runs.len() as u64);
        let base = rng.clone();
        let n_passes = p.passes.len();
        let results: Vec<RunResult> = runs
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
        let errors = (0..APPROACHES.len())
            .map(|a| results[..n_passes].iter().map(|r| r.errors[a][0]).collect())
            .collect();
        let sweep = (0..p.calibration_sweep_deg.len())
            .map(|s| {
                (0..APPROACHES.len())
                    .map(|a| results[..n_passes].iter().map(|r| r.sweep[s][a]).collect())
                    .collect()
            })
            .collect();
        let multi = results[n_passes..]
            .iter()
            .zip(&p.multi)
            .map(|(r, spec)| (spec.len(), r.mota.clone(), r.ospa.clone()))
            .collect();
        let multi_single_settings = results[n_passes..]
            .iter()
            .map(|r| r.mota_single_settings.clone())
            .collect();
        let map = results.into_iter().rev().find_map(|r| r.map);
        Ok(Output {
            passes: p
                .passes
                .iter()
                .map(|s| (s.duration_s, REGION_M[0] / s.duration_s / MPS_PER_MPH))
                .collect(),
            errors,
            sweep_deg: p.calibration_sweep_deg.clone(),
            sweep,
            multi,
            multi_single_settings,
            map,
            calibration_error_deg: p.calibration_error_deg,
            audio_calibration_error_deg: p.audio_calibration_error_deg,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut m = Metrics::new();
        for (a, (name, _, _)) in APPROACHES.iter().enumerate() {
            let key = key(name);
            let found: Vec<f64> = out.errors[a].iter().flatten().copied().collect();
            let (mean, ci) = mean_ci(&found);
            if mean.is_finite() {
                m.insert(format!("error_m_{key}_mean"), mean);
                m.insert(format!("error_m_{key}_ci95"), ci);
            }
            m.insert(format!("passes_tracked_{key}"), found.len() as f64);
            if let Some(gain) = fusion_gain(out, a, Modalities::Audio) {
                m.insert(format!("fusion_gain_m_{key}_mean"), gain.0);
                m.insert(format!("fusion_gain_m_{key}_ci95"), gain.1);
            }
            if let Some(gain) = fusion_gain(out, a, Modalities::Video) {
                m.insert(format!("fusion_gain_over_video_m_{key}_mean"), gain.0);
                m.insert(format!("fusion_gain_over_video_m_{key}_ci95"), gain.1);
            }
            for (s, deg) in out.sweep_deg.iter().enumerate() {
                if let Some(e) = average(&out.sweep[s][a]) {
                    m.insert(format!("calibration_{deg}deg_error_m_{key}"), e);
                }
            }
            for (r, (n, mota, ospa)) in out.multi.iter().enumerate() {
                m.insert(format!("multi{r}_{n}veh_mota_{key}"), mota[a]);
                m.insert(format!("multi{r}_{n}veh_ospa_m_{key}"), ospa[a]);
                if let Some(x) = out.multi_single_settings[r][a] {
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
        let avg = |a: usize| average(&out.errors[a]).unwrap_or(f64::INFINITY);
        let mut claims = vec![
            // The averages below skip passes without a track; this keeps them comparable.
            Claim::new(
                "every approach forms a track on every single-vehicle pass",
                out.errors
                    .iter()
                    .all(|per_pass| per_pass.iter().all(Option::is_some)),
            ),
            Claim::new(
                "audio+video's average error over the passes is at most 2 m (the paper's ≈ 2 m) under both rules",
                avg(2) <= 2.0 && avg(5) <= 2.0,
            ),
            Claim::new(
                "audio+video is better than video alone under both rules: the paired per-pass \
                 gain over video (video − audio+video) has its 95 % CI above 0",
                significant(fusion_gain(out, 2, Modalities::Video))
                    && significant(fusion_gain(out, 5, Modalities::Video)),
            ),
            Claim::new(
                "under the product rule audio+video is better than each single modality: the \
                 paired per-pass gains over audio and over video have their 95 % CIs above 0 \
                 (the issue's target; each approach with its own settings tuned on seeds 1–3)",
                significant(fusion_gain(out, 5, Modalities::Audio))
                    && significant(fusion_gain(out, 5, Modalities::Video)),
            ),
            Claim::new(
                "under the product rule audio+video reaches the issue's MOTA 0.8 on every \
                 multi-vehicle run of this seed (this seed only: other seeds have runs below \
                 0.8, see docs/av-fusion.md)",
                !out.multi.is_empty() && out.multi.iter().all(|(_, mota, _)| mota[5] >= 0.8),
            ),
            Claim::new(
                "under the weighted sum audio+video does not reach MOTA 0.8 on every \
                 multi-vehicle run",
                out.multi.iter().any(|(_, mota, _)| mota[2] < 0.8),
            ),
        ];
        if let (Some(first), Some(last)) = (out.sweep.first(), out.sweep.last())
            && out.sweep.len() >= 2
        {
            claims.push(Claim::new(
                format!(
                    "video-only (product) error grows with camera calibration error: higher at {}° than at {}°",
                    fmt_num(out.sweep_deg[out.sweep_deg.len() - 1]),
                    fmt_num(out.sweep_deg[0])
                ),
                average(&last[4]).unwrap_or(f64::INFINITY) > average(&first[4]).unwrap_or(0.0),
            ));
            claims.push(Claim::new(
                format!(
                    "audio-only (product) error grows with the acoustic nodes' heading error: higher at {}° than at {}°",
                    fmt_num(out.sweep_deg[out.sweep_deg.len() - 1]),
                    fmt_num(out.sweep_deg[0])
                ),
                average(&last[3]).unwrap_or(f64::INFINITY) > average(&first[3]).unwrap_or(0.0),
            ));
        }
        claims
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let fmt = |a: usize| {
            let found: Vec<f64> = out.errors[a].iter().flatten().copied().collect();
            let (m, c) = mean_ci(&found);
            format!("{} ± {} m", fmt_num(m), fmt_num(c))
        };
        vec![Headline {
            quantity: format!(
                "Average tracking error, audio+video, {} single-vehicle passes",
                out.passes.len()
            ),
            paper: Some("≈ 2 m (Kushwaha et al. 2008, Figs. 10–11)".into()),
            ours: format!("{} (product), {} (weighted sum)", fmt(5), fmt(2)),
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

/// Each pass's error per approach, their means, and fusion's paired gains.
fn per_pass_table(out: &Output) -> Table {
    let mut per_pass = Table::new(
        &format!(
            "Mean tracking error (m) per pass and approach, heading error ±{}° (cameras) and ±{}° (acoustic nodes); — = no track formed",
            fmt_num(out.calibration_error_deg),
            fmt_num(out.audio_calibration_error_deg)
        ),
        &[
            "pass",
            "duration (s)",
            "speed (mph)",
            APPROACHES[0].0,
            APPROACHES[1].0,
            APPROACHES[2].0,
            APPROACHES[3].0,
            APPROACHES[4].0,
            APPROACHES[5].0,
        ],
    );
    let cell = |e: Option<f64>| e.map_or("—".to_string(), fmt_num);
    for (i, (d, mph)) in out.passes.iter().enumerate() {
        let mut row = vec![(i + 1).to_string(), fmt_num(*d), fmt_num(*mph)];
        row.extend((0..APPROACHES.len()).map(|a| cell(out.errors[a][i])));
        per_pass.row(row);
    }
    let mut avg_row = vec!["mean ± 95 % CI".into(), String::new(), String::new()];
    for a in 0..APPROACHES.len() {
        let found: Vec<f64> = out.errors[a].iter().flatten().copied().collect();
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
        gain_row.extend((0..APPROACHES.len()).map(|a| {
            fusion_gain(out, a, over).map_or(String::new(), |(m, c)| {
                format!("{} ± {}", fmt_num(m), fmt_num(c))
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
    for (r, (n, mota, ospa)) in out.multi.iter().enumerate() {
        for (a, (name, _, _)) in APPROACHES.iter().enumerate() {
            multi.row(vec![
                (r + 1).to_string(),
                n.to_string(),
                (*name).into(),
                fmt_num(mota[a]),
                fmt_num(ospa[a]),
            ]);
        }
    }
    multi
}

/// The average error against the nodes' heading error, product rule.
fn sweep_table(out: &Output) -> Table {
    let cell = |e: Option<f64>| e.map_or("—".to_string(), fmt_num);
    let mut sweep_table = Table::new(
        "Average error (m) over the passes against the heading error δ of every node (cameras and acoustic nodes alike, signs alternating), product rule",
        &[
            "heading error δ (°)",
            APPROACHES[3].0,
            APPROACHES[4].0,
            APPROACHES[5].0,
        ],
    );
    for (s, deg) in out.sweep_deg.iter().enumerate() {
        sweep_table.row(vec![
            fmt_num(*deg),
            cell(average(&out.sweep[s][3])),
            cell(average(&out.sweep[s][4])),
            cell(average(&out.sweep[s][5])),
        ]);
    }
    sweep_table
}

/// Grouped bars per pass index, as the paper's Figs. 10-11 (the product rule's approaches or
/// the weighted sum's); a missing bar is a pass with no track.
fn bar_chart(out: &Output, rule_product: bool) -> Chart {
    let offset = if rule_product { 3 } else { 0 };
    let series = (0..3)
        .map(|m| {
            let a = offset + m;
            let pts = out.errors[a]
                .iter()
                .enumerate()
                .filter_map(|(i, e)| e.map(|e| ((i + 1) as f64 + BAR_WIDTH * (m as f64 - 1.0), e)))
                .collect();
            Series::new(APPROACHES[a].0, pts, Style::Bars, m)
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
        (0..APPROACHES.len())
            .filter_map(|a| {
                average(&out.errors[a]).map(|e| {
                    Series::new(
                        APPROACHES[a].0,
                        vec![((a + 1) as f64, e)],
                        Style::Bars,
                        a % 3,
                    )
                })
            })
            .collect(),
    );
    let sweep_chart = Chart::new(
        "Error against calibration error",
        "heading error δ of cameras and acoustic nodes (°)",
        "average error (m)",
        [3usize, 4, 5]
            .iter()
            .map(|&a| {
                let pts = out
                    .sweep_deg
                    .iter()
                    .enumerate()
                    .filter_map(|(s, d)| average(&out.sweep[s][a]).map(|e| (*d, e)))
                    .collect();
                Series::new(APPROACHES[a].0, pts, Style::Line, a)
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
            .filter(|(_, _, v)| v >= lo && v < hi)
            .map(|(x, y, _)| (*x, *y))
            .collect();
        series.push(Series::new(
            &format!("likelihood {lo}–{}", hi.min(1.0)),
            pts,
            Style::Markers,
            [7, 2, 1][k],
        ));
    }
    for (i, t) in map.truth.iter().enumerate() {
        series.push(Series::new(
            if i == 0 { "truth" } else { "" },
            t.clone(),
            Style::ThinLine,
            7,
        ));
    }
    for (i, t) in map.tracks.iter().enumerate() {
        series.push(Series::new(
            if i == 0 { "tracks" } else { "" },
            t.clone(),
            Style::Line,
            0,
        ));
    }
    for (kind, label, colour) in [
        (SensorKind::Audio, "acoustic nodes", 3),
        (SensorKind::Video, "cameras", 4),
    ] {
        series.push(Series::new(
            label,
            map.sensors
                .iter()
                .filter(|s| s.2 == kind)
                .map(|s| (s.0, s.1))
                .collect(),
            Style::Markers,
            colour,
        ));
    }
    Figure::new(
        "map",
        "Last multi-vehicle run, audio+video product: the fused likelihood (each tick scaled to maximum 1, maximum over the ticks) with the tracks over it",
        Chart::new("Fused likelihood and tracks", "x (m)", "y (m)", series),
    )
}

/// The section's text: the setting, the averages against the paper's, where fusion gains
/// and where it loses (the prose is `summary.txt`).
fn summary(out: &Output) -> String {
    // Where audio alone beats fusion, per rule.
    let audio_wins: Vec<String> = [(0usize, 2usize, "sum"), (3, 5, "product")]
        .iter()
        .map(|&(a, b, rule)| {
            let passes: Vec<String> = (0..out.passes.len())
                .filter(|&i| match (out.errors[a][i], out.errors[b][i]) {
                    (Some(ea), Some(eb)) => ea < eb,
                    (Some(_), None) => true,
                    _ => false,
                })
                .map(|i| (i + 1).to_string())
                .collect();
            if passes.is_empty() {
                format!("under the {rule} rule, on no pass")
            } else {
                format!("under the {rule} rule, on passes {}", passes.join(", "))
            }
        })
        .collect();
    // The multi-vehicle runs (numbered from 1) whose MOTAs satisfy `pick`, per rule.
    let runs_where = |a: usize, b: usize, rule: &str, pick: fn(f64, f64) -> bool| {
        let runs: Vec<String> = out
            .multi
            .iter()
            .enumerate()
            .filter(|(_, (_, mota, _))| pick(mota[a], mota[b]))
            .map(|(r, _)| (r + 1).to_string())
            .collect();
        match runs.len() {
            0 => format!("under the {rule} rule, on no run"),
            1 => format!("under the {rule} rule, on run {}", runs[0]),
            _ => format!("under the {rule} rule, on runs {}", runs.join(", ")),
        }
    };
    // Audio+video below the MOTA 0.8, and audio alone ahead of it.
    let short_of_target = [
        runs_where(2, 2, "sum", |m, _| m < 0.8),
        runs_where(5, 5, "product", |m, _| m < 0.8),
    ];
    let audio_wins_multi = [
        runs_where(0, 2, "sum", |audio, both| audio > both),
        runs_where(3, 5, "product", |audio, both| audio > both),
    ];
    let av = |a: usize| average(&out.errors[a]).map_or("—".into(), fmt_num);
    let gain = |a: usize| {
        fusion_gain(out, a, Modalities::Audio).map_or("—".into(), |(m, c)| {
            format!("{} ± {}", fmt_num(m), fmt_num(c))
        })
    };
    let motas = |a: usize| {
        out.multi
            .iter()
            .map(|(_, m, _)| fmt_num(m[a]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    fill(
        include_str!("summary.txt").trim_end(),
        &[
            ("camera_error", fmt_num(out.calibration_error_deg)),
            ("audio_error", fmt_num(out.audio_calibration_error_deg)),
            ("av_sum", av(2)),
            ("av_product", av(5)),
            ("audio_sum", av(0)),
            ("audio_product", av(3)),
            ("video_sum", av(1)),
            ("video_product", av(4)),
            ("gain_sum", gain(2)),
            ("gain_product", gain(5)),
            ("audio_wins", audio_wins.join("; ")),
            ("mota_sum", motas(2)),
            ("mota_product", motas(5)),
            ("n_multi", out.multi.len().to_string()),
            ("short_of_target", short_of_target.join("; ")),
            ("audio_wins_multi", audio_wins_multi.join("; ")),
        ],
    )
}

fn key(name: &str) -> String {
    name.replace([',', '+'], "")
        .replace(' ', "_")
        .to_lowercase()
        .replace("__", "_")
}

/// For an audio+video approach: the paired per-pass gain over one modality alone under the
/// same rule (that modality's error − audio+video's, over the passes where both formed a
/// track), mean and 95 % CI half-width. `None` for the other approaches.
fn fusion_gain(out: &Output, a: usize, over: Modalities) -> Option<(f64, f64)> {
    let single = match (a, over) {
        (2, Modalities::Audio) => 0,
        (2, Modalities::Video) => 1,
        (5, Modalities::Audio) => 3,
        (5, Modalities::Video) => 4,
        _ => return None,
    };
    let gains: Vec<f64> = out.errors[single]
        .iter()
        .zip(&out.errors[a])
        .filter_map(|(x, y)| Some((*x)? - (*y)?))
        .collect();
    let (mean, ci) = mean_ci(&gains);
    mean.is_finite().then_some((mean, ci))
}

/// Whether a paired gain's 95 % CI lies above 0.
fn significant(gain: Option<(f64, f64)>) -> bool {
    gain.is_some_and(|(mean, ci)| mean - ci > 0.0)
}

fn average(values: &[Option<f64>]) -> Option<f64> {
    let found: Vec<f64> = values.iter().flatten().copied().collect();
    (!found.is_empty()).then(|| found.iter().sum::<f64>() / found.len() as f64)
}
