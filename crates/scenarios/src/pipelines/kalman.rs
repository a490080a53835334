//! `kalman-crossing`: two targets on crossing paths, each filtered and smoothed with its true
//! measurements (no association problem), over many seeded Monte Carlo runs. Shows what RTS
//! smoothing buys over filtering and checks that both are consistent (average NEES inside its
//! 95 % χ² interval).

use anyhow::{Context, Result};
use nalgebra::{Matrix4, Vector2, Vector4};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::{
    ConstantVelocity2, CvNoise, Gaussian, TransitionModel, anees_interval_95, filter,
    position_measurement, smooth,
};

use crate::{Chart, Claim, Env, Figure, Metrics, Pipeline, Section, Series, Style, Table, fmt_num};

/// The `kalman-crossing` pipeline.
pub struct KalmanCrossing;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Monte Carlo runs.
    n_runs: usize,
    /// Scans per run.
    n_steps: usize,
    /// Sampling period.
    dt_s: f64,
    /// White-acceleration spectral density q.
    accel_psd: f64,
    /// Position measurement standard deviation (per axis).
    measurement_sigma: f64,
    /// Probability that a scan has the target's measurement.
    p_detect: f64,
    /// Speed of both targets at the start.
    speed: f64,
    /// Prior standard deviations of position and velocity.
    prior_sigma_position: f64,
    prior_sigma_velocity: f64,
}

/// Per-run accumulators, indexed by time step.
#[derive(Clone)]
pub struct RunStats {
    sq_pos_filtered: Vec<f64>,
    sq_pos_smoothed: Vec<f64>,
    sq_vel_filtered: Vec<f64>,
    sq_vel_smoothed: Vec<f64>,
    nees_filtered: Vec<f64>,
    nees_smoothed: Vec<f64>,
    missed: usize,
}

impl RunStats {
    fn zeros(n: usize) -> Self {
        Self {
            sq_pos_filtered: vec![0.0; n],
            sq_pos_smoothed: vec![0.0; n],
            sq_vel_filtered: vec![0.0; n],
            sq_vel_smoothed: vec![0.0; n],
            nees_filtered: vec![0.0; n],
            nees_smoothed: vec![0.0; n],
            missed: 0,
        }
    }

    fn add(&mut self, other: &Self) {
        let pairs = [
            (&mut self.sq_pos_filtered, &other.sq_pos_filtered),
            (&mut self.sq_pos_smoothed, &other.sq_pos_smoothed),
            (&mut self.sq_vel_filtered, &other.sq_vel_filtered),
            (&mut self.sq_vel_smoothed, &other.sq_vel_smoothed),
            (&mut self.nees_filtered, &other.nees_filtered),
            (&mut self.nees_smoothed, &other.nees_smoothed),
        ];
        for (a, b) in pairs {
            a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        }
        self.missed += other.missed;
    }
}

/// One target's truth, measurements and estimates in one run (kept for the plot).
pub struct TargetRun {
    truth: Vec<Vector4<f64>>,
    measurements: Vec<Option<Vector2<f64>>>,
    filtered: Vec<Gaussian<4>>,
    smoothed: Vec<Gaussian<4>>,
}

fn normal4(rng: &mut ChaCha8Rng) -> Vector4<f64> {
    Vector4::from_fn(|_, _| StandardNormal.sample(rng))
}

fn simulate_target(
    p: &Params,
    motion: &ConstantVelocity2,
    start: Vector4<f64>,
    rng: &mut ChaCha8Rng,
) -> Result<TargetRun> {
    let f = motion.transition_matrix(1);
    let l_q = motion
        .process_noise(1)
        .cholesky()
        .context("white-acceleration Q must be positive definite")?
        .l();
    let sensor = position_measurement(p.measurement_sigma.powi(2))?;
    let mut x = start;
    let mut truth = Vec::with_capacity(p.n_steps);
    let mut measurements = Vec::with_capacity(p.n_steps);
    for k in 0..p.n_steps {
        if k > 0 {
            x = f * x + l_q * normal4(rng);
        }
        truth.push(x);
        let detected = rng.random_bool(p.p_detect);
        let noise = Vector2::from_fn(|_, _| StandardNormal.sample(rng)) * p.measurement_sigma;
        measurements.push(detected.then(|| x.fixed_rows::<2>(0) + noise));
    }
    // The prior is centred on a draw around the true start, so the filter is consistent by
    // construction and its NEES must be χ²(4)-distributed.
    let prior_sd = Vector4::new(
        p.prior_sigma_position,
        p.prior_sigma_position,
        p.prior_sigma_velocity,
        p.prior_sigma_velocity,
    );
    let prior_mean = start + normal4(rng).component_mul(&prior_sd);
    let prior = Gaussian::new(
        prior_mean,
        Matrix4::from_diagonal(&prior_sd.component_mul(&prior_sd)),
    )?;
    let run = filter(motion, &sensor, &prior, &measurements)?;
    let smoothed = smooth(motion, &run)?;
    Ok(TargetRun {
        truth,
        measurements,
        filtered: run.filtered().cloned().collect(),
        smoothed,
    })
}

fn starts(p: &Params) -> [Vector4<f64>; 2] {
    // Both move right; one climbs and one descends so that they cross half-way.
    let duration = p.n_steps as f64 * p.dt_s;
    let (vx, vy) = (p.speed * 0.8, p.speed * 0.6);
    [
        Vector4::new(0.0, 0.0, vx, vy),
        Vector4::new(0.0, vy * duration, vx, -vy),
    ]
}

fn one_run(
    p: &Params,
    motion: &ConstantVelocity2,
    rng: &mut ChaCha8Rng,
) -> Result<(RunStats, Vec<TargetRun>)> {
    let mut stats = RunStats::zeros(p.n_steps);
    let mut targets = Vec::with_capacity(2);
    for start in starts(p) {
        let t = simulate_target(p, motion, start, rng)?;
        for k in 0..p.n_steps {
            let x = &t.truth[k];
            for (est, sq_pos, sq_vel, nees) in [
                (
                    &t.filtered[k],
                    &mut stats.sq_pos_filtered,
                    &mut stats.sq_vel_filtered,
                    &mut stats.nees_filtered,
                ),
                (
                    &t.smoothed[k],
                    &mut stats.sq_pos_smoothed,
                    &mut stats.sq_vel_smoothed,
                    &mut stats.nees_smoothed,
                ),
            ] {
                let e = est.mean() - x;
                sq_pos[k] += e[0] * e[0] + e[1] * e[1];
                sq_vel[k] += e[2] * e[2] + e[3] * e[3];
                nees[k] += est.mahalanobis_sq(x)?;
            }
        }
        stats.missed += t.measurements.iter().filter(|m| m.is_none()).count();
        targets.push(t);
    }
    Ok((stats, targets))
}

/// The summed statistics over all runs and the targets of run 0.
pub struct Output {
    /// Monte Carlo runs.
    n_runs: usize,
    /// Scans per run.
    n_steps: usize,
    /// Per-step sums over all runs and both targets.
    total: RunStats,
    /// The two targets of run 0, for the track plot.
    run0: Vec<TargetRun>,
    /// The ANEES 95 % interval per scan.
    anees_95: (f64, f64),
}

impl Output {
    /// Tracks over all runs (two per run).
    fn n_tracks(&self) -> f64 {
        (2 * self.n_runs) as f64
    }

    /// The mean of per-step sums over all tracks and steps.
    fn mean_all(&self, v: &[f64]) -> f64 {
        v.iter().sum::<f64>() / (self.n_tracks() * self.n_steps as f64)
    }

    /// The share of steps whose ANEES lies in the 95 % interval.
    fn share_inside(&self, v: &[f64]) -> f64 {
        let (lo, hi) = self.anees_95;
        let n_tracks = self.n_tracks();
        v.iter()
            .filter(|&&s| (lo..=hi).contains(&(s / n_tracks)))
            .count() as f64
            / self.n_steps as f64
    }

    /// Per-step RMSE from per-step sums of squares.
    fn per_step(&self, v: &[f64]) -> Vec<(f64, f64)> {
        let n_tracks = self.n_tracks();
        v.iter()
            .enumerate()
            .map(|(k, s)| (k as f64, (s / n_tracks).sqrt()))
            .collect()
    }
}

impl Pipeline for KalmanCrossing {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        anyhow::ensure!(
            p.n_runs > 0 && p.n_steps > 1,
            "need n_runs > 0 and n_steps > 1"
        );
        anyhow::ensure!(
            (0.0..=1.0).contains(&p.p_detect),
            "p_detect must lie in [0, 1]"
        );
        let motion = ConstantVelocity2::new(p.dt_s, CvNoise::WhiteAcceleration { q: p.accel_psd })?;
        env.progress.set_length(p.n_runs as u64);
        let base = rng.clone();
        // One generator stream per run: the result does not depend on rayon's thread count.
        let runs: Vec<(RunStats, Vec<TargetRun>)> = (0..p.n_runs)
            .into_par_iter()
            .map(|r| {
                let mut rng = base.clone();
                rng.set_stream(r as u64);
                let out = one_run(p, &motion, &mut rng);
                env.progress.advance(1);
                out
            })
            .collect::<Result<_>>()?;
        let mut total = RunStats::zeros(p.n_steps);
        for (stats, _) in &runs {
            total.add(stats);
        }
        let run0 = runs
            .into_iter()
            .next()
            .map(|(_, targets)| targets)
            .context("no run")?;
        Ok(Output {
            n_runs: p.n_runs,
            n_steps: p.n_steps,
            total,
            run0,
            anees_95: anees_interval_95(4, 2 * p.n_runs),
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let total = &out.total;
        let mut metrics = Metrics::new();
        metrics.insert(
            "position_rmse_filtered".into(),
            out.mean_all(&total.sq_pos_filtered).sqrt(),
        );
        metrics.insert(
            "position_rmse_smoothed".into(),
            out.mean_all(&total.sq_pos_smoothed).sqrt(),
        );
        metrics.insert(
            "velocity_rmse_filtered".into(),
            out.mean_all(&total.sq_vel_filtered).sqrt(),
        );
        metrics.insert(
            "velocity_rmse_smoothed".into(),
            out.mean_all(&total.sq_vel_smoothed).sqrt(),
        );
        metrics.insert("anees_filtered".into(), out.mean_all(&total.nees_filtered));
        metrics.insert("anees_smoothed".into(), out.mean_all(&total.nees_smoothed));
        metrics.insert(
            "steps_with_anees_in_95_filtered".into(),
            out.share_inside(&total.nees_filtered),
        );
        metrics.insert(
            "steps_with_anees_in_95_smoothed".into(),
            out.share_inside(&total.nees_smoothed),
        );
        metrics.insert(
            "missed_fraction".into(),
            total.missed as f64 / (out.n_tracks() * out.n_steps as f64),
        );
        metrics
    }

    fn claims(out: &Output) -> Vec<Claim> {
        let m = Self::metrics(out);
        let (lo, hi) = out.anees_95;
        // A consistent estimator's per-scan ANEES falls inside its 95 % interval on 95 % of the
        // scans; 3 binomial standard errors around that allows for chance.
        let band = 3.0 * (0.95 * 0.05 / out.n_steps as f64).sqrt();
        let share_ok = |k: &str| (m[k] - 0.95).abs() <= band;
        vec![
            Claim::new(
                "smoothed RMSE < filtered RMSE, for position and for velocity",
                m["position_rmse_smoothed"] < m["position_rmse_filtered"]
                    && m["velocity_rmse_smoothed"] < m["velocity_rmse_filtered"],
            ),
            Claim::new(
                format!(
                    "the ANEES over all scans lies inside the per-scan 95 % χ² interval \
                     [{}, {}], for the filter and the smoother",
                    fmt_num(lo),
                    fmt_num(hi)
                ),
                [m["anees_filtered"], m["anees_smoothed"]]
                    .iter()
                    .all(|a| (lo..=hi).contains(a)),
            ),
            Claim::new(
                format!(
                    "the share of scans whose ANEES is inside its 95 % χ² interval is within \
                     3 binomial s.e. of 95 % (± {}), for the filter and the smoother",
                    fmt_num(band)
                ),
                share_ok("steps_with_anees_in_95_filtered")
                    && share_ok("steps_with_anees_in_95_smoothed"),
            ),
        ]
    }

    fn present(out: &Output) -> Section {
        Section {
            title: "Kalman filter and RTS smoother on two crossing targets".into(),
            summary:
                "Constant-velocity targets with white-acceleration noise, position measurements \
                      with missed scans, each target filtered with its own measurements. Smoothing \
                      uses the future as well as the past, so its error is lower; both estimators \
                      must stay consistent (average NEES near the state dimension, 4)."
                    .into(),
            tables: vec![table(out)],
            figures: vec![
                Figure::new(
                    "tracks",
                    "Truth, measurements, filtered and smoothed tracks of run 0",
                    track_chart(&out.run0),
                ),
                Figure::new(
                    "rmse",
                    "Position RMSE against scan, over all runs",
                    Chart::new(
                        "Position RMSE per scan",
                        "scan",
                        "position RMSE (length units)",
                        vec![
                            Series::new(
                                "filtered",
                                out.per_step(&out.total.sq_pos_filtered),
                                Style::Line,
                                0,
                            ),
                            Series::new(
                                "RTS smoothed",
                                out.per_step(&out.total.sq_pos_smoothed),
                                Style::Line,
                                1,
                            ),
                        ],
                    ),
                ),
            ],
        }
    }
}

/// The table of filtered against smoothed metrics.
fn table(out: &Output) -> Table {
    let metrics = KalmanCrossing::metrics(out);
    let (lo, hi) = out.anees_95;
    let mut table = Table::new(
        &format!(
            "Two crossing targets, {} runs × {} scans, true associations (ANEES 95 % interval per scan: [{}, {}])",
            out.n_runs,
            out.n_steps,
            fmt_num(lo),
            fmt_num(hi)
        ),
        &["quantity", "filtered", "RTS smoothed"],
    );
    for (label, key) in [
        ("position RMSE", "position_rmse"),
        ("velocity RMSE", "velocity_rmse"),
        ("average NEES (4 = consistent)", "anees"),
        (
            "share of scans with ANEES in 95 % interval",
            "steps_with_anees_in_95",
        ),
    ] {
        table.row(vec![
            label.to_string(),
            fmt_num(metrics[&format!("{key}_filtered")]),
            fmt_num(metrics[&format!("{key}_smoothed")]),
        ]);
    }
    table
}

/// Run 0's truth, measurements and estimates on the plane.
fn track_chart(run0: &[TargetRun]) -> Chart {
    let mut series = Vec::new();
    for (i, t) in run0.iter().enumerate() {
        let pos = |v: &Vector4<f64>| (v[0], v[1]);
        let suffix = |s: &str| if i == 0 { s.to_string() } else { String::new() };
        series.push(
            Series::new(
                &suffix("truth"),
                t.truth.iter().map(pos).collect(),
                Style::ThinLine,
                2,
            )
            .in_front(),
        );
        series.push(Series::new(
            &suffix("measurements"),
            t.measurements
                .iter()
                .flatten()
                .map(|z| (z.x, z.y))
                .collect(),
            Style::Markers,
            3,
        ));
        series.push(Series::new(
            &suffix("filtered"),
            t.filtered.iter().map(|g| pos(g.mean())).collect(),
            Style::ThinLine,
            0,
        ));
        series.push(Series::new(
            &suffix("smoothed"),
            t.smoothed.iter().map(|g| pos(g.mean())).collect(),
            Style::Line,
            1,
        ));
    }
    Chart::new(
        "Run 0: truth, measurements and estimates",
        "x (length units)",
        "y (length units)",
        series,
    )
    .with_equal_aspect()
}
