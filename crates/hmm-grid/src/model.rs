//! The model λ = (π, A, B), checked at construction: π and every row of A and B are
//! probability vectors, and the sizes fit together. Transition storage lives in
//! [`transitions`](crate::transitions).

use std::sync::OnceLock;

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::transitions::{StorageChoice, Transitions, check_row};

/// A discrete hidden Markov model with N states and M observation symbols.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "RawHmm", into = "RawHmm")]
pub struct Hmm {
    initial: Vec<f64>,
    transitions: Transitions,
    /// Row-major N × M: b_i(m).
    emissions: Vec<f64>,
    n_symbols: usize,
    /// Derived: M × N, b_·(m) contiguous for each symbol.
    by_symbol: Vec<f64>,
    /// Derived on first use (only Viterbi needs them, so Baum-Welch's M-step, which builds a
    /// new model per iteration, never pays for N·M + nnz logarithms).
    logs: OnceLock<Logs>,
}

/// The logarithms Viterbi works with.
#[derive(Debug, Clone)]
pub(crate) struct Logs {
    /// M × N: log b_·(m) contiguous for each symbol.
    pub by_symbol: Vec<f64>,
    /// log a_ij in column order: for dense storage the N × N matrix column-major (row j of
    /// this buffer is column j of log A, so the max-plus recursion runs over contiguous
    /// memory); for sparse storage one value per entry in the CSC order of
    /// [`Transitions`].
    pub transitions_by_column: Vec<f64>,
    /// log π.
    pub initial: Vec<f64>,
}

/// Equality of the parameters λ = (π, A, B); derived buffers and caches are not compared.
impl PartialEq for Hmm {
    fn eq(&self, other: &Self) -> bool {
        self.initial == other.initial
            && self.transitions == other.transitions
            && self.emissions == other.emissions
            && self.n_symbols == other.n_symbols
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHmm {
    initial: Vec<f64>,
    transitions: Transitions,
    emissions: Vec<f64>,
    n_symbols: usize,
}

impl TryFrom<RawHmm> for Hmm {
    type Error = Error;
    fn try_from(r: RawHmm) -> Result<Self> {
        // `Transitions` re-checks itself when deserialised.
        Hmm::new(r.initial, r.transitions, r.emissions, r.n_symbols)
    }
}

impl From<Hmm> for RawHmm {
    fn from(h: Hmm) -> Self {
        RawHmm {
            initial: h.initial,
            transitions: h.transitions,
            emissions: h.emissions,
            n_symbols: h.n_symbols,
        }
    }
}

impl Hmm {
    /// A model from π (length N), A and B (row-major N × M); every row must be a probability
    /// vector, otherwise the error names the row.
    pub fn new(
        initial: Vec<f64>,
        transitions: Transitions,
        emissions: Vec<f64>,
        n_symbols: usize,
    ) -> Result<Self> {
        let n = transitions.n_states();
        if initial.len() != n {
            return Err(Error::ShapeMismatch {
                what: "initial distribution entries (N)",
                expected: n,
                got: initial.len(),
            });
        }
        if n_symbols == 0 {
            return Err(Error::Empty("symbol alphabet"));
        }
        let expected = n.checked_mul(n_symbols).ok_or(Error::SizeOverflow {
            what: "emission matrix entries (N × M)",
            rows: n,
            cols: n_symbols,
        })?;
        if emissions.len() != expected {
            return Err(Error::ShapeMismatch {
                what: "emission matrix entries (N × M)",
                expected,
                got: emissions.len(),
            });
        }
        check_row(&initial, "initial distribution", 0)?;
        for i in 0..n {
            check_row(
                &emissions[i * n_symbols..(i + 1) * n_symbols],
                "emission matrix",
                i,
            )?;
        }
        let mut by_symbol = vec![0.0; expected];
        for (i, row) in emissions.chunks_exact(n_symbols).enumerate() {
            for (m, &b) in row.iter().enumerate() {
                by_symbol[m * n + i] = b;
            }
        }
        Ok(Self {
            by_symbol,
            initial,
            transitions,
            emissions,
            n_symbols,
            logs: OnceLock::new(),
        })
    }

    /// N.
    pub fn n_states(&self) -> usize {
        self.initial.len()
    }

    /// M.
    pub fn n_symbols(&self) -> usize {
        self.n_symbols
    }

    /// π.
    pub fn initial(&self) -> &[f64] {
        &self.initial
    }

    /// A.
    pub fn transitions(&self) -> &Transitions {
        &self.transitions
    }

    /// B, row-major N × M.
    pub fn emissions(&self) -> &[f64] {
        &self.emissions
    }

    /// b_i(m).
    pub fn emission(&self, i: usize, m: usize) -> f64 {
        self.emissions[i * self.n_symbols + m]
    }

    /// b_·(m) for every state, contiguous.
    pub(crate) fn emission_column(&self, m: usize) -> &[f64] {
        let n = self.n_states();
        &self.by_symbol[m * n..(m + 1) * n]
    }

    /// The logarithms of π, A (column order) and B (by symbol), computed on first use.
    pub(crate) fn logs(&self) -> &Logs {
        self.logs.get_or_init(|| {
            let a = &self.transitions;
            let n = self.n_states();
            let transitions_by_column = match (a.dense_rows(), a.sparse_view()) {
                (Some(rows), _) => {
                    let mut out = vec![0.0; rows.len()];
                    for (i, row) in rows.chunks_exact(n).enumerate() {
                        for (j, v) in row.iter().enumerate() {
                            out[j * n + i] = v.ln();
                        }
                    }
                    out
                }
                (None, Some(view)) => view.col_values.iter().map(|v| v.ln()).collect(),
                (None, None) => Vec::new(),
            };
            Logs {
                by_symbol: self.by_symbol.iter().map(|v| v.ln()).collect(),
                transitions_by_column,
                initial: self.initial.iter().map(|v| v.ln()).collect(),
            }
        })
    }

    /// The same model with its transitions stored as `storage` says: for comparing the dense
    /// and sparse paths, or choosing by fill after building A by hand.
    pub fn with_transition_storage(&self, storage: StorageChoice) -> Self {
        Self {
            initial: self.initial.clone(),
            transitions: self.transitions.to_storage(storage),
            emissions: self.emissions.clone(),
            n_symbols: self.n_symbols,
            by_symbol: self.by_symbol.clone(),
            logs: OnceLock::new(),
        }
    }

    /// Checks that `obs` is non-empty and every symbol is below M.
    pub fn check_observations(&self, obs: &[usize], sequence: usize) -> Result<()> {
        if obs.is_empty() {
            return Err(Error::Empty("observation sequence"));
        }
        match obs.iter().enumerate().find(|(_, o)| **o >= self.n_symbols) {
            Some((index, &symbol)) => Err(Error::SymbolOutOfRange {
                sequence,
                index,
                symbol,
                n_symbols: self.n_symbols,
            }),
            None => Ok(()),
        }
    }

    /// Draws a state path and its observations of length `len` from the model.
    pub fn sample<R: Rng + ?Sized>(&self, len: usize, rng: &mut R) -> (Vec<usize>, Vec<usize>) {
        let mut states = Vec::with_capacity(len);
        let mut obs = Vec::with_capacity(len);
        let m = self.n_symbols;
        // One buffer for the current transition row, reused at every step.
        let mut row = Vec::new();
        for t in 0..len {
            let state = if t == 0 {
                categorical(self.initial.iter().copied().enumerate(), rng)
            } else {
                row.clear();
                self.transitions
                    .for_each_in_row(states[t - 1], |j, a, _| row.push((j, a)));
                categorical(row.iter().copied(), rng)
            };
            states.push(state);
            let e = &self.emissions[state * m..(state + 1) * m];
            obs.push(categorical(e.iter().copied().enumerate(), rng));
        }
        (states, obs)
    }
}

/// Draws an index from (index, probability) pairs summing to 1; rounding that leaves the
/// uniform draw past the last cumulative sum returns the last index with positive probability.
fn categorical<R: Rng + ?Sized>(items: impl Iterator<Item = (usize, f64)>, rng: &mut R) -> usize {
    let u: f64 = rng.random();
    let mut acc = 0.0;
    let mut last = 0;
    for (i, p) in items {
        if p > 0.0 {
            last = i;
            acc += p;
            if u < acc {
                return i;
            }
        }
    }
    last
}
