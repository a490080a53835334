//! `hmm-tracking`: seed 002's experiment. A target moves on a map (a road graph of crossroads or
//! a cell grid with obstacles) with habits the generic model does not know; sensors give coarse
//! position fixes whose accuracy falls with distance. A non-learned model (kinematic
//! constraints only, a mis-specified sensor model) is compared with the same model after
//! Baum-Welch on K training sequences, and with the true model, by the distance error of the
//! Viterbi and posterior-decoded paths on fresh test sequences.

use anyhow::{Context, Result};
use hmm_grid::{
    BaumWelchConfig, CellGrid, Freeze, Hmm, PseudoCounts, SensorModel, SpeedDistribution,
    StateSpace, Transitions, baum_welch, forward, posterior_decode, viterbi,
};
use indicatif::ProgressBar;
use rand::{Rng, RngExt};
use serde::Deserialize;
use tracker_model::Point2;

use crate::plot::{Axes, Series, Style, chart};
use crate::report::{Plot, Section, Table, fmt_num};
use crate::scenario::{Metrics, PipelineOutput, Scenario};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
enum MapParams {
    /// Crossroads and the roads between them.
    Road {
        crossroads: Vec<[f64; 2]>,
        roads: Vec<[usize; 2]>,
    },
    /// A cell grid with obstacles.
    Grid(CellGrid),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SensorParams {
    base_sigma: f64,
    sigma_per_distance: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Params {
    map: MapParams,
    sensors: Vec<[f64; 2]>,
    /// The truth's hop-count distribution; its per-state habits are drawn from the seed.
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
        sensors: p.sensors.iter().map(|q| Point2::new(q[0], q[1])).collect(),
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

/// Mean over test sequences of the distance between true and decoded positions, per step.
fn error_curve(space: &StateSpace, truth: &[Vec<usize>], decoded: &[Vec<usize>]) -> Vec<f64> {
    let len = truth[0].len();
    (0..len)
        .map(|t| {
            truth
                .iter()
                .zip(decoded)
                .map(|(s, d)| (space.position(s[t]) - space.position(d[t])).norm())
                .sum::<f64>()
                / truth.len() as f64
        })
        .collect()
}

pub fn run(scenario: &Scenario, progress: &ProgressBar) -> Result<PipelineOutput> {
    let p: Params = scenario.params()?;
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
            crossroads.iter().map(|c| Point2::new(c[0], c[1])).collect(),
            &roads.iter().map(|r| (r[0], r[1])).collect::<Vec<_>>(),
        )?,
        MapParams::Grid(grid) => StateSpace::from_grid(grid)?,
    };
    let n = space.n_states();
    let mut rng = scenario.rng();
    let uniform = vec![1.0 / n as f64; n];
    let generic_true = space.transitions(&SpeedDistribution::new(p.true_speed.clone())?)?;
    let truth = Hmm::new(
        uniform.clone(),
        habitual(&generic_true, p.habit_strength, &mut rng)?,
        space.sensor_emissions(&sensor_model(&p, &p.true_sensor))?,
        n,
    )?;
    let naive = Hmm::new(
        uniform,
        space.transitions(&SpeedDistribution::new(p.model_speed.clone())?)?,
        space.sensor_emissions(&sensor_model(&p, &p.model_sensor))?,
        n,
    )?;
    let train: Vec<Vec<usize>> = (0..n_train)
        .map(|_| truth.sample(p.train_len, &mut rng).1)
        .collect();
    let test: Vec<(Vec<usize>, Vec<usize>)> = (0..p.n_test)
        .map(|_| truth.sample(p.test_len, &mut rng))
        .collect();
    progress.set_length(p.train_sizes.len() as u64);
    // The initial distribution is known (uniform), as in the seed: freeze it.
    let config = BaumWelchConfig {
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
    };
    // Learn from the first K sequences for every K of the sweep; keep the largest K's model.
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
    let mut learned_runs = Vec::new();
    for &k in &p.train_sizes {
        let (model, fit) = baum_welch(&naive, &train[..k], &config).context("Baum-Welch")?;
        progress.inc(1);
        learned_runs.push((k, model, fit));
    }
    let (_, learned, fit) = learned_runs.last().cloned().context("no training run")?;

    let true_states: Vec<Vec<usize>> = test.iter().map(|t| t.0.clone()).collect();
    let mut metrics = Metrics::new();
    let mut table = Table::new(
        &format!(
            "{} states; {} training sequences of {} steps; {} test sequences of {} steps",
            n, n_train, p.train_len, p.n_test, p.test_len
        ),
        &[
            "model",
            "test log-likelihood per step",
            "mean error, Viterbi",
            "mean error, posterior decoding",
        ],
    );
    let mut curves = Vec::new();
    let mut example = Vec::new();
    for (name, key, model) in [
        ("non-learned", "nonlearned", &naive),
        ("learned (Baum-Welch)", "learned", &learned),
        ("true model", "true", &truth),
    ] {
        let mut ll = 0.0;
        let mut vit = Vec::with_capacity(test.len());
        let mut post = Vec::with_capacity(test.len());
        for (_, obs) in &test {
            ll += forward(model, obs)?.log_likelihood;
            vit.push(viterbi(model, obs)?.0);
            post.push(posterior_decode(model, obs)?);
        }
        let per_step = ll / (p.n_test * p.test_len) as f64;
        let vit_curve = error_curve(&space, &true_states, &vit);
        let post_curve = error_curve(&space, &true_states, &post);
        let mean = |c: &[f64]| c.iter().sum::<f64>() / c.len() as f64;
        metrics.insert(format!("test_log_likelihood_per_step_{key}"), per_step);
        metrics.insert(format!("mean_error_viterbi_{key}"), mean(&vit_curve));
        metrics.insert(format!("mean_error_posterior_{key}"), mean(&post_curve));
        table.row(vec![
            name.into(),
            fmt_num(per_step),
            fmt_num(mean(&vit_curve)),
            fmt_num(mean(&post_curve)),
        ]);
        curves.push((name, vit_curve, post_curve));
        example.push((name, vit[0].clone()));
    }
    let test_error = |model: &Hmm| -> Result<f64> {
        let mut decoded = Vec::with_capacity(test.len());
        for (_, obs) in &test {
            decoded.push(viterbi(model, obs)?.0);
        }
        let curve = error_curve(&space, &true_states, &decoded);
        Ok(curve.iter().sum::<f64>() / curve.len() as f64)
    };
    let mut k_curve = Vec::new();
    for (k, model, fit) in &learned_runs {
        let e = test_error(model)?;
        metrics.insert(format!("mean_error_viterbi_learned_k{k:04}"), e);
        k_curve.push((*k as f64, e));
        sweep.row(vec![
            k.to_string(),
            (fit.log_likelihoods.len() - 1).to_string(),
            fmt_num(e),
            fmt_num(metrics["mean_error_viterbi_nonlearned"]),
            fmt_num(metrics["mean_error_viterbi_true"]),
        ]);
    }
    metrics.insert(
        "baum_welch_iterations".into(),
        (fit.log_likelihoods.len() - 1) as f64,
    );
    metrics.insert(
        "train_log_likelihood_gain".into(),
        fit.log_likelihoods.last().copied().unwrap_or(0.0) - fit.log_likelihoods[0],
    );

    let mut err_series = Vec::new();
    for (c, (name, vit, post)) in curves.iter().enumerate() {
        let pts = |v: &[f64]| {
            v.iter()
                .enumerate()
                .map(|(t, e)| (t as f64, *e))
                .collect::<Vec<_>>()
        };
        err_series.push(Series::new(
            &format!("{name}, Viterbi"),
            pts(vit),
            Style::Line,
            c,
        ));
        err_series.push(Series::new(
            &format!("{name}, posterior"),
            pts(post),
            Style::ThinLine,
            c,
        ));
    }
    let error_plot = chart(
        &Axes {
            title: "Distance error against time (mean over test sequences)",
            x: "time step",
            y: "distance error",
        },
        &err_series,
    )?;

    // The map: links between states, the true path of test sequence 0 and the estimates,
    // offset slightly so overlapping paths stay visible.
    let mut map_series = Vec::new();
    for i in 0..n {
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
        path_points(&test[0].0, 0.0),
        Style::Line,
        3,
    ));
    for (c, (name, path)) in example.iter().enumerate() {
        map_series.push(Series::new(
            &format!("{name} (Viterbi)"),
            path_points(path, (c as f64 + 1.0) * 0.008 * extent),
            Style::Line,
            c,
        ));
    }
    let map_plot = chart(
        &Axes {
            title: "Test sequence 0 on the map",
            x: "x",
            y: "y",
        },
        &map_series,
    )?;
    let ll_plot = chart(
        &Axes {
            title: "Baum-Welch training log-likelihood",
            x: "iteration",
            y: "log-likelihood",
        },
        &[Series::new(
            "training sequences",
            fit.log_likelihoods
                .iter()
                .enumerate()
                .map(|(k, v)| (k as f64, *v))
                .collect(),
            Style::Line,
            0,
        )],
    )?;
    let flat = |v: f64| vec![(k_curve[0].0, v), (k_curve[k_curve.len() - 1].0, v)];
    let k_plot = chart(
        &Axes {
            title: "Learning curve",
            x: "training sequences K",
            y: "mean Viterbi distance error",
        },
        &[
            Series::new("learned", k_curve.clone(), Style::Line, 1),
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
    )?;
    Ok(PipelineOutput {
        metrics,
        section: Section {
            title: format!("HMM ground-target tracking: learning against not learning ({} map)", match p.map { MapParams::Road { .. } => "road graph", MapParams::Grid(_) => "cell grid" }),
            summary: "The target's true transition habits and the sensors' true accuracy are unknown to the \
                      non-learned model; Baum-Welch learns them from the training sequences (initial \
                      distribution frozen). Lower distance error is better; the true model is the bound."
                .into(),
            tables: vec![table, sweep],
            plots: vec![
                Plot { name: "error".into(), caption: "Distance error against time step, Viterbi (thick) and posterior decoding (thin)".into(), svg: error_plot },
                Plot { name: "map".into(), caption: "True path and Viterbi paths of the three models on the map".into(), svg: map_plot },
                Plot { name: "learning-curve".into(), caption: "Viterbi distance error of the learned model against the number of training sequences".into(), svg: k_plot },
                Plot { name: "training".into(), caption: "Training log-likelihood by Baum-Welch iteration".into(), svg: ll_plot },
            ],
        },
    })
}
