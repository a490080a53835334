//! The transition matrix A and its storage: dense row-major, or compressed sparse rows (CSR)
//! with a compressed-sparse-column (CSC) index of the same entries. Every algorithm visits A
//! through [`Transitions::for_each_in_row`], [`Transitions::for_each_in_column`] or
//! [`Transitions::dense_rows`], so it costs O(nnz) per time step when sparse and runs over
//! contiguous rows when dense.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// How far a probability row may sum from 1.
pub const ROW_SUM_TOLERANCE: f64 = 1e-9;

/// With [`StorageChoice::Auto`], a transition matrix with at most this share of non-zeros is
/// stored sparse.
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

/// How to store a transition matrix. The storage changes speed and memory, never a result
/// beyond rounding.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StorageChoice {
    /// Sparse when at most [`SPARSE_FILL`] of the N² entries are non-zero, dense otherwise.
    #[default]
    Auto,
    /// All N² entries, row-major.
    Dense,
    /// The non-zero entries only (CSR with a CSC index).
    Sparse,
}

#[derive(Debug, Clone, PartialEq)]
enum Layout {
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
#[serde(rename_all = "snake_case", deny_unknown_fields)]
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
        match t.layout {
            Layout::Dense => RawTransitions::Dense {
                n: t.n,
                values: t.values,
            },
            Layout::Sparse { .. } => RawTransitions::Sparse { rows: t.rows() },
        }
    }
}

/// The transition matrix A (a_ij = P(state j at t+1 | state i at t)), every row checked to be
/// a probability vector.
///
/// `values` holds the stored entries: all N² of them for dense storage, the non-zeros in row
/// order for sparse storage. Every algorithm visits rows through [`Transitions::for_each_in_row`],
/// so it costs O(nnz) per time step when sparse and runs over contiguous rows when dense.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawTransitions", into = "RawTransitions")]
pub struct Transitions {
    n: usize,
    layout: Layout,
    values: Vec<f64>,
}

impl Transitions {
    /// From a row-major N × N matrix, stored as `storage` says: with [`StorageChoice::Auto`],
    /// sparse when at most [`SPARSE_FILL`] of it is non-zero and dense otherwise.
    pub fn from_row_major(n: usize, values: Vec<f64>, storage: StorageChoice) -> Result<Self> {
        Ok(Self::dense(n, values)?.to_storage(storage))
    }

    /// Dense storage whatever the fill (the same as [`Transitions::from_row_major`] with
    /// [`StorageChoice::Dense`]).
    pub fn dense(n: usize, values: Vec<f64>) -> Result<Self> {
        if n == 0 {
            return Err(Error::Empty("transition matrix"));
        }
        let expected = n.checked_mul(n).ok_or(Error::SizeOverflow {
            what: "transition matrix entries (N × N)",
            rows: n,
            cols: n,
        })?;
        if values.len() != expected {
            return Err(Error::ShapeMismatch {
                what: "transition matrix entries (N × N)",
                expected,
                got: values.len(),
            });
        }
        for i in 0..n {
            check_row(&values[i * n..(i + 1) * n], "transition matrix", i)?;
        }
        Ok(Self {
            n,
            layout: Layout::Dense,
            values,
        })
    }

    /// Sparse storage from rows of (column, probability); zero entries are dropped.
    pub fn sparse(rows: Vec<Vec<(usize, f64)>>) -> Result<Self> {
        let n = rows.len();
        if n == 0 {
            return Err(Error::Empty("transition matrix"));
        }
        let mut sorted = Vec::with_capacity(n);
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
            sorted.push(row);
        }
        Ok(Self::sparse_from_checked_rows(sorted))
    }

    /// Builds CSR and CSC from rows that are already checked: columns ascending, unique and
    /// in range, every row a probability vector. Zero entries are dropped.
    fn sparse_from_checked_rows(rows: Vec<Vec<(usize, f64)>>) -> Self {
        let n = rows.len();
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut cols = Vec::new();
        let mut values = Vec::new();
        row_ptr.push(0);
        for row in rows {
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
        Self {
            n,
            layout: Layout::Sparse {
                row_ptr,
                cols,
                col_ptr,
                col_rows,
                col_index,
                col_values,
            },
            values,
        }
    }

    /// The non-zero entries as (column, probability) rows, columns ascending.
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

    /// The same matrix stored as `storage` says (values unchanged).
    pub fn to_storage(&self, storage: StorageChoice) -> Self {
        let sparse = match storage {
            StorageChoice::Dense => false,
            StorageChoice::Sparse => true,
            StorageChoice::Auto => {
                let nnz = self.values.iter().filter(|v| **v != 0.0).count();
                (nnz as f64) <= SPARSE_FILL * (self.n as f64) * (self.n as f64)
            }
        };
        if sparse {
            // The rows were checked when `self` was built, and `rows` keeps them sorted.
            Self::sparse_from_checked_rows(self.rows())
        } else {
            Self {
                n: self.n,
                layout: Layout::Dense,
                values: self.dense_values(),
            }
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
        matches!(self.layout, Layout::Sparse { .. })
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
        matches!(self.layout, Layout::Dense).then_some(self.values.as_slice())
    }

    /// The stored values, in storage order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Calls `f(j, a_ij, storage index)` for every stored entry of row `i`.
    #[inline]
    pub fn for_each_in_row(&self, i: usize, mut f: impl FnMut(usize, f64, usize)) {
        match &self.layout {
            Layout::Dense => {
                let start = i * self.n;
                for (j, &a) in self.values[start..start + self.n].iter().enumerate() {
                    f(j, a, start + j);
                }
            }
            Layout::Sparse { row_ptr, cols, .. } => {
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
        match &self.layout {
            Layout::Dense => {
                for i in 0..self.n {
                    let k = i * self.n + j;
                    f(i, self.values[k], k);
                }
            }
            Layout::Sparse {
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

    /// Sparse storage as plain slices for the hot loops: (row pointers, column of each entry,
    /// value of each entry) in row order (CSR), and (column pointers, row of each entry, value
    /// of each entry) in column order (CSC). The column-ordered copy of the values makes a
    /// gather down a column one load per non-zero instead of an index load and a dependent
    /// value load.
    pub(crate) fn sparse_view(&self) -> Option<SparseView<'_>> {
        match &self.layout {
            Layout::Dense => None,
            Layout::Sparse {
                row_ptr,
                cols,
                col_ptr,
                col_rows,
                col_values,
                ..
            } => Some(SparseView {
                row_ptr,
                cols,
                values: &self.values,
                col_ptr,
                col_rows,
                col_values,
            }),
        }
    }

    /// The storage range of row `i`.
    pub(crate) fn row_range(&self, i: usize) -> std::ops::Range<usize> {
        match &self.layout {
            Layout::Dense => i * self.n..(i + 1) * self.n,
            Layout::Sparse { row_ptr, .. } => row_ptr[i]..row_ptr[i + 1],
        }
    }

    /// Replaces the stored values (same sparsity pattern), re-checking every row.
    pub(crate) fn with_values(&self, values: Vec<f64>) -> Result<Self> {
        if values.len() != self.values.len() {
            return Err(Error::ShapeMismatch {
                what: "stored transition values",
                expected: self.values.len(),
                got: values.len(),
            });
        }
        let mut layout = self.layout.clone();
        if let Layout::Sparse {
            col_index,
            col_values,
            ..
        } = &mut layout
        {
            *col_values = col_index.iter().map(|&k| values[k]).collect();
        }
        let out = Self {
            n: self.n,
            layout,
            values,
        };
        for i in 0..out.n {
            check_row(&out.values[out.row_range(i)], "transition matrix", i)?;
        }
        Ok(out)
    }
}

/// Borrowed CSR and CSC slices of a sparse [`Transitions`] (see [`Transitions::sparse_view`]).
pub(crate) struct SparseView<'a> {
    /// CSR row pointers (N + 1).
    pub row_ptr: &'a [usize],
    /// Column of each entry, row order.
    pub cols: &'a [usize],
    /// Value of each entry, row order (the storage order).
    pub values: &'a [f64],
    /// CSC column pointers (N + 1).
    pub col_ptr: &'a [usize],
    /// Row of each entry, column order.
    pub col_rows: &'a [usize],
    /// Value of each entry, column order.
    pub col_values: &'a [f64],
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
