//! Evaluation and decoding: the scaled forward-backward recursions (Rabiner 1989; Huynh & Vu
//! 2006 eqs. 3-11), posterior marginals, expected transition counts, Viterbi in log space (eqs.
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
    let a = hmm.transitions();
    let n = prev.len();
    match a.dense_rows() {
        // next += p · row i for every i: axpys over contiguous memory.
        Some(rows) => {
            next.iter_mut().for_each(|v| *v = 0.0);
            for (i, &p) in prev.iter().enumerate() {
                if p != 0.0 {
                    next.iter_mut()
                        .zip(&rows[i * n..(i + 1) * n])
                        .for_each(|(v, aij)| *v += p * aij);
                }
            }
        }
        // Sparse: gather down each column.
        None => {
            for (j, v) in next.iter_mut().enumerate() {
                let mut s = 0.0;
                a.for_each_in_column(j, |i, aij, _| s += prev[i] * aij);
                *v = s;
            }
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

/// Σ_j row[j] · w[j] with four independent partial sums, so the compiler can vectorise the
/// loop (a single running sum forces strict left-to-right order). The summation order is fixed,
/// so the result does not depend on the machine.
fn dot(row: &[f64], w: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (rc, wc) = (row.chunks_exact(4), w.chunks_exact(4));
    let (rr, wr) = (rc.remainder(), wc.remainder());
    for (r, x) in rc.zip(wc) {
        for k in 0..4 {
            acc[k] += r[k] * x[k];
        }
    }
    let tail: f64 = rr.iter().zip(wr).map(|(r, x)| r * x).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// Runs the scaled backward recursion from t = T−1 down to 0, keeping only two rows of β̂, and
/// calls `visit(t, β̂_t, w_{t+1})` at each step, where w_{t+1}(j) = b_j(o_{t+1}) β̂_{t+1}(j) /
/// c_{t+1} (absent at t = T−1). Posteriors, expected counts and the public [`backward`] are all
/// built on this one sweep.
pub(crate) fn backward_sweep(
    hmm: &Hmm,
    obs: &[usize],
    scale: &[f64],
    mut visit: impl FnMut(usize, &[f64], Option<&[f64]>),
) {
    let n = hmm.n_states();
    let len = obs.len();
    let a = hmm.transitions();
    let mut beta_next = vec![1.0; n];
    let mut beta = vec![0.0; n];
    let mut weighted = vec![0.0; n];
    visit(len - 1, &beta_next, None);
    for t in (0..len - 1).rev() {
        let inv = 1.0 / scale[t + 1];
        for ((w, b), nb) in weighted
            .iter_mut()
            .zip(hmm.emission_column(obs[t + 1]))
            .zip(&beta_next)
        {
            *w = b * nb * inv;
        }
        match a.dense_rows() {
            Some(rows) => {
                for (i, out) in beta.iter_mut().enumerate() {
                    *out = dot(&rows[i * n..(i + 1) * n], &weighted);
                }
            }
            None => {
                for (i, out) in beta.iter_mut().enumerate() {
                    let mut s = 0.0;
                    a.for_each_in_row(i, |j, aij, _| s += aij * weighted[j]);
                    *out = s;
                }
            }
        }
        visit(t, &beta, Some(&weighted));
        std::mem::swap(&mut beta, &mut beta_next);
    }
}

/// The scaled backward pass for the scale factors of a forward pass: β̂, row-major T × N.
pub fn backward(hmm: &Hmm, obs: &[usize], scale: &[f64]) -> Result<Vec<f64>> {
    hmm.check_observations(obs, 0)?;
    if scale.len() != obs.len() {
        return Err(Error::ShapeMismatch {
            what: "scale factors (one per observation)",
            expected: obs.len(),
            got: scale.len(),
        });
    }
    let n = hmm.n_states();
    let mut out = vec![0.0; obs.len() * n];
    backward_sweep(hmm, obs, scale, |t, beta, _| {
        out[t * n..(t + 1) * n].copy_from_slice(beta)
    });
    Ok(out)
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
    let Forward {
        alpha: mut gamma,
        scale,
        log_likelihood,
    } = forward(hmm, obs)?;
    let n = hmm.n_states();
    // γ_t = α̂_t β̂_t, formed in place in the α̂ buffer.
    backward_sweep(hmm, obs, &scale, |t, beta, _| {
        gamma[t * n..(t + 1) * n]
            .iter_mut()
            .zip(beta)
            .for_each(|(g, b)| *g *= b);
    });
    Ok(Posterior {
        gamma,
        log_likelihood,
        n_states: n,
    })
}

/// Adds ξ_t(i, j) = α̂_t(i) a_ij w_{t+1}(j) to `xi`, one entry per stored element of A (storage
/// order, see [`crate::Transitions::values`]).
pub(crate) fn add_xi(hmm: &Hmm, alpha_t: &[f64], weighted_next: &[f64], xi: &mut [f64]) {
    let a = hmm.transitions();
    let n = alpha_t.len();
    for (i, &al) in alpha_t.iter().enumerate() {
        if al == 0.0 {
            continue;
        }
        match a.dense_rows() {
            Some(rows) => {
                let row = &rows[i * n..(i + 1) * n];
                for ((x, aij), w) in xi[i * n..(i + 1) * n]
                    .iter_mut()
                    .zip(row)
                    .zip(weighted_next)
                {
                    *x += al * aij * w;
                }
            }
            None => a.for_each_in_row(i, |j, aij, k| xi[k] += al * aij * weighted_next[j]),
        }
    }
}

/// Expected transition counts Σ_t ξ_t(i, j) as a row-major N × N matrix.
pub fn expected_transitions(hmm: &Hmm, obs: &[usize]) -> Result<Vec<f64>> {
    let f = forward(hmm, obs)?;
    let n = hmm.n_states();
    let mut xi = vec![0.0; hmm.transitions().n_stored()];
    backward_sweep(hmm, obs, &f.scale, |t, _, weighted| {
        if let Some(w) = weighted {
            add_xi(hmm, &f.alpha[t * n..(t + 1) * n], w, &mut xi);
        }
    });
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
        let psi = &mut back[t * n..(t + 1) * n];
        match a.dense_rows() {
            // Contiguous rows: a branch-free max-plus update per row that the compiler can
            // vectorise; rows in ascending order with a strict comparison keep the lowest
            // predecessor on ties.
            Some(_) => {
                next.iter_mut().for_each(|v| *v = f64::NEG_INFINITY);
                for (i, &d) in delta.iter().enumerate() {
                    if d == f64::NEG_INFINITY {
                        continue;
                    }
                    let row = &log_a[i * n..(i + 1) * n];
                    for ((v, p), la) in next.iter_mut().zip(psi.iter_mut()).zip(row) {
                        let cand = d + la;
                        let better = cand > *v;
                        *v = if better { cand } else { *v };
                        *p = if better { i as u32 } else { *p };
                    }
                }
            }
            // Sparse: gather down each column (rows ascending, so the same tie rule).
            None => {
                for (j, (v, p)) in next.iter_mut().zip(psi.iter_mut()).enumerate() {
                    let (mut best, mut arg) = (f64::NEG_INFINITY, 0);
                    a.for_each_in_column(j, |i, _, k| {
                        let cand = delta[i] + log_a[k];
                        if cand > best {
                            best = cand;
                            arg = i;
                        }
                    });
                    *v = best;
                    *p = arg as u32;
                }
            }
        }
        for (v, lb) in next.iter_mut().zip(hmm.log_emission_column(obs[t])) {
            *v += lb;
        }
        std::mem::swap(&mut delta, &mut next);
    }
    let (mut state, &best) =
        delta
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

/// The individually most probable state at each step, argmax_i γ_t(i) (Huynh & Vu 2006 eq.
/// 13). Unlike Viterbi's path it may use transitions of probability 0.
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
/// + log a_ij). Slower than the scaled recursion.
///
/// Returns log α (row-major T × N) and log P(O | λ).
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
