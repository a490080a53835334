//! Likelihood grids over a 2-D region: the common currency of bearing-only sensors (audio beams,
//! video angle profiles). Grids from several sensors are fused, and the peaks of the fused grid
//! become point measurements for a tracker.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, ensure_positive};
use crate::geometry::{Region2, Vec2};

/// A non-negative value per cell over a region, row-major with row 0 at the region's lower y.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LikelihoodGrid {
    region: Region2,
    cell_size: f64,
    n_cols: usize,
    n_rows: usize,
    values: Vec<f64>,
}

/// A local maximum of a grid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Peak {
    /// Centre of the peak cell.
    pub position: Vec2,
    /// The grid value there.
    pub value: f64,
}

/// How peaks are extracted: cells that are local maxima of their 8-neighbourhood, at least
/// `relative_threshold` × the grid maximum, thinned by greedy non-maximum suppression within
/// `suppression_radius`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeakConfig {
    /// κ in (0, 1]: a peak must reach κ · max.
    pub relative_threshold: f64,
    /// Peaks closer than this to a stronger kept peak are dropped (≈ the target size).
    pub suppression_radius: f64,
}

impl Default for PeakConfig {
    fn default() -> Self {
        Self {
            relative_threshold: 0.5,
            suppression_radius: 1.0,
        }
    }
}

impl LikelihoodGrid {
    /// An all-zero grid covering `region` with square cells of side `cell_size`; the last
    /// column and row may extend past the region's upper edge.
    pub fn zeros(region: Region2, cell_size: f64) -> Result<Self> {
        ensure_positive(cell_size, "cell_size")?;
        let extent = region.extent();
        let n_cols = (extent.x / cell_size).ceil() as usize;
        let n_rows = (extent.y / cell_size).ceil() as usize;
        let n_cells = n_cols
            .checked_mul(n_rows)
            .filter(|&n| n <= 100_000_000)
            .ok_or(Error::InvalidParameter {
                name: "cell_size",
                reason: format!("{cell_size} gives more than 1e8 cells"),
            })?;
        Ok(Self {
            region,
            cell_size,
            n_cols,
            n_rows,
            values: vec![0.0; n_cells],
        })
    }

    /// A grid whose cell values are `f(cell centre)`; every value must be finite and ≥ 0.
    pub fn from_fn(
        region: Region2,
        cell_size: f64,
        mut f: impl FnMut(Vec2) -> f64,
    ) -> Result<Self> {
        let mut grid = Self::zeros(region, cell_size)?;
        for row in 0..grid.n_rows {
            for col in 0..grid.n_cols {
                let v = f(grid.cell_centre(col, row));
                grid.set(col, row, v)?;
            }
        }
        Ok(grid)
    }

    /// The region covered.
    pub fn region(&self) -> &Region2 {
        &self.region
    }

    /// Side of a cell.
    pub fn cell_size(&self) -> f64 {
        self.cell_size
    }

    /// (columns, rows).
    pub fn shape(&self) -> (usize, usize) {
        (self.n_cols, self.n_rows)
    }

    /// The values, row-major.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Centre of cell (`col`, `row`).
    pub fn cell_centre(&self, col: usize, row: usize) -> Vec2 {
        self.region.lower()
            + Vec2::new(
                (col as f64 + 0.5) * self.cell_size,
                (row as f64 + 0.5) * self.cell_size,
            )
    }

    /// The cell containing `p`, if it lies in the grid.
    pub fn cell_of(&self, p: &Vec2) -> Option<(usize, usize)> {
        let rel = (p - self.region.lower()) / self.cell_size;
        if rel.x < 0.0 || rel.y < 0.0 || !rel.x.is_finite() || !rel.y.is_finite() {
            return None;
        }
        let (col, row) = (rel.x as usize, rel.y as usize);
        (col < self.n_cols && row < self.n_rows).then_some((col, row))
    }

    /// The value of cell (`col`, `row`); 0 outside the grid.
    pub fn value(&self, col: usize, row: usize) -> f64 {
        if col < self.n_cols && row < self.n_rows {
            self.values[row * self.n_cols + col]
        } else {
            0.0
        }
    }

    /// Sets a cell; the value must be finite and ≥ 0.
    pub fn set(&mut self, col: usize, row: usize, value: f64) -> Result<()> {
        if !(value.is_finite() && value >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "grid value",
                reason: format!("cell ({col}, {row}) got {value}; values must be finite and >= 0"),
            });
        }
        if col >= self.n_cols || row >= self.n_rows {
            return Err(Error::ShapeMismatch(format!(
                "cell ({col}, {row}) outside a {}×{} grid",
                self.n_cols, self.n_rows
            )));
        }
        self.values[row * self.n_cols + col] = value;
        Ok(())
    }

    /// Scales the values to sum to 1; an all-zero grid is an error (it carries no evidence).
    pub fn normalise(&mut self) -> Result<()> {
        let total: f64 = self.values.iter().sum();
        if total <= 0.0 || !total.is_finite() {
            return Err(Error::InvalidParameter {
                name: "likelihood grid",
                reason: format!("cannot normalise a grid whose values sum to {total}"),
            });
        }
        self.values.iter_mut().for_each(|v| *v /= total);
        Ok(())
    }

    /// Weighted sum Σ_s w_s L_s, normalised to sum 1. Robust to one sensor missing a target.
    pub fn fuse_weighted_sum(grids: &[(&Self, f64)]) -> Result<Self> {
        let mut fused = Self::fusion_base(grids)?;
        for (grid, weight) in grids {
            for (out, v) in fused.values.iter_mut().zip(&grid.values) {
                *out += weight * v;
            }
        }
        fused.normalise()?;
        Ok(fused)
    }

    /// Weighted product Π_s L_s^{w_s}, normalised to sum 1. Sharper than the sum but a zero in
    /// any grid vetoes the cell. Computed in log space so that many sensors do not underflow.
    pub fn fuse_product(grids: &[(&Self, f64)]) -> Result<Self> {
        let mut fused = Self::fusion_base(grids)?;
        for (out, cell) in fused.values.iter_mut().zip(0..) {
            *out = grids
                .iter()
                .map(|(g, w)| {
                    if *w == 0.0 {
                        0.0
                    } else {
                        w * g.values[cell].ln()
                    }
                })
                .sum();
        }
        let max = fused
            .values
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        if max == f64::NEG_INFINITY {
            return Err(Error::InvalidParameter {
                name: "likelihood grid",
                reason: "the product of the grids is zero everywhere".into(),
            });
        }
        fused.values.iter_mut().for_each(|v| *v = (*v - max).exp());
        fused.normalise()?;
        Ok(fused)
    }

    /// Checks that all grids share a shape and that the weights are usable; returns a zero grid
    /// of that shape.
    fn fusion_base(grids: &[(&Self, f64)]) -> Result<Self> {
        let Some((first, _)) = grids.first() else {
            return Err(Error::Empty {
                what: "grids to fuse",
            });
        };
        let mut weight_sum = 0.0;
        for (idx, (grid, weight)) in grids.iter().enumerate() {
            if grid.region != first.region || grid.cell_size.to_bits() != first.cell_size.to_bits()
            {
                return Err(Error::ShapeMismatch(format!(
                    "grid {idx} does not cover the same region with the same cells as grid 0"
                )));
            }
            if !(weight.is_finite() && *weight >= 0.0) {
                return Err(Error::InvalidParameter {
                    name: "fusion weight",
                    reason: format!("weight {idx} is {weight}; weights must be finite and >= 0"),
                });
            }
            weight_sum += weight;
        }
        if weight_sum <= 0.0 {
            return Err(Error::InvalidParameter {
                name: "fusion weight",
                reason: "all weights are zero".into(),
            });
        }
        let mut base = (*first).clone();
        base.values.iter_mut().for_each(|v| *v = 0.0);
        Ok(base)
    }

    /// Peaks of the grid, strongest first (see [`PeakConfig`]).
    pub fn peaks(&self, config: &PeakConfig) -> Result<Vec<Peak>> {
        if !(config.relative_threshold > 0.0 && config.relative_threshold <= 1.0) {
            return Err(Error::InvalidParameter {
                name: "relative_threshold",
                reason: format!("{} is outside (0, 1]", config.relative_threshold),
            });
        }
        if !(config.suppression_radius.is_finite() && config.suppression_radius >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "suppression_radius",
                reason: format!("{} must be finite and >= 0", config.suppression_radius),
            });
        }
        let max = self.values.iter().copied().fold(0.0, f64::max);
        if max <= 0.0 {
            return Ok(Vec::new());
        }
        let threshold = config.relative_threshold * max;
        let mut candidates = Vec::new();
        for row in 0..self.n_rows {
            for col in 0..self.n_cols {
                let v = self.value(col, row);
                if v >= threshold && self.is_local_max(col, row, v) {
                    candidates.push(Peak {
                        position: self.cell_centre(col, row),
                        value: v,
                    });
                }
            }
        }
        // Strongest first; ties broken by position so the order is deterministic.
        candidates.sort_by(|a, b| {
            b.value
                .total_cmp(&a.value)
                .then(a.position.y.total_cmp(&b.position.y))
                .then(a.position.x.total_cmp(&b.position.x))
        });
        let r2 = config.suppression_radius * config.suppression_radius;
        let mut kept: Vec<Peak> = Vec::new();
        for c in candidates {
            if kept
                .iter()
                .all(|k| (k.position - c.position).norm_squared() > r2)
            {
                kept.push(c);
            }
        }
        Ok(kept)
    }

    /// ≥ every 8-neighbour (plateaus yield several candidates; suppression thins them).
    fn is_local_max(&self, col: usize, row: usize, v: f64) -> bool {
        let rows = row.saturating_sub(1)..=(row + 1).min(self.n_rows - 1);
        rows.flat_map(|r| {
            let cols = col.saturating_sub(1)..=(col + 1).min(self.n_cols - 1);
            cols.map(move |c| (c, r))
        })
        .all(|(c, r)| self.value(c, r) <= v)
    }
}
