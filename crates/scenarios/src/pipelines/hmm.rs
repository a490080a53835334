//! `hmm-tracking`: Huynh & Vu's (2006) experiment. A target moves on a map (a road graph of crossroads or
//! a cell grid with obstacles) with habits the generic model does not know; sensors give coarse
//! position fixes whose accuracy falls with distance. A non-learned model (kinematic
//! constraints only, a mis-specified sensor model) is compared with the same model after
//! Baum-Welch on K training sequences, and with the true model, by the distance error of the
//! Viterbi and posterior-decoded paths on fresh test sequences.

use anyhow::{Context, Result};
use eval_metrics::distance_error_series;
use hmm_grid::{
    BaumWelchConfig, CellGrid, FitReport, Freeze, Hmm, PseudoCounts, SensorModel,
    SpeedDistribution, StateSpace, Transitions, forward, posterior_decode, viterbi,
};
use rand::{Rng, RngExt};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use tracker_model::{Frame, Track, TrackId, Vec2};

use crate::{Chart, Env, Figure, Metrics, Pipeline, Section, Series, Style, Table, fmt_num};

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
    /// Keep B fixed during training (useful when M is large and data few).
    freeze_emissions: bool,
    transition_pseudo_count: f64,
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

/// One model's scores on the test sequences.
pub struct ModelScore {
    /// Name in tables and legends.
    name: &'static str,
    /// Metric key suffix.
    key: &'static str,
    /// Test log-likelihood per step.
    log_likelihood_per_step: f64,
    /// Mean distance error per step, Viterbi.
    viterbi_curve: Vec<f64>,
    /// Mean distance error per step, posterior decoding.
    posterior_curve: Vec<f64>,
    /// The Viterbi path of test sequence 0.
    example: Vec<usize>,
}

/// One point of the learning curve.
pub struct SweepPoint {
    /// Training sequences K.
    k: usize,
    /// Baum-Welch iterations.
    iterations: usize,
    /// Mean Viterbi distance error of the model learned from K sequences.
    mean_error: f64,
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
    /// Test sequences.
    n_test: usize,
    /// Steps per test sequence.
    test_len: usize,
    /// The true path of test sequence 0.
    true_path: Vec<usize>,
    /// Non-learned, learned (largest K) and true model, in that order.
    models: Vec<ModelScore>,
    /// The learning curve, by ascending K.
    sweep: Vec<SweepPoint>,
    /// Training log-likelihoods of the largest K's Baum-Welch run.
    log_likelihoods: Vec<f64>,
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

/// Learns from the first K sequences for every K of the sweep.
fn learn(
    p: &Params,
    naive: &Hmm,
    train: &[Vec<usize>],
    env: &Env<'_>,
) -> Result<Vec<(usize, Hmm, FitReport)>> {
    // The initial distribution is known (uniform), as in Huynh & Vu (2006): freeze it.
    let trainer = BaumWelchConfig {
        max_iterations: p.bw_max_iterations,
        tolerance: 1e-6,
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
    .check()?;
    env.progress.set_length(p.train_sizes.len() as u64);
    let mut runs = Vec::new();
    for &k in &p.train_sizes {
        let (model, fit) = trainer.fit(naive, &train[..k]).context("Baum-Welch")?;
        env.progress.advance(1);
        runs.push((k, model, fit));
    }
    Ok(runs)
}

/// Test log-likelihood and decoding errors of one model.
fn score(
    (name, key, model): (&'static str, &'static str, &Hmm),
    space: &StateSpace,
    test: &[(Vec<usize>, Vec<usize>)],
    true_tracks: &[Track],
) -> Result<ModelScore> {
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
    Ok(ModelScore {
        name,
        key,
        log_likelihood_per_step: ll / n_steps as f64,
        viterbi_curve,
        posterior_curve,
        example: vit.into_iter().next().unwrap_or_default(),
    })
}

/// Mean Viterbi distance error of `model` on the test sequences.
fn viterbi_error(
    model: &Hmm,
    space: &StateSpace,
    test: &[(Vec<usize>, Vec<usize>)],
    true_tracks: &[Track],
) -> Result<f64> {
    let mut decoded = Vec::with_capacity(test.len());
    for (_, obs) in test {
        decoded.push(viterbi(model, obs)?.0);
    }
    Ok(mean(&mean_error_series(
        true_tracks,
        &paths_to_tracks(space, &decoded)?,
    )?))
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
        let space = match &p.map {
            MapParams::Road { crossroads, roads } => StateSpace::from_road_graph(
                crossroads.iter().map(|c| Vec2::new(c[0], c[1])).collect(),
                &roads.iter().map(|r| (r[0], r[1])).collect::<Vec<_>>(),
            )?,
            MapParams::Grid(grid) => StateSpace::from_grid(grid)?,
        };
        let (truth, naive) = build_models(p, &space, rng)?;
        let train: Vec<Vec<usize>> = (0..n_train)
            .map(|_| truth.sample(p.train_len, rng).1)
            .collect();
        let test: Vec<(Vec<usize>, Vec<usize>)> = (0..p.n_test)
            .map(|_| truth.sample(p.test_len, rng))
            .collect();
        let learned_runs = learn(p, &naive, &train, env)?;
        let (_, learned, fit) = learned_runs.last().context("no training run")?;

        let true_paths: Vec<Vec<usize>> = test.iter().map(|t| t.0.clone()).collect();
        let true_tracks = paths_to_tracks(&space, &true_paths)?;
        let models = [
            ("non-learned", "nonlearned", &naive),
            ("learned (Baum-Welch)", "learned", learned),
            ("true model", "true", &truth),
        ]
        .into_iter()
        .map(|m| score(m, &space, &test, &true_tracks))
        .collect::<Result<Vec<_>>>()?;
        let sweep = learned_runs
            .iter()
            .map(|(k, model, fit)| {
                Ok(SweepPoint {
                    k: *k,
                    iterations: fit.log_likelihoods.len() - 1,
                    mean_error: viterbi_error(model, &space, &test, &true_tracks)?,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Output {
            is_road: matches!(p.map, MapParams::Road { .. }),
            n_train,
            train_len: p.train_len,
            n_test: p.n_test,
            test_len: p.test_len,
            true_path: test[0].0.clone(),
            models,
            sweep,
            log_likelihoods: fit.log_likelihoods.clone(),
            space,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for m in &out.models {
            metrics.insert(
                format!("test_log_likelihood_per_step_{}", m.key),
                m.log_likelihood_per_step,
            );
            metrics.insert(
                format!("mean_error_viterbi_{}", m.key),
                mean(&m.viterbi_curve),
            );
            metrics.insert(
                format!("mean_error_posterior_{}", m.key),
                mean(&m.posterior_curve),
            );
        }
        for s in &out.sweep {
            metrics.insert(
                format!("mean_error_viterbi_learned_k{:04}", s.k),
                s.mean_error,
            );
        }
        let ll = &out.log_likelihoods;
        metrics.insert("baum_welch_iterations".into(), (ll.len() - 1) as f64);
        metrics.insert(
            "train_log_likelihood_gain".into(),
            ll.last().copied().unwrap_or(0.0) - ll.first().copied().unwrap_or(0.0),
        );
        metrics
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
            summary: "The target's true transition habits and the sensors' true accuracy are unknown to the \
                      non-learned model; Baum-Welch learns them from the training sequences (initial \
                      distribution frozen). Lower distance error is better; the true model is the bound."
                .into(),
            tables: vec![model_table(out), sweep_table(out, &metrics)],
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
                    "Viterbi distance error of the learned model against the number of training sequences",
                    learning_chart(out, &metrics),
                ),
                Figure::new(
                    "training",
                    "Training log-likelihood by Baum-Welch iteration",
                    Chart::new(
                        "Baum-Welch training log-likelihood",
                        "iteration",
                        "log-likelihood",
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

/// Log-likelihood and mean errors of the three models.
fn model_table(out: &Output) -> Table {
    let mut table = Table::new(
        &format!(
            "{} states; {} training sequences of {} steps; {} test sequences of {} steps",
            out.space.n_states(),
            out.n_train,
            out.train_len,
            out.n_test,
            out.test_len
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
            fmt_num(m.log_likelihood_per_step),
            fmt_num(mean(&m.viterbi_curve)),
            fmt_num(mean(&m.posterior_curve)),
        ]);
    }
    table
}

/// The learning curve as a table.
fn sweep_table(out: &Output, metrics: &Metrics) -> Table {
    let mut sweep = Table::new(
        "Viterbi distance error on the test sequences against the number K of training sequences",
        &[
            "K",
            "Baum-Welch iterations",
            "mean error, learned",
            "mean error, non-learned",
            "mean error, true model",
        ],
    );
    for s in &out.sweep {
        sweep.row(vec![
            s.k.to_string(),
            s.iterations.to_string(),
            fmt_num(s.mean_error),
            fmt_num(metrics["mean_error_viterbi_nonlearned"]),
            fmt_num(metrics["mean_error_viterbi_true"]),
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
        err_series.push(Series::new(
            &format!("{}, posterior", m.name),
            pts(&m.posterior_curve),
            Style::ThinLine,
            c,
        ));
    }
    Chart::new(
        "Distance error against time (mean over test sequences)",
        "time step",
        "distance error",
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
                    Style::ThinLine,
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
    map_series.push(Series::new(
        "true path",
        path_points(&out.true_path, 0.0),
        Style::Line,
        3,
    ));
    for (c, m) in out.models.iter().enumerate() {
        map_series.push(Series::new(
            &format!("{} (Viterbi)", m.name),
            path_points(&m.example, (c as f64 + 1.0) * 0.008 * extent),
            Style::Line,
            c,
        ));
    }
    Chart::new("Test sequence 0 on the map", "x", "y", map_series)
}

/// Mean Viterbi error of the learned model against K, with the other two as flat lines.
fn learning_chart(out: &Output, metrics: &Metrics) -> Chart {
    let k_curve: Vec<(f64, f64)> = out
        .sweep
        .iter()
        .map(|s| (s.k as f64, s.mean_error))
        .collect();
    let (first, last) = (k_curve[0].0, k_curve[k_curve.len() - 1].0);
    let flat = |v: f64| vec![(first, v), (last, v)];
    Chart::new(
        "Learning curve",
        "training sequences K",
        "mean Viterbi distance error",
        vec![
            Series::new("learned", k_curve, Style::Line, 1),
            Series::new(
                "non-learned",
                flat(metrics["mean_error_viterbi_nonlearned"]),
                Style::ThinLine,
                0,
            ),
            Series::new(
                "true model",
                flat(metrics["mean_error_viterbi_true"]),
                Style::ThinLine,
                2,
            ),
        ],
    )
}
