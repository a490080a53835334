//! Planar microphone arrays.

use serde::{Deserialize, Serialize};
use tracker_model::{Error, Vec2};

use crate::error::Result;

/// Speed of sound in air at about 20 °C, m/s.
pub const SOUND_SPEED_MPS: f64 = 343.0;

/// A planar array: microphone positions in metres in the array's own frame (x forward along the
/// node's heading, y to its left). Positions are stored relative to their centroid, so steering
/// delays are relative to the array centre (Kushwaha et al. 2008, our §5.1 reconstruction).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, try_from = "MicArrayFields")]
pub struct MicArray {
    positions_m: Vec<[f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MicArrayFields {
    positions_m: Vec<[f64; 2]>,
}

impl TryFrom<MicArrayFields> for MicArray {
    type Error = Error;
    fn try_from(f: MicArrayFields) -> Result<Self, Error> {
        Self::new(&f.positions_m)
    }
}

impl Default for MicArray {
    /// The papers' mote array: four microphones at the corners of a 10 cm × 6 cm rectangle.
    fn default() -> Self {
        Self::rectangle(0.10, 0.06)
            .unwrap_or_else(|_| unreachable!("constant dimensions are valid"))
    }
}

impl MicArray {
    /// An array from microphone positions (metres, any origin; re-centred on their centroid).
    /// Needs at least one microphone, finite coordinates and no two microphones at one place.
    pub fn new(positions_m: &[[f64; 2]]) -> Result<Self, Error> {
        if positions_m.is_empty() {
            return Err(Error::Empty {
                what: "microphone positions",
            });
        }
        if positions_m.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                what: "microphone positions",
            });
        }
        for (i, a) in positions_m.iter().enumerate() {
            for (j, b) in positions_m.iter().enumerate().skip(i + 1) {
                if (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-6 {
                    return Err(Error::InvalidParameter {
                        name: "positions_m",
                        reason: format!("microphones {i} and {j} coincide at {a:?}"),
                    });
                }
            }
        }
        let n = positions_m.len() as f64;
        let cx = positions_m.iter().map(|p| p[0]).sum::<f64>() / n;
        let cy = positions_m.iter().map(|p| p[1]).sum::<f64>() / n;
        Ok(Self {
            positions_m: positions_m.iter().map(|p| [p[0] - cx, p[1] - cy]).collect(),
        })
    }

    /// Four microphones at the corners of a `width_m` (along x) × `height_m` (along y)
    /// rectangle, counter-clockwise from (+x, +y).
    pub fn rectangle(width_m: f64, height_m: f64) -> Result<Self, Error> {
        tracker_model::ensure_positive(width_m, "width_m")?;
        tracker_model::ensure_positive(height_m, "height_m")?;
        let (w, h) = (width_m / 2.0, height_m / 2.0);
        Self::new(&[[w, h], [-w, h], [-w, -h], [w, -h]])
    }

    /// A uniform circular array of `n_mics` ≥ 2 on a circle of `radius_m`, microphone 0 on +x.
    pub fn uniform_circular(n_mics: usize, radius_m: f64) -> Result<Self, Error> {
        tracker_model::ensure_positive(radius_m, "radius_m")?;
        if n_mics < 2 {
            return Err(Error::InvalidParameter {
                name: "n_mics",
                reason: format!("{n_mics}: a circular array needs at least 2 microphones"),
            });
        }
        let positions: Vec<[f64; 2]> = (0..n_mics)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n_mics as f64;
                [radius_m * a.cos(), radius_m * a.sin()]
            })
            .collect();
        Self::new(&positions)
    }

    /// Number of microphones.
    pub fn n_mics(&self) -> usize {
        self.positions_m.len()
    }

    /// Microphone positions relative to the array centre, metres.
    pub fn positions_m(&self) -> &[[f64; 2]] {
        &self.positions_m
    }

    /// Position of microphone `mic` as a vector.
    pub fn position(&self, mic: usize) -> Option<Vec2> {
        self.positions_m.get(mic).map(|p| Vec2::new(p[0], p[1]))
    }

    /// The largest distance between two microphones (the aperture), metres.
    pub fn aperture_m(&self) -> f64 {
        let mut best = 0.0_f64;
        for a in &self.positions_m {
            for b in &self.positions_m {
                best = best.max((a[0] - b[0]).hypot(a[1] - b[1]));
            }
        }
        best
    }

    /// The far-field arrival advance τ_m(θ) = (r_m · u_θ)/c of every microphone for a plane
    /// wave from direction `bearing_rad` (array frame), in seconds: a positive τ means the wave
    /// reaches that microphone τ seconds before the array centre.
    pub fn arrival_advances_s(&self, bearing_rad: f64, sound_speed_mps: f64) -> Vec<f64> {
        let (s, c) = bearing_rad.sin_cos();
        self.positions_m
            .iter()
            .map(|p| (p[0] * c + p[1] * s) / sound_speed_mps)
            .collect()
    }
}
