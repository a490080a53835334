//! IoU matrices and the thresholded optimal assignment the three trackers share.
//!
//! The reference stores similarities in single precision (supervision's `box_iou_batch`
//! computes in f64 and returns f32) and compares them with thresholds cast to f32 (NumPy 2's
//! rules for a Python float beside an f32 array). The matrices here are f32 for that reason:
//! the same pairs then pass the same thresholds and tie the same way in the assignment.

use tracker_model::assignment;

use crate::error::Result;
use crate::kalman::Corners;

/// Intersection over union of two corner boxes, rounded to f32; 0 where the union has no
/// area or a box is not finite (a diverged prediction matches nothing).
pub fn iou(a: &Corners, b: &Corners) -> f32 {
    if !a.iter().chain(b).all(|v| v.is_finite()) {
        return 0.0;
    }
    let w = (a[2].min(b[2]) - a[0].max(b[0])).max(0.0);
    let h = (a[3].min(b[3]) - a[1].max(b[1])).max(0.0);
    let inter = w * h;
    let union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter;
    if union > 0.0 {
        (inter / union) as f32
    } else {
        0.0
    }
}

/// A row-major similarity matrix.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Matrix {
    /// Rows (tracks).
    pub n_rows: usize,
    /// Columns (detections).
    pub n_cols: usize,
    /// The entries, row after row.
    pub values: Vec<f32>,
}

impl Matrix {
    /// The IoU of every row box with every column box.
    pub fn iou(rows: &[Corners], cols: &[Corners]) -> Self {
        let mut values = Vec::with_capacity(rows.len() * cols.len());
        for r in rows {
            values.extend(cols.iter().map(|c| iou(r, c)));
        }
        Self {
            n_rows: rows.len(),
            n_cols: cols.len(),
            values,
        }
    }

    /// Entry (row, col).
    pub fn at(&self, row: usize, col: usize) -> f32 {
        self.values[row * self.n_cols + col]
    }
}

/// The outcome of one association: matched (row, col) pairs in row order, and the rows and
/// columns left over, each in increasing order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Matching {
    /// Matched (row, column) pairs.
    pub matched: Vec<(usize, usize)>,
    /// Rows with no column.
    pub unmatched_rows: Vec<usize>,
    /// Columns with no row.
    pub unmatched_cols: Vec<usize>,
}

/// The maximum-`score` assignment (SciPy's solver, so ties break as in the reference), with
/// every pair whose `gate` entry is below `threshold` undone. `score` and `gate` have the
/// same shape; SORT and ByteTrack gate on the score itself, OC-SORT on the IoU inside its
/// score.
pub fn assign(score: &Matrix, gate: &Matrix, threshold: f64) -> Result<Matching> {
    let mut row_free = vec![true; score.n_rows];
    let mut col_free = vec![true; score.n_cols];
    let mut matched = Vec::new();
    if score.n_rows > 0 && score.n_cols > 0 {
        let weights: Vec<f64> = score.values.iter().map(|&v| f64::from(v)).collect();
        let mut pairs = assignment::maximise(score.n_rows, score.n_cols, &weights)?;
        pairs.sort_unstable();
        let threshold = threshold as f32;
        for (r, c) in pairs {
            if gate.at(r, c) >= threshold {
                matched.push((r, c));
                row_free[r] = false;
                col_free[c] = false;
            }
        }
    }
    let free = |flags: Vec<bool>| {
        flags
            .into_iter()
            .enumerate()
            .filter_map(|(i, f)| f.then_some(i))
            .collect()
    };
    Ok(Matching {
        matched,
        unmatched_rows: free(row_free),
        unmatched_cols: free(col_free),
    })
}
