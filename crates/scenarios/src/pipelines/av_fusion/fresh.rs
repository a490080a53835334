//! The fresh seeds: every run of seeds generated once after the one configuration was
//! frozen, scored with it and with the count-aware reference, and the comparisons the
//! scenario claims, each by a paired 95 % t interval whose verdict is recorded
//! (`[params.fresh_verdicts]`).

use std::collections::BTreeMap;

use anyhow::{Result, bail};
use av_fusion::scene::{
    Approach, Calibration, PerApproach, RunSpec, Settings, nominal, peak_scores_of,
    score_count_aware, score_with, simulate_run,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::Params;
use crate::fresh::{self as claimed, Comparison, negated};
use crate::stats::{MeanCi, Verdict};
use crate::{BAR_WIDTH, Chart, Claim, Env, Figure, Series, Style, Table, fmt_num};

/// The paper's average error of audio+video, m (Kushwaha et al. 2008, Figs. 10–11: ≈ 2 m).
const PAPER_ERROR_M: f64 = 2.0;

/// One approach on one fresh run under one configuration.
#[derive(Debug, Clone)]
struct Scored {
    /// Per vehicle: the mean error of its paired track, the match distance without one.
    errors: Vec<f64>,
    /// MOTA.
    mota: f64,
}

/// One fresh run.
struct FreshRun {
    /// More than one vehicle.
    multi: bool,
    /// Each approach with the one configuration.
    one: PerApproach<Scored>,
    /// Each approach with the count-aware reference (it reads the true count).
    count_aware: PerApproach<Scored>,
    /// The single modalities under the product rule with every node at the sweep's first and
    /// last heading errors, one configuration: (audio, video) × (first, last) pass errors.
    sweep: Option<[[f64; 2]; 2]>,
}

/// What the fresh seeds measured: per approach and configuration, every pass's error and
/// every multi-vehicle run's MOTA, and the sweep's ends.
pub(super) struct Fresh {
    /// The fresh seeds.
    pub(super) seeds: Vec<u64>,
    runs: Vec<FreshRun>,
    /// The sweep's first and last heading errors, degrees.
    sweep_deg: [f64; 2],
    /// The recorded verdicts.
    verdicts: BTreeMap<String, Verdict>,
}

/// Which configuration a figure or table row reads.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Config {
    /// The one configuration.
    One,
    /// The count-aware reference.
    CountAware,
}

impl Fresh {
    /// Every pass's error of approach `a` under `config`, run after run.
    pub(super) fn pass_errors(&self, a: Approach, config: Config) -> Vec<f64> {
        self.of(false, a, config)
            .flat_map(|s| s.errors.iter().copied())
            .collect()
    }

    /// Every multi-vehicle run's MOTA of approach `a` under `config`.
    pub(super) fn multi_motas(&self, a: Approach, config: Config) -> Vec<f64> {
        self.of(true, a, config).map(|s| s.mota).collect()
    }

    fn of(&self, multi: bool, a: Approach, config: Config) -> impl Iterator<Item = &Scored> {
        self.runs
            .iter()
            .filter(move |r| r.multi == multi)
            .map(move |r| match config {
                Config::One => r.one.get(a),
                Config::CountAware => r.count_aware.get(a),
            })
    }

    /// The pass errors at the sweep's first (`end` 0) or last heading error of the audio (0)
    /// or video (1) product approach.
    fn sweep_errors(&self, modality: usize, end: usize) -> Vec<f64> {
        self.runs
            .iter()
            .filter_map(|r| r.sweep.map(|s| s[modality][end]))
            .collect()
    }

    pub(super) fn passes(&self) -> usize {
        self.runs.iter().filter(|r| !r.multi).count()
    }

    pub(super) fn multi_runs(&self) -> usize {
        self.runs.iter().filter(|r| r.multi).count()
    }
}

/// Every run of every fresh seed, scored; run i of a seed on stream i of the generator seeded
/// by it, as the reported runs draw theirs.
pub(super) fn run(p: &Params, one: &Settings, runs: &[RunSpec], env: &Env<'_>) -> Result<Fresh> {
    let scene = &p.scene;
    let jobs: Vec<(u64, usize)> = scene
        .fresh_seeds
        .iter()
        .flat_map(|&s| (0..runs.len()).map(move |i| (s, i)))
        .collect();
    let sweep_deg = match (
        scene.calibration_sweep_deg.first(),
        scene.calibration_sweep_deg.last(),
    ) {
        (Some(&a), Some(&b)) if a < b => [a, b],
        _ => bail!("calibration_sweep_deg needs two heading errors, rising"),
    };
    let scored = jobs
        .par_iter()
        .map(|&(seed, i)| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(i as u64);
            let r = fresh_run(p, one, &runs[i], &mut rng, sweep_deg);
            env.progress.advance(1);
            r
        })
        .collect::<Result<_>>()?;
    Ok(Fresh {
        seeds: scene.fresh_seeds.clone(),
        runs: scored,
        sweep_deg,
        verdicts: p.fresh_verdicts.clone(),
    })
}

/// The jobs [`run`] advances the progress by: one per fresh run.
pub(super) fn job_count(p: &Params, runs: &[RunSpec]) -> usize {
    p.scene.fresh_seeds.len() * runs.len()
}

fn fresh_run(
    p: &Params,
    one: &Settings,
    run: &RunSpec,
    rng: &mut ChaCha8Rng,
    sweep_deg: [f64; 2],
) -> Result<FreshRun> {
    let scene = &p.scene;
    let sim = simulate_run(scene, run, rng)?;
    let cut = |errors: &[Option<f64>]| -> Vec<f64> {
        errors
            .iter()
            .map(|e| e.unwrap_or(scene.match_distance_m))
            .collect()
    };
    let with_one = |a: Approach, calib: Calibration| -> Result<Scored> {
        let s = one.get(a);
        let r = score_with(scene, &sim, calib, a, s, peak_scores_of(scene, a, s)?)?;
        Ok(Scored {
            errors: cut(&r.errors),
            mota: r.mota,
        })
    };
    let one_scores = PerApproach::try_from_fn(|a| with_one(a, nominal(scene)))?;
    let count_aware = PerApproach::try_from_fn(|a| -> Result<Scored> {
        let r = score_count_aware(scene, &sim, nominal(scene), a)?;
        Ok(Scored {
            errors: cut(&r.errors),
            mota: r.mota,
        })
    })?;
    let sweep = if sim.multi {
        None
    } else {
        let at = |a: Approach, deg: f64| -> Result<f64> {
            let calib = Calibration {
                audio_deg: deg,
                video_deg: deg,
            };
            // A pass has one vehicle; without its track the error is the match distance.
            let errors = with_one(a, calib)?.errors;
            Ok(errors.first().copied().unwrap_or(scene.match_distance_m))
        };
        let ends =
            |a: Approach| -> Result<[f64; 2]> { Ok([at(a, sweep_deg[0])?, at(a, sweep_deg[1])?]) };
        Some([ends(Approach::AudioProduct)?, ends(Approach::VideoProduct)?])
    };
    Ok(FreshRun {
        multi: sim.multi,
        one: one_scores,
        count_aware,
        sweep,
    })
}

/// Every comparison, in report order: fusion against each modality alone (pass errors and
/// multi-vehicle MOTA, each rule), audio+video against the paper's 2 m, the one configuration
/// against the count-aware reference (each approach), and the calibration sweep.
fn comparisons(f: &Fresh) -> Vec<Comparison> {
    let mut out = Vec::new();
    for product in [false, true] {
        let rule = if product { "product" } else { "sum" };
        let both = Approach::new(av_fusion::Modalities::Both, product);
        for single in [av_fusion::Modalities::Audio, av_fusion::Modalities::Video] {
            let alone = Approach::new(single, product);
            let who = if single == av_fusion::Modalities::Audio {
                "audio"
            } else {
                "video"
            };
            out.extend(error_and_mota(
                f,
                &format!("{rule}_av_vs_{who}"),
                &format!("{rule} rule"),
                ["audio+video", &format!("{who} alone")],
                [(both, Config::One), (alone, Config::One)],
            ));
        }
        let errors = f.pass_errors(both, Config::One);
        out.push(Comparison {
            key: format!("error_{rule}_av_within_paper"),
            statement: format!("{rule} rule: audio+video's pass error ≤ the paper's ≈ 2 m"),
            units: "passes",
            theirs: vec![-PAPER_ERROR_M; errors.len()],
            ours: negated(&errors),
        });
    }
    for a in Approach::ALL {
        let key = a.settings_key();
        out.extend(error_and_mota(
            f,
            &format!("one_vs_count_aware_{key}"),
            &a.to_string(),
            ["the one configuration", "the count-aware one"],
            [(a, Config::One), (a, Config::CountAware)],
        ));
    }
    for (m, who) in [(0, "audio"), (1, "video")] {
        out.push(Comparison {
            key: format!("sweep_{who}_product_grows"),
            statement: format!(
                "{who} alone (product): the pass error at {}° heading error ≥ at {}°",
                fmt_num(f.sweep_deg[1]),
                fmt_num(f.sweep_deg[0])
            ),
            units: "passes",
            ours: f.sweep_errors(m, 1),
            theirs: f.sweep_errors(m, 0),
        });
    }
    out
}

/// Ours against theirs (each an approach under a configuration) on the pass errors and on the
/// multi-vehicle MOTA: keys `error_<key>` and `mota_<key>`, stated for `label` with the two
/// sides' `names`.
fn error_and_mota(
    f: &Fresh,
    key: &str,
    label: &str,
    names: [&str; 2],
    sides: [(Approach, Config); 2],
) -> [Comparison; 2] {
    let [(ours, ours_config), (theirs, theirs_config)] = sides;
    let [ours_name, theirs_name] = names;
    [
        Comparison {
            key: format!("error_{key}"),
            statement: format!("{label}: {ours_name}'s pass error ≤ {theirs_name}'s"),
            units: "passes",
            ours: negated(&f.pass_errors(ours, ours_config)),
            theirs: negated(&f.pass_errors(theirs, theirs_config)),
        },
        Comparison {
            key: format!("mota_{key}"),
            statement: format!("{label}: {ours_name}'s multi-vehicle MOTA ≥ {theirs_name}'s"),
            units: "multi-vehicle runs",
            ours: f.multi_motas(ours, ours_config),
            theirs: f.multi_motas(theirs, theirs_config),
        },
    ]
}

/// Every recorded verdict names a comparison (a comparison without one fails its claim).
pub(super) fn check_verdicts(verdicts: &BTreeMap<String, Verdict>) -> Result<()> {
    let empty = Fresh {
        seeds: Vec::new(),
        runs: Vec::new(),
        sweep_deg: [0.0, 1.0],
        verdicts: BTreeMap::new(),
    };
    claimed::check_verdicts(&comparisons(&empty), verdicts)
}

/// The claims: each comparison's verdict on the fresh runs is the recorded one (a missing
/// record fails).
pub(super) fn claims(f: &Fresh) -> Vec<Claim> {
    let seeds = format!("seeds {}", seed_range(&f.seeds));
    claimed::claims(&comparisons(f), &f.verdicts, &seeds)
}

/// "1901–1908", or the seeds listed when they are not consecutive.
fn seed_range(seeds: &[u64]) -> String {
    match (seeds.first(), seeds.last()) {
        (Some(a), Some(b)) if seeds.windows(2).all(|w| w[1] == w[0] + 1) && a != b => {
            format!("{a}–{b}")
        }
        _ => seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// The metrics of the fresh runs: per approach and configuration the mean pass error and
/// multi-vehicle MOTA with their 95 % half-widths, every comparison's interval and the
/// verdicts' tally.
pub(super) fn metrics(f: &Fresh, m: &mut crate::Metrics, key_of: fn(Approach) -> String) {
    for a in Approach::ALL {
        let key = key_of(a);
        for (config, suffix) in [(Config::One, ""), (Config::CountAware, "_count_aware")] {
            let e = MeanCi::of(f.pass_errors(a, config));
            let mota = MeanCi::of(f.multi_motas(a, config));
            m.insert(format!("fresh_error_m_{key}{suffix}_mean"), e.mean);
            m.insert(format!("fresh_error_m_{key}{suffix}_ci95"), e.ci);
            m.insert(format!("fresh_multi_mota_{key}{suffix}_mean"), mota.mean);
            m.insert(format!("fresh_multi_mota_{key}{suffix}_ci95"), mota.ci);
        }
    }
    claimed::metrics(&comparisons(f), m);
}

/// Per approach: the mean pass error and multi-vehicle MOTA (± 95 % CI) under the one
/// configuration and the count-aware reference.
pub(super) fn means_table(f: &Fresh) -> Table {
    let mut t = Table::new(
        &format!(
            "Fresh seeds {} ({} passes, {} multi-vehicle runs; never used to choose anything): \
             mean ± 95 % CI; a pass without a track counts as the match distance",
            seed_range(&f.seeds),
            f.passes(),
            f.multi_runs()
        ),
        &[
            "approach",
            "pass error (m), one configuration",
            "pass error (m), count-aware",
            "multi-vehicle MOTA, one configuration",
            "multi-vehicle MOTA, count-aware",
        ],
    );
    for a in Approach::ALL {
        t.row(vec![
            a.name().into(),
            MeanCi::of(f.pass_errors(a, Config::One)).show(),
            MeanCi::of(f.pass_errors(a, Config::CountAware)).show(),
            MeanCi::of(f.multi_motas(a, Config::One)).show(),
            MeanCi::of(f.multi_motas(a, Config::CountAware)).show(),
        ]);
    }
    t
}

/// Every comparison: its paired difference and interval, the verdict and the recorded one.
pub(super) fn comparisons_table(f: &Fresh) -> Table {
    claimed::table(
        "Fresh seeds: each comparison per pass or multi-vehicle run (ours − theirs, errors \
         negated so that higher is better)",
        &comparisons(f),
        &f.verdicts,
    )
}

/// The verdicts' tally: (holds, undecided, loses).
pub(super) fn tally(f: &Fresh) -> [usize; 3] {
    claimed::tally(&comparisons(f))
}

/// The comparisons of the one configuration against the count-aware reference that lose.
pub(super) fn losses_to_count_aware(f: &Fresh) -> Vec<String> {
    comparisons(f)
        .iter()
        .filter(|c| c.key.contains("count_aware"))
        .filter(|c| c.verdict() == Verdict::Loses)
        .map(|c| format!("{} ({})", c.statement, c.paired().show()))
        .collect()
}

/// Mean multi-vehicle MOTA and mean pass error per approach, one configuration beside the
/// count-aware reference, with their 95 % intervals.
pub(super) fn figures(f: &Fresh) -> Vec<Figure> {
    let chart = |title: &str, y: &str, values: &dyn Fn(Approach, Config) -> Vec<f64>| {
        let mut series = Vec::new();
        for (k, (config, label)) in [
            (Config::One, "one configuration"),
            (Config::CountAware, "count-aware reference"),
        ]
        .into_iter()
        .enumerate()
        {
            let offset = BAR_WIDTH * (k as f64 - 0.5);
            let means: Vec<(f64, MeanCi)> = Approach::ALL
                .iter()
                .map(|&a| {
                    (
                        (a.index() + 1) as f64 + offset,
                        MeanCi::of(values(a, config)),
                    )
                })
                .collect();
            let bars = means.iter().map(|&(x, m)| (x, m.mean)).collect();
            series.push(Series::new(label, bars, Style::Bars, k));
            for &(x, m) in &means {
                let interval = vec![(x, m.mean - m.ci), (x, m.mean + m.ci)];
                series.push(Series::new("", interval, Style::Line, 7).in_front());
            }
        }
        Chart::new(
            title,
            "approach (1–3: sum, 4–6: product; audio, video, audio+video)",
            y,
            series,
        )
    };
    vec![
        Figure::new(
            "fresh-mota",
            "Fresh seeds: mean multi-vehicle MOTA per approach with its 95 % interval (dark \
             lines), the one configuration beside the count-aware reference",
            chart("Multi-vehicle MOTA, fresh seeds", "MOTA", &|a, c| {
                f.multi_motas(a, c)
            }),
        ),
        Figure::new(
            "fresh-error",
            "Fresh seeds: mean pass error per approach with its 95 % interval (dark lines), \
             the one configuration beside the count-aware reference",
            chart("Pass error, fresh seeds", "mean error (m)", &|a, c| {
                f.pass_errors(a, c)
            }),
        ),
    ]
}
