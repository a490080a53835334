//! `hmm-tracking`: Huynh & Vu's (2006) experiment. A target moves on a map (a road graph of crossroads or
//! a cell grid with obstacles) with habits the generic model does not know; sensors give coarse
//! position fixes whose accuracy falls with distance. A non-learned model (kinematic
//! constraints only, a mis-specified sensor model) is compared with the same model after
//! Baum-Welch on K training sequences, and with the true model, by the distance error of the
//! Viterbi and posterior-decoded paths on fresh test sequences.
//!
//! The truth model (the map's habits) is drawn once from the scenario's generator; then
//! `n_seeds` independent replicates each draw their own training and test sequences (the
//! generator's stream `set_stream(r)`), so every error is reported as mean ± 95 % CI
//! (1.96 s/√n over the replicates).

use anyhow::{Context, Result};
use eval_metrics::distance_error_series;
use hmm_grid::{
    BaumWelchConfig, CellGrid, Freeze, Hmm, PseudoCounts, SensorModel, SpeedDistribution,
    StateSpace, Transitions, forward, posterior_decode, viterbi,
};
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::{Frame, Track, TrackId, Vec2};

use std::collections::BTreeMap;

use crate::fresh::{self, Comparison, negated};
use crate::stats::{MeanCi, Verdict};
use crate::{
    Chart, Claim, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style, Table, fmt_num,
};

/// The `hmm-tracking` pipeline.
pub struct HmmTracking;

/// The map the target moves on.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum MapParams {
    /// Crossroads and the roads between them.
    Road {
        crossroads: Vec<[f64; 2]>,
        roads: Vec<[usize; 2]>,
    },
    /// A cell grid with obstacles.
    Grid(CellGrid),
}

/// A sensor model's accuracy.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorParams {
    base_sigma: f64,
    sigma_per_distance: f64,
}

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    map: MapParams,
    sensors: Vec<[f64; 2]>,
    /// The truth's hop-count distribution; its per-state habits are drawn from the scenario's generator.
    true_speed: Vec<f64>,
    /// How strongly habits deviate from the even split (0 = none).
    habit_strength: f64,
    true_sensor: SensorParams,
    /// The non-learned model's kinematics and sensor model.
    model_speed: Vec<f64>,
    model_sensor: SensorParams,
    /// Numbers K of training sequences to learn from, ascending; the detailed comparison uses
    /// the largest, and the report shows the error against K.
    train_sizes: Vec<usize>,
    train_len: usize,
    n_test: usize,
    test_len: usize,
    bw_max_iterations: usize,
    /// Baum-Welch stops when |ΔLL| ≤ this · |LL| (hmm-grid's `relative_tolerance`).
    bw_relative_tolerance: f64,
    /// Independent replicates (training and test sets) behind each mean and CI.
    n_seeds: usize,
    /// A sentence appended to the report's summary (e.g. a robustness check run separately).
    #[serde(default)]
    note: String,
    /// Keep B fixed during training (useful when M is large and data few).
    freeze_emissions: bool,
    transition_pseudo_count: f64,
    /// The fresh replicates' seed: `n_seeds` more replicates (streams of ChaCha8(fresh_seed))
    /// of the same world, drawn once after these settings were frozen, carry the claims.
    fresh_seed: u64,
    /// Each fresh comparison's verdict, recorded from its first run.
    #[serde(default)]
    fresh_verdicts: BTreeMap<String, Verdict>,
}

fn sensor_model(p: &Params, s: &SensorParams) -> SensorModel {
    SensorModel {
        sensors: p.sensors.iter().map(|q| Vec2::new(q[0], q[1])).collect(),
        base_sigma: s.base_sigma,
        sigma_per_distance: s.sigma_per_distance,
    }
}

/// The truth's transitions: the kinematic model with each allowed move re-weighted by a
/// random habit factor, so some roads are preferred.
fn habitual(generic: &Transitions, strength: f64, rng: &mut impl Rng) -> Result<Transitions> {
    let n = generic.n_states();
    let rows = (0..n)
        .map(|i| {
            let mut row = Vec::new();
            generic.for_each_in_row(i, |j, a, _| {
                row.push((j, a * (1.0 + strength * rng.random::<f64>()).powi(2)))
            });
            let total: f64 = row.iter().map(|e| e.1).sum();
            row.into_iter().map(|(j, a)| (j, a / total)).collect()
        })
        .collect();
    Ok(Transitions::sparse(rows)?)
}

/// One state path per sequence as a track (frames 0, 1, …; id = the sequence's index).
fn paths_to_tracks(space: &StateSpace, paths: &[Vec<usize>]) -> Result<Vec<Track>> {
    paths
        .iter()
        .enumerate()
        .map(|(i, path)| Ok(space.path_to_track(path, 0, TrackId(i as u64))?))
        .collect()
}

/// Mean over test sequences of eval-metrics' distance error between true and decoded tracks,
/// per step.
fn mean_error_series(truth: &[Track], decoded: &[Track]) -> Result<Vec<f64>> {
    let len = truth.first().map_or(0, Track::len);
    let series: Vec<Vec<(Frame, f64)>> = truth
        .iter()
        .zip(decoded)
        .map(|(t, d)| distance_error_series(t, d))
        .collect();
    anyhow::ensure!(
        series.iter().all(|s| s.len() == len),
        "every decoded path must cover the {len} steps of its test sequence"
    );
    Ok((0..len)
        .map(|t| series.iter().map(|s| s[t].1).sum::<f64>() / truth.len() as f64)
        .collect())
}

/// The mean of a curve's values.
fn mean(curve: &[f64]) -> f64 {
    curve.iter().sum::<f64>() / curve.len() as f64
}

fn mean_ci(values: impl IntoIterator<Item = f64>) -> MeanCi {
    MeanCi::of(values)
}

/// One model's scores on one replicate's test sequences.
struct Score {
    /// Test log-likelihood per step.
    log_likelihood_per_step: f64,
    /// Mean distance error per step, Viterbi.
    viterbi_curve: Vec<f64>,
    /// Mean distance error per step, posterior decoding.
    posterior_curve: Vec<f64>,
    /// The Viterbi path of test sequence 0.
    example: Vec<usize>,
}

/// One Baum-Welch run of one replicate.
struct Fit {
    /// Re-estimation steps.
    iterations: usize,
    /// Whether the relative tolerance was met.
    converged: bool,
    /// The learned model's scores.
    score: Score,
    /// Training log-likelihood history.
    log_likelihoods: Vec<f64>,
}

/// One replicate: the non-learned and true models' scores and one fit per K.
struct Replicate {
    nonlearned: Score,
    truth: Score,
    fits: Vec<Fit>,
    /// The true path of test sequence 0.
    true_path: Vec<usize>,
}

/// One model's scores over the replicates.
pub struct ModelScore {
    /// Name in tables and legends.
    name: &'static str,
    /// Metric key suffix.
    key: &'static str,
    /// Test log-likelihood per step.
    log_likelihood_per_step: MeanCi,
    /// Mean distance error, Viterbi.
    viterbi: MeanCi,
    /// Mean distance error, posterior decoding.
    posterior: MeanCi,
    /// Mean distance error per step, Viterbi, averaged over replicates.
    viterbi_curve: Vec<f64>,
    /// Mean distance error per step, posterior decoding, averaged over replicates.
    posterior_curve: Vec<f64>,
    /// The Viterbi path of replicate 0's test sequence 0.
    example: Vec<usize>,
}

/// One point of the learning curve.
pub struct SweepPoint {
    /// Training sequences K.
    k: usize,
    /// Baum-Welch iterations.
    iterations: MeanCi,
    /// Replicates whose Baum-Welch met the tolerance.
    converged: usize,
    /// Mean Viterbi distance error of the model learned from K sequences.
    viterbi: MeanCi,
    /// Mean posterior-decoding distance error of the model learned from K sequences.
    posterior: MeanCi,
    /// Test log-likelihood per step.
    log_likelihood_per_step: MeanCi,
}

/// Everything the metrics and the report need.
pub struct Output {
    /// Whether the map is a road graph (else a cell grid).
    is_road: bool,
    /// The map.
    space: StateSpace,
    /// Training sequences (the largest K).
    n_train: usize,
    /// Steps per training sequence.
    train_len: usize,
    /// Test sequences per replicate.
    n_test: usize,
    /// Steps per test sequence.
    test_len: usize,
    /// Replicates.
    n_seeds: usize,
    /// Baum-Welch's iteration cap and relative tolerance.
    max_iterations: usize,
    relative_tolerance: f64,
    /// The scenario's note for the summary.
    note: String,
    /// The true path of replicate 0's test sequence 0.
    true_path: Vec<usize>,
    /// Non-learned, learned (largest K) and true model, in that order.
    models: Vec<ModelScore>,
    /// The learning curve, by ascending K.
    sweep: Vec<SweepPoint>,
    /// Training log-likelihoods of replicate 0's Baum-Welch run at the largest K.
    log_likelihoods: Vec<f64>,
    /// The fresh replicates: whether Baum-Welch converged in each fit, and the comparisons.
    fresh_converged: bool,
    fresh: Vec<Comparison>,
    fresh_seed: u64,
    fresh_verdicts: BTreeMap<String, Verdict>,
}

/// The true and the non-learned model (draws the truth's habits from `rng`).
fn build_models(p: &Params, space: &StateSpace, rng: &mut ChaCha8Rng) -> Result<(Hmm, Hmm)> {
    let n = space.n_states();
    let uniform = vec![1.0 / n as f64; n];
    let generic_true = space.transitions(&SpeedDistribution::new(p.true_speed.clone())?)?;
    let truth = Hmm::new(
        uniform.clone(),
        habitual(&generic_true, p.habit_strength, rng)?,
        space.sensor_emissions(&sensor_model(p, &p.true_sensor))?,
        n,
    )?;
    let naive = Hmm::new(
        uniform,
        space.transitions(&SpeedDistribution::new(p.model_speed.clone())?)?,
        space.sensor_emissions(&sensor_model(p, &p.model_sensor))?,
        n,
    )?;
    Ok((truth, naive))
}

/// The Baum-Welch trainer of the learned model.
fn trainer(p: &Params) -> Result<hmm_grid::BaumWelch> {
    // The initial distribution is known (uniform), as in Huynh & Vu (2006): freeze it.
    Ok(BaumWelchConfig {
        max_iterations: p.bw_max_iterations,
        tolerance: 0.0,
        relative_tolerance: p.bw_relative_tolerance,
        freeze: Freeze {
            initial: true,
            transitions: false,
            emissions: p.freeze_emissions,
        },
        pseudo_counts: PseudoCounts {
            transitions: p.transition_pseudo_count,
            ..PseudoCounts::default()
        },
    }
    .check()?)
}

/// One replicate: fresh training and test sequences from `rng`, the models scored on them, and
/// a model learned from the first K training sequences for every K of the sweep.
fn replicate(
    p: &Params,
    space: &StateSpace,
    (truth, naive): (&Hmm, &Hmm),
    trainer: &hmm_grid::BaumWelch,
    rng: &mut ChaCha8Rng,
    env: &Env<'_>,
) -> Result<Replicate> {
    let n_train = *p.train_sizes.last().unwrap_or(&0);
    let train: Vec<Vec<usize>> = (0..n_train)
        .map(|_| truth.sample(p.train_len, rng).1)
        .collect();
    let test: Vec<(Vec<usize>, Vec<usize>)> = (0..p.n_test)
        .map(|_| truth.sample(p.test_len, rng))
        .collect();
    let true_paths: Vec<Vec<usize>> = test.iter().map(|t| t.0.clone()).collect();
    let true_tracks = paths_to_tracks(space, &true_paths)?;
    let mut fits = Vec::with_capacity(p.train_sizes.len());
    for &k in &p.train_sizes {
        let (model, fit) = trainer.fit(naive, &train[..k]).context("Baum-Welch")?;
        fits.push(Fit {
            iterations: fit.iterations(),
            converged: fit.converged,
            score: score(&model, space, &test, &true_tracks)?,
            log_likelihoods: fit.log_likelihoods,
        });
        env.progress.advance(1);
    }
    Ok(Replicate {
        nonlearned: score(naive, space, &test, &true_tracks)?,
        truth: score(truth, space, &test, &true_tracks)?,
        fits,
        true_path: true_paths.into_iter().next().unwrap_or_default(),
    })
}

/// A model's scores over the replicates.
fn summarise(name: &'static str, key: &'static str, scores: &[&Score]) -> ModelScore {
    let n = scores.len() as f64;
    let average = |curve: fn(&Score) -> &Vec<f64>| -> Vec<f64> {
        let len = scores.first().map_or(0, |s| curve(s).len());
        (0..len)
            .map(|t| scores.iter().map(|s| curve(s)[t]).sum::<f64>() / n)
            .collect()
    };
    ModelScore {
        name,
        key,
        log_likelihood_per_step: mean_ci(scores.iter().map(|s| s.log_likelihood_per_step)),
        viterbi: mean_ci(scores.iter().map(|s| mean(&s.viterbi_curve))),
        posterior: mean_ci(scores.iter().map(|s| mean(&s.posterior_curve))),
        viterbi_curve: average(|s| &s.viterbi_curve),
        posterior_curve: average(|s| &s.posterior_curve),
        example: scores
            .first()
            .map(|s| s.example.clone())
            .unwrap_or_default(),
    }
}

/// Test log-likelihood and decoding errors of one model.
fn score(
    model: &Hmm,
    space: &StateSpace,
    test: &[(Vec<usize>, Vec<usize>)],
    true_tracks: &[Track],
) -> Result<Score> {
    let mut ll = 0.0;
    let mut vit = Vec::with_capacity(test.len());
    let mut post = Vec::with_capacity(test.len());
    for (_, obs) in test {
        ll += forward(model, obs)?.log_likelihood;
        vit.push(viterbi(model, obs)?.0);
        post.push(posterior_decode(model, obs)?);
    }
    let n_steps = test.iter().map(|t| t.1.len()).sum::<usize>();
    let viterbi_curve = mean_error_series(true_tracks, &paths_to_tracks(space, &vit)?)?;
    let posterior_curve = mean_error_series(true_tracks, &paths_to_tracks(space, &post)?)?;
    Ok(Score {
        log_likelihood_per_step: ll / n_steps as f64,
        viterbi_curve,
        posterior_curve,
        example: vit.into_iter().next().unwrap_or_default(),
    })
}

/// The map's state space: the crossroads of a road graph or the free cells of a grid (Huynh &
/// Vu 2006 track on both).
fn state_space(map: &MapParams) -> Result<StateSpace> {
    Ok(match map {
        MapParams::Road { crossroads, roads } => StateSpace::from_road_graph(
            crossroads.iter().map(|c| Vec2::new(c[0], c[1])).collect(),
            &roads.iter().map(|r| (r[0], r[1])).collect::<Vec<_>>(),
        )?,
        MapParams::Grid(grid) => StateSpace::from_grid(grid)?,
    })
}

/// Every replicate, in parallel: replicate r draws from stream r of one generator seeded from
/// the scenario's (one draw of `rng`); results are collected in replicate order.
/// `n_seeds` replicates, replicate r drawn from stream r of ChaCha8(`base`).
fn run_replicates(
    p: &Params,
    space: &StateSpace,
    models: (&Hmm, &Hmm),
    trainer: &hmm_grid::BaumWelch,
    base: u64,
    env: &Env<'_>,
) -> Result<Vec<Replicate>> {
    (0..p.n_seeds)
        .into_par_iter()
        .map(|r| {
            let mut r_rng = ChaCha8Rng::seed_from_u64(base);
            r_rng.set_stream(r as u64);
            replicate(p, space, models, trainer, &mut r_rng, env)
        })
        .collect::<Result<Vec<_>>>()
}

/// The non-learned model, the model learned from the largest K (index `last_k`) and the true
/// model, each summarised over the replicates: the three rows of Huynh & Vu's (2006)
/// comparison.
/// The claimed comparisons, replicate by replicate (paired): the learned model (largest K)
/// against the non-learned one, the error from the smallest to the largest K, and the true
/// model against both.
fn fresh_comparisons(replicates: &[Replicate]) -> Vec<Comparison> {
    let of = |f: &dyn Fn(&Replicate) -> f64| replicates.iter().map(f).collect::<Vec<f64>>();
    fn learned(r: &Replicate) -> &Score {
        &r.fits[r.fits.len() - 1].score
    }
    fn smallest(r: &Replicate) -> &Score {
        &r.fits[0].score
    }
    let post = |s: &Score| mean(&s.posterior_curve);
    let vit = |s: &Score| mean(&s.viterbi_curve);
    let compare = |key: &str, statement: &str, ours: Vec<f64>, theirs: Vec<f64>| Comparison {
        key: key.into(),
        statement: statement.into(),
        units: "replicates",
        ours,
        theirs,
    };
    vec![
        compare(
            "learned_log_likelihood_above_nonlearned",
            "learned (largest K) test log-likelihood per step ≥ the non-learned model's",
            of(&|r| learned(r).log_likelihood_per_step),
            of(&|r| r.nonlearned.log_likelihood_per_step),
        ),
        compare(
            "learned_posterior_error_below_nonlearned",
            "learned (largest K) posterior-decoding error ≤ the non-learned model's",
            negated(&of(&|r| post(learned(r)))),
            negated(&of(&|r| post(&r.nonlearned))),
        ),
        compare(
            "learned_posterior_error_falls_with_k",
            "learned posterior-decoding error at the largest K ≤ at the smallest",
            negated(&of(&|r| post(learned(r)))),
            negated(&of(&|r| post(smallest(r)))),
        ),
        compare(
            "truth_viterbi_error_below_learned",
            "the true model's Viterbi error ≤ the learned model's (largest K)",
            negated(&of(&|r| vit(&r.truth))),
            negated(&of(&|r| vit(learned(r)))),
        ),
        compare(
            "truth_posterior_error_below_learned",
            "the true model's posterior-decoding error ≤ the learned model's (largest K)",
            negated(&of(&|r| post(&r.truth))),
            negated(&of(&|r| post(learned(r)))),
        ),
        compare(
            "truth_posterior_error_below_nonlearned",
            "the true model's posterior-decoding error ≤ the non-learned model's",
            negated(&of(&|r| post(&r.truth))),
            negated(&of(&|r| post(&r.nonlearned))),
        ),
    ]
}

fn model_scores(replicates: &[Replicate], last_k: usize) -> Vec<ModelScore> {
    vec![
        summarise(
            "non-learned",
            "nonlearned",
            &replicates.iter().map(|r| &r.nonlearned).collect::<Vec<_>>(),
        ),
        summarise(
            "learned (Baum-Welch)",
            "learned",
            &replicates
                .iter()
                .map(|r| &r.fits[last_k].score)
                .collect::<Vec<_>>(),
        ),
        summarise(
            "true model",
            "true",
            &replicates.iter().map(|r| &r.truth).collect::<Vec<_>>(),
        ),
    ]
}

/// The learning curve: for every K of `train_sizes`, the Baum-Welch iterations, the
/// replicates that converged, and the learned model's errors and test log-likelihood.
fn sweep_points(p: &Params, replicates: &[Replicate]) -> Vec<SweepPoint> {
    p.train_sizes
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let fits = || replicates.iter().map(|r| &r.fits[i]);
            SweepPoint {
                k,
                iterations: mean_ci(fits().map(|f| f.iterations as f64)),
                converged: fits().filter(|f| f.converged).count(),
                viterbi: mean_ci(fits().map(|f| mean(&f.score.viterbi_curve))),
                posterior: mean_ci(fits().map(|f| mean(&f.score.posterior_curve))),
                log_likelihood_per_step: mean_ci(fits().map(|f| f.score.log_likelihood_per_step)),
            }
        })
        .collect()
}

impl Pipeline for HmmTracking {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        anyhow::ensure!(
            p.train_sizes.first().is_some_and(|&k| k > 0)
                && p.train_sizes.windows(2).all(|w| w[0] < w[1]),
            "train_sizes must be ascending and positive"
        );
        anyhow::ensure!(
            p.n_test > 0 && p.train_len > 1 && p.test_len > 1,
            "need training and test sequences"
        );
        let n_train = *p.train_sizes.last().unwrap_or(&0);
        let space = state_space(&p.map)?;
        anyhow::ensure!(p.n_seeds > 0, "n_seeds must be positive");
        let (truth, naive) = build_models(p, &space, rng)?;
        let trainer = trainer(p)?;
        crate::seeds::check_disjoint(&[("reported", &[env.seed]), ("fresh", &[p.fresh_seed])])?;
        env.progress
            .set_length((2 * p.n_seeds * p.train_sizes.len()) as u64);
        let base: u64 = rng.random();
        let models = (&truth, &naive);
        let replicates = run_replicates(p, &space, models, &trainer, base, env)?;
        let fresh_replicates = run_replicates(p, &space, models, &trainer, p.fresh_seed, env)?;
        let fresh = fresh_comparisons(&fresh_replicates);
        fresh::check_verdicts(&fresh, &p.fresh_verdicts)?;
        let first = replicates.first().context("no replicate")?;
        let last_k = p.train_sizes.len() - 1;
        Ok(Output {
            is_road: matches!(p.map, MapParams::Road { .. }),
            n_train,
            train_len: p.train_len,
            n_test: p.n_test,
            test_len: p.test_len,
            n_seeds: p.n_seeds,
            max_iterations: p.bw_max_iterations,
            relative_tolerance: p.bw_relative_tolerance,
            note: p.note.clone(),
            true_path: first.true_path.clone(),
            models: model_scores(&replicates, last_k),
            sweep: sweep_points(p, &replicates),
            log_likelihoods: first.fits[last_k].log_likelihoods.clone(),
            space,
            fresh_converged: fresh_replicates
                .iter()
                .all(|r| r.fits.iter().all(|f| f.converged)),
            fresh,
            fresh_seed: p.fresh_seed,
            fresh_verdicts: p.fresh_verdicts.clone(),
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for m in &out.models {
            let key = m.key;
            for (name, v) in [
                ("test_log_likelihood_per_step", m.log_likelihood_per_step),
                ("mean_error_viterbi", m.viterbi),
                ("mean_error_posterior", m.posterior),
            ] {
                metrics.insert(format!("{name}_{key}"), v.mean);
                metrics.insert(format!("{name}_{key}_ci95"), v.ci);
            }
        }
        for s in &out.sweep {
            let k = s.k;
            for (name, v) in [
                ("mean_error_viterbi", s.viterbi),
                ("mean_error_posterior", s.posterior),
                ("baum_welch_iterations", s.iterations),
            ] {
                metrics.insert(format!("{name}_learned_k{k:04}"), v.mean);
                metrics.insert(format!("{name}_learned_k{k:04}_ci95"), v.ci);
            }
            metrics.insert(
                format!("baum_welch_converged_fraction_k{k:04}"),
                s.converged as f64 / out.n_seeds as f64,
            );
        }
        let ll = &out.log_likelihoods;
        metrics.insert(
            "train_log_likelihood_gain_seed0".into(),
            ll.last().copied().unwrap_or(0.0) - ll.first().copied().unwrap_or(0.0),
        );
        fresh::metrics(&out.fresh, &mut metrics);
        metrics
    }

    fn claims(out: &Output) -> Vec<Claim> {
        // The orderings are claimed on the fresh replicates only (the reported ones were
        // looked at while the model was chosen).
        let mut claims = vec![Claim::new(
            "Baum-Welch meets its relative tolerance in every run (every K, every replicate, \
             reported and fresh)",
            out.sweep.iter().all(|s| s.converged == out.n_seeds) && out.fresh_converged,
        )];
        claims.extend(fresh::claims(
            &out.fresh,
            &out.fresh_verdicts,
            &format!("seed {}", out.fresh_seed),
        ));
        claims
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        // Huynh & Vu (2006) publish no number: Fig. 6 shows the learned model's distance error
        // below the non-learned one's at nearly every time step. Ours put numbers on it.
        let map = if out.is_road {
            "road graph"
        } else {
            "cell grid"
        };
        let paper = |text: &str| Some(text.to_string());
        let [nonlearned, learned, truth] = [&out.models[0], &out.models[1], &out.models[2]];
        vec![
            Headline {
                quantity: format!("mean distance error (m), Viterbi, non-learned model ({map})"),
                paper: paper("above the learned model's (Fig. 6, no value)"),
                ours: nonlearned.viterbi.show(),
                peer: None,
            },
            Headline {
                quantity: format!(
                    "mean distance error (m), Viterbi, learned by Baum-Welch ({map})"
                ),
                paper: paper("below the non-learned model's (Fig. 6, no value)"),
                ours: learned.viterbi.show(),
                peer: None,
            },
            Headline {
                quantity: format!("mean distance error (m), Viterbi, true model ({map})"),
                paper: None,
                ours: truth.viterbi.show(),
                peer: None,
            },
        ]
    }

    fn present(out: &Output) -> Section {
        let metrics = Self::metrics(out);
        let map_kind = if out.is_road {
            "road graph"
        } else {
            "cell grid"
        };
        Section {
            title: format!(
                "HMM ground-target tracking: learning against not learning ({map_kind} map)"
            ),
            summary: summary(out),
            tables: vec![
                fresh::table(
                    &format!(
                        "Fresh replicates (seed {}; never used to choose anything): per \
                         replicate, ours − theirs (errors negated so that higher is better)",
                        out.fresh_seed
                    ),
                    &out.fresh,
                    &out.fresh_verdicts,
                ),
                model_table(out),
                sweep_table(out, &metrics),
            ],
            figures: vec![
                Figure::new(
                    "error",
                    "Distance error against time step, Viterbi (thick) and posterior decoding (thin)",
                    error_chart(out),
                ),
                Figure::new(
                    "map",
                    "True path and Viterbi paths of the three models on the map",
                    map_chart(out),
                ),
                Figure::new(
                    "learning-curve",
                    "Distance error of the learned model against the number of training sequences, \
                     mean (thick) and 95 % CI (thin) over the replicates",
                    learning_chart(out, &metrics),
                ),
                Figure::new(
                    "training",
                    "Training log-likelihood by Baum-Welch iteration",
                    Chart::new(
                        "Baum-Welch training log-likelihood",
                        "iteration",
                        "log-likelihood (nats)",
                        vec![Series::new(
                            "training sequences",
                            out.log_likelihoods
                                .iter()
                                .enumerate()
                                .map(|(k, v)| (k as f64, *v))
                                .collect(),
                            Style::Line,
                            0,
                        )],
                    ),
                ),
            ],
        }
    }
}

/// The section's summary: the setup and, in plain words, where learning helps and where not.
fn summary(out: &Output) -> String {
    let [nonlearned, learned, _] = [&out.models[0], &out.models[1], &out.models[2]];
    let viterbi_apart =
        learned.viterbi.mean + learned.viterbi.ci < nonlearned.viterbi.mean - nonlearned.viterbi.ci;
    let viterbi_text = if viterbi_apart {
        format!(
            "Learning also lowers the Viterbi error ({} against {} non-learned, CIs apart).",
            learned.viterbi.show(),
            nonlearned.viterbi.show()
        )
    } else {
        format!(
            "Learning does not measurably lower the Viterbi error on this map ({} against {} \
             non-learned, CIs overlap): the gain is in posterior decoding and in the likelihood.",
            learned.viterbi.show(),
            nonlearned.viterbi.show()
        )
    };
    // Where learning loses: the K at which the learned model decodes worse than the
    // non-learned one.
    let worse = |get: fn(&SweepPoint) -> MeanCi, base: MeanCi| -> Vec<String> {
        out.sweep
            .iter()
            .filter(|s| get(s).mean > base.mean)
            .map(|s| s.k.to_string())
            .collect()
    };
    let losses = [
        (
            "posterior decoding",
            worse(|s| s.posterior, nonlearned.posterior),
        ),
        ("Viterbi", worse(|s| s.viterbi, nonlearned.viterbi)),
    ]
    .into_iter()
    .filter(|(_, ks)| !ks.is_empty())
    .map(|(name, ks)| format!("{name} at K = {}", ks.join(", ")))
    .collect::<Vec<_>>();
    let loss_text = if losses.is_empty() {
        "The learned model is no worse than the non-learned one at any K.".to_string()
    } else {
        format!(
            "Where learning loses: the learned model decodes worse than the non-learned one \
             (higher mean error, whether or not the CIs overlap) with {}.",
            losses.join(" and with ")
        )
    };
    format!(
        "The target's true transition habits and the sensors' true accuracy are unknown to the \
         non-learned model; Baum-Welch learns them from the training sequences (initial \
         distribution frozen; at most {} iterations, stopping when |ΔLL| ≤ {:e}·|LL|). Every \
         number is mean ± 95 % CI (1.96 s/√n) over {} replicates, each with its own training and \
         test sequences. Lower distance error is better; the true model is the bound. Learned \
         from K = {}, the posterior-decoding error is {} against {} non-learned. {} {} {}",
        out.max_iterations,
        out.relative_tolerance,
        out.n_seeds,
        out.n_train,
        learned.posterior.show(),
        nonlearned.posterior.show(),
        viterbi_text,
        loss_text,
        out.note
    )
    .trim_end()
    .to_string()
}

/// Log-likelihood and mean errors of the three models.
fn model_table(out: &Output) -> Table {
    let mut table = Table::new(
        &format!(
            "{} states; {} training sequences of {} steps; {} test sequences of {} steps; \
             mean ± 95 % CI over {} replicates",
            out.space.n_states(),
            out.n_train,
            out.train_len,
            out.n_test,
            out.test_len,
            out.n_seeds
        ),
        &[
            "model",
            "test log-likelihood per step",
            "mean error, Viterbi",
            "mean error, posterior decoding",
        ],
    );
    for m in &out.models {
        table.row(vec![
            m.name.into(),
            m.log_likelihood_per_step.show(),
            m.viterbi.show(),
            m.posterior.show(),
        ]);
    }
    table
}

/// The learning curve as a table.
fn sweep_table(out: &Output, metrics: &Metrics) -> Table {
    let mut sweep = Table::new(
        &format!(
            "Distance error on the test sequences against the number K of training sequences, \
             mean ± 95 % CI over {} replicates (non-learned: Viterbi {}, posterior {}; true \
             model: Viterbi {}, posterior {})",
            out.n_seeds,
            fmt_num(metrics["mean_error_viterbi_nonlearned"]),
            fmt_num(metrics["mean_error_posterior_nonlearned"]),
            fmt_num(metrics["mean_error_viterbi_true"]),
            fmt_num(metrics["mean_error_posterior_true"]),
        ),
        &[
            "K",
            "Baum-Welch iterations",
            "converged",
            "test log-likelihood per step",
            "mean error, Viterbi",
            "mean error, posterior decoding",
        ],
    );
    for s in &out.sweep {
        sweep.row(vec![
            s.k.to_string(),
            s.iterations.show(),
            format!("{}/{}", s.converged, out.n_seeds),
            s.log_likelihood_per_step.show(),
            s.viterbi.show(),
            s.posterior.show(),
        ]);
    }
    sweep
}

/// Distance error against time, per model and decoder.
fn error_chart(out: &Output) -> Chart {
    let mut err_series = Vec::new();
    for (c, m) in out.models.iter().enumerate() {
        let pts = |v: &[f64]| {
            v.iter()
                .enumerate()
                .map(|(t, e)| (t as f64, *e))
                .collect::<Vec<_>>()
        };
        err_series.push(Series::new(
            &format!("{}, Viterbi", m.name),
            pts(&m.viterbi_curve),
            Style::Line,
            c,
        ));
        // A colour of its own (after the models' Viterbi colours): the two estimators of a
        // model are what the chart compares, and a paler shade of one colour hid that.
        err_series.push(Series::new(
            &format!("{}, posterior", m.name),
            pts(&m.posterior_curve),
            Style::Line,
            c + out.models.len(),
        ));
    }
    Chart::new(
        "Distance error against time (mean over test sequences)",
        "time step",
        "distance error (m)",
        err_series,
    )
}

/// The map: links between states, the true path of test sequence 0 and the estimates,
/// offset slightly so overlapping paths stay visible.
fn map_chart(out: &Output) -> Chart {
    let space = &out.space;
    let mut map_series = Vec::new();
    for i in 0..space.n_states() {
        for &j in space.neighbours(i) {
            if i < j {
                let (a, b) = (space.position(i), space.position(j));
                map_series.push(Series::new(
                    "",
                    vec![(a.x, a.y), (b.x, b.y)],
                    Style::Faint,
                    7,
                ));
            }
        }
    }
    let extent = space
        .positions()
        .iter()
        .fold(0.0f64, |m, q| m.max(q.x).max(q.y));
    let path_points = |path: &[usize], offset: f64| -> Vec<(f64, f64)> {
        path.iter()
            .map(|&s| space.position(s))
            .map(|q| (q.x + offset, q.y + offset))
            .collect()
    };
    // The truth over the estimates, in grey (the models take the colours).
    map_series.push(
        Series::new(
            "true path",
            path_points(&out.true_path, 0.0),
            Style::Line,
            7,
        )
        .in_front(),
    );
    for (c, m) in out.models.iter().enumerate() {
        map_series.push(Series::new(
            &format!("{} (Viterbi)", m.name),
            path_points(&m.example, (c as f64 + 1.0) * 0.008 * extent),
            Style::Line,
            c,
        ));
    }
    Chart::new("Test sequence 0 on the map", "x (m)", "y (m)", map_series).with_equal_aspect()
}

/// Mean error of the learned model against K with its 95 % CI band, Viterbi and posterior
/// decoding, and the other two models as flat lines.
fn learning_chart(out: &Output, metrics: &Metrics) -> Chart {
    let curve = |f: &dyn Fn(&SweepPoint) -> f64| -> Vec<(f64, f64)> {
        out.sweep.iter().map(|s| (s.k as f64, f(s))).collect()
    };
    let (first, last) = (
        out.sweep[0].k as f64,
        out.sweep[out.sweep.len() - 1].k as f64,
    );
    let flat = |v: f64| vec![(first, v), (last, v)];
    let mut series = Vec::new();
    for (name, colour, get) in [
        (
            "Viterbi",
            1,
            (|s: &SweepPoint| s.viterbi) as fn(&SweepPoint) -> MeanCi,
        ),
        ("posterior", 4, |s: &SweepPoint| s.posterior),
    ] {
        series.push(Series::new(
            &format!("learned, {name}"),
            curve(&|s| get(s).mean),
            Style::Line,
            colour,
        ));
        series.push(Series::new(
            &format!("95 % CI, {name}"),
            curve(&|s| get(s).mean - get(s).ci),
            Style::ThinLine,
            colour,
        ));
        series.push(Series::new(
            "",
            curve(&|s| get(s).mean + get(s).ci),
            Style::ThinLine,
            colour,
        ));
    }
    for (label, key, colour) in [
        ("non-learned, Viterbi", "mean_error_viterbi_nonlearned", 0),
        (
            "non-learned, posterior",
            "mean_error_posterior_nonlearned",
            0,
        ),
        ("true model, Viterbi", "mean_error_viterbi_true", 2),
        ("true model, posterior", "mean_error_posterior_true", 2),
    ] {
        series.push(Series::new(
            label,
            flat(metrics[key]),
            Style::ThinLine,
            colour,
        ));
    }
    Chart::new(
        "Learning curve",
        "training sequences K",
        "mean distance error (m)",
        series,
    )
}
