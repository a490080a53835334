//! `mcmcda-batch`: MCMCDA, GNN, the NNF initialisation and the oracle against the number of
//! targets K, with the true model and with a model mis-specified by a factor of 2.

use std::collections::BTreeMap;

use anyhow::Result;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use tracker_model::SimulationConfig;

use super::fresh::comparisons;
use super::{
    RunScores, Seeds, Stat, Trackers, Tuned, Tuning, Variant, paired, pm, run_grid, ties_and_losses,
};
use crate::fresh::{self, Comparison};
use crate::stats::Verdict;
use crate::{
    Chart, Claim, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style, Table, fmt_num,
};

/// The `mcmcda-batch` pipeline.
pub struct Batch;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Numbers of targets K; births per scan are K / T.
    targets: Vec<u32>,
    /// Reported scenarios per K (streams of the scenario's seed).
    runs: usize,
    /// The simulated world (births_per_scan is set from K).
    simulation: SimulationConfig,
    trackers: Trackers,
    /// GNN's tuning (its own seed).
    tuning: Tuning,
    /// MCMCDA and GNN also run with p_d, the clutter rate and Q off by this factor ...
    misspecified_factor: f64,
    /// ... in these directions.
    misspecified: Vec<Direction>,
    /// The fresh scenarios' seed (`runs` per K, streams of ChaCha8(fresh_seed)).
    fresh_seed: u64,
    /// Each fresh comparison's verdict, recorded from its first run.
    #[serde(default)]
    fresh_verdicts: BTreeMap<String, Verdict>,
}

/// Which way a mis-specified model is off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Direction {
    /// p_d ÷ f, clutter × f, Q × f.
    Pessimistic,
    /// p_d × f (at most 0.99), clutter ÷ f, Q ÷ f.
    Optimistic,
}

/// Statistics over the scenarios of one K.
pub struct KSummary {
    /// Number of targets.
    k: u32,
    /// Scenarios averaged.
    runs: usize,
    /// MCMCDA and GNN under each model variant.
    mcmcda: Vec<Stat>,
    gnn: Vec<Stat>,
    /// The NNF initialisation and the oracle (true model).
    init: Stat,
    oracle: Stat,
    /// Paired MCMCDA − GNN differences of F1 and GOSPA, per variant.
    f1_diff: Vec<(f64, f64)>,
    gospa_diff: Vec<(f64, f64)>,
    /// GNN's tuned settings per variant.
    tuned: Vec<Tuned>,
    /// Mean MAP − truth log posterior over the scenarios whose truth is feasible, if any.
    map_minus_truth: Option<f64>,
    /// Scenarios whose truth is feasible.
    n_feasible: usize,
    /// Mean seconds of MCMCDA per scenario.
    seconds: f64,
}

/// The per-K statistics and the settings the report quotes.
pub struct Output {
    runs: usize,
    simulation: SimulationConfig,
    trackers: Trackers,
    tuning: Tuning,
    variants: Vec<Variant>,
    groups: Vec<KSummary>,
    /// The fresh scenarios' comparisons per K and variant, with the seed and the recorded
    /// verdicts.
    fresh: Vec<Comparison>,
    fresh_seed: u64,
    fresh_verdicts: BTreeMap<String, Verdict>,
}

/// The comparisons of the fresh runs of every K (`runs` each, K by K) under every variant.
fn fresh_comparisons(
    targets: &[u32],
    results: &[RunScores],
    runs: usize,
    variants: &[Variant],
) -> Vec<Comparison> {
    let mut out = Vec::new();
    for (i, &k) in targets.iter().enumerate() {
        let group = &results[i * runs..(i + 1) * runs];
        for (v, variant) in variants.iter().enumerate() {
            out.extend(comparisons(
                &format!("K = {k}, {}", variant.label()),
                &format!("k{k}{}", variant_key(*variant)),
                group,
                v,
            ));
        }
    }
    out
}

/// A variant's part of verdict keys: `_truth`, or the variant's metric suffix.
fn variant_key(variant: Variant) -> &'static str {
    match variant.key() {
        "" => "_truth",
        k => k,
    }
}

/// The statistics of one K's scenarios.
fn summarise(k: u32, group: &[RunScores], tuned: Vec<Tuned>, n_variants: usize) -> KSummary {
    let gaps: Vec<f64> = group.iter().filter_map(|r| r.map_minus_truth).collect();
    let gap = gaps.iter().sum::<f64>() / gaps.len().max(1) as f64;
    KSummary {
        k,
        runs: group.len(),
        mcmcda: (0..n_variants)
            .map(|v| Stat::of(group, |r| r.mcmcda[v]))
            .collect(),
        gnn: (0..n_variants)
            .map(|v| Stat::of(group, |r| r.gnn[v]))
            .collect(),
        init: Stat::of(group, |r| r.init),
        oracle: Stat::of(group, |r| r.oracle),
        f1_diff: (0..n_variants)
            .map(|v| paired(group, |r| r.mcmcda[v].f1 - r.gnn[v].f1))
            .collect(),
        gospa_diff: (0..n_variants)
            .map(|v| paired(group, |r| r.mcmcda[v].gospa - r.gnn[v].gospa))
            .collect(),
        tuned,
        map_minus_truth: (!gaps.is_empty()).then_some(gap),
        n_feasible: gaps.len(),
        seconds: group.iter().map(|r| r.seconds).sum::<f64>() / group.len() as f64,
    }
}

impl Pipeline for Batch {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        anyhow::ensure!(
            p.misspecified_factor.is_finite() && p.misspecified_factor > 0.0,
            "misspecified_factor must be positive"
        );
        let settings: Vec<(SimulationConfig, u32)> = p
            .targets
            .iter()
            .map(|&k| (p.simulation.clone(), k))
            .collect();
        let f = p.misspecified_factor;
        let mut variants = vec![Variant::Truth];
        variants.extend(p.misspecified.iter().map(|d| match d {
            Direction::Pessimistic => Variant::Pessimistic(f),
            Direction::Optimistic => Variant::Optimistic(f),
        }));
        let seeds = Seeds {
            reported: rng,
            fresh: p.fresh_seed,
        };
        let (tuned, [results, fresh_results]) = run_grid(
            &seeds,
            env,
            &settings,
            p.runs,
            &variants,
            &p.trackers,
            &p.tuning,
        )?;
        let groups = p
            .targets
            .iter()
            .zip(tuned)
            .enumerate()
            .map(|(i, (&k, tuned))| {
                summarise(
                    k,
                    &results[i * p.runs..(i + 1) * p.runs],
                    tuned,
                    variants.len(),
                )
            })
            .collect();
        let fresh = fresh_comparisons(&p.targets, &fresh_results, p.runs, &variants);
        fresh::check_verdicts(&fresh, &p.fresh_verdicts)?;
        Ok(Output {
            runs: p.runs,
            simulation: p.simulation.clone(),
            trackers: p.trackers.clone(),
            tuning: p.tuning.clone(),
            variants,
            groups,
            fresh,
            fresh_seed: p.fresh_seed,
            fresh_verdicts: p.fresh_verdicts.clone(),
        })
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let Some(k) = out.groups.iter().map(|g| g.k).max() else {
            return Vec::new();
        };
        let m = Self::metrics(out);
        let key = |what: &str, who: &str| format!("k{k}_{what}_{who}");
        let ci = |what: &str, who: &str| format!("k{k}_{what}_{who}_ci95");
        ["f1", "gospa"]
            .into_iter()
            .map(|what| {
                let quantity = match what {
                    "f1" => format!("association F1, K = {k} targets, true model"),
                    _ => format!("GOSPA (region units), K = {k} targets, true model"),
                };
                let (ours, ours_ci) = (key(what, "mcmcda"), ci(what, "mcmcda"));
                let (gnn, gnn_ci) = (key(what, "gnn"), ci(what, "gnn"));
                Headline::of_metrics(
                    &m,
                    &quantity,
                    (&ours, Some(&ours_ci)),
                    Some(("GNN, tuned", &gnn, Some(&gnn_ci))),
                )
            })
            .collect()
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for g in &out.groups {
            let k = g.k;
            let mut put = |name: String, (mean, ci): (f64, f64)| {
                metrics.insert(format!("{name}_ci95"), ci);
                metrics.insert(name, mean);
            };
            for (v, variant) in out.variants.iter().enumerate() {
                let key = variant.key();
                put(format!("k{k}_f1_mcmcda{key}"), g.mcmcda[v].f1);
                put(format!("k{k}_gospa_mcmcda{key}"), g.mcmcda[v].gospa);
                put(format!("k{k}_f1_gnn{key}"), g.gnn[v].f1);
                put(format!("k{k}_gospa_gnn{key}"), g.gnn[v].gospa);
                put(format!("k{k}_f1_mcmcda_minus_gnn{key}"), g.f1_diff[v]);
                put(format!("k{k}_gospa_mcmcda_minus_gnn{key}"), g.gospa_diff[v]);
            }
            put(format!("k{k}_f1_init"), g.init.f1);
            put(format!("k{k}_gospa_init"), g.init.gospa);
            put(format!("k{k}_f1_oracle"), g.oracle.f1);
            put(format!("k{k}_gospa_oracle"), g.oracle.gospa);
            for (v, variant) in out.variants.iter().enumerate() {
                let key = variant.key();
                let t = &g.tuned[v];
                for (what, c) in [("f1", &t.by_f1), ("gospa", &t.by_gospa)] {
                    let prefix = format!("k{k}_gnn{key}_tuned_for_{what}");
                    metrics.insert(format!("{prefix}_m"), f64::from(c.confirm_hits));
                    metrics.insert(format!("{prefix}_n"), f64::from(c.confirm_window));
                    metrics.insert(
                        format!("{prefix}_max_gap"),
                        f64::from(c.max_gap.unwrap_or(0)),
                    );
                }
            }
            if let Some(gap) = g.map_minus_truth {
                metrics.insert(format!("k{k}_map_minus_truth"), gap);
            }
        }
        fresh::metrics(&out.fresh, &mut metrics);
        metrics
    }

    fn present(out: &Output) -> Section {
        let (sim, t) = (&out.simulation, &out.trackers);
        Section {
            title: "Multi-scan MCMCDA: batch experiment of TAC 2009".into(),
            summary: format!(
                "Region [0, 1000]², T = {} scans, p_d = {}, λ_f V = {}, p_z = {}, d̄ = {}, v̄ = {}. \
                 Association F1 counts links between consecutive measurements of a track; GOSPA \
                 (c = {}, p = 2, α = 2) is averaged over frames of the Kalman-smoothed tracks. \
                 The oracle uses the true associations with the same smoother. \"MAP − truth\" \
                 is the MAP's log posterior minus the true partition's (positive: the sampler \
                 found a partition the model prefers to the truth). GNN uses the \
                 log-likelihood-ratio costs of the same model (a track may stay unassigned when \
                 clutter explains a measurement better; Blackman 2004), and its M-of-N \
                 confirmation and deletion gap are tuned per K and per model on {} tuning \
                 scenarios of seed {} (F1 with the F1-best settings, GOSPA with the GOSPA-best \
                 ones); the {} reported scenarios per K come from the scenario seed, streams \
                 0..{}. MCMCDA is not tuned. Values are means ± the 95 % normal-approximation \
                 interval 1.96·s/√n over the scenarios; differences are paired. On the reported \
                 scenarios, shown and not claimed: {} The claims are made on {} fresh scenarios \
                 per K of seed {} (drawn once after the tuning and these results were frozen), \
                 each by a paired 95 % t interval: {} (table below).",
                sim.n_scans,
                sim.p_detect,
                sim.clutter_per_scan,
                t.model.p_disappear,
                t.model.max_gap,
                t.model.max_speed,
                t.gospa_cutoff,
                out.tuning.runs,
                out.tuning.seed,
                out.runs,
                out.groups.len() * out.runs,
                verdict(out),
                out.runs,
                out.fresh_seed,
                fresh::tally_text(&out.fresh),
            ),
            tables: vec![
                super::fresh::table(&out.fresh, &out.fresh_verdicts, out.fresh_seed),
                summary_table(out),
                misspecified_table(out),
                tuned_table(out),
                parts_table(out),
            ],
            figures: figures(out),
        }
    }

    fn claims(out: &Output) -> Vec<Claim> {
        claims(out)
    }
}

/// Where MCMCDA wins and where it loses, in words, from the numbers: a difference counts as
/// significant when its paired 95 % interval excludes 0.
fn verdict(out: &Output) -> String {
    let describe = |what: &str, diff: &dyn Fn(&KSummary) -> (f64, f64), lower_is_better: bool| {
        let sign = if lower_is_better { -1.0 } else { 1.0 };
        let mut wins = Vec::new();
        let mut ties = Vec::new();
        let mut losses = Vec::new();
        for g in &out.groups {
            let (d, ci) = diff(g);
            let (d, ci) = (sign * d, ci);
            let text = format!("K = {} ({:+.4} ± {:.4})", g.k, sign * d, ci);
            if d - ci > 0.0 {
                wins.push(text);
            } else if d + ci < 0.0 {
                losses.push(text);
            } else {
                ties.push(text);
            }
        }
        let mut out = format!("{what}: MCMCDA is significantly better at ");
        out.push_str(&if wins.is_empty() {
            "no K".into()
        } else {
            wins.join(", ")
        });
        out.push_str(&ties_and_losses(&ties, &losses));
        out
    };
    let mut text = String::new();
    for (v, variant) in out.variants.iter().enumerate() {
        text.push_str(&describe(
            &format!("F1 MCMCDA − GNN, {}", variant.label()),
            &|g| g.f1_diff[v],
            false,
        ));
        text.push_str(&describe(
            &format!("GOSPA MCMCDA − GNN, {}", variant.label()),
            &|g| g.gospa_diff[v],
            true,
        ));
    }
    text
}

/// The claims: each fresh comparison's verdict is the recorded one (the reported scenarios'
/// orderings are shown in the summary, not claimed).
fn claims(out: &Output) -> Vec<Claim> {
    fresh::claims(
        &out.fresh,
        &out.fresh_verdicts,
        &format!("seed {}", out.fresh_seed),
    )
}

/// F1, GOSPA, MAP − truth and time per K, with the true model.
fn summary_table(out: &Output) -> Table {
    let t = &out.trackers;
    let mut table = Table::new(
        &format!(
            "True model: mean ± 95 % CI over {} scenarios per K ({} scans, {} chain(s) × {} samples)",
            out.runs, out.simulation.n_scans, t.chains, t.samples
        ),
        &[
            "K",
            "F1 MCMCDA",
            "F1 GNN (tuned)",
            "F1 MCMCDA − GNN",
            "F1 NNF (init)",
            "GOSPA MCMCDA",
            "GOSPA GNN (tuned)",
            "GOSPA oracle",
            "MCMCDA / oracle",
            "MAP − truth log post.",
            "time per run (s)",
        ],
    );
    for g in &out.groups {
        table.row(vec![
            g.k.to_string(),
            pm(g.mcmcda[0].f1, 4),
            pm(g.gnn[0].f1, 4),
            pm(g.f1_diff[0], 4),
            pm(g.init.f1, 4),
            pm(g.mcmcda[0].gospa, 1),
            pm(g.gnn[0].gospa, 1),
            pm(g.oracle.gospa, 1),
            format!("{:.3}", g.mcmcda[0].gospa.0 / g.oracle.gospa.0),
            match g.map_minus_truth {
                None => "–".into(),
                Some(gap) => format!("{gap:+.2} ({} of {})", g.n_feasible, g.runs),
            },
            format!("{:.3}", g.seconds),
        ]);
    }
    table
}

/// MCMCDA and GNN under each mis-specified model.
fn misspecified_table(out: &Output) -> Table {
    let mut table = Table::new(
        "Robustness: both trackers given a model off by the factor shown (GNN re-tuned under it); \
         mean ± 95 % CI",
        &[
            "K",
            "model",
            "F1 MCMCDA",
            "F1 GNN",
            "F1 MCMCDA − GNN",
            "GOSPA MCMCDA",
            "GOSPA GNN",
        ],
    );
    for g in &out.groups {
        for (v, variant) in out.variants.iter().enumerate() {
            table.row(vec![
                g.k.to_string(),
                variant.label(),
                pm(g.mcmcda[v].f1, 4),
                pm(g.gnn[v].f1, 4),
                pm(g.f1_diff[v], 4),
                pm(g.mcmcda[v].gospa, 1),
                pm(g.gnn[v].gospa, 1),
            ]);
        }
    }
    table
}

/// GNN's tuned settings.
fn tuned_table(out: &Output) -> Table {
    let mut table = Table::new(
        &format!(
            "GNN settings chosen on the tuning scenarios (seed {}, {} per K): M-of-N \
             confirmation and deletion gap (scans)",
            out.tuning.seed, out.tuning.runs
        ),
        &[
            "K",
            "model",
            "for F1: M/N, gap",
            "tuning F1",
            "for GOSPA: M/N, gap",
            "tuning GOSPA",
        ],
    );
    let cfg = |c: &mcmcda::NearestNeighbourConfig| {
        format!(
            "{}/{}, {}",
            c.confirm_hits,
            c.confirm_window,
            c.max_gap.unwrap_or(0)
        )
    };
    for g in &out.groups {
        for (v, variant) in out.variants.iter().enumerate() {
            let t = &g.tuned[v];
            table.row(vec![
                g.k.to_string(),
                variant.label(),
                cfg(&t.by_f1),
                format!("{:.4}", t.tuning_f1),
                cfg(&t.by_gospa),
                fmt_num(t.tuning_gospa),
            ]);
        }
    }
    table
}

/// GOSPA's parts per K and tracker (true model).
fn parts_table(out: &Output) -> Table {
    let mut parts = Table::new(
        "GOSPA's parts with the true model, mean per frame: cardinality errors cost c²/2 each",
        &[
            "K",
            "tracker",
            "missed targets",
            "false estimates",
            "Σ d² of pairs",
        ],
    );
    for g in &out.groups {
        let rows = [
            ("MCMCDA", &g.mcmcda[0]),
            ("GNN (tuned for GOSPA)", &g.gnn[0]),
            ("NNF (init)", &g.init),
            ("oracle", &g.oracle),
        ];
        for (name, s) in rows {
            parts.row(vec![
                g.k.to_string(),
                name.into(),
                format!("{:.2}", s.missed),
                format!("{:.2}", s.false_targets),
                fmt_num(s.localisation),
            ]);
        }
    }
    parts
}

/// Picks one tracker's statistics out of a K's summary.
type StatOf = fn(&KSummary) -> &Stat;

/// F1 (without the oracle) and GOSPA against K, true model.
fn figures(out: &Output) -> Vec<Figure> {
    // Each tracker's mean, and its 95 % CI as thin lines either side.
    let series = |with_oracle: bool, f: fn(&Stat) -> (f64, f64)| -> Vec<Series> {
        let mut pick: Vec<(&str, StatOf)> = vec![
            ("MCMCDA", |g| &g.mcmcda[0]),
            ("GNN (tuned)", |g| &g.gnn[0]),
            ("NNF (init)", |g| &g.init),
        ];
        if with_oracle {
            pick.push(("oracle", |g| &g.oracle));
        }
        let mut all = Vec::new();
        for (m, (name, get)) in pick.into_iter().enumerate() {
            let at = |side: f64| -> Vec<(f64, f64)> {
                let value = |g| {
                    let (mean, ci) = f(get(g));
                    mean + side * ci
                };
                out.groups
                    .iter()
                    .map(|g| (f64::from(g.k), value(g)))
                    .collect()
            };
            all.push(Series::new(name, at(0.0), Style::Line, m));
            all.push(Series::new("", at(-1.0), Style::ThinLine, m));
            all.push(Series::new("", at(1.0), Style::ThinLine, m));
        }
        all
    };
    let f1_chart = Chart::new(
        "Association F1 against the number of targets (thin: 95 % CI of the mean)",
        "targets K",
        "F1",
        series(false, |s| s.f1),
    );
    let gospa_chart = Chart::new(
        "Mean GOSPA against the number of targets (thin: 95 % CI of the mean)",
        "targets K",
        "GOSPA (region units; c, p = 2)",
        series(true, |s| s.gospa),
    );
    vec![
        Figure::new(
            "f1",
            "Association F1 of MCMCDA, the tuned GNN and the NNF initialisation",
            f1_chart,
        ),
        Figure::new(
            "gospa",
            "Mean GOSPA of each tracker and the oracle",
            gospa_chart,
        ),
    ]
}
