//! Evaluation and decoding: the scaled forward-backward recursions (Rabiner 1989; Huynh & Vu
//! 2006 eqs. 3-11), posterior marginals, expected transition counts, Viterbi in log space (eqs.
//! 14-18) and per-step posterior decoding (eq. 13), plus a log-space forward recursion as an
//! independent formulation.
//!
//! Scaling: α̂_t = α_t / (c_1 ⋯ c_t) with c_t = Σ_j α̃_t(j), so log P(O | λ) = Σ_t log c_t and
//! nothing underflows however long the sequence; β̂ is scaled by the same c_{t+1}, which makes
//! γ_t(i) = α̂_t(i) β̂_t(i) and ξ_t(i, j) = α̂_t(i) a_ij b_j(o_{t+1}) β̂_{t+1}(j) / c_{t+1}.

use crate::error::{Error, Result};
use crate::model::{Hmm, Logs};
use crate::transitions::SparseView;

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

/// One forward step: `next[j] = b_j(o) Σ_i prev[i] a_ij` (O(nnz)); returns Σ_j next[j],
/// summed in ascending j as the values are formed, so that the chain of additions overlaps
/// the gathers instead of following them.
fn propagate(hmm: &Hmm, prev: &[f64], next: &mut [f64], symbol: usize) -> f64 {
    let a = hmm.transitions();
    let b = hmm.emission_column(symbol);
    let mut total = 0.0;
    match (a.dense_rows(), a.sparse_view()) {
        (Some(rows), _) => {
            axpy_rows(rows, prev, next);
            for (v, b) in next.iter_mut().zip(b) {
                *v *= b;
                total += *v;
            }
        }
        // Sparse: gather down each column (rows ascending) from the column-ordered values.
        (None, Some(view)) => {
            for (j, (v, &bj)) in next.iter_mut().zip(b).enumerate() {
                let range = view.col_ptr[j]..view.col_ptr[j + 1];
                let mut s = 0.0;
                for (&i, &aij) in view.col_rows[range.clone()]
                    .iter()
                    .zip(&view.col_values[range])
                {
                    s += prev[i] * aij;
                }
                *v = s * bj;
                total += *v;
            }
        }
        (None, None) => {}
    }
    total
}

/// `next = Σ_i prev[i] · row i` over a dense row-major matrix, accumulated row by row in
/// ascending order for every column (the order of a plain loop of axpys), four rows per pass
/// over `next` so that it is loaded and stored a quarter as often. A group of rows whose
/// weights are all zero is skipped (adding 0 · a_ij changes nothing).
fn axpy_rows(rows: &[f64], prev: &[f64], next: &mut [f64]) {
    let n = next.len();
    next.iter_mut().for_each(|v| *v = 0.0);
    let mut groups = prev.chunks_exact(4);
    let mut row_blocks = rows.chunks_exact(4 * n);
    for (p, block) in (&mut groups).zip(&mut row_blocks) {
        if p.iter().all(|&x| x == 0.0) {
            continue;
        }
        let (r0, rest) = block.split_at(n);
        let (r1, rest) = rest.split_at(n);
        let (r2, r3) = rest.split_at(n);
        for ((((v, a0), a1), a2), a3) in next.iter_mut().zip(r0).zip(r1).zip(r2).zip(r3) {
            let mut x = *v;
            x += p[0] * a0;
            x += p[1] * a1;
            x += p[2] * a2;
            x += p[3] * a3;
            *v = x;
        }
    }
    let tail_rows = row_blocks.remainder().chunks_exact(n);
    for (&p, row) in groups.remainder().iter().zip(tail_rows) {
        if p != 0.0 {
            next.iter_mut().zip(row).for_each(|(v, a)| *v += p * a);
        }
    }
}

/// Divides `v` by its sum `c`, returning `c`; a zero sum means the observation is impossible.
fn normalise(v: &mut [f64], c: f64, sequence: usize, index: usize) -> Result<f64> {
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
    let c = alpha[..n].iter().sum();
    scale.push(normalise(&mut alpha[..n], c, sequence, 0)?);
    for t in 1..obs.len() {
        let (done, rest) = alpha.split_at_mut(t * n);
        let next = &mut rest[..n];
        let c = propagate(hmm, &done[(t - 1) * n..], next, obs[t]);
        scale.push(normalise(next, c, sequence, t)?);
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

/// [`dot`] of four rows with the same `w` in one pass: each result is summed exactly as
/// [`dot`] sums it, but sixteen independent partial sums hide the latency of the additions
/// and every load of `w` serves four rows.
fn dot4(rows: &[f64], w: &[f64]) -> [f64; 4] {
    let n = w.len();
    let (r0, rest) = rows.split_at(n);
    let (r1, rest) = rest.split_at(n);
    let (r2, r3) = rest.split_at(n);
    let mut acc = [[0.0; 4]; 4];
    let chunks = r0
        .chunks_exact(4)
        .zip(r1.chunks_exact(4))
        .zip(r2.chunks_exact(4).zip(r3.chunks_exact(4)))
        .zip(w.chunks_exact(4));
    for (((a0, a1), (a2, a3)), x) in chunks {
        // Written as whole-array expressions per row, so that the compiler pairs neighbouring
        // partial sums of one row into a vector register (written element by element, it
        // packs the same element of two rows instead and spends a shuffle per product).
        let x = [x[0], x[1], x[2], x[3]];
        for (acc, a) in acc.iter_mut().zip([a0, a1, a2, a3]) {
            let p = [a[0] * x[0], a[1] * x[1], a[2] * x[2], a[3] * x[3]];
            *acc = [acc[0] + p[0], acc[1] + p[1], acc[2] + p[2], acc[3] + p[3]];
        }
    }
    let tail_start = n - n % 4;
    let wr = &w[tail_start..];
    let mut out = [0.0; 4];
    for (r, (o, acc)) in [r0, r1, r2, r3].into_iter().zip(out.iter_mut().zip(&acc)) {
        let tail: f64 = r[tail_start..].iter().zip(wr).map(|(r, x)| r * x).sum();
        *o = (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail;
    }
    out
}

/// β̂_t(i) = Σ_j a_ij w(j) over dense row-major rows.
fn beta_dense(rows: &[f64], weighted: &[f64], beta: &mut [f64]) {
    let n = weighted.len();
    let mut blocks = beta.chunks_exact_mut(4);
    let mut row_blocks = rows.chunks_exact(4 * n);
    for (out, block) in (&mut blocks).zip(&mut row_blocks) {
        out.copy_from_slice(&dot4(block, weighted));
    }
    let tail_rows = row_blocks.remainder().chunks_exact(n);
    for (out, row) in blocks.into_remainder().iter_mut().zip(tail_rows) {
        *out = dot(row, weighted);
    }
}

/// w_{t+1}(j) = b_j(o_{t+1}) β̂_{t+1}(j) / c_{t+1}.
fn weigh(hmm: &Hmm, symbol: usize, beta_next: &[f64], scale: f64, weighted: &mut [f64]) {
    let inv = 1.0 / scale;
    for ((w, b), nb) in weighted
        .iter_mut()
        .zip(hmm.emission_column(symbol))
        .zip(beta_next)
    {
        *w = b * nb * inv;
    }
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
        weigh(hmm, obs[t + 1], &beta_next, scale[t + 1], &mut weighted);
        match (a.dense_rows(), a.sparse_view()) {
            (Some(rows), _) => beta_dense(rows, &weighted, &mut beta),
            (None, Some(view)) => {
                for (i, out) in beta.iter_mut().enumerate() {
                    let range = view.row_ptr[i]..view.row_ptr[i + 1];
                    let mut s = 0.0;
                    for (&j, &aij) in view.cols[range.clone()].iter().zip(&view.values[range]) {
                        s += aij * weighted[j];
                    }
                    *out = s;
                }
            }
            (None, None) => {}
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

/// The backward sweep of [`backward_sweep`] that also adds Σ_t ξ_t(i, j) = Σ_t α̂_t(i) a_ij
/// w_{t+1}(j) to `xi`, one entry per stored element of A (storage order, see
/// [`crate::Transitions::values`]), and calls `visit(t, β̂_t)` at every step.
///
/// Sparse storage: ξ is added in the same pass over a row that forms β̂_t(i), so every non-zero
/// is loaded once for both. Dense storage: Σ_t α̂_t(i) w_{t+1}(j) is the N × N matrix product
/// α̂ᵀ W over the stored forward variables and a stored W, formed after the sweep by
/// [`add_outer_products`] in blocks that stay in cache, then multiplied entry-wise by A; the
/// per-step alternative reads and writes all N² counts at every step.
pub(crate) fn backward_with_xi(
    hmm: &Hmm,
    obs: &[usize],
    forward: &Forward,
    xi: &mut [f64],
    mut visit: impl FnMut(usize, &[f64]),
) {
    let n = hmm.n_states();
    let len = obs.len();
    let a = hmm.transitions();
    let alpha = &forward.alpha;
    let mut beta_next = vec![1.0; n];
    let mut beta = vec![0.0; n];
    visit(len - 1, &beta_next);
    match (a.dense_rows(), a.sparse_view()) {
        (Some(rows), _) => {
            // W, row t holding w_{t+1}.
            let mut w_all = vec![0.0; (len - 1) * n];
            for t in (0..len - 1).rev() {
                let weighted = &mut w_all[t * n..(t + 1) * n];
                weigh(hmm, obs[t + 1], &beta_next, forward.scale[t + 1], weighted);
                beta_dense(rows, weighted, &mut beta);
                visit(t, &beta);
                std::mem::swap(&mut beta, &mut beta_next);
            }
            let mut products = vec![0.0; n * n];
            add_outer_products(&alpha[..(len - 1) * n], &w_all, n, &mut products);
            for ((x, aij), c) in xi.iter_mut().zip(rows).zip(&products) {
                *x += aij * c;
            }
        }
        (None, Some(view)) => {
            let mut weighted = vec![0.0; n];
            for t in (0..len - 1).rev() {
                weigh(
                    hmm,
                    obs[t + 1],
                    &beta_next,
                    forward.scale[t + 1],
                    &mut weighted,
                );
                let alpha_t = &alpha[t * n..(t + 1) * n];
                for (i, (out, &al)) in beta.iter_mut().zip(alpha_t).enumerate() {
                    let range = view.row_ptr[i]..view.row_ptr[i + 1];
                    let mut s = 0.0;
                    let entries = view.cols[range.clone()]
                        .iter()
                        .zip(&view.values[range.clone()]);
                    for ((&j, &aij), x) in entries.zip(&mut xi[range]) {
                        let wj = weighted[j];
                        s += aij * wj;
                        *x += al * aij * wj;
                    }
                    *out = s;
                }
                visit(t, &beta);
                std::mem::swap(&mut beta, &mut beta_next);
            }
        }
        (None, None) => {}
    }
}

/// Adds Σ_t u_t(i) v_t(j) to `out[i · n + j]`, for `u` and `v` row-major (rows = steps, n
/// columns): the product uᵀ v, taken eight steps at a time so that each pass over `out` does
/// eight multiply-adds per entry from rows that stay in the first-level cache. Rows of `u`
/// whose eight entries are all zero are skipped.
fn add_outer_products(u: &[f64], v: &[f64], n: usize, out: &mut [f64]) {
    const STEPS: usize = 8;
    let rows = u.len() / n;
    let full = rows - rows % STEPS;
    for t0 in (0..full).step_by(STEPS) {
        let ub = &u[t0 * n..(t0 + STEPS) * n];
        let vb = &v[t0 * n..(t0 + STEPS) * n];
        let vr: [&[f64]; STEPS] = std::array::from_fn(|s| &vb[s * n..(s + 1) * n]);
        for (i, row) in out.chunks_exact_mut(n).enumerate() {
            let c: [f64; STEPS] = std::array::from_fn(|s| ub[s * n + i]);
            if c.iter().all(|&x| x == 0.0) {
                continue;
            }
            let row = &mut row[..n];
            let [v0, v1, v2, v3, v4, v5, v6, v7] = vr.map(|x| &x[..n]);
            for j in 0..n {
                let acc = c[0] * v0[j]
                    + c[1] * v1[j]
                    + c[2] * v2[j]
                    + c[3] * v3[j]
                    + c[4] * v4[j]
                    + c[5] * v5[j]
                    + c[6] * v6[j]
                    + c[7] * v7[j];
                row[j] += acc;
            }
        }
    }
    for t in full..rows {
        let (ut, vt) = (&u[t * n..(t + 1) * n], &v[t * n..(t + 1) * n]);
        for (row, &c) in out.chunks_exact_mut(n).zip(ut) {
            if c != 0.0 {
                row.iter_mut().zip(vt).for_each(|(o, x)| *o += c * x);
            }
        }
    }
}

/// Expected transition counts Σ_t ξ_t(i, j) as a row-major N × N matrix.
pub fn expected_transitions(hmm: &Hmm, obs: &[usize]) -> Result<Vec<f64>> {
    let f = forward(hmm, obs)?;
    let n = hmm.n_states();
    let mut xi = vec![0.0; hmm.transitions().n_stored()];
    backward_with_xi(hmm, obs, &f, &mut xi, |_, _| {});
    let mut out = vec![0.0; n * n];
    for i in 0..n {
        hmm.transitions()
            .for_each_in_row(i, |j, _, k| out[i * n + j] = xi[k]);
    }
    Ok(out)
}

/// The most probable state path and its log-probability log P(Q*, O | λ), in log space.
/// Ties go to the lowest-numbered predecessor.
///
/// Dense storage keeps δ_t for every step and runs the recursion as a pure max-plus product
/// over the transposed log A (contiguous, branch-free, vectorised); the predecessor of each
/// state on the path is found again while tracing back, one column per step. Sparse storage
/// gathers down each column and keeps the predecessors.
pub fn viterbi(hmm: &Hmm, obs: &[usize]) -> Result<(Vec<usize>, f64)> {
    hmm.check_observations(obs, 0)?;
    let n = hmm.n_states();
    let len = obs.len();
    let logs = hmm.logs();
    let mut path = vec![0; len];
    let best = match hmm.transitions().sparse_view() {
        None => viterbi_dense(logs, n, obs, &mut path),
        Some(view) => viterbi_sparse(logs, &view, n, obs, &mut path),
    };
    if best == f64::NEG_INFINITY {
        return Err(Error::ImpossibleObservation {
            sequence: 0,
            index: len - 1,
        });
    }
    Ok((path, best))
}

/// log π + log b(o₀), δ₁ of the Viterbi recursion.
fn viterbi_start<'a>(logs: &'a Logs, n: usize, o0: usize) -> impl Iterator<Item = f64> + 'a {
    logs.initial
        .iter()
        .zip(&logs.by_symbol[o0 * n..(o0 + 1) * n])
        .map(|(p, b)| p + b)
}

/// [`viterbi`] on dense storage: δ_t kept for every step, the recursion a max-plus product
/// over the transposed log A, the predecessors found again while tracing back. Fills `path`
/// and returns the best log-probability.
fn viterbi_dense(logs: &Logs, n: usize, obs: &[usize], path: &mut [usize]) -> f64 {
    let len = obs.len();
    let log_emission = |m: usize| &logs.by_symbol[m * n..(m + 1) * n];
    let first = viterbi_start(logs, n, obs[0]);
    let columns = &logs.transitions_by_column;
    let mut delta = vec![0.0; len * n];
    delta[..n].iter_mut().zip(first).for_each(|(d, v)| *d = v);
    for t in 1..len {
        let (done, rest) = delta.split_at_mut(t * n);
        let prev = &done[(t - 1) * n..];
        let cur = &mut rest[..n];
        let lb = log_emission(obs[t]);
        let mut blocks = columns.chunks_exact(4 * n);
        let mut out = cur.chunks_exact_mut(4);
        for ((block, lb), out) in (&mut blocks).zip(lb.chunks_exact(4)).zip(&mut out) {
            let m = max_plus4(prev, block);
            for ((o, m), b) in out.iter_mut().zip(m).zip(lb) {
                *o = m + b;
            }
        }
        let tail_lb = &lb[lb.len() - lb.len() % 4..];
        let tail_columns = blocks.remainder().chunks_exact(n);
        for ((o, column), b) in out
            .into_remainder()
            .iter_mut()
            .zip(tail_columns)
            .zip(tail_lb)
        {
            *o = max_plus(prev, column) + b;
        }
    }
    let (mut state, best) = first_max(&delta[(len - 1) * n..]);
    path[len - 1] = state;
    for t in (1..len).rev() {
        let prev = &delta[(t - 1) * n..t * n];
        state = first_max_plus(prev, &columns[state * n..(state + 1) * n]);
        path[t - 1] = state;
    }
    best
}

/// [`viterbi`] on sparse storage: a gather down each column of log A, keeping the
/// predecessors. Fills `path` and returns the best log-probability.
fn viterbi_sparse(
    logs: &Logs,
    view: &SparseView<'_>,
    n: usize,
    obs: &[usize],
    path: &mut [usize],
) -> f64 {
    let len = obs.len();
    let log_emission = |m: usize| &logs.by_symbol[m * n..(m + 1) * n];
    let first = viterbi_start(logs, n, obs[0]);
    let columns = &logs.transitions_by_column;
    let mut delta: Vec<f64> = first.collect();
    let mut next = vec![f64::NEG_INFINITY; n];
    let mut back = vec![0u32; len * n];
    for t in 1..len {
        let psi = &mut back[t * n..(t + 1) * n];
        let lb = log_emission(obs[t]);
        // Rows ascending within each column with a strict comparison keep the lowest
        // predecessor on ties.
        for (j, ((v, p), b)) in next.iter_mut().zip(psi.iter_mut()).zip(lb).enumerate() {
            let range = view.col_ptr[j]..view.col_ptr[j + 1];
            let (mut best, mut arg) = (f64::NEG_INFINITY, 0);
            for (&i, &la) in view.col_rows[range.clone()].iter().zip(&columns[range]) {
                let cand = delta[i] + la;
                if cand > best {
                    best = cand;
                    arg = i;
                }
            }
            *v = best + b;
            *p = arg as u32;
        }
        std::mem::swap(&mut delta, &mut next);
    }
    let (mut state, best) = first_max(&delta);
    path[len - 1] = state;
    for t in (1..len).rev() {
        state = back[t * n + state] as usize;
        path[t - 1] = state;
    }
    best
}

/// The first index of the largest value (0 and −∞ when every value is −∞).
fn first_max(v: &[f64]) -> (usize, f64) {
    v.iter().enumerate().fold(
        (0, f64::NEG_INFINITY),
        |acc, (i, &x)| {
            if x > acc.1 { (i, x) } else { acc }
        },
    )
}

/// The larger of two values as a compare-and-select, which the compiler turns into a vector
/// maximum (no NaN can occur: log-probabilities are finite or −∞).
#[inline(always)]
fn larger(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

/// max_i (prev[i] + column[i]). The maximum does not depend on the order of comparison, so
/// eight running maxima are as exact as one.
fn max_plus(prev: &[f64], column: &[f64]) -> f64 {
    let mut acc = [f64::NEG_INFINITY; 8];
    let (pc, cc) = (prev.chunks_exact(8), column.chunks_exact(8));
    let (pr, cr) = (pc.remainder(), cc.remainder());
    for (p, c) in pc.zip(cc) {
        for k in 0..8 {
            acc[k] = larger(p[k] + c[k], acc[k]);
        }
    }
    let tail = pr
        .iter()
        .zip(cr)
        .fold(f64::NEG_INFINITY, |m, (p, c)| larger(p + c, m));
    acc.iter().fold(tail, |m, &x| larger(x, m))
}

/// [`max_plus`] of four consecutive columns (`columns` holds them one after another) in one
/// pass over `prev`.
fn max_plus4(prev: &[f64], columns: &[f64]) -> [f64; 4] {
    let n = prev.len();
    let (c0, rest) = columns.split_at(n);
    let (c1, rest) = rest.split_at(n);
    let (c2, c3) = rest.split_at(n);
    let mut acc = [[f64::NEG_INFINITY; 4]; 4];
    let chunks = prev
        .chunks_exact(4)
        .zip(c0.chunks_exact(4).zip(c1.chunks_exact(4)))
        .zip(c2.chunks_exact(4).zip(c3.chunks_exact(4)));
    for ((p, (a0, a1)), (a2, a3)) in chunks {
        let p = [p[0], p[1], p[2], p[3]];
        for (acc, a) in acc.iter_mut().zip([a0, a1, a2, a3]) {
            let s = [p[0] + a[0], p[1] + a[1], p[2] + a[2], p[3] + a[3]];
            *acc = [
                larger(s[0], acc[0]),
                larger(s[1], acc[1]),
                larger(s[2], acc[2]),
                larger(s[3], acc[3]),
            ];
        }
    }
    let tail_start = n - n % 4;
    let mut out = [f64::NEG_INFINITY; 4];
    for (o, (acc, column)) in out.iter_mut().zip(acc.iter().zip([c0, c1, c2, c3])) {
        let tail = prev[tail_start..]
            .iter()
            .zip(&column[tail_start..])
            .fold(f64::NEG_INFINITY, |m, (p, c)| larger(p + c, m));
        *o = acc.iter().fold(tail, |m, &x| larger(x, m));
    }
    out
}

/// The lowest i with the largest prev[i] + column[i] (0 when all are −∞): the predecessor
/// the recursion chose, found again while tracing back.
fn first_max_plus(prev: &[f64], column: &[f64]) -> usize {
    let (mut best, mut arg) = (f64::NEG_INFINITY, 0);
    for (i, (p, c)) in prev.iter().zip(column).enumerate() {
        let cand = p + c;
        if cand > best {
            best = cand;
            arg = i;
        }
    }
    arg
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
    let logs = hmm.logs();
    let log_emission = |m: usize| &logs.by_symbol[m * n..(m + 1) * n];
    out.extend(
        logs.initial
            .iter()
            .zip(log_emission(obs[0]))
            .map(|(p, b)| p + b),
    );
    for t in 1..obs.len() {
        let lb = log_emission(obs[t]);
        for j in 0..n {
            let prev = &out[(t - 1) * n..t * n];
            let v = log_sum_exp((0..n).map(|i| prev[i] + dense_log_a[i * n + j])) + lb[j];
            out.push(v);
        }
    }
    let ll = log_sum_exp(out[(obs.len() - 1) * n..].iter().copied());
    Ok((out, ll))
}
