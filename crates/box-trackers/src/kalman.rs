//! The constant-velocity box Kalman filter the three trackers share.
//!
//! Two state layouts, as in the papers and the reference implementation:
//! - corners `[x₁, y₁, x₂, y₂, ẋ₁, ẏ₁, ẋ₂, ẏ₂]` ([`StateLayout::Corners`]);
//! - centre, area and aspect `[x_c, y_c, s, r, ẋ_c, ẏ_c, ṡ]` (Bewley et al. 2016, §3.2:
//!   the aspect ratio r is constant, [`StateLayout::CentreAreaAspect`]).
//!
//! Both live in one 8-vector; the centre layout leaves the last entry at zero. The
//! measurement is the first four entries (H = [I 0]).
//!
//! With diagonal Q, R and P₀ (as every tracker here has) nothing couples entry i with any but
//! its own rate i + 4, so the covariance is four 2 × 2 blocks and the filter runs axis by
//! axis, S diagonal. Each block's arithmetic is the full matrices' with their exact zeros left
//! out, in the reference's order (F P, then (F P) Fᵀ; K = P Hᵀ S⁻¹ with S⁻¹ the reciprocal;
//! the Joseph form), so rounding follows it; the tests compare it with the full 8 × 8 (7 × 7)
//! formulas.

use serde::{Deserialize, Serialize};

use crate::error::Result;

/// An axis-aligned box as corners `[x₁, y₁, x₂, y₂]`.
pub type Corners = [f64; 4];
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
    pub(crate) fn measure(self, b: &Corners) -> [f64; 4] {
        match self {
            StateLayout::Corners => *b,
            StateLayout::CentreAreaAspect => {
                let (w, h) = (b[2] - b[0], b[3] - b[1]);
                // The reference's 1e-6 keeps the ratio finite for a zero-height box.
                [b[0] + w * 0.5, b[1] + h * 0.5, w * h, w / (h + 1e-6)]
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

/// The noise of one tracker's filters, all diagonal: the process noise Q of one frame, the
/// measurement noise R and the first covariance P₀.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Noise {
    pub layout: StateLayout,
    pub q: [f64; 8],
    pub r: [f64; 4],
    pub p0: [f64; 8],
}

impl Noise {
    /// Diagonal noise (in the centre layout the eighth entries are set to zero, and the
    /// aspect ratio's rate, the unused seventh velocity slot, stays at zero too).
    pub fn diagonal(layout: StateLayout, mut q: [f64; 8], r: [f64; 4], mut p0: [f64; 8]) -> Self {
        if layout == StateLayout::CentreAreaAspect {
            q[7] = 0.0;
            p0[7] = 0.0;
        }
        Self { layout, q, r, p0 }
    }
}

/// One track's filter: the state, and per axis a the 2 × 2 block of entries (a, a + 4) of the
/// covariance, row-major.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BoxFilter {
    pub x: [f64; 8],
    p: [[f64; 4]; 4],
}

impl BoxFilter {
    /// Started at a box, with zero velocity and covariance P₀.
    pub fn new(noise: &Noise, b: &Corners) -> Self {
        let z = noise.layout.measure(b);
        let mut x = [0.0; 8];
        x[..4].copy_from_slice(&z);
        let p = std::array::from_fn(|a| [noise.p0[a], 0.0, 0.0, noise.p0[a + 4]]);
        Self { x, p }
    }

    /// The box of the state.
    pub fn corners(&self, layout: StateLayout) -> Corners {
        layout.corners(&self.x[..4])
    }

    /// The covariance entry (i, j) of the full matrix.
    #[cfg(test)]
    pub fn covariance(&self, i: usize, j: usize) -> f64 {
        let (a, b) = (i % 4, j % 4);
        if a != b {
            return 0.0;
        }
        self.p[a][2 * (i / 4) + j / 4]
    }

    /// One frame ahead: x ← F x, P ← (F P) Fᵀ + Q. In the centre layout a shrinking area that
    /// would reach zero within the frame has its rate set to zero first (the area's square root
    /// gives the box).
    pub fn predict(&mut self, noise: &Noise) {
        if noise.layout == StateLayout::CentreAreaAspect && self.x[2] + self.x[6] <= 0.0 {
            self.x[6] = 0.0;
        }
        for a in 0..noise.layout.n_moving() {
            self.x[a] += self.x[a + 4];
            let [pp, pv, vp, vv] = self.p[a];
            // (F P): the position row gains the rate row; then (F P) Fᵀ on the columns.
            let (fpp, fpv) = (pp + vp, pv + vv);
            self.p[a] = [fpp + fpv, fpv, vp + vv, vv];
        }
        for a in 0..4 {
            self.p[a][0] += noise.q[a];
            self.p[a][3] += noise.q[a + 4];
        }
    }

    /// The update with a measurement-space vector `z`: per axis S = P₀₀ + R, K = P Hᵀ S⁻¹,
    /// x ← x + K (z − H x), and the Joseph form P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ.
    pub fn update(&mut self, noise: &Noise, z: &[f64; 4]) -> Result<()> {
        for (a, &za) in z.iter().enumerate() {
            let [pp, pv, vp, vv] = self.p[a];
            let s = pp + noise.r[a];
            if s.is_nan() || s <= 0.0 {
                return Err(tracker_model::Error::NotPositiveDefinite {
                    what: "box filter innovation covariance",
                }
                .into());
            }
            let s_inv = 1.0 / s;
            let (kp, kv) = (pp * s_inv, vp * s_inv);
            let innovation = za - self.x[a];
            self.x[a] += kp * innovation;
            self.x[a + 4] += kv * innovation;
            // A = (I − K H) P with I − K H = [[1 − kp, 0], [−kv, 1]], then A (I − K H)ᵀ.
            let one_kp = 1.0 - kp;
            let (app, apv) = (one_kp * pp, one_kp * pv);
            let (avp, avv) = (-kv * pp + vp, -kv * pv + vv);
            let (krp, krv) = (kp * noise.r[a], kv * noise.r[a]);
            self.p[a] = [
                app * one_kp + krp * kp,
                app * -kv + apv + krp * kv,
                avp * one_kp + krv * kp,
                avp * -kv + avv + krv * kv,
            ];
        }
        Ok(())
    }
}
