//! Motion models for aircraft and other manoeuvring targets, in seconds: nearly constant
//! velocity in 2-D and 3-D and the coordinated turn, with a known turn rate or the turn rate
//! in the state (Bar-Shalom, Li & Kirubarajan 2001, §11.7; Li & Jilkov 2003, "Survey of
//! maneuvering target tracking, Part I", §4.2). ω > 0 turns counter-clockwise (east to north).

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, ensure_in_range, ensure_non_negative};
use crate::models::{ConstantVelocity2, LinearObservation, ObservationModel};
use crate::nonlinear::{MeasurementModel, MotionModel};

/// The largest turn rate accepted, rad/s: 2 rad/s is beyond any aircraft or vehicle.
pub const MAX_TURN_RATE_RAD_S: f64 = 2.0;

/// |ωΔ| below which the turn terms are summed as series: the direct forms of the
/// derivatives lose about ε/(ωΔ)² to cancellation, the series (twelve terms) are exact to
/// rounding up to here.
const SERIES_TURN: f64 = 0.5;

/// Σ_{k<12} (−1)ᵏ a2ᵏ c(k), the alternating power series in a² = (ωΔ)² of the turn terms.
fn alternating_series(a2: f64, c: impl Fn(u32) -> f64) -> f64 {
    (0..12).rev().fold(0.0, |acc, k| c(k) - a2 * acc)
}

/// n! as a float, for the series' coefficients.
fn factorial(n: u32) -> f64 {
    (1..=n).map(f64::from).product()
}

/// sin(ωΔ)/ω and (1 − cos(ωΔ))/ω, and their derivatives in ω.
#[derive(Debug, Clone, Copy)]
struct TurnTerms {
    sin_over: f64,
    vers_over: f64,
    cos: f64,
    sin: f64,
    d_sin_over: f64,
    d_vers_over: f64,
}

impl TurnTerms {
    fn new(omega: f64, dt: f64) -> Self {
        let a = omega * dt;
        let (sin, cos) = a.sin_cos();
        // 1 − cos a = 2 sin²(a/2), without the cancellation.
        let versine = 2.0 * (0.5 * a).sin().powi(2);
        if a.abs() < SERIES_TURN {
            let a2 = a * a;
            // sin a / a = Σ (−1)ᵏ a²ᵏ/(2k+1)!, (1 − cos a)/a = a Σ (−1)ᵏ a²ᵏ/(2k+2)!,
            // (a cos a − sin a)/a² = −a Σ (−1)ᵏ a²ᵏ (2k+2)/(2k+3)!,
            // (a sin a − (1 − cos a))/a² = Σ (−1)ᵏ a²ᵏ (2k+1)/(2k+2)!.
            let sinc = alternating_series(a2, |k| 1.0 / factorial(2 * k + 1));
            let versc = alternating_series(a2, |k| 1.0 / factorial(2 * k + 2));
            let d_sinc = -alternating_series(a2, |k| f64::from(2 * k + 2) / factorial(2 * k + 3));
            let d_versc = alternating_series(a2, |k| f64::from(2 * k + 1) / factorial(2 * k + 2));
            Self {
                sin_over: dt * sinc,
                vers_over: dt * a * versc,
                cos,
                sin,
                d_sin_over: dt * dt * a * d_sinc,
                d_vers_over: dt * dt * d_versc,
            }
        } else {
            let w2 = omega * omega;
            Self {
                sin_over: sin / omega,
                vers_over: versine / omega,
                cos,
                sin,
                d_sin_over: (a * cos - sin) / w2,
                d_vers_over: (a * sin - versine) / w2,
            }
        }
    }

    /// The 4 × 4 transition of [x, y, ẋ, ẏ] at this turn rate.
    fn matrix(&self) -> SMatrix<f64, 4, 4> {
        let (s, v, c, sn) = (self.sin_over, self.vers_over, self.cos, self.sin);
        SMatrix::<f64, 4, 4>::new(
            1.0, 0.0, s, -v, //
            0.0, 1.0, v, s, //
            0.0, 0.0, c, -sn, //
            0.0, 0.0, sn, c,
        )
    }
}

/// Q(Δ) of continuous white acceleration with spectral density q per axis on `axes` axes,
/// state [positions (axes), velocities (axes)] in an N-D state: q [[Δ³/3, Δ²/2], [Δ²/2, Δ]].
fn white_acceleration<const N: usize>(q: f64, dt: f64, axes: usize) -> SMatrix<f64, N, N> {
    let (a, b, c) = (q * dt.powi(3) / 3.0, q * dt.powi(2) / 2.0, q * dt);
    let mut out = SMatrix::<f64, N, N>::zeros();
    for i in 0..axes {
        out[(i, i)] = a;
        out[(i, i + axes)] = b;
        out[(i + axes, i)] = b;
        out[(i + axes, i + axes)] = c;
    }
    out
}

fn check_turn_rate(omega: f64) -> Result<f64> {
    ensure_in_range(
        omega,
        -MAX_TURN_RATE_RAD_S,
        MAX_TURN_RATE_RAD_S,
        "turn_rate_rad_s",
    )
}

/// The constant-velocity model over any interval: Δ is the argument, not the model's own
/// sampling period, and Q(Δ) is [`ConstantVelocity2::noise_over`].
impl MotionModel<4> for ConstantVelocity2 {
    fn propagate(&self, x: &SVector<f64, 4>, dt_s: f64) -> SVector<f64, 4> {
        SVector::<f64, 4>::new(x[0] + dt_s * x[2], x[1] + dt_s * x[3], x[2], x[3])
    }

    fn jacobian(&self, _x: &SVector<f64, 4>, dt_s: f64) -> SMatrix<f64, 4, 4> {
        TurnTerms::new(0.0, dt_s).matrix()
    }

    fn noise_covariance(&self, _x: &SVector<f64, 4>, dt_s: f64) -> SMatrix<f64, 4, 4> {
        self.noise_over(dt_s)
    }
}

/// A coordinated turn at a known rate ω, state [x, y, ẋ, ẏ]: linear, the velocity rotating
/// by ωΔ. Q is the white-acceleration form, the usual approximation (Bar-Shalom et al. 2001,
/// eq. 11.7.1-4 with 6.2.2-12).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawTurn", into = "RawTurn")]
pub struct CoordinatedTurn {
    turn_rate_rad_s: f64,
    q: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTurn {
    turn_rate_rad_s: f64,
    q: f64,
}

impl TryFrom<RawTurn> for CoordinatedTurn {
    type Error = Error;
    fn try_from(raw: RawTurn) -> Result<Self> {
        CoordinatedTurn::new(raw.turn_rate_rad_s, raw.q)
    }
}

impl From<CoordinatedTurn> for RawTurn {
    fn from(m: CoordinatedTurn) -> Self {
        RawTurn {
            turn_rate_rad_s: m.turn_rate_rad_s,
            q: m.q,
        }
    }
}

impl CoordinatedTurn {
    /// Turn rate ω in rad/s (|ω| ≤ [`MAX_TURN_RATE_RAD_S`]) and the acceleration noise's
    /// spectral density q ≥ 0.
    pub fn new(turn_rate_rad_s: f64, q: f64) -> Result<Self> {
        check_turn_rate(turn_rate_rad_s)?;
        ensure_non_negative(q, "q")?;
        Ok(Self { turn_rate_rad_s, q })
    }

    /// F(Δ).
    pub fn transition_matrix(&self, dt_s: f64) -> SMatrix<f64, 4, 4> {
        TurnTerms::new(self.turn_rate_rad_s, dt_s).matrix()
    }
}

impl MotionModel<4> for CoordinatedTurn {
    fn propagate(&self, x: &SVector<f64, 4>, dt_s: f64) -> SVector<f64, 4> {
        self.transition_matrix(dt_s) * x
    }

    fn jacobian(&self, _x: &SVector<f64, 4>, dt_s: f64) -> SMatrix<f64, 4, 4> {
        self.transition_matrix(dt_s)
    }

    fn noise_covariance(&self, _x: &SVector<f64, 4>, dt_s: f64) -> SMatrix<f64, 4, 4> {
        white_acceleration(self.q, dt_s, 2)
    }
}

/// Noise of the five-component turn layout [x, y, ẋ, ẏ, ω].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TurnNoise {
    /// Spectral density of the white acceleration per axis, (m/s²)²·s.
    pub q_accel: f64,
    /// Spectral density of the turn rate's random walk, (rad/s)²/s.
    pub q_turn: f64,
}

impl TurnNoise {
    fn check(self) -> Result<Self> {
        ensure_non_negative(self.q_accel, "q_accel")?;
        ensure_non_negative(self.q_turn, "q_turn")?;
        Ok(self)
    }

    fn covariance(&self, dt: f64) -> SMatrix<f64, 5, 5> {
        let mut q = SMatrix::<f64, 5, 5>::zeros();
        q.fixed_view_mut::<4, 4>(0, 0)
            .copy_from(&white_acceleration::<4>(self.q_accel, dt, 2));
        q[(4, 4)] = self.q_turn * dt;
        q
    }
}

/// The coordinated turn with the turn rate in the state, [x, y, ẋ, ẏ, ω] (Li & Jilkov 2003,
/// eq. 4.2.3): nonlinear in ω; ω follows a random walk.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "TurnNoise", into = "TurnNoise")]
pub struct CoordinatedTurnRate {
    noise: TurnNoise,
}

impl TryFrom<TurnNoise> for CoordinatedTurnRate {
    type Error = Error;
    fn try_from(noise: TurnNoise) -> Result<Self> {
        Ok(Self {
            noise: noise.check()?,
        })
    }
}

impl From<CoordinatedTurnRate> for TurnNoise {
    fn from(m: CoordinatedTurnRate) -> Self {
        m.noise
    }
}

impl CoordinatedTurnRate {
    /// A model with these noise densities (each ≥ 0).
    pub fn new(noise: TurnNoise) -> Result<Self> {
        Self::try_from(noise)
    }
}

impl MotionModel<5> for CoordinatedTurnRate {
    fn propagate(&self, x: &SVector<f64, 5>, dt_s: f64) -> SVector<f64, 5> {
        let f = TurnTerms::new(x[4], dt_s).matrix();
        let moved = f * x.fixed_rows::<4>(0);
        SVector::<f64, 5>::new(moved[0], moved[1], moved[2], moved[3], x[4])
    }

    fn jacobian(&self, x: &SVector<f64, 5>, dt_s: f64) -> SMatrix<f64, 5, 5> {
        let t = TurnTerms::new(x[4], dt_s);
        let (vx, vy) = (x[2], x[3]);
        let mut j = SMatrix::<f64, 5, 5>::identity();
        j.fixed_view_mut::<4, 4>(0, 0).copy_from(&t.matrix());
        j[(0, 4)] = t.d_sin_over * vx - t.d_vers_over * vy;
        j[(1, 4)] = t.d_vers_over * vx + t.d_sin_over * vy;
        j[(2, 4)] = -dt_s * (t.sin * vx + t.cos * vy);
        j[(3, 4)] = dt_s * (t.cos * vx - t.sin * vy);
        j
    }

    fn noise_covariance(&self, _x: &SVector<f64, 5>, dt_s: f64) -> SMatrix<f64, 5, 5> {
        self.noise.covariance(dt_s)
    }
}

/// Nearly constant velocity in the turn layout [x, y, ẋ, ẏ, ω]: the straight-flight mode of a
/// CV / coordinated-turn IMM whose modes must share one state. The target moves straight and
/// the turn rate is reset to zero, with variance q_turn Δ, so that a turn mode mixed from this
/// one starts from flying straight.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "TurnNoise", into = "TurnNoise")]
pub struct ConstantVelocityTurnLayout {
    noise: TurnNoise,
}

impl TryFrom<TurnNoise> for ConstantVelocityTurnLayout {
    type Error = Error;
    fn try_from(noise: TurnNoise) -> Result<Self> {
        Ok(Self {
            noise: noise.check()?,
        })
    }
}

impl From<ConstantVelocityTurnLayout> for TurnNoise {
    fn from(m: ConstantVelocityTurnLayout) -> Self {
        m.noise
    }
}

impl ConstantVelocityTurnLayout {
    /// A model with these noise densities (each ≥ 0).
    pub fn new(noise: TurnNoise) -> Result<Self> {
        Self::try_from(noise)
    }
}

impl MotionModel<5> for ConstantVelocityTurnLayout {
    fn propagate(&self, x: &SVector<f64, 5>, dt_s: f64) -> SVector<f64, 5> {
        SVector::<f64, 5>::new(x[0] + dt_s * x[2], x[1] + dt_s * x[3], x[2], x[3], 0.0)
    }

    fn jacobian(&self, _x: &SVector<f64, 5>, dt_s: f64) -> SMatrix<f64, 5, 5> {
        let mut j = SMatrix::<f64, 5, 5>::identity();
        j[(0, 2)] = dt_s;
        j[(1, 3)] = dt_s;
        j[(4, 4)] = 0.0;
        j
    }

    fn noise_covariance(&self, _x: &SVector<f64, 5>, dt_s: f64) -> SMatrix<f64, 5, 5> {
        self.noise.covariance(dt_s)
    }
}

/// Nearly constant velocity in 3-D, state [x, y, z, ẋ, ẏ, ż], white acceleration with spectral
/// density q per axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawCv3", into = "RawCv3")]
pub struct ConstantVelocity3 {
    q: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCv3 {
    q: f64,
}

impl TryFrom<RawCv3> for ConstantVelocity3 {
    type Error = Error;
    fn try_from(raw: RawCv3) -> Result<Self> {
        ConstantVelocity3::new(raw.q)
    }
}

impl From<ConstantVelocity3> for RawCv3 {
    fn from(m: ConstantVelocity3) -> Self {
        RawCv3 { q: m.q }
    }
}

impl ConstantVelocity3 {
    /// A model with spectral density q ≥ 0.
    pub fn new(q: f64) -> Result<Self> {
        ensure_non_negative(q, "q")?;
        Ok(Self { q })
    }
}

impl MotionModel<6> for ConstantVelocity3 {
    fn propagate(&self, x: &SVector<f64, 6>, dt_s: f64) -> SVector<f64, 6> {
        let mut out = *x;
        for i in 0..3 {
            out[i] += dt_s * x[i + 3];
        }
        out
    }

    fn jacobian(&self, _x: &SVector<f64, 6>, dt_s: f64) -> SMatrix<f64, 6, 6> {
        let mut j = SMatrix::<f64, 6, 6>::identity();
        for i in 0..3 {
            j[(i, i + 3)] = dt_s;
        }
        j
    }

    fn noise_covariance(&self, _x: &SVector<f64, 6>, dt_s: f64) -> SMatrix<f64, 6, 6> {
        white_acceleration(self.q, dt_s, 3)
    }
}

/// A linear measurement is its own linearisation: the EKF on it is the Kalman filter.
impl<const N: usize, const M: usize> MeasurementModel<N, M> for LinearObservation<N, M> {
    fn measure(&self, x: &SVector<f64, N>) -> SVector<f64, M> {
        self.observation_matrix() * x
    }

    fn jacobian(&self, _x: &SVector<f64, N>) -> SMatrix<f64, M, N> {
        self.observation_matrix()
    }

    fn noise(&self) -> SMatrix<f64, M, M> {
        self.measurement_noise()
    }
}
