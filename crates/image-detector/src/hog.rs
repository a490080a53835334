//! The Dalal-Triggs (CVPR 2005) histogram of oriented gradients on a cell grid.
//!
//! * Gradients by the centred [-1, 0, 1] mask in x and y, on every colour channel; each pixel
//!   keeps the channel with the largest magnitude (Dalal and Triggs §6.2). Image borders are
//!   reflected without repeating the edge pixel (OpenCV's `BORDER_REFLECT_101`).
//! * Unsigned orientation θ ∈ [0°, 180°) in 9 bins of 20° centred at 10°, 30°, …, 170°; a
//!   pixel's magnitude is split linearly between the two nearest bin centres (the orientation
//!   part of Dalal and Triggs' trilinear vote; the spatial part is not used: each pixel votes
//!   only in its own cell).
//! * 8 × 8-pixel cells; 16 × 16 blocks (2 × 2 cells) at a stride of one cell; each block's
//!   36 values normalised by L2-Hys: v ← v / √(‖v‖² + ε²), clipped at 0.2, renormalised.
//!
//! The grid is computed once per image ([`CellGrid::compute`], [`BlockGrid::from_cells`]);
//! the descriptor of any window aligned to the cells is then read from the blocks without
//! recomputation ([`BlockGrid::value`], [`BlockGrid::window_descriptor`]).

use crate::error::{Error, Result};

/// Pixels per cell side.
pub const CELL: usize = 8;
/// Orientation bins.
pub const BINS: usize = 9;
/// Values per block: 2 × 2 cells × 9 bins.
pub const BLOCK_LEN: usize = 4 * BINS;
/// L2-Hys clipping level.
pub const CLIP: f32 = 0.2;
/// ε of the L2 normalisation (in the units of a block's summed gradient magnitudes).
pub const EPSILON: f32 = 1e-3;

/// A floating-point image: row-major, channels interleaved (1 or 3 channels).
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    width: usize,
    height: usize,
    channels: usize,
    data: Vec<f32>,
}

impl Plane {
    /// A plane from its values; `channels` is 1 or 3 and width, height ≥ 1.
    pub fn new(width: usize, height: usize, channels: usize, data: Vec<f32>) -> Result<Self> {
        if !(channels == 1 || channels == 3) || width == 0 || height == 0 {
            return Err(Error::BadImage {
                width,
                height,
                channels,
                reason: "1 or 3 channels and a non-empty size are needed",
            });
        }
        let expected = width * height * channels;
        if data.len() != expected {
            return Err(Error::BufferSize {
                len: data.len(),
                expected,
                width,
                height,
                channels,
            });
        }
        Ok(Self {
            width,
            height,
            channels,
            data,
        })
    }

    /// An RGB plane from an 8-bit image.
    pub fn from_rgb(image: &image::RgbImage) -> Result<Self> {
        Self::new(
            image.width() as usize,
            image.height() as usize,
            3,
            image.as_raw().iter().map(|&v| f32::from(v)).collect(),
        )
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Channels per pixel.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// The values.
    pub fn data(&self) -> &[f32] {
        &self.data
    }
}

/// Reflect-101 index: −1 → 1, n → n − 2 (n ≥ 2); a single row or column maps to 0.
fn reflect(i: isize, n: usize) -> usize {
    let n = n as isize;
    if n == 1 {
        return 0;
    }
    let mut i = i;
    if i < 0 {
        i = -i;
    }
    if i >= n {
        i = 2 * (n - 1) - i;
    }
    i.clamp(0, n - 1) as usize
}

/// The unsigned orientation of (gx, gy) in [0, π): atan by Cephes' `atanf` reduction and
/// polynomial (error about 1e-7 rad), inlined because libm's atan2 dominated the cost.
///
/// Written without branches: every case is computed and the result selected, so a loop over
/// pixels can run several at once and noisy pixels cause no mispredictions. The value of each
/// case is the same as a branching version's (only the selection differs).
#[inline]
pub fn unsigned_angle(gx: f32, gy: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    // Fold into the upper half-plane: (gx, gy) and (−gx, −gy) have the same orientation.
    let flip = (gy < 0.0) | ((gy == 0.0) & (gx < 0.0));
    let (gx, gy) = (if flip { -gx } else { gx }, if flip { -gy } else { gy });
    // t is ±∞ or NaN when gx = 0; that case is selected away at the end.
    let t = gy / gx.abs();
    let (far, mid) = (-1.0 / t, (t - 1.0) / (t + 1.0));
    let (big, medium) = (t > 2.414_213_6, t > 0.414_213_57);
    let base = if big {
        FRAC_PI_2
    } else if medium {
        FRAC_PI_4
    } else {
        0.0
    };
    let x = if big {
        far
    } else if medium {
        mid
    } else {
        t
    };
    let z = x * x;
    let a = base
        + ((((8.053_744_5e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1)
            * z
            * x
            + x);
    let theta = if gx < 0.0 { PI - a } else { a };
    let theta = if theta >= PI { 0.0 } else { theta };
    let vertical = if gy == 0.0 { 0.0 } else { FRAC_PI_2 };
    if gx == 0.0 { vertical } else { theta }
}

/// Calls `vote(x, y, lo, hi, w_lo, w_hi)` for every pixel of the top-left `nx × ny` of
/// `plane` with a non-zero gradient: its magnitude split between the two nearest bins.
fn for_each_vote(
    plane: &Plane,
    nx: usize,
    ny: usize,
    vote: impl FnMut(usize, usize, usize, usize, f32, f32),
) {
    // The channel count as a constant, so the per-channel loop unrolls (the arithmetic, and
    // so every value, is the same for both).
    if plane.channels == 3 {
        votes_of::<3>(plane, nx, ny, vote);
    } else {
        votes_of::<1>(plane, nx, ny, vote);
    }
}

/// [`for_each_vote`] for `C` channels. Rows are sliced once per row, and the reflected
/// neighbours are looked up only at the first and last columns, so the inner loop has no
/// branches on the border and no bounds checks on the rows (this loop is most of a
/// detector's time).
fn votes_of<const C: usize>(
    plane: &Plane,
    nx: usize,
    ny: usize,
    mut vote: impl FnMut(usize, usize, usize, usize, f32, f32),
) {
    let (w, h) = (plane.width, plane.height);
    let row_len = w * C;
    let row = |y: usize| &plane.data[y * row_len..(y + 1) * row_len];
    let bin_width = std::f32::consts::PI / BINS as f32;
    // One row at a time in three passes: gradients (the strongest channel), then magnitude and
    // bin position (no branches, so the compiler runs several pixels at once), then the votes.
    let (mut gxs, mut gys, mut m2s) = (vec![0.0f32; nx], vec![0.0f32; nx], vec![0.0f32; nx]);
    let (mut mags, mut poss) = (vec![0.0f32; nx], vec![0.0f32; nx]);
    for y in 0..ny {
        let (ym, yp) = (reflect(y as isize - 1, h), reflect(y as isize + 1, h));
        let (here, up, down) = (row(y), row(ym), row(yp));
        for (x, ((gxo, gyo), m2o)) in gxs
            .iter_mut()
            .zip(gys.iter_mut())
            .zip(m2s.iter_mut())
            .enumerate()
        {
            let (xm, xp) = if x == 0 || x + 1 >= w {
                (reflect(x as isize - 1, w), reflect(x as isize + 1, w))
            } else {
                (x - 1, x + 1)
            };
            let (left, right) = (&here[xm * C..][..C], &here[xp * C..][..C]);
            let (above, below) = (&up[x * C..][..C], &down[x * C..][..C]);
            let (mut best, mut gx, mut gy) = (-1.0f32, 0.0f32, 0.0f32);
            for ch in 0..C {
                let dx = right[ch] - left[ch];
                let dy = below[ch] - above[ch];
                let m2 = dx * dx + dy * dy;
                if m2 > best {
                    (best, gx, gy) = (m2, dx, dy);
                }
            }
            (*gxo, *gyo, *m2o) = (gx, gy, best);
        }
        for ((((mag, pos), &gx), &gy), &m2) in mags
            .iter_mut()
            .zip(poss.iter_mut())
            .zip(&gxs)
            .zip(&gys)
            .zip(&m2s)
        {
            *mag = m2.sqrt();
            // Bin position with centres at (i + 0.5) · 20°; pos ∈ [−0.5, 8.5).
            *pos = unsigned_angle(gx, gy) / bin_width - 0.5;
        }
        for (x, ((&m2, &mag), &pos)) in m2s.iter().zip(&mags).zip(&poss).enumerate() {
            if m2 <= 0.0 {
                continue;
            }
            let (lo, frac) = if pos < 0.0 {
                (BINS - 1, pos + 1.0)
            } else {
                let lo = pos as usize;
                (lo.min(BINS - 1), pos - lo as f32)
            };
            vote(x, y, lo, (lo + 1) % BINS, mag * (1.0 - frac), mag * frac);
        }
    }
}

/// Integral images of the orientation votes (one per bin): the histogram of any rectangle in
/// four look-ups per bin, so cell grids at any pixel offset cost no new gradients.
#[derive(Debug, Clone, PartialEq)]
pub struct OrientedIntegral {
    width: usize,
    height: usize,
    /// (height + 1) × (width + 1) × BINS, row-major; entry (y, x) sums pixels above-left.
    sums: Vec<f64>,
}

impl OrientedIntegral {
    /// The integral of `plane`'s votes.
    pub fn compute(plane: &Plane) -> Self {
        let (w, h) = (plane.width, plane.height);
        let stride = (w + 1) * BINS;
        let mut sums = vec![0.0f64; (h + 1) * stride];
        for_each_vote(plane, w, h, |x, y, lo, hi, a, b| {
            let i = (y + 1) * stride + (x + 1) * BINS;
            sums[i + lo] += f64::from(a);
            sums[i + hi] += f64::from(b);
        });
        for y in 1..=h {
            let (above, row) = sums.split_at_mut(y * stride);
            let above = &above[(y - 1) * stride..];
            let row = &mut row[..stride];
            // Running sum along the row, plus the integral of the rows above.
            let mut acc = [0.0f64; BINS];
            for (cell, up) in row
                .chunks_exact_mut(BINS)
                .zip(above.chunks_exact(BINS))
                .skip(1)
            {
                for b in 0..BINS {
                    acc[b] += cell[b];
                    cell[b] = acc[b] + up[b];
                }
            }
        }
        Self {
            width: w,
            height: h,
            sums,
        }
    }

    /// The cell grid whose first cell's top-left pixel is (ox, oy): as many whole cells as
    /// fit; `None` if fewer than 2 × 2.
    pub fn cells(&self, ox: usize, oy: usize) -> Option<CellGrid> {
        let cells_x = self.width.checked_sub(ox)? / CELL;
        let cells_y = self.height.checked_sub(oy)? / CELL;
        if cells_x < 2 || cells_y < 2 {
            return None;
        }
        let stride = (self.width + 1) * BINS;
        let mut hist = vec![0.0f32; cells_x * cells_y * BINS];
        for cy in 0..cells_y {
            let (y0, y1) = (oy + cy * CELL, oy + (cy + 1) * CELL);
            for cx in 0..cells_x {
                let (x0, x1) = (ox + cx * CELL, ox + (cx + 1) * CELL);
                let out = &mut hist[(cy * cells_x + cx) * BINS..][..BINS];
                for (b, o) in out.iter_mut().enumerate() {
                    let s = |y: usize, x: usize| self.sums[y * stride + x * BINS + b];
                    *o = (s(y1, x1) - s(y0, x1) - s(y1, x0) + s(y0, x0)) as f32;
                }
            }
        }
        Some(CellGrid {
            cells_x,
            cells_y,
            hist,
        })
    }
}

/// The votes of pixel (x, y) read back from an integral (a 1 × 1 rectangle), for tests.
#[cfg(test)]
pub(crate) fn pixel_votes(i: &OrientedIntegral, x: usize, y: usize) -> [f64; BINS] {
    let stride = (i.width + 1) * BINS;
    let mut out = [0.0; BINS];
    for (b, o) in out.iter_mut().enumerate() {
        let s = |yy: usize, xx: usize| i.sums[yy * stride + xx * BINS + b];
        *o = s(y + 1, x + 1) - s(y, x + 1) - s(y + 1, x) + s(y, x);
    }
    out
}

/// Per-cell orientation histograms of an image: `cells_x × cells_y` cells of [`CELL`]
/// pixels (pixels past the last whole cell are not counted), [`BINS`] values each.
#[derive(Debug, Clone, PartialEq)]
pub struct CellGrid {
    cells_x: usize,
    cells_y: usize,
    hist: Vec<f32>,
}

impl CellGrid {
    /// The cell histograms of `plane`; it must hold at least one block (16 × 16 pixels).
    pub fn compute(plane: &Plane) -> Result<Self> {
        let (w, h, c) = (plane.width, plane.height, plane.channels);
        if w < 2 * CELL || h < 2 * CELL {
            return Err(Error::BadImage {
                width: w,
                height: h,
                channels: c,
                reason: "smaller than one 16 x 16 block",
            });
        }
        let (cells_x, cells_y) = (w / CELL, h / CELL);
        let mut hist = vec![0.0f32; cells_x * cells_y * BINS];
        for_each_vote(
            plane,
            cells_x * CELL,
            cells_y * CELL,
            |x, y, lo, hi, a, b| {
                let cell = &mut hist[((y / CELL) * cells_x + x / CELL) * BINS..][..BINS];
                cell[lo] += a;
                cell[hi] += b;
            },
        );
        Ok(Self {
            cells_x,
            cells_y,
            hist,
        })
    }

    /// Cells across.
    pub fn cells_x(&self) -> usize {
        self.cells_x
    }

    /// Cells down.
    pub fn cells_y(&self) -> usize {
        self.cells_y
    }

    /// The histogram of cell (cx, cy).
    pub fn cell(&self, cx: usize, cy: usize) -> &[f32] {
        let i = (cy * self.cells_x + cx) * BINS;
        &self.hist[i..i + BINS]
    }
}

/// L2-Hys in place: L2, clip at [`CLIP`], L2 again.
pub fn l2_hys(v: &mut [f32]) {
    let norm = |v: &[f32]| (v.iter().map(|x| x * x).sum::<f32>() + EPSILON * EPSILON).sqrt();
    let n = norm(v);
    for x in v.iter_mut() {
        *x = (*x / n).min(CLIP);
    }
    let n = norm(v);
    for x in v.iter_mut() {
        *x /= n;
    }
}

/// The normalised blocks of a [`CellGrid`]: one per cell position (bx, by) with
/// bx < cells_x − 1, by < cells_y − 1, holding cells (bx, by), (bx + 1, by), (bx, by + 1),
/// (bx + 1, by + 1) in that order (row-major within the block), 9 bins each.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockGrid {
    blocks_x: usize,
    blocks_y: usize,
    data: Vec<f32>,
}

impl BlockGrid {
    /// Normalises every block of `cells`.
    pub fn from_cells(cells: &CellGrid) -> Self {
        let (blocks_x, blocks_y) = (cells.cells_x - 1, cells.cells_y - 1);
        let mut data = vec![0.0f32; blocks_x * blocks_y * BLOCK_LEN];
        for by in 0..blocks_y {
            for bx in 0..blocks_x {
                let out = &mut data[(by * blocks_x + bx) * BLOCK_LEN..][..BLOCK_LEN];
                for (k, (dx, dy)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                    out[k * BINS..(k + 1) * BINS].copy_from_slice(cells.cell(bx + dx, by + dy));
                }
                l2_hys(out);
            }
        }
        Self {
            blocks_x,
            blocks_y,
            data,
        }
    }

    /// The grid of `plane` in one call.
    pub fn compute(plane: &Plane) -> Result<Self> {
        Ok(Self::from_cells(&CellGrid::compute(plane)?))
    }

    /// Blocks across.
    pub fn blocks_x(&self) -> usize {
        self.blocks_x
    }

    /// Blocks down.
    pub fn blocks_y(&self) -> usize {
        self.blocks_y
    }

    /// The 36 values of block (bx, by).
    pub fn block(&self, bx: usize, by: usize) -> &[f32] {
        &self.data[(by * self.blocks_x + bx) * BLOCK_LEN..][..BLOCK_LEN]
    }

    /// Value `k` of block (bx, by).
    #[inline]
    pub fn value(&self, bx: usize, by: usize, k: usize) -> f32 {
        self.data[(by * self.blocks_x + bx) * BLOCK_LEN + k]
    }

    /// The descriptor of the window of `cells_w × cells_h` cells whose top-left cell is
    /// (cx, cy): its blocks row by row, `(cells_w − 1)(cells_h − 1) · 36` values, or `None` if
    /// the window does not fit.
    pub fn window_descriptor(
        &self,
        cx: usize,
        cy: usize,
        cells_w: usize,
        cells_h: usize,
    ) -> Option<Vec<f32>> {
        if cells_w < 2
            || cells_h < 2
            || cx + cells_w - 1 > self.blocks_x
            || cy + cells_h - 1 > self.blocks_y
        {
            return None;
        }
        let mut out = Vec::with_capacity((cells_w - 1) * (cells_h - 1) * BLOCK_LEN);
        for by in cy..cy + cells_h - 1 {
            for bx in cx..cx + cells_w - 1 {
                out.extend_from_slice(self.block(bx, by));
            }
        }
        Some(out)
    }
}
