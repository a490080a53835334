//! Parameters shared by the SMC-PHD and GM-PHD filters over bounding boxes.
//!
//! A target's state is x = [c_x, c_y, w, h, v_x, v_y] (box centre, size, centre velocity); a
//! measurement is a box z = [c_x, c_y, w, h].

use serde::{Deserialize, Serialize};
use tracker_model::{
    BoundingBox, LN_2PI, ensure_in_range, ensure_open_probability, ensure_positive,
};

use crate::error::{Error, Result, invalid_parameter};

/// Box state [c_x, c_y, w, h, v_x, v_y].
pub type BoxState = [f64; 6];
/// Box measurement [c_x, c_y, w, h].
pub type BoxMeasurement = [f64; 4];

/// How boxes move between frames.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum Motion {
    /// Random walk of centre and size (Yoon et al. 2016's model); velocities stay 0.
    RandomWalk {
        /// Standard deviation of the centre's step per frame (pixels).
        position_std: f64,
        /// Standard deviation of the size's step per frame (pixels).
        size_std: f64,
    },
    /// Nearly constant velocity of the centre (white acceleration), random walk of the size.
    ConstantVelocity {
        /// Standard deviation of the velocity's change per frame (pixels/frame).
        acceleration_std: f64,
        /// Standard deviation of the size's step per frame (pixels).
        size_std: f64,
    },
}

/// A 6 × 6 matrix over [`BoxState`], row-major.
pub type StateMatrix = [[f64; 6]; 6];

impl Motion {
    /// The exact transition over `frames` frames, as the `frames`-fold composition of the
    /// one-frame model x ← F x + w, w ~ N(0, Q): F(k) = Fᵏ and Q(k) = Σ_{j<k} Fʲ Q Fʲᵀ, in
    /// closed form, so a gap of any length costs one prediction.
    ///
    /// - Random walk: F(k) = I, Q(k) = k Q.
    /// - Constant velocity: the one-frame model moves the centre by the velocity, then adds
    ///   white noise of variance σ_a² to the velocity only (Q = diag(0, σ_a²) per axis), so
    ///   per axis (position, velocity) F(k) = \[\[1, k\], \[0, 1\]\] and, with Fʲ Q Fʲᵀ =
    ///   σ_a² \[\[j², j\], \[j, 1\]\], Q(k) = σ_a² \[\[Σj², Σj\], \[Σj, k\]\] over j = 0..k−1:
    ///   σ_a² \[\[(k−1)k(2k−1)/6, k(k−1)/2\], \[k(k−1)/2, k\]\]. (This is the composition of
    ///   the filter's own one-frame model; Bar-Shalom's piecewise-constant "DWNA" model, with
    ///   noise Γ = \[Δ²/2, Δ\], is not closed under composition, so F(kΔ), Q(kΔ) of that model
    ///   would not equal k steps of it.) The size is a random walk: k σ_s².
    ///
    /// ```
    /// use phd_filter::Motion;
    ///
    /// let cv = Motion::ConstantVelocity { acceleration_std: 2.0, size_std: 1.0 };
    /// let (f, q) = cv.transition(3);
    /// assert_eq!(f[0][4], 3.0);
    /// // σ_a² (0² + 1² + 2²), σ_a² (0 + 1 + 2), σ_a² · 3.
    /// assert_eq!((q[0][0], q[0][4], q[4][4]), (20.0, 12.0, 12.0));
    /// ```
    pub fn transition(&self, frames: u64) -> (StateMatrix, StateMatrix) {
        let k = frames as f64;
        let mut f = [[0.0; 6]; 6];
        let mut q = [[0.0; 6]; 6];
        for (i, row) in f.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        match *self {
            Motion::RandomWalk {
                position_std,
                size_std,
            } => {
                q[0][0] = k * position_std * position_std;
                q[1][1] = q[0][0];
                q[2][2] = k * size_std * size_std;
                q[3][3] = q[2][2];
            }
            Motion::ConstantVelocity {
                acceleration_std,
                size_std,
            } => {
                let a2 = acceleration_std * acceleration_std;
                let (s1, s2) = power_sums(frames);
                for axis in 0..2 {
                    f[axis][axis + 4] = k;
                    q[axis][axis] = a2 * s2;
                    q[axis][axis + 4] = a2 * s1;
                    q[axis + 4][axis] = a2 * s1;
                    q[axis + 4][axis + 4] = a2 * k;
                }
                q[2][2] = k * size_std * size_std;
                q[3][3] = q[2][2];
            }
        }
        (f, q)
    }

    /// F(k) x: where a state's mean is `frames` frames on (the centre moved by k times the
    /// velocity under constant velocity; unchanged under the random walk).
    pub fn predict_mean(&self, x: &BoxState, frames: u64) -> BoxState {
        let mut out = *x;
        if let Motion::ConstantVelocity { .. } = self {
            let k = frames as f64;
            out[0] += k * x[4];
            out[1] += k * x[5];
        }
        out
    }
}

/// A filter step goes forward in time: `frames` (after the last step) must be at least 1.
pub(crate) fn check_frames_after(frames: u64) -> crate::error::Result<()> {
    if frames == 0 {
        return Err(invalid_parameter(
            "frames",
            "0 frames after the last one; a step moves time forward".into(),
        ));
    }
    Ok(())
}

/// Σ j and Σ j² over j = 0..k−1: k(k−1)/2 and (k−1)k(2k−1)/6, in f64 (exact for k < 2²⁰;
/// beyond, within rounding, and finite for every u64).
pub(crate) fn power_sums(frames: u64) -> (f64, f64) {
    let k = frames as f64;
    (k * (k - 1.0) / 2.0, (k - 1.0) * k * (2.0 * k - 1.0) / 6.0)
}

/// Parameters of the PHD filters. Defaults follow Yoon, Hwang, Choi & Yoon (2016) where the
/// paper gives values (p_D = 0.95, birth intensity 0.1, extraction threshold 0.5) and are
/// otherwise sized for pedestrians of 50-150 pixels in a 640 × 480 image.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PhdConfig {
    /// Survival probability p_S.
    pub p_survive: f64,
    /// Detection probability p_D.
    pub p_detect: f64,
    /// Expected false detections per frame, λ_c.
    pub clutter_rate: f64,
    /// Volume of measurement space (image area × range of widths × range of heights) over
    /// which clutter is uniform: κ(z) = λ_c / volume.
    pub measurement_volume: f64,
    /// Expected births per frame ν_b, spread evenly over the frame's measurements.
    pub birth_rate: f64,
    /// Standard deviations of the measurement noise of [c_x, c_y, w, h] (eq. 7's Σ, diagonal).
    pub measurement_std: [f64; 4],
    /// Motion model.
    pub motion: Motion,
    /// Standard deviation of a newborn's velocity per axis (constant-velocity model only).
    pub birth_velocity_std: f64,
    /// SMC: particles per expected target (ρ).
    pub particles_per_target: usize,
    /// SMC: particles drawn for each measurement's newborn group (J_b), at most
    /// `max_particles` (a frame's newborns are allocated as one block of measurements × J_b).
    pub birth_particles: usize,
    /// SMC: the most persistent particles after resampling.
    pub max_particles: usize,
    /// An estimate is reported for a measurement whose persistent weight W(z) exceeds this
    /// (grouping extraction, eq. 8; GM-PHD: a component's weight).
    pub extraction_threshold: f64,
    /// SMC: an estimate takes the oldest identity that carries at least this share of its
    /// W(z), so a target re-born after a missed detection keeps its identity.
    pub label_min_share: f64,
}

impl Default for PhdConfig {
    fn default() -> Self {
        Self {
            p_survive: 0.99,
            p_detect: 0.95,
            clutter_rate: 1.0,
            measurement_volume: 640.0 * 480.0 * 100.0 * 200.0,
            birth_rate: 0.1,
            measurement_std: [4.0, 4.0, 3.0, 6.0],
            motion: Motion::RandomWalk {
                position_std: 4.0,
                size_std: 1.0,
            },
            birth_velocity_std: 2.0,
            particles_per_target: 1000,
            birth_particles: 200,
            max_particles: 100_000,
            extraction_threshold: 0.5,
            label_min_share: 0.05,
        }
    }
}

impl PhdConfig {
    /// A configuration scaled to detector boxes (what `cargo xtask track --tracker phd` uses
    /// without a configuration file): noise and motion follow the median box width w and
    /// height h (measurement σ = [0.1 w, 0.05 h, 0.1 w, 0.05 h], a random walk of 0.1 w in
    /// position and 0.02 h in size per frame), clutter is uniform over the range of centres
    /// and sizes, p_D = 0.8 (public detectors miss far more than Yoon et al.'s 5 %; a lower
    /// p_D keeps a track through a missed detection), 300 particles per target and 100 per
    /// newborn group, and an extraction threshold of 0.3 (with p_D ≈ 0.8, a target's W(z)
    /// after a miss or beside a neighbour often sits between 0.3 and 0.5).
    ///
    /// ```
    /// use phd_filter::PhdConfig;
    /// use tracker_model::BoundingBox;
    ///
    /// let boxes = [BoundingBox::new(10.0, 20.0, 40.0, 80.0)?, BoundingBox::new(300.0, 25.0, 40.0, 80.0)?];
    /// let config = PhdConfig::for_boxes(&boxes)?;
    /// assert_eq!(config.measurement_std, [4.0, 4.0, 4.0, 4.0]);
    /// # Ok::<(), phd_filter::Error>(())
    /// ```
    pub fn for_boxes(boxes: &[BoundingBox]) -> Result<Self> {
        if boxes.is_empty() {
            return Err(Error::NoBoxes);
        }
        let median = |f: fn(&BoundingBox) -> f64| {
            let mut v: Vec<f64> = boxes.iter().map(f).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2].max(1.0)
        };
        let range = |f: fn(&BoundingBox) -> f64| {
            let (lo, hi) = boxes
                .iter()
                .map(f)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                });
            (hi - lo).max(1.0)
        };
        let (w, h) = (median(|b| b.width), median(|b| b.height));
        let config = Self {
            measurement_volume: range(|b| b.centre().x)
                * range(|b| b.centre().y)
                * range(|b| b.width)
                * range(|b| b.height),
            measurement_std: [0.1 * w, 0.05 * h, 0.1 * w, 0.05 * h],
            motion: Motion::RandomWalk {
                position_std: 0.1 * w,
                size_std: 0.02 * h,
            },
            p_detect: 0.8,
            particles_per_target: 300,
            birth_particles: 100,
            extraction_threshold: 0.3,
            ..Self::default()
        };
        config.check()?;
        Ok(config)
    }

    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        ensure_open_probability(self.p_survive, "p_survive")?;
        ensure_open_probability(self.p_detect, "p_detect")?;
        ensure_positive(self.clutter_rate, "clutter_rate")?;
        ensure_positive(self.measurement_volume, "measurement_volume")?;
        ensure_positive(self.birth_rate, "birth_rate")?;
        for s in &self.measurement_std {
            ensure_positive(*s, "measurement_std")?;
        }
        match self.motion {
            Motion::RandomWalk {
                position_std,
                size_std,
            } => {
                ensure_positive(position_std, "position_std")?;
                ensure_positive(size_std, "size_std")?;
            }
            Motion::ConstantVelocity {
                acceleration_std,
                size_std,
            } => {
                ensure_positive(acceleration_std, "acceleration_std")?;
                ensure_positive(size_std, "size_std")?;
            }
        }
        ensure_positive(self.birth_velocity_std, "birth_velocity_std")?;
        for (name, count) in [
            ("particles_per_target", self.particles_per_target),
            ("birth_particles", self.birth_particles),
            ("max_particles", self.max_particles),
        ] {
            if count == 0 {
                return Err(invalid_parameter(
                    name,
                    "0 particles; it must be at least 1".into(),
                ));
            }
        }
        if self.birth_particles > self.max_particles {
            return Err(invalid_parameter(
                "birth_particles",
                format!(
                    "{} exceeds max_particles = {}",
                    self.birth_particles, self.max_particles
                ),
            ));
        }
        ensure_positive(self.extraction_threshold, "extraction_threshold")?;
        ensure_in_range(self.label_min_share, 0.0, 1.0, "label_min_share")?;
        Ok(())
    }

    /// κ(z): clutter intensity, uniform over measurement space.
    pub fn clutter_intensity(&self) -> f64 {
        self.clutter_rate / self.measurement_volume
    }

    /// The factor on a target's PHD weight from one stepped frame to the frame `frames` later,
    /// the frames between holding no detection: survival in each of the k frames, p_Sᵏ, and a
    /// missed detection in each of the k − 1 frames between, (1 − p_D)ᵏ⁻¹ (an update with no
    /// measurement scales every weight by 1 − p_D and adds no birth, since births come from
    /// measurements; Vo, Singh & Doucet 2005's recursion with Z = ∅). For k = 1, p_S.
    pub fn gap_weight(&self, frames: u64) -> f64 {
        if frames <= 1 {
            return self.p_survive;
        }
        let k = frames as f64;
        // In logarithms; a gap of billions of frames gives 0 (an underflow, and the answer).
        (k * self.p_survive.ln() + (k - 1.0) * (1.0 - self.p_detect).ln()).exp()
    }
}

/// A usable measurement from a box, or `None` for a degenerate one (non-finite coordinates,
/// zero or negative size): such boxes are skipped and counted, never fed to the filter.
pub fn measurement_from_box(b: &BoundingBox) -> Option<BoxMeasurement> {
    let z = [
        b.left + b.width / 2.0,
        b.top + b.height / 2.0,
        b.width,
        b.height,
    ];
    (z.iter().all(|v| v.is_finite()) && b.width > 0.0 && b.height > 0.0).then_some(z)
}

/// The box of a state (size clamped to at least one pixel).
pub fn state_box(x: &BoxState) -> BoundingBox {
    let (w, h) = (x[2].max(1.0), x[3].max(1.0));
    BoundingBox {
        left: x[0] - w / 2.0,
        top: x[1] - h / 2.0,
        width: w,
        height: h,
    }
}

/// The diagonal Gaussian likelihood of eq. 7 for one measurement: precomputed constants.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Likelihood {
    inv_var: [f64; 4],
    log_norm: f64,
    /// Squared Mahalanobis distance beyond which g is treated as 0 (e^-50/2 ≈ 1e-11 of the
    /// peak: far below any weight that matters).
    cutoff: f64,
}

impl Likelihood {
    pub(crate) fn new(std: &[f64; 4]) -> Self {
        let inv_var = std.map(|s| 1.0 / (s * s));
        let log_det: f64 = std.iter().map(|s| 2.0 * s.ln()).sum();
        Self {
            inv_var,
            log_norm: -2.0 * LN_2PI - 0.5 * log_det,
            cutoff: 50.0,
        }
    }

    /// Half-width in c_x beyond which g(z | x) is 0 (the cut-off along the first axis alone).
    pub(crate) fn reach_x(&self) -> f64 {
        (self.cutoff / self.inv_var[0]).sqrt()
    }

    /// g(z | x): density of measuring `z` from state `x`.
    #[inline]
    pub(crate) fn density(&self, z: &BoxMeasurement, x: &BoxState) -> f64 {
        let mut d2 = 0.0;
        for k in 0..4 {
            let e = z[k] - x[k];
            d2 += e * e * self.inv_var[k];
            if d2 > self.cutoff {
                return 0.0;
            }
        }
        (self.log_norm - 0.5 * d2).exp()
    }
}
