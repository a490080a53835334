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
    let mut matched = Vec::new();
    if score.n_rows > 0 && score.n_cols > 0 {
        let weights: Vec<f64> = score.values.iter().map(|&v| f64::from(v)).collect();
        let mut pairs = assignment::maximise(score.n_rows, score.n_cols, &weights)?;
        pairs.sort_unstable();
        let threshold = threshold as f32;
        matched.extend(
            pairs
                .into_iter()
                .filter(|&(r, c)| gate.at(r, c) >= threshold),
        );
    }
    Ok(Matching::of(matched, score.n_rows, score.n_cols))
}

impl Matching {
    /// `matched` (in row order) with the rows and columns it leaves.
    fn of(matched: Vec<(usize, usize)>, n_rows: usize, n_cols: usize) -> Self {
        let mut row_free = vec![true; n_rows];
        let mut col_free = vec![true; n_cols];
        for &(r, c) in &matched {
            row_free[r] = false;
            col_free[c] = false;
        }
        let free = |flags: Vec<bool>| {
            flags
                .into_iter()
                .enumerate()
                .filter_map(|(i, f)| f.then_some(i))
                .collect()
        };
        Self {
            matched,
            unmatched_rows: free(row_free),
            unmatched_cols: free(col_free),
        }
    }
}

/// The maximum-IoU assignment of `rows` to `cols` gated at `threshold` (SORT's and
/// ByteTrack's): [`assign_overlapping`] for a positive gate, else the dense problem (a zero
/// gate passes the pairs that do not overlap, which only the dense solve decides as the
/// reference does).
pub fn assign_iou(rows: &[Corners], cols: &[Corners], threshold: f64) -> Result<Matching> {
    if (threshold as f32) > 0.0 {
        return assign_overlapping(rows, cols, threshold);
    }
    let iou = Matrix::iou(rows, cols);
    assign(&iou, &iou, threshold)
}

/// [`assign`] on an IoU matrix gated on itself at `threshold` > 0, without forming the dense
/// problem: the pairs that overlap at all split the tracks and boxes into connected groups,
/// and each group is assigned on its own (a single pair directly, a larger group by the same
/// solver on its submatrix). Zero entries add nothing to an assignment's weight and fail any
/// positive gate, so wherever the maximum-weight assignment is unique (exactly tied IoUs
/// aside) the matches are those of the dense problem; the tests compare the two on random
/// scenes. Cost: a sort and the overlapping pairs, instead of a dense n × m solve.
pub fn assign_overlapping(rows: &[Corners], cols: &[Corners], threshold: f64) -> Result<Matching> {
    let pairs = overlapping_pairs(rows, cols);
    let mut groups = Groups::new(rows.len() + cols.len());
    for &(r, c, _) in &pairs {
        groups.join(r, rows.len() + c);
    }
    let mut members: std::collections::BTreeMap<usize, Vec<(usize, usize, f32)>> =
        std::collections::BTreeMap::new();
    for &pair in &pairs {
        members.entry(groups.root(pair.0)).or_default().push(pair);
    }
    let gate = threshold as f32;
    let mut matched = Vec::new();
    for group in members.into_values() {
        if let [(r, c, v)] = group.as_slice() {
            // One pair: the solver has nothing to choose.
            if *v >= gate {
                matched.push((*r, *c));
            }
            continue;
        }
        let sorted = |mut v: Vec<usize>| {
            v.sort_unstable();
            v.dedup();
            v
        };
        let group_rows = sorted(group.iter().map(|p| p.0).collect());
        let group_cols = sorted(group.iter().map(|p| p.1).collect());
        // The pairs' IoUs, already computed; every other entry of the group is zero (no
        // overlap).
        let mut sub = Matrix {
            n_rows: group_rows.len(),
            n_cols: group_cols.len(),
            values: vec![0.0; group_rows.len() * group_cols.len()],
        };
        for &(r, c, v) in &group {
            if let (Ok(i), Ok(j)) = (group_rows.binary_search(&r), group_cols.binary_search(&c)) {
                sub.values[i * sub.n_cols + j] = v;
            }
        }
        let m = assign(&sub, &sub, threshold)?;
        matched.extend(
            m.matched
                .iter()
                .map(|&(r, c)| (group_rows[r], group_cols[c])),
        );
    }
    matched.sort_unstable();
    Ok(Matching::of(matched, rows.len(), cols.len()))
}

/// Every (row, col, IoU) with IoU > 0, found by sweeping the columns sorted by left edge:
/// a row can only overlap the columns whose left edge lies within (its left − the widest
/// column, its right).
fn overlapping_pairs(rows: &[Corners], cols: &[Corners]) -> Vec<(usize, usize, f32)> {
    let mut order: Vec<usize> = (0..cols.len())
        .filter(|&c| cols[c].iter().all(|v| v.is_finite()))
        .collect();
    order.sort_by(|&a, &b| cols[a][0].total_cmp(&cols[b][0]));
    let widest = order
        .iter()
        .map(|&c| cols[c][2] - cols[c][0])
        .fold(0.0, f64::max);
    let lefts: Vec<f64> = order.iter().map(|&c| cols[c][0]).collect();
    let mut pairs = Vec::new();
    for (r, row) in rows.iter().enumerate() {
        if !row.iter().all(|v| v.is_finite()) {
            continue;
        }
        let start = lefts.partition_point(|&l| l < row[0] - widest);
        // An inverted box (a prediction whose corners crossed) ends before it starts.
        let end = lefts.partition_point(|&l| l < row[2]).max(start);
        for &c in &order[start..end] {
            let v = iou(row, &cols[c]);
            if v > 0.0 {
                pairs.push((r, c, v));
            }
        }
    }
    pairs
}

/// Union-find over tracks and boxes.
struct Groups {
    parent: Vec<usize>,
}

impl Groups {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
        }
    }

    fn root(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.root(a), self.root(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb);
        }
    }
}
