//! Optimal one-to-one assignment through the `lsap` crate, a port of SciPy's
//! `linear_sum_assignment` (the solver py-motmetrics and TrackEval call), so ties break the same
//! way as in those tools. Every crate that matches things one-to-one calls these.

use crate::error::{Error, Result};

/// Pairs (row, column) of a maximum-weight assignment of a row-major `n_rows × n_cols` matrix;
/// min(n_rows, n_cols) pairs, including pairs of weight zero (callers filter those).
pub fn maximise(n_rows: usize, n_cols: usize, weights: &Vec<f64>) -> Result<Vec<(usize, usize)>> {
    solve(n_rows, n_cols, weights, true)
}

/// Pairs (row, column) of a minimum-cost assignment of a row-major `n_rows × n_cols` matrix.
pub fn minimise(n_rows: usize, n_cols: usize, costs: &Vec<f64>) -> Result<Vec<(usize, usize)>> {
    solve(n_rows, n_cols, costs, false)
}

fn solve(
    n_rows: usize,
    n_cols: usize,
    m: &Vec<f64>,
    maximize: bool,
) -> Result<Vec<(usize, usize)>> {
    if n_rows == 0 || n_cols == 0 {
        return Ok(Vec::new());
    }
    if m.len() != n_rows * n_cols {
        return Err(Error::ShapeMismatch(format!(
            "a {n_rows}×{n_cols} assignment needs {} entries, got {}",
            n_rows * n_cols,
            m.len()
        )));
    }
    let (rows, cols) =
        lsap::solve(n_rows, n_cols, m, maximize).map_err(|e| Error::InvalidParameter {
            name: "assignment matrix",
            reason: format!("the solver rejected it ({e:?}); it must be finite"),
        })?;
    Ok(rows.into_iter().zip(cols).collect())
}
