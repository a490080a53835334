//! The MCMCDA model and sampler parameters (Oh, Russell & Sastry 2009 §II, §IV), checked once
//! into the log-constants the sampler uses.

use nalgebra::{Matrix2, Matrix4};
use serde::{Deserialize, Serialize};
use tracker_model::{
    BoundingBox, ConstantVelocity2, TransitionModel, check_positive_semidefinite, ensure_in_range,
    ensure_open_probability, ensure_positive,
};

use crate::error::{Result, invalid_parameter};

/// The eight MCMCDA moves, in the paper's order (Fig. 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Move {
    /// A new track from free measurements.
    Birth,
    /// A track's measurements become false alarms.
    Death,
    /// A track splits into two.
    Split,
    /// Two tracks join.
    Merge,
    /// A track grows past its last measurement.
    Extension,
    /// A track's tail becomes false alarms.
    Reduction,
    /// A track's tail is re-grown.
    Update,
    /// Two tracks exchange tails.
    Switch,
}

impl Move {
    /// All moves in the paper's order.
    pub const ALL: [Move; 8] = [
        Move::Birth,
        Move::Death,
        Move::Split,
        Move::Merge,
        Move::Extension,
        Move::Reduction,
        Move::Update,
        Move::Switch,
    ];

    /// Position in [`Move::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// Whether the move can be proposed when the partition has `k` tracks (birth is the only
    /// move with no track; merge and switch need two).
    pub fn allowed_with(self, k: usize) -> bool {
        match self {
            Move::Birth => true,
            Move::Merge | Move::Switch => k >= 2,
            _ => k >= 1,
        }
    }
}

/// ζ(d): the distribution of the gap d ∈ {1..d̄} drawn when a track grows. The paper says only
/// that it is "computed based on p_d".
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum GapDistribution {
    /// ζ(d) ∝ p_d (1 − p_d)^(d−1): the chance that the next detection comes d scans later
    /// (default).
    Geometric,
    /// ζ(d) = 1/d̄.
    Uniform,
}

/// How a track's Kalman filter starts (the paper defers this to a technical report).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum TrackInit {
    /// Position N(y₁, R), velocity N(0, σ_v² I) with σ_v² = `velocity_variance`, or v̄²/3 (the
    /// variance of each velocity component uniform on [−v̄, v̄]) when unset; likelihood terms from
    /// the second measurement on (default).
    FirstMeasurement {
        /// Per-axis variance of the initial velocity.
        velocity_variance: Option<f64>,
    },
    /// The authors' code: x₀ = [y₁; (y₂ − y₁)/(Δ T_s)] with covariance `initial_covariance`,
    /// the second measurement scored with its (zero) innovation, and each track paying the
    /// density 1/(π v̄²) of its initial velocity.
    TwoPoint {
        /// P₀ (the authors use the identity); rows in files (`tracker_model::matrix_rows`).
        #[serde(with = "tracker_model::matrix_rows")]
        initial_covariance: Matrix4<f64>,
    },
}

/// How the posterior scores the end of a track whose last measurement comes before the last
/// scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum TrackEnd {
    /// Oh, Russell & Sastry 2009 eq. 7 (and the authors' code): the target disappeared right
    /// after its last detection, a factor p_z (default).
    Disappeared,
    /// The exact probability of no further detection in the window: the target disappears
    /// at some later scan, undetected until then, or survives undetected to the window's end,
    /// Σ_{j<n} s^j p_z + s^n with s = (1 − p_z)(1 − p_d) over the n remaining scans. With a
    /// small p_z the paper's factor makes a target that is missed in the last scans look
    /// like clutter or part of another track; this one does not.
    Undetected,
}

/// Weights of the move distribution ξ_K; moves not allowed with K tracks get weight 0 and
/// the rest are renormalised. The paper's experiments use uniform weights (default).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct MoveWeights(pub [f64; 8]);

impl Default for MoveWeights {
    fn default() -> Self {
        Self([1.0; 8])
    }
}

/// Everything that defines the MCMCDA posterior and its proposal. Defaults are the batch
/// experiment of Oh, Russell & Sastry 2009 (region [0, 1000]², 10 scans, p_d = 0.9,
/// λ_f V = 1, p_z = 1e-4, d̄ = 5, v̄ = 100, Q = R = diag(100, 100)) with 10 targets.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct McmcdaConfig {
    /// Volume V of the surveillance region.
    pub volume: f64,
    /// Expected births per scan, λ_b V.
    pub births_per_scan: f64,
    /// Expected false alarms per scan, λ_f V.
    pub clutter_per_scan: f64,
    /// Probability p_z that a target disappears between scans.
    pub p_disappear: f64,
    /// Detection probability p_d.
    pub p_detect: f64,
    /// Target motion; its sampling period is the scan period T_s.
    pub motion: ConstantVelocity2,
    /// Position-measurement noise covariance R; rows in files, `[[r, 0.0], [0.0, r]]`
    /// (`tracker_model::matrix_rows`).
    #[serde(with = "tracker_model::matrix_rows")]
    pub measurement_noise: Matrix2<f64>,
    /// d̄: the most scans between two consecutive measurements of one track.
    pub max_gap: u32,
    /// v̄: the largest speed (length per unit time); two measurements d scans apart can belong
    /// to one track only if they are at most d·v̄·T_s apart.
    pub max_speed: f64,
    /// γ: the probability that growing a track stops before each further measurement (the
    /// paper leaves it open; the authors' code has 0.5).
    pub stop_probability: f64,
    /// ζ, the gap distribution.
    pub gap_distribution: GapDistribution,
    /// Probability that an extension, reduction or update acts on the track's head (its
    /// earliest measurements, growing backwards in time) instead of its tail. The paper's
    /// moves act on the tail only (0); then a track's first measurement can change only
    /// through death and rebirth, which the chain almost never does, so a wrong start
    /// persists. Default 0.5.
    pub head_probability: f64,
    /// ξ, the move weights.
    pub move_weights: MoveWeights,
    /// How track filters start.
    pub track_init: TrackInit,
    /// How a track's end is scored.
    pub track_end: TrackEnd,
}

impl Default for McmcdaConfig {
    fn default() -> Self {
        Self {
            volume: 1.0e6,
            births_per_scan: 1.0,
            clutter_per_scan: 1.0,
            p_disappear: 1e-4,
            p_detect: 0.9,
            motion: ConstantVelocity2::mcmcda(1.0, 100.0)
                .expect("a period of 1 and a variance of 100 are valid"),
            measurement_noise: Matrix2::identity() * 100.0,
            max_gap: 5,
            max_speed: 100.0,
            stop_probability: 0.5,
            gap_distribution: GapDistribution::Geometric,
            head_probability: 0.5,
            move_weights: MoveWeights::default(),
            track_init: TrackInit::FirstMeasurement {
                velocity_variance: None,
            },
            track_end: TrackEnd::Disappeared,
        }
    }
}

impl McmcdaConfig {
    /// A model for tracking the centres of detector boxes, scaled to the boxes themselves
    /// (what `cargo xtask track` uses without a configuration file). Lengths follow the median
    /// box width w: measurement σ = 0.1 w, speed ≤ w per frame, acceleration σ = 0.05 w per
    /// frame², newborn velocity σ = 0.3 w; the region is the bounding rectangle of the box
    /// centres (at least w on a side); a track ends when its target goes undetected
    /// ([`TrackEnd::Undetected`]), with p_d = 0.8, 0.1 births and 1 false alarm per frame.
    ///
    /// ```
    /// use mcmcda::McmcdaConfig;
    /// use tracker_model::BoundingBox;
    ///
    /// let boxes = [BoundingBox::new(10.0, 20.0, 40.0, 90.0)?, BoundingBox::new(300.0, 25.0, 44.0, 95.0)?];
    /// let config = McmcdaConfig::for_boxes(&boxes)?;
    /// assert_eq!(config.max_speed, 44.0);
    /// # Ok::<(), mcmcda::Error>(())
    /// ```
    pub fn for_boxes(boxes: &[BoundingBox]) -> Result<Self> {
        let mut widths: Vec<f64> = boxes.iter().map(|b| b.width).collect();
        widths.sort_by(f64::total_cmp);
        let Some(&median) = widths.get(widths.len() / 2) else {
            return Err(tracker_model::Error::Empty {
                what: "boxes for a box-scaled model",
            }
            .into());
        };
        let w = median.max(1.0);
        let (mut lo, mut hi) = (
            nalgebra::Vector2::repeat(f64::INFINITY),
            nalgebra::Vector2::repeat(f64::NEG_INFINITY),
        );
        for b in boxes {
            let c = b.centre();
            lo = lo.inf(&c);
            hi = hi.sup(&c);
        }
        let extent = hi - lo;
        let volume = (extent.x.max(w) * extent.y.max(w)).max(1.0);
        Ok(Self {
            volume,
            births_per_scan: 0.1,
            clutter_per_scan: 1.0,
            p_disappear: 0.01,
            p_detect: 0.8,
            motion: ConstantVelocity2::mcmcda(1.0, (0.05 * w).powi(2))?,
            measurement_noise: Matrix2::identity() * (0.1 * w).powi(2),
            max_speed: w,
            track_init: TrackInit::FirstMeasurement {
                velocity_variance: Some((0.3 * w).powi(2)),
            },
            track_end: TrackEnd::Undetected,
            ..Self::default()
        })
    }
}

/// A checked configuration with everything the sampler needs precomputed: log-constants of
/// the posterior, ζ, and the Kalman matrices for every gap 1..d̄.
#[derive(Debug, Clone)]
pub struct Model {
    pub(crate) config: McmcdaConfig,
    /// Constant part of a track's weight: log λ_b (+ the two-point velocity density).
    pub(crate) log_birth: f64,
    pub(crate) log_p_z: f64,
    pub(crate) log_survive: f64,
    /// log p_d − log λ_f: the gain of explaining one measurement by a track.
    pub(crate) log_detect_vs_clutter: f64,
    pub(crate) log_miss: f64,
    /// log λ_f, per measurement, for the all-false-alarm baseline.
    pub(crate) log_clutter_density: f64,
    /// ζ(d) for d = 1..d̄ at index d − 1, its logarithm and cumulative sums.
    pub(crate) zeta: Vec<f64>,
    pub(crate) log_zeta: Vec<f64>,
    /// The largest ln ζ(d).
    pub(crate) max_log_zeta: f64,
    /// Whether nothing couples the x and y axes (R, every Q(d) and the start covariance),
    /// so that the Kalman step runs per axis (`track_filter::Model::step_by_axis`).
    pub(crate) axes_decoupled: bool,
    pub(crate) zeta_cdf: Vec<f64>,
    pub(crate) log_go_on: f64,
    /// Per gap d (index d − 1): Q(d).
    pub(crate) process_noise: Vec<Matrix4<f64>>,
    /// Scan-period length radius per scan of gap: v̄·T_s.
    pub(crate) radius_per_scan: f64,
    pub(crate) initial_velocity_variance: f64,
    /// ξ_K(m) and its logarithm, by K = 0, 1, ≥ 2 (the moves allowed depend on K only
    /// through these three cases), in [`Move::ALL`] order: the chain reads them at every step.
    move_table: [[f64; 8]; 3],
    log_move_table: [[f64; 8]; 3],
}

impl McmcdaConfig {
    /// Checks every field. Probabilities must lie strictly inside (0, 1) and rates must be
    /// positive: these are the conditions of the paper's Theorem 4 (ergodicity), and they keep
    /// every logarithm finite.
    pub fn check(&self) -> Result<Model> {
        self.check_scalars()?;
        let dt = self.motion.dt_s();
        let radius_per_scan = self.max_speed * dt;
        let initial_velocity_variance = self.initial_velocity_variance()?;
        let (zeta, zeta_cdf) = self.zeta_table();
        let velocity_term = match self.track_init {
            TrackInit::TwoPoint { .. } => -(std::f64::consts::PI * self.max_speed.powi(2)).ln(),
            TrackInit::FirstMeasurement { .. } => 0.0,
        };
        let volume = self.volume;
        let process_noise: Vec<Matrix4<f64>> = (1..=self.max_gap)
            .map(|d| self.motion.process_noise(d))
            .collect();
        let axes_decoupled = self.axes_decoupled(&process_noise);
        let move_table: [[f64; 8]; 3] = std::array::from_fn(|k| {
            std::array::from_fn(|i| self.move_weights.probability(Move::ALL[i], k))
        });
        let log_move_table = move_table.map(|row| row.map(f64::ln));
        Ok(Model {
            move_table,
            log_move_table,
            log_birth: (self.births_per_scan / volume).ln() + velocity_term,
            log_p_z: self.p_disappear.ln(),
            log_survive: (-self.p_disappear).ln_1p(),
            log_detect_vs_clutter: self.p_detect.ln() - (self.clutter_per_scan / volume).ln(),
            log_miss: (-self.p_detect).ln_1p(),
            log_clutter_density: (self.clutter_per_scan / volume).ln(),
            log_zeta: zeta.iter().map(|z| z.ln()).collect(),
            max_log_zeta: zeta.iter().copied().fold(0.0, f64::max).ln(),
            zeta,
            zeta_cdf,
            log_go_on: (-self.stop_probability).ln_1p(),
            process_noise,
            axes_decoupled,
            radius_per_scan,
            initial_velocity_variance,
            config: self.clone(),
        })
    }

    /// Checks the scalar fields, the measurement noise and the move weights, in that order
    /// (the first failure is reported).
    fn check_scalars(&self) -> Result<()> {
        ensure_positive(self.volume, "volume")?;
        ensure_positive(self.births_per_scan, "births_per_scan")?;
        ensure_positive(self.clutter_per_scan, "clutter_per_scan")?;
        ensure_open_probability(self.p_disappear, "p_disappear")?;
        ensure_open_probability(self.p_detect, "p_detect")?;
        ensure_open_probability(self.stop_probability, "stop_probability")?;
        ensure_positive(self.max_speed, "max_speed")?;
        ensure_in_range(self.head_probability, 0.0, 1.0, "head_probability")?;
        if self.max_gap == 0 || self.max_gap > 64 {
            return Err(invalid_parameter(
                "max_gap",
                format!("{} must lie in 1..=64", self.max_gap),
            ));
        }
        tracker_model::cholesky_checked(&self.measurement_noise, "measurement_noise")?;
        let weights = &self.move_weights.0;
        if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) || weights[0] <= 0.0 {
            return Err(invalid_parameter(
                "move_weights",
                format!("{weights:?} must be finite and ≥ 0, with birth > 0"),
            ));
        }
        Ok(())
    }

    /// The variance of each velocity component of a track started from one measurement:
    /// the configured one (checked), or v̄²/3 when unset ([`TrackInit::FirstMeasurement`]);
    /// 0 for the two-point start (whose covariance is checked positive semi-definite).
    fn initial_velocity_variance(&self) -> Result<f64> {
        Ok(match self.track_init {
            TrackInit::FirstMeasurement {
                velocity_variance: Some(v),
            } => {
                ensure_positive(v, "velocity_variance")?;
                v
            }
            TrackInit::FirstMeasurement {
                velocity_variance: None,
            } => self.max_speed * self.max_speed / 3.0,
            TrackInit::TwoPoint { initial_covariance } => {
                check_positive_semidefinite(&initial_covariance, "initial_covariance")?;
                0.0
            }
        })
    }

    /// ζ(d), the distribution of the gap d = 1..=d̄ between consecutive detections of a track
    /// (geometric in p_d, truncated at d̄ and renormalised, or uniform; Oh, Russell & Sastry
    /// 2009), and its cumulative sums.
    fn zeta_table(&self) -> (Vec<f64>, Vec<f64>) {
        let d_bar = self.max_gap as usize;
        let raw: Vec<f64> = (0..d_bar)
            .map(|i| match self.gap_distribution {
                GapDistribution::Geometric => self.p_detect * (1.0 - self.p_detect).powi(i as i32),
                GapDistribution::Uniform => 1.0,
            })
            .collect();
        let total: f64 = raw.iter().sum();
        let zeta: Vec<f64> = raw.iter().map(|z| z / total).collect();
        let mut zeta_cdf = Vec::with_capacity(d_bar);
        let mut acc = 0.0;
        for z in &zeta {
            acc += z;
            zeta_cdf.push(acc);
        }
        (zeta, zeta_cdf)
    }

    /// Whether nothing couples the x and y axes — R, every Q(d) in `process_noise` and the
    /// two-point start covariance have zero x–y entries — so that the Kalman filter factors
    /// into one filter per axis.
    fn axes_decoupled(&self, process_noise: &[Matrix4<f64>]) -> bool {
        // x–y entries of a 4 × 4 covariance ordered [x, y, vx, vy].
        let uncoupled4 = |m: &Matrix4<f64>| {
            [(0, 1), (0, 3), (1, 2), (2, 3)]
                .iter()
                .all(|&(i, j)| m[(i, j)] == 0.0 && m[(j, i)] == 0.0)
        };
        let r = &self.measurement_noise;
        r[(0, 1)] == 0.0
            && r[(1, 0)] == 0.0
            && process_noise.iter().all(uncoupled4)
            && match self.track_init {
                TrackInit::FirstMeasurement { .. } => true,
                TrackInit::TwoPoint { initial_covariance } => uncoupled4(&initial_covariance),
            }
    }
}

impl Model {
    /// log P(no detection in the `n` ≥ 1 scans after a track's last measurement), under
    /// the configured [`TrackEnd`].
    pub(crate) fn log_track_end(&self, n: usize) -> f64 {
        match self.config.track_end {
            TrackEnd::Disappeared => self.log_p_z,
            TrackEnd::Undetected => {
                let p_z = self.config.p_disappear;
                let s = (1.0 - p_z) * (1.0 - self.config.p_detect);
                // powf: n can exceed i32 (a gap of billions of frames).
                let s_n = s.powf(n as f64);
                (p_z * (1.0 - s_n) / (1.0 - s) + s_n).ln()
            }
        }
    }

    /// The configuration this model was checked from.
    pub fn config(&self) -> &McmcdaConfig {
        &self.config
    }

    /// d̄.
    pub fn max_gap(&self) -> u32 {
        self.config.max_gap
    }

    /// ζ(d), d = 1..d̄.
    pub fn gap_probabilities(&self) -> &[f64] {
        &self.zeta
    }

    /// ξ_K(m): the probability of proposing `m` when the partition has `k` tracks.
    #[inline]
    pub fn move_probability(&self, m: Move, k: usize) -> f64 {
        self.move_table[k.min(2)][m.index()]
    }

    /// ln ξ_K(m) (−∞ for a move not allowed with `k` tracks), tabulated.
    #[inline]
    pub(crate) fn log_move_probability(&self, m: Move, k: usize) -> f64 {
        self.log_move_table[k.min(2)][m.index()]
    }
}

impl MoveWeights {
    /// ξ_K(m) with these weights: the weight of `m` over the summed weights of the moves
    /// allowed with `k` tracks (0 for a move not allowed).
    fn probability(&self, m: Move, k: usize) -> f64 {
        if !m.allowed_with(k) {
            return 0.0;
        }
        let w = &self.0;
        let total: f64 = Move::ALL
            .iter()
            .filter(|m| m.allowed_with(k))
            .map(|m| w[m.index()])
            .sum();
        w[m.index()] / total
    }
}
