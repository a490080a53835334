//! Evaluation and decoding: the scaled forward-backward recursions (Rabiner 1989; seed 002
//! eqs. 3-11), posterior marginals, expected transition counts, Viterbi in log space (eqs.
//! 14-18) and per-step posterior decoding (eq. 13), plus a log-space forward recursion as an
//! independent formulation.
//!
//! Scaling: α̂_t = α_t / (c_1 ⋯ c_t) with c_t = Σ_j α̃_t(j), so log P(O | λ) = Σ_t log c_t and
//! nothing underflows however long the sequence; β̂ is scaled by the same c_{t+1}, which makes
//! γ_t(i) = α̂_t(i) β̂_t(i) and ξ_t(i, j) = α̂_t(i) a_ij b_j(o_{t+1}) β̂_{t+1}(j) / c_{t+1}.

use crate::error::{Error, Result};
use crate::model::Hmm;

/// Scaled forward variables.
#[derive(Debug, Clone, PartialEq)]
pub struct Forward {
    /// α̂, row-major T × N; each row sums to 1.
    pub alpha: Vec<f64>,
    /// c_t.
    pub scale: Vec<f64>,
    /// log P(O | λ) = Σ log c_t.
    pub log_likelihood: f64,
}

/// One forward step: `next[j] = b_j(o) Σ_i prev[i] a_ij`, scattered row by row (O(nnz)).
fn propagate(hmm: &Hmm, prev: &[f64], next: &mut [f64], symbol: usize) {
    next.iter_mut().for_each(|v| *v = 0.0);
    let a = hmm.transitions();
    for (i, &p) in prev.iter().enumerate() {
        if p != 0.0 {
            a.for_each_in_row(i, |j, aij, _| next[j] += p * aij);
        }
    }
    for (v, b) in next.iter_mut().zip(hmm.emission_column(symbol)) {
        *v *= b;
    }
}

/// Divides `v` by its sum, returning the sum; a zero sum means the observation is impossible.
fn normalise(v: &mut [f64], sequence: usize, index: usize) -> Result<f64> {
    let c: f64 = v.iter().sum();
    if !(c > 0.0 && c.is_finite()) {
        return Err(Error::ImpossibleObservation { sequence, index });
    }
    let inv = 1.0 / c;
    v.iter_mut().for_each(|x| *x *= inv);
    Ok(c)
}

/// The scaled forward pass.
pub fn forward(hmm: &Hmm, obs: &[usize]) -> Result<Forward> {
    forward_in(hmm, obs, 0)
}

pub(crate) fn forward_in(hmm: &Hmm, obs: &[usize], sequence: usize) -> Result<Forward> {
    hmm.check_observations(obs, sequence)?;
    let n = hmm.n_states();
    let mut alpha = vec![0.0; obs.len() * n];
    let mut scale = Vec::with_capacity(obs.len());
    for (a, (p, b)) in alpha[..n]
        .iter_mut()
        .zip(hmm.initial().iter().zip(hmm.emission_column(obs[0])))
    {
        *a = p * b;
    }
    scale.push(normalise(&mut alpha[..n], sequence, 0)?);
    for t in 1..obs.len() {
        let (done, rest) = alpha.split_at_mut(t * n);
        let next = &mut rest[..n];
        propagate(hmm, &done[(t - 1) * n..], next, obs[t]);
        scale.push(normalise(next, sequence, t)?);
    }
    let log_likelihood = scale.iter().map(|c| c.ln()).sum();
    Ok(Forward {
        alpha,
        scale,
        log_likelihood,
    })
}

/// The scaled backward pass for the scale factors of a forward pass: β̂, row-major T × N.
pub fn backward(hmm: &Hmm, obs: &[usize], scale: &[f64]) -> Result<Vec<f64>> {
    hmm.check_observations(obs, 0)?;
    if scale.len() != obs.len() {
        return Err(Error::Shape(format!(
            "{} scale factors for {} observations",
            scale.len(),
            obs.len()
        )));
    }
    let n = hmm.n_states();
    let len = obs.len();
    let mut beta = vec![0.0; len * n];
    beta[(len - 1) * n..].iter_mut().for_each(|v| *v = 1.0);
    let mut weighted = vec![0.0; n];
    let a = hmm.transitions();
    for t in (0..len - 1).rev() {
        // weighted[j] = b_j(o_{t+1}) β̂_{t+1}(j) / c_{t+1}
        let inv = 1.0 / scale[t + 1];
        for ((w, b), nb) in weighted
            .iter_mut()
            .zip(hmm.emission_column(obs[t + 1]))
            .zip(&beta[(t + 1) * n..(t + 2) * n])
        {
            *w = b * nb * inv;
        }
        for (i, out) in beta[t * n..(t + 1) * n].iter_mut().enumerate() {
            let mut s = 0.0;
            a.for_each_in_row(i, |j, aij, _| s += aij * weighted[j]);
            *out = s;
        }
    }
    Ok(beta)
}

/// Posterior state marginals γ_t(i) = P(q_t = i | O, λ).
#[derive(Debug, Clone, PartialEq)]
pub struct Posterior {
    /// Row-major T × N.
    pub gamma: Vec<f64>,
    /// log P(O | λ).
    pub log_likelihood: f64,
    /// N.
    pub n_states: usize,
}

impl Posterior {
    /// γ_t as a slice over states.
    pub fn at(&self, t: usize) -> &[f64] {
        &self.gamma[t * self.n_states..(t + 1) * self.n_states]
    }
}

/// Forward-backward: the posterior marginals of every state at every step.
pub fn posterior(hmm: &Hmm, obs: &[usize]) -> Result<Posterior> {
    let f = forward(hmm, obs)?;
    let beta = backward(hmm, obs, &f.scale)?;
    let gamma = f.alpha.iter().zip(&beta).map(|(a, b)| a * b).collect();
    Ok(Posterior {
        gamma,
        log_likelihood: f.log_likelihood,
        n_states: hmm.n_states(),
    })
}

/// Σ_t ξ_t(i, j): expected transition counts, one per stored entry of A (storage order, see
/// [`crate::Transitions::values`]), from the forward and backward variables.
pub(crate) fn accumulate_xi(hmm: &Hmm, obs: &[usize], f: &Forward, beta: &[f64], xi: &mut [f64]) {
    let n = hmm.n_states();
    let a = hmm.transitions();
    let mut weighted = vec![0.0; n];
    for t in 0..obs.len() - 1 {
        let inv = 1.0 / f.scale[t + 1];
        for ((w, b), nb) in weighted
            .iter_mut()
            .zip(hmm.emission_column(obs[t + 1]))
            .zip(&beta[(t + 1) * n..(t + 2) * n])
        {
            *w = b * nb * inv;
        }
        for (i, &al) in f.alpha[t * n..(t + 1) * n].iter().enumerate() {
            if al != 0.0 {
                a.for_each_in_row(i, |j, aij, k| xi[k] += al * aij * weighted[j]);
            }
        }
    }
}

/// Expected transition counts Σ_t ξ_t(i, j) as a row-major N × N matrix.
pub fn expected_transitions(hmm: &Hmm, obs: &[usize]) -> Result<Vec<f64>> {
    let f = forward(hmm, obs)?;
    let beta = backward(hmm, obs, &f.scale)?;
    let mut xi = vec![0.0; hmm.transitions().n_stored()];
    accumulate_xi(hmm, obs, &f, &beta, &mut xi);
    let n = hmm.n_states();
    let mut out = vec![0.0; n * n];
    for i in 0..n {
        hmm.transitions()
            .for_each_in_row(i, |j, _, k| out[i * n + j] = xi[k]);
    }
    Ok(out)
}

/// The most probable state path and its log-probability log P(Q*, O | λ), in log space.
/// Ties go to the lowest-numbered predecessor.
pub fn viterbi(hmm: &Hmm, obs: &[usize]) -> Result<(Vec<usize>, f64)> {
    hmm.check_observations(obs, 0)?;
    let n = hmm.n_states();
    let len = obs.len();
    let log_a = hmm.log_transitions();
    let a = hmm.transitions();
    let mut delta: Vec<f64> = hmm
        .log_initial()
        .iter()
        .zip(hmm.log_emission_column(obs[0]))
        .map(|(p, b)| p + b)
        .collect();
    let mut next = vec![f64::NEG_INFINITY; n];
    let mut back = vec![0u32; len * n];
    for t in 1..len {
        next.iter_mut().for_each(|v| *v = f64::NEG_INFINITY);
        let psi = &mut back[t * n..(t + 1) * n];
        for (i, &d) in delta.iter().enumerate() {
            if d == f64::NEG_INFINITY {
                continue;
            }
            a.for_each_in_row(i, |j, _, k| {
                let cand = d + log_a[k];
                if cand > next[j] {
                    next[j] = cand;
                    psi[j] = i as u32;
                }
            });
        }
        for (v, lb) in next.iter_mut().zip(hmm.log_emission_column(obs[t])) {
            *v += lb;
        }
        std::mem::swap(&mut delta, &mut next);
    }
    let (mut state, &best) = delta
        .iter()
        .enumerate()
        .fold((0, &f64::NEG_INFINITY), |acc, (i, v)| {
            if *v > *acc.1 { (i, v) } else { acc }
        });
    if best == f64::NEG_INFINITY {
        return Err(Error::ImpossibleObservation {
            sequence: 0,
            index: len - 1,
        });
    }
    let mut path = vec![0; len];
    path[len - 1] = state;
    for t in (1..len).rev() {
        state = back[t * n + state] as usize;
        path[t - 1] = state;
    }
    Ok((path, best))
}

/// The individually most probable state at each step, argmax_i γ_t(i) (seed eq. 13). Unlike
/// Viterbi's path it may use transitions of probability 0.
pub fn posterior_decode(hmm: &Hmm, obs: &[usize]) -> Result<Vec<usize>> {
    let post = posterior(hmm, obs)?;
    Ok((0..obs.len())
        .map(|t| {
            post.at(t)
                .iter()
                .enumerate()
                .fold(
                    (0, f64::NEG_INFINITY),
                    |acc, (i, &g)| if g > acc.1 { (i, g) } else { acc },
                )
                .0
        })
        .collect())
}

/// log-sum-exp of a slice, −∞ for an empty or all −∞ slice.
fn log_sum_exp(v: impl Iterator<Item = f64> + Clone) -> f64 {
    let max = v.clone().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY {
        return max;
    }
    max + v.map(|x| (x - max).exp()).sum::<f64>().ln()
}

/// The forward recursion in log space: log α_t(j) = log b_j(o_t) + logsumexp_i(log α_{t−1}(i)
/// + log a_ij). Slower than the scaled recursion; returns (log α row-major T × N,
/// log P(O | λ)).
pub fn forward_log(hmm: &Hmm, obs: &[usize]) -> Result<(Vec<f64>, f64)> {
    hmm.check_observations(obs, 0)?;
    let n = hmm.n_states();
    let dense_log_a: Vec<f64> = hmm
        .transitions()
        .dense_values()
        .iter()
        .map(|v| v.ln())
        .collect();
    let mut out = Vec::with_capacity(obs.len() * n);
    out.extend(
        hmm.log_initial()
            .iter()
            .zip(hmm.log_emission_column(obs[0]))
            .map(|(p, b)| p + b),
    );
    for t in 1..obs.len() {
        let lb = hmm.log_emission_column(obs[t]);
        for j in 0..n {
            let prev = &out[(t - 1) * n..t * n];
            let v = log_sum_exp((0..n).map(|i| prev[i] + dense_log_a[i * n + j])) + lb[j];
            out.push(v);
        }
    }
    let ll = log_sum_exp(out[(obs.len() - 1) * n..].iter().copied());
    Ok((out, ll))
}
