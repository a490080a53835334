//! The constant-velocity box Kalman filter the three trackers share.
//!
//! Two state layouts, as in the papers and the reference implementation:
//! - corners `[x₁, y₁, x₂, y₂, ẋ₁, ẏ₁, ẋ₂, ẏ₂]` ([`StateLayout::Corners`]);
//! - centre, area and aspect `[x_c, y_c, s, r, ẋ_c, ẏ_c, ṡ]` (Bewley et al. 2016, §3.2:
//!   the aspect ratio r is constant, [`StateLayout::CentreAreaAspect`]).
//!
//! Both live in one 8-vector; the centre layout leaves the last entry at zero with zero
//! variance and no coupling, which adds only exact zeros to every sum, so the arithmetic is
//! that of the 7-state filter. The measurement is the first four entries (H = [I 0]).
//! Matrix products are taken in the reference's order (F P, then (F P) Fᵀ; Joseph form), so
//! that rounding follows it.

use nalgebra::{SMatrix, SVector, Vector4};
use serde::{Deserialize, Serialize};

use crate::error::Result;

/// An axis-aligned box as corners `[x₁, y₁, x₂, y₂]`.
pub type Corners = [f64; 4];

pub(crate) type State = SVector<f64, 8>;
pub(crate) type Covariance = SMatrix<f64, 8, 8>;
type Gain = SMatrix<f64, 8, 4>;

/// The filter's state layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StateLayout {
    /// Corners and their velocities (8 states): the box may change shape freely.
    Corners,
    /// Centre, area, aspect ratio and the velocities of centre and area (7 states), as in the
    /// SORT and OC-SORT papers.
    CentreAreaAspect,
}

impl StateLayout {
    /// How many leading entries have a velocity beside them (four later).
    fn n_moving(self) -> usize {
        match self {
            StateLayout::Corners => 4,
            StateLayout::CentreAreaAspect => 3,
        }
    }

    /// The measurement of a box in this layout.
    pub(crate) fn measure(self, b: &Corners) -> Vector4<f64> {
        match self {
            StateLayout::Corners => Vector4::new(b[0], b[1], b[2], b[3]),
            StateLayout::CentreAreaAspect => {
                let (w, h) = (b[2] - b[0], b[3] - b[1]);
                // The reference's 1e-6 keeps the ratio finite for a zero-height box.
                Vector4::new(b[0] + w * 0.5, b[1] + h * 0.5, w * h, w / (h + 1e-6))
            }
        }
    }

    /// The box of a measurement-space vector (the state's first four entries).
    pub(crate) fn corners(self, z: &[f64]) -> Corners {
        match self {
            StateLayout::Corners => [z[0], z[1], z[2], z[3]],
            StateLayout::CentreAreaAspect => {
                let w = (z[2] * z[3]).sqrt();
                let h = if w != 0.0 { z[2] / w } else { 0.0 };
                let (hw, hh) = (w * 0.5, h * 0.5);
                [z[0] - hw, z[1] - hh, z[0] + hw, z[1] + hh]
            }
        }
    }
}

/// The noise of one tracker's filters: the process noise Q of one frame, the measurement
/// noise R and the first covariance P₀, all diagonal.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Noise {
    pub layout: StateLayout,
    pub q: Covariance,
    pub r: SMatrix<f64, 4, 4>,
    pub p0: Covariance,
}

impl Noise {
    /// Diagonal noise from the diagonals (the centre layout's eighth entry is ignored and
    /// set to zero).
    pub fn diagonal(layout: StateLayout, q: [f64; 8], r: [f64; 4], p0: [f64; 8]) -> Self {
        let mut q = Covariance::from_diagonal(&State::from(q));
        let mut p0 = Covariance::from_diagonal(&State::from(p0));
        if layout == StateLayout::CentreAreaAspect {
            q[(7, 7)] = 0.0;
            p0[(7, 7)] = 0.0;
        }
        Self {
            layout,
            q,
            r: SMatrix::<f64, 4, 4>::from_diagonal(&Vector4::from(r)),
            p0,
        }
    }
}

/// One track's filter.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BoxFilter {
    pub x: State,
    pub p: Covariance,
}

impl BoxFilter {
    /// Started at a box, with zero velocity and covariance P₀.
    pub fn new(noise: &Noise, b: &Corners) -> Self {
        let z = noise.layout.measure(b);
        let mut x = State::zeros();
        x.fixed_rows_mut::<4>(0).copy_from(&z);
        Self { x, p: noise.p0 }
    }

    /// The box of the state.
    pub fn corners(&self, layout: StateLayout) -> Corners {
        layout.corners(&self.x.as_slice()[..4])
    }

    /// One frame ahead: x ← F x, P ← (F P) Fᵀ + Q. In the centre layout a shrinking area that
    /// would reach zero within the frame has its rate set to zero first (the area's square root
    /// gives the box).
    pub fn predict(&mut self, noise: &Noise) {
        let n = noise.layout.n_moving();
        if noise.layout == StateLayout::CentreAreaAspect && self.x[2] + self.x[6] <= 0.0 {
            self.x[6] = 0.0;
        }
        for i in 0..n {
            self.x[i] += self.x[i + 4];
        }
        // (F P)[i, j] = P[i, j] + P[i + 4, j] for the moving rows, then the same on columns.
        let mut fp = self.p;
        for i in 0..n {
            for j in 0..8 {
                fp[(i, j)] = self.p[(i, j)] + self.p[(i + 4, j)];
            }
        }
        let mut fpf = fp;
        for j in 0..n {
            for i in 0..8 {
                fpf[(i, j)] = fp[(i, j)] + fp[(i, j + 4)];
            }
        }
        self.p = fpf + noise.q;
    }

    /// The update with a measurement-space vector `z`: K = P Hᵀ S⁻¹ with S = H P Hᵀ + R,
    /// x ← x + K (z − H x), and the Joseph form P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ.
    pub fn update(&mut self, noise: &Noise, z: &Vector4<f64>) -> Result<()> {
        let innovation = z - self.x.fixed_rows::<4>(0);
        let pht: Gain = self.p.fixed_columns::<4>(0).into_owned();
        let s = pht.fixed_rows::<4>(0) + noise.r;
        let s_inv = s
            .lu()
            .try_inverse()
            .ok_or(tracker_model::Error::NotPositiveDefinite {
                what: "box filter innovation covariance",
            })?;
        let k: Gain = pht * s_inv;
        self.x += k * innovation;
        let mut i_kh = Covariance::identity();
        let mut left = i_kh.fixed_columns_mut::<4>(0);
        left -= k;
        self.p = i_kh * self.p * i_kh.transpose() + k * noise.r * k.transpose();
        Ok(())
    }
}
