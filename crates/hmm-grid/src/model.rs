//! The model λ = (π, A, B): validated at construction, with A stored densely or as compressed
//! sparse rows (CSR), chosen automatically from its fill.

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// How far a probability row may sum from 1.
pub const ROW_SUM_TOLERANCE: f64 = 1e-9;

/// A transition matrix with at most this share of non-zeros is stored sparse.
pub const SPARSE_FILL: f64 = 0.25;

/// Checks one probability row: finite, non-negative, summing to 1.
pub(crate) fn check_row(values: &[f64], what: &'static str, row: usize) -> Result<()> {
    if let Some((col, v)) = values
        .iter()
        .enumerate()
        .find(|(_, v)| !v.is_finite() || **v < 0.0)
    {
        return Err(Error::InvalidRow {
            what,
            row,
            reason: format!("entry {col} is {v}; probabilities must be finite and >= 0"),
        });
    }
    let sum: f64 = values.iter().sum();
    if (sum - 1.0).abs() > ROW_SUM_TOLERANCE {
        return Err(Error::InvalidRow {
            what,
            row,
            reason: format!("sums to {sum}, not 1"),
        });
    }
    Ok(())
}

#[derive(Debug, Clone, PartialEq)]
enum Storage {
    /// Row-major N × N.
    Dense,
    /// Compressed sparse rows; columns ascending within a row.
    Sparse {
        row_ptr: Vec<usize>,
        cols: Vec<usize>,
        /// The same entries by column (CSC), rows ascending: `col_rows[e]` is the row,
        /// `col_index[e]` the storage index and `col_values[e]` the value of entry e.
        /// Forward-type recursions gather down a column into a register instead of scattering
        /// into memory, which removes a read-modify-write dependency per entry.
        col_ptr: Vec<usize>,
        col_rows: Vec<usize>,
        col_index: Vec<usize>,
        col_values: Vec<f64>,
    },
}

/// The serialised form: dense values or sparse rows, rebuilt and re-checked on reading.
#[derive(Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum RawTransitions {
    Dense { n: usize, values: Vec<f64> },
    Sparse { rows: Vec<Vec<(usize, f64)>> },
}

impl TryFrom<RawTransitions> for Transitions {
    type Error = Error;
    fn try_from(raw: RawTransitions) -> Result<Self> {
        match raw {
            RawTransitions::Dense { n, values } => Transitions::dense(n, values),
            RawTransitions::Sparse { rows } => Transitions::sparse(rows),
        }
    }
}

impl From<Transitions> for RawTransitions {
    fn from(t: Transitions) -> Self {
        match t.storage {
            Storage::Dense => RawTransitions::Dense {
                n: t.n,
                values: t.values,
            },
            Storage::Sparse { .. } => RawTransitions::Sparse { rows: t.rows() },
        }
    }
}

/// The transition matrix A (a_ij = P(state j at t+1 | state i at t)).
///
/// `values` holds the stored entries: all N² of them for dense storage, the non-zeros in row
/// order for sparse storage. Every algorithm visits rows through [`Transitions::for_each_in_row`],
/// so it costs O(nnz) per time step when sparse and runs over contiguous rows when dense.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawTransitions", into = "RawTransitions")]
pub struct Transitions {
    n: usize,
    storage: Storage,
    values: Vec<f64>,
}

impl Transitions {
    /// From a row-major N × N matrix; stored sparse when at most [`SPARSE_FILL`] of it is
    /// non-zero, dense otherwise.
    pub fn from_dense(n: usize, values: Vec<f64>) -> Result<Self> {
        let nnz = values.iter().filter(|v| **v != 0.0).count();
        let dense = Self::dense(n, values)?;
        if (nnz as f64) <= SPARSE_FILL * (n * n) as f64 {
            Ok(dense.to_sparse())
        } else {
            Ok(dense)
        }
    }

    /// Dense storage whatever the fill.
    pub fn dense(n: usize, values: Vec<f64>) -> Result<Self> {
        if n == 0 {
            return Err(Error::Empty("transition matrix"));
        }
        if values.len() != n * n {
            return Err(Error::Shape(format!(
                "a {n}-state transition matrix needs {} entries, got {}",
                n * n,
                values.len()
            )));
        }
        for i in 0..n {
            check_row(&values[i * n..(i + 1) * n], "transition matrix", i)?;
        }
        Ok(Self {
            n,
            storage: Storage::Dense,
            values,
        })
    }

    /// Sparse storage from rows of (column, probability); zero entries are dropped.
    pub fn sparse(rows: Vec<Vec<(usize, f64)>>) -> Result<Self> {
        let n = rows.len();
        if n == 0 {
            return Err(Error::Empty("transition matrix"));
        }
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut cols = Vec::new();
        let mut values = Vec::new();
        row_ptr.push(0);
        for (i, mut row) in rows.into_iter().enumerate() {
            row.sort_by_key(|e| e.0);
            if let Some(w) = row.windows(2).find(|w| w[0].0 == w[1].0) {
                return Err(Error::InvalidRow {
                    what: "transition matrix",
                    row: i,
                    reason: format!("column {} appears twice", w[0].0),
                });
            }
            if let Some(&(c, _)) = row.iter().find(|e| e.0 >= n) {
                return Err(Error::InvalidRow {
                    what: "transition matrix",
                    row: i,
                    reason: format!("column {c} is outside 0..{n}"),
                });
            }
            let probs: Vec<f64> = row.iter().map(|e| e.1).collect();
            check_row(&probs, "transition matrix", i)?;
            for (c, v) in row {
                if v != 0.0 {
                    cols.push(c);
                    values.push(v);
                }
            }
            row_ptr.push(cols.len());
        }
        let (col_ptr, col_rows, col_index) = by_column(n, &row_ptr, &cols);
        let col_values = col_index.iter().map(|&k| values[k]).collect();
        Ok(Self {
            n,
            storage: Storage::Sparse {
                row_ptr,
                cols,
                col_ptr,
                col_rows,
                col_index,
                col_values,
            },
            values,
        })
    }

    /// The non-zero entries as (column, probability) rows.
    pub fn rows(&self) -> Vec<Vec<(usize, f64)>> {
        (0..self.n)
            .map(|i| {
                let mut row = Vec::new();
                self.for_each_in_row(i, |j, a, _| {
                    if a != 0.0 {
                        row.push((j, a));
                    }
                });
                row
            })
            .collect()
    }

    /// The same matrix in sparse storage.
    pub fn to_sparse(&self) -> Self {
        // The rows were valid before, so they are valid now.
        Self::sparse(self.rows()).unwrap_or_else(|_| self.clone())
    }

    /// The same matrix in dense storage.
    pub fn to_dense(&self) -> Self {
        Self {
            n: self.n,
            storage: Storage::Dense,
            values: self.dense_values(),
        }
    }

    /// Row-major N × N values.
    pub fn dense_values(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.n * self.n];
        for i in 0..self.n {
            self.for_each_in_row(i, |j, a, _| out[i * self.n + j] = a);
        }
        out
    }

    /// N.
    pub fn n_states(&self) -> usize {
        self.n
    }

    /// Stored entries (N² when dense).
    pub fn n_stored(&self) -> usize {
        self.values.len()
    }

    /// Whether the storage is sparse.
    pub fn is_sparse(&self) -> bool {
        matches!(self.storage, Storage::Sparse { .. })
    }

    /// a_ij.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let mut out = 0.0;
        if i < self.n {
            self.for_each_in_row(i, |c, a, _| {
                if c == j {
                    out = a;
                }
            });
        }
        out
    }

    /// The row-major N × N values when stored densely; the algorithms then use contiguous
    /// slice loops that the compiler vectorises.
    pub fn dense_rows(&self) -> Option<&[f64]> {
        matches!(self.storage, Storage::Dense).then_some(self.values.as_slice())
    }

    /// The stored values, in storage order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Calls `f(j, a_ij, storage index)` for every stored entry of row `i`.
    #[inline]
    pub fn for_each_in_row(&self, i: usize, mut f: impl FnMut(usize, f64, usize)) {
        match &self.storage {
            Storage::Dense => {
                let start = i * self.n;
                for (j, &a) in self.values[start..start + self.n].iter().enumerate() {
                    f(j, a, start + j);
                }
            }
            Storage::Sparse { row_ptr, cols, .. } => {
                let range = row_ptr[i]..row_ptr[i + 1];
                let entries = cols[range.clone()].iter().zip(&self.values[range.clone()]);
                for (k, (&j, &a)) in range.zip(entries) {
                    f(j, a, k);
                }
            }
        }
    }

    /// Calls `f(i, a_ij, storage index)` for every stored entry of column `j`, rows ascending.
    /// Dense storage visits all N rows.
    #[inline]
    pub fn for_each_in_column(&self, j: usize, mut f: impl FnMut(usize, f64, usize)) {
        match &self.storage {
            Storage::Dense => {
                for i in 0..self.n {
                    let k = i * self.n + j;
                    f(i, self.values[k], k);
                }
            }
            Storage::Sparse {
                col_ptr,
                col_rows,
                col_index,
                col_values,
                ..
            } => {
                let range = col_ptr[j]..col_ptr[j + 1];
                let entries = col_rows[range.clone()]
                    .iter()
                    .zip(&col_index[range.clone()]);
                for ((&i, &k), &a) in entries.zip(&col_values[range]) {
                    f(i, a, k);
                }
            }
        }
    }

    /// The storage range of row `i`.
    pub(crate) fn row_range(&self, i: usize) -> std::ops::Range<usize> {
        match &self.storage {
            Storage::Dense => i * self.n..(i + 1) * self.n,
            Storage::Sparse { row_ptr, .. } => row_ptr[i]..row_ptr[i + 1],
        }
    }

    /// Replaces the stored values (same sparsity pattern), re-checking every row.
    pub(crate) fn with_values(&self, values: Vec<f64>) -> Result<Self> {
        if values.len() != self.values.len() {
            return Err(Error::Shape(format!(
                "{} transition values for {} stored entries",
                values.len(),
                self.values.len()
            )));
        }
        let mut storage = self.storage.clone();
        if let Storage::Sparse {
            col_index,
            col_values,
            ..
        } = &mut storage
        {
            *col_values = col_index.iter().map(|&k| values[k]).collect();
        }
        let out = Self {
            n: self.n,
            storage,
            values,
        };
        for i in 0..out.n {
            check_row(&out.values[out.row_range(i)], "transition matrix", i)?;
        }
        Ok(out)
    }
}

/// The CSC index of a CSR pattern: (column pointers, row of each entry, storage index of each
/// entry), rows ascending within a column.
fn by_column(n: usize, row_ptr: &[usize], cols: &[usize]) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let mut col_ptr = vec![0usize; n + 1];
    cols.iter().for_each(|&c| col_ptr[c + 1] += 1);
    for j in 0..n {
        col_ptr[j + 1] += col_ptr[j];
    }
    let mut fill = col_ptr.clone();
    let mut col_rows = vec![0; cols.len()];
    let mut col_index = vec![0; cols.len()];
    for i in 0..n {
        for k in row_ptr[i]..row_ptr[i + 1] {
            let slot = fill[cols[k]];
            col_rows[slot] = i;
            col_index[slot] = k;
            fill[cols[k]] += 1;
        }
    }
    (col_ptr, col_rows, col_index)
}

/// A discrete hidden Markov model with N states and M observation symbols.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawHmm", into = "RawHmm")]
pub struct Hmm {
    initial: Vec<f64>,
    transitions: Transitions,
    /// Row-major N × M: b_i(m).
    emissions: Vec<f64>,
    n_symbols: usize,
    /// Derived: M × N, b_·(m) contiguous for each symbol, and its logarithm; log a per stored
    /// entry; log π.
    by_symbol: Vec<f64>,
    log_by_symbol: Vec<f64>,
    log_transitions: Vec<f64>,
    log_initial: Vec<f64>,
}

#[derive(Serialize, Deserialize)]
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
            return Err(Error::Shape(format!(
                "initial distribution has {} entries for {n} states",
                initial.len()
            )));
        }
        if n_symbols == 0 {
            return Err(Error::Empty("symbol alphabet"));
        }
        if emissions.len() != n * n_symbols {
            return Err(Error::Shape(format!(
                "emission matrix needs {n} × {n_symbols} = {} entries, got {}",
                n * n_symbols,
                emissions.len()
            )));
        }
        check_row(&initial, "initial distribution", 0)?;
        for i in 0..n {
            check_row(
                &emissions[i * n_symbols..(i + 1) * n_symbols],
                "emission matrix",
                i,
            )?;
        }
        let mut by_symbol = vec![0.0; n * n_symbols];
        for i in 0..n {
            for m in 0..n_symbols {
                by_symbol[m * n + i] = emissions[i * n_symbols + m];
            }
        }
        Ok(Self {
            log_by_symbol: by_symbol.iter().map(|v| v.ln()).collect(),
            log_transitions: transitions.values().iter().map(|v| v.ln()).collect(),
            log_initial: initial.iter().map(|v| v.ln()).collect(),
            by_symbol,
            initial,
            transitions,
            emissions,
            n_symbols,
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

    /// log b_·(m) for every state.
    pub(crate) fn log_emission_column(&self, m: usize) -> &[f64] {
        let n = self.n_states();
        &self.log_by_symbol[m * n..(m + 1) * n]
    }

    /// log a per stored entry.
    pub(crate) fn log_transitions(&self) -> &[f64] {
        &self.log_transitions
    }

    /// log π.
    pub(crate) fn log_initial(&self) -> &[f64] {
        &self.log_initial
    }

    /// The same model with sparse (or dense) transition storage: for comparing the two paths.
    pub fn with_transition_storage(&self, sparse: bool) -> Self {
        let transitions = if sparse {
            self.transitions.to_sparse()
        } else {
            self.transitions.to_dense()
        };
        Self {
            log_transitions: transitions.values().iter().map(|v| v.ln()).collect(),
            transitions,
            ..self.clone()
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
