//! Single-scan MCMCDA (Oh, Russell & Sastry 2009 Algorithms 1 and 2): the joint probabilistic
//! data association (JPDA) probabilities β for a known number of targets, estimated by a
//! Markov chain over the feasible joint events instead of enumerating them, and the JPDA state
//! update. [`jpda_exact`] enumerates every event, for small problems and for checking.

use nalgebra::{Matrix4, Vector2, Vector4};
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};
use tracker_model::{
    GATE_CHI2_2D, Gaussian, LinearObservation, ObservationModel, ensure_open_probability,
    ensure_positive,
};

use crate::error::{Error, Result, ensure_samples, invalid_parameter};

/// Settings of single-scan association.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SingleScanConfig {
    /// Detection probability p_d.
    pub p_detect: f64,
    /// Clutter density λ_f (false alarms per unit area per scan).
    pub clutter_density: f64,
    /// Validation gate: measurement j is validated for target k if its innovation's squared
    /// Mahalanobis distance is at most this (the paper's likelihood threshold δ^k in χ² form).
    pub gate: f64,
    /// Samples discarded before β is estimated (n_bi).
    pub burn_in: u64,
    /// Samples after burn-in.
    pub samples: u64,
    /// Probability that a step stays put (Algorithm 2 uses 1/2, which makes the chain
    /// aperiodic; the paper notes it can be near 0 in practice).
    pub laziness: f64,
}

impl Default for SingleScanConfig {
    fn default() -> Self {
        Self {
            p_detect: 0.9,
            clutter_density: 1e-4,
            gate: GATE_CHI2_2D,
            burn_in: 10_000,
            samples: 100_000,
            laziness: 0.5,
        }
    }
}

/// Association probabilities and updated states.
#[derive(Debug, Clone, PartialEq)]
pub struct JpdaResult {
    /// `beta[k][j]`: probability that measurement j came from target k.
    pub beta: Vec<Vec<f64>>,
    /// `beta_missed[k]`: probability that target k was not detected, 1 − Σ_j `beta[k][j]`.
    pub beta_missed: Vec<f64>,
    /// The JPDA posterior of each target (mean mixture, with the spread of innovations).
    pub states: Vec<Gaussian<4>>,
}

/// A validated (measurement, target) pair and its log-likelihood.
#[derive(Debug, Clone, Copy)]
struct Edge {
    meas: usize,
    target: usize,
    log_likelihood: f64,
}

impl SingleScanConfig {
    /// Checks p_d ∈ (0, 1), λ_f > 0, gate > 0 and laziness ∈ [0, 1). [`single_scan_mcmcda`]
    /// and [`jpda_exact`] call this first.
    pub fn check(&self) -> Result<()> {
        ensure_open_probability(self.p_detect, "p_detect")?;
        ensure_positive(self.clutter_density, "clutter_density")?;
        ensure_positive(self.gate, "gate")?;
        if !(0.0..1.0).contains(&self.laziness) {
            return Err(invalid_parameter(
                "laziness",
                format!("{} must lie in [0, 1)", self.laziness),
            ));
        }
        ensure_samples(self.burn_in, "burn_in")?;
        ensure_samples(self.samples, "samples")
    }
}

/// Checks the configuration and that every measurement is finite.
fn check_inputs(config: &SingleScanConfig, measurements: &[Vector2<f64>]) -> Result<()> {
    config.check()?;
    if measurements
        .iter()
        .any(|m| !(m.x.is_finite() && m.y.is_finite()))
    {
        return Err(Error::Model(tracker_model::Error::NonFinite {
            what: "measurement",
        }));
    }
    Ok(())
}

/// The validated edges of the bipartite graph G = (measurements, targets, E).
fn validate(
    predicted: &[Gaussian<4>],
    sensor: &LinearObservation<4, 2>,
    measurements: &[Vector2<f64>],
    gate: f64,
) -> Result<Vec<Edge>> {
    let mut edges = Vec::new();
    for (k, target) in predicted.iter().enumerate() {
        for (j, y) in measurements.iter().enumerate() {
            let innovation = sensor.innovation(target, y)?;
            if innovation.mahalanobis_sq <= gate {
                edges.push(Edge {
                    meas: j,
                    target: k,
                    log_likelihood: innovation.log_likelihood,
                });
            }
        }
    }
    Ok(edges)
}

/// log of an edge's factor in P(ω | Y) relative to leaving both ends unmatched:
/// p_d P(y | target) / ((1 − p_d) λ_f)  (Oh, Russell & Sastry 2009 eq. 26).
fn edge_gain(edge: &Edge, config: &SingleScanConfig) -> f64 {
    config.p_detect.ln() + edge.log_likelihood
        - (-config.p_detect).ln_1p()
        - config.clutter_density.ln()
}

/// β by Algorithms 1 and 2: a chain over matchings of the validated graph, whose moves add,
/// delete or switch one edge, accepted with min(1, π(ω')/π(ω)).
pub fn single_scan_mcmcda<R: Rng + ?Sized>(
    predicted: &[Gaussian<4>],
    sensor: &LinearObservation<4, 2>,
    measurements: &[Vector2<f64>],
    config: &SingleScanConfig,
    rng: &mut R,
) -> Result<JpdaResult> {
    check_inputs(config, measurements)?;
    let edges = validate(predicted, sensor, measurements, config.gate)?;
    let gains: Vec<f64> = edges.iter().map(|e| edge_gain(e, config)).collect();
    let (n_targets, n_meas) = (predicted.len(), measurements.len());
    // Current matching: the edge index used by each target and each measurement.
    let mut by_target: Vec<Option<usize>> = vec![None; n_targets];
    let mut by_meas: Vec<Option<usize>> = vec![None; n_meas];
    let mut counts = vec![0u64; edges.len()];
    let total = config.burn_in + config.samples;
    for n in 0..total {
        if !edges.is_empty() && !rng.random_bool(config.laziness) {
            let e = rng.random_range(0..edges.len());
            let (k, j) = (edges[e].target, edges[e].meas);
            match (by_target[k], by_meas[j]) {
                (Some(a), _) if a == e => {
                    // Delete e.
                    if rng.random::<f64>().ln() < -gains[e] {
                        by_target[k] = None;
                        by_meas[j] = None;
                    }
                }
                (None, None) => {
                    // Add e.
                    if rng.random::<f64>().ln() < gains[e] {
                        by_target[k] = Some(e);
                        by_meas[j] = Some(e);
                    }
                }
                (Some(other), None) | (None, Some(other)) => {
                    // Switch: e replaces the one edge it conflicts with.
                    if rng.random::<f64>().ln() < gains[e] - gains[other] {
                        let o = edges[other];
                        by_target[o.target] = None;
                        by_meas[o.meas] = None;
                        by_target[k] = Some(e);
                        by_meas[j] = Some(e);
                    }
                }
                (Some(_), Some(_)) => {}
            }
        }
        if n >= config.burn_in {
            for e in by_target.iter().flatten() {
                counts[*e] += 1;
            }
        }
    }
    let weight = 1.0 / config.samples.max(1) as f64;
    let mut beta = vec![vec![0.0; n_meas]; n_targets];
    for (e, c) in edges.iter().zip(&counts) {
        beta[e.target][e.meas] = *c as f64 * weight;
    }
    finish(predicted, sensor, measurements, beta)
}

/// β by enumerating every feasible joint event (exponential; for small problems).
pub fn jpda_exact(
    predicted: &[Gaussian<4>],
    sensor: &LinearObservation<4, 2>,
    measurements: &[Vector2<f64>],
    config: &SingleScanConfig,
) -> Result<JpdaResult> {
    check_inputs(config, measurements)?;
    let edges = validate(predicted, sensor, measurements, config.gate)?;
    let n_targets = predicted.len();
    let mut options: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n_targets];
    for e in &edges {
        options[e.target].push((e.meas, edge_gain(e, config)));
    }
    // Each event: the measurement (or none) of every target, and its log weight.
    let mut events: Vec<(Vec<Option<usize>>, f64)> = Vec::new();
    let mut current = vec![None; n_targets];
    let mut used = vec![false; measurements.len()];
    fn recurse(
        k: usize,
        log_w: f64,
        options: &[Vec<(usize, f64)>],
        current: &mut Vec<Option<usize>>,
        used: &mut Vec<bool>,
        events: &mut Vec<(Vec<Option<usize>>, f64)>,
    ) {
        if k == options.len() {
            events.push((current.clone(), log_w));
            return;
        }
        current[k] = None;
        recurse(k + 1, log_w, options, current, used, events);
        for &(j, gain) in &options[k] {
            if !used[j] {
                used[j] = true;
                current[k] = Some(j);
                recurse(k + 1, log_w + gain, options, current, used, events);
                used[j] = false;
            }
        }
        current[k] = None;
    }
    recurse(0, 0.0, &options, &mut current, &mut used, &mut events);
    let max = events.iter().map(|e| e.1).fold(f64::NEG_INFINITY, f64::max);
    let z: f64 = events.iter().map(|e| (e.1 - max).exp()).sum();
    let mut beta = vec![vec![0.0; measurements.len()]; n_targets];
    for (event, log_w) in &events {
        let p = (log_w - max).exp() / z;
        for (k, j) in event.iter().enumerate() {
            if let Some(j) = j {
                beta[k][*j] += p;
            }
        }
    }
    finish(predicted, sensor, measurements, beta)
}

/// The JPDA update x̂ = β₀ x̂⁻ + Σ_j β_j x̂_j, P = β₀ P⁻ + (1 − β₀) P_upd + spread of means.
fn finish(
    predicted: &[Gaussian<4>],
    sensor: &LinearObservation<4, 2>,
    measurements: &[Vector2<f64>],
    beta: Vec<Vec<f64>>,
) -> Result<JpdaResult> {
    let mut states = Vec::with_capacity(predicted.len());
    let mut beta_missed = Vec::with_capacity(predicted.len());
    for (k, prior) in predicted.iter().enumerate() {
        let b0 = (1.0 - beta[k].iter().sum::<f64>()).max(0.0);
        let mut means: Vec<(f64, Vector4<f64>)> = vec![(b0, *prior.mean())];
        let mut cov = prior.covariance() * b0;
        for (j, y) in measurements.iter().enumerate() {
            let b = beta[k][j];
            if b > 0.0 {
                let updated = sensor.update(prior, y)?;
                cov += updated.state.covariance() * b;
                means.push((b, *updated.state.mean()));
            }
        }
        let mean: Vector4<f64> = means.iter().map(|(b, m)| m * *b).sum();
        let spread: Matrix4<f64> = means
            .iter()
            .map(|(b, m)| (m - mean) * (m - mean).transpose() * *b)
            .sum();
        let total = cov + spread;
        states.push(Gaussian::new(mean, (total + total.transpose()) * 0.5)?);
        beta_missed.push(b0);
    }
    Ok(JpdaResult {
        beta,
        beta_missed,
        states,
    })
}
