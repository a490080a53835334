//! Linear-Gaussian motion and measurement models behind two small traits.
//!
//! A model only provides its matrices (F, Q for motion; H, R for measurement); prediction and
//! the Kalman update come free as default methods, in the shape of adskalman's
//! `TransitionModelLinearNoControl` / `ObservationModel`.

use nalgebra::{Matrix2, SMatrix, SVector};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, ensure_non_negative, ensure_positive};
use crate::gaussian::{
    CholeskyFactor, Gaussian, check_finite_matrix, check_positive_semidefinite, cholesky_checked,
    symmetrise,
};

/// State [x, y, ẋ, ẏ] of a 2-D constant-velocity target (the MCMCDA paper's ordering).
pub type CvState = SVector<f64, 4>;

/// x_{t+k} = F(k) x_t + w, w ~ N(0, Q(k)): a linear-Gaussian transition over `k` sampling
/// periods. `k = 0` must give F = I, Q = 0.
pub trait TransitionModel<const N: usize> {
    /// F(k), the state transition over `steps` sampling periods.
    fn transition_matrix(&self, steps: u32) -> SMatrix<f64, N, N>;

    /// Q(k), the process-noise covariance accumulated over `steps` sampling periods.
    fn process_noise(&self, steps: u32) -> SMatrix<f64, N, N>;

    /// Predicts one sampling period ahead.
    fn predict(&self, state: &Gaussian<N>) -> Gaussian<N> {
        self.predict_steps(state, 1)
    }

    /// F(k) P F(k)ᵀ + Q(k). Models with a sparse F override this with a closed form; the
    /// result must equal the default.
    fn propagate_covariance(&self, p: &SMatrix<f64, N, N>, steps: u32) -> SMatrix<f64, N, N> {
        let f = self.transition_matrix(steps);
        f * p * f.transpose() + self.process_noise(steps)
    }

    /// Predicts `steps` sampling periods ahead in one go (a gap of missed scans).
    fn predict_steps(&self, state: &Gaussian<N>, steps: u32) -> Gaussian<N> {
        let mean = self.transition_matrix(steps) * state.mean();
        let cov = symmetrise(&self.propagate_covariance(state.covariance(), steps));
        Gaussian::from_parts(mean, cov)
    }
}

/// The innovation of a measurement against a predicted state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Innovation<const M: usize> {
    /// z − H x⁻.
    pub residual: SVector<f64, M>,
    /// S = H P⁻ Hᵀ + R.
    pub covariance: SMatrix<f64, M, M>,
    /// residualᵀ S⁻¹ residual.
    pub mahalanobis_sq: f64,
    /// log N(z; H x⁻, S).
    pub log_likelihood: f64,
}

/// The result of a Kalman measurement update.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Updated<const N: usize, const M: usize> {
    /// The posterior state.
    pub state: Gaussian<N>,
    /// The innovation that produced it.
    pub innovation: Innovation<M>,
}

/// z = H x + v, v ~ N(0, R).
pub trait ObservationModel<const N: usize, const M: usize> {
    /// H.
    fn observation_matrix(&self) -> SMatrix<f64, M, N>;

    /// R (symmetric positive definite).
    fn measurement_noise(&self) -> SMatrix<f64, M, M>;

    /// The predicted measurement distribution N(H x⁻, S).
    fn predict_measurement(&self, predicted: &Gaussian<N>) -> Gaussian<M> {
        let h = self.observation_matrix();
        let s =
            symmetrise(&(h * predicted.covariance() * h.transpose() + self.measurement_noise()));
        Gaussian::from_parts(h * predicted.mean(), s)
    }

    /// Innovation, its covariance and its log-likelihood; an error if S is not positive
    /// definite or `z` is not finite.
    fn innovation(&self, predicted: &Gaussian<N>, z: &SVector<f64, M>) -> Result<Innovation<M>> {
        innovate(self, predicted, z).map(|i| i.innovation)
    }

    /// The Kalman update in Joseph form, P = (I − KH) P⁻ (I − KH)ᵀ + K R Kᵀ, which stays
    /// symmetric positive definite under rounding where the short form P = (I − KH) P⁻ does not.
    fn update(&self, predicted: &Gaussian<N>, z: &SVector<f64, M>) -> Result<Updated<N, M>> {
        let Innovated {
            innovation,
            chol,
            h,
            hp,
        } = innovate(self, predicted, z)?;
        let p = predicted.covariance();
        // K = P Hᵀ S⁻¹, computed as (S⁻¹ H P)ᵀ because S and P are symmetric.
        let gain = chol.solve(&hp).transpose();
        // (I − KH) P (I − KH)ᵀ = A − (A Hᵀ) Kᵀ with A = (I − KH) P = P − K (H P): the same
        // Joseph form with fewer multiplications than forming I − KH.
        let a = p - gain * hp;
        let cov = a - (a * h.transpose()) * gain.transpose()
            + gain * self.measurement_noise() * gain.transpose();
        let mean = predicted.mean() + gain * innovation.residual;
        Ok(Updated {
            state: Gaussian::from_parts(mean, symmetrise(&cov)),
            innovation,
        })
    }
}

/// The innovation with what the update reuses: the factor of S, H and H P.
struct Innovated<const N: usize, const M: usize> {
    innovation: Innovation<M>,
    chol: CholeskyFactor<M>,
    h: SMatrix<f64, M, N>,
    hp: SMatrix<f64, M, N>,
}

fn innovate<O, const N: usize, const M: usize>(
    model: &O,
    predicted: &Gaussian<N>,
    z: &SVector<f64, M>,
) -> Result<Innovated<N, M>>
where
    O: ObservationModel<N, M> + ?Sized,
{
    check_finite_matrix(z, "measurement")?;
    let h = model.observation_matrix();
    let hp = h * predicted.covariance();
    let s = symmetrise(&(hp * h.transpose() + model.measurement_noise()));
    // S is symmetric by construction; the factorisation itself rejects non-finite values.
    let chol = CholeskyFactor::new(&s, "innovation covariance")?;
    let residual = z - h * predicted.mean();
    let mahalanobis_sq = chol.mahalanobis_sq(&residual);
    let innovation = Innovation {
        residual,
        covariance: s,
        mahalanobis_sq,
        log_likelihood: chol.log_normal_given(mahalanobis_sq),
    };
    Ok(Innovated {
        innovation,
        chol,
        h,
        hp,
    })
}

/// How the constant-velocity model's process noise is built.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum CvNoise {
    /// Continuous white acceleration with power spectral density `q` (per axis):
    /// Q(Δ) = q [[Δ³/3, Δ²/2], [Δ²/2, Δ]] per axis. Exact for any Δ.
    WhiteAcceleration {
        /// Spectral density, (length/time²)²·time.
        q: f64,
    },
    /// The MCMCDA paper's discrete form Q(Δ) = G(Δ) Σ G(Δ)ᵀ with G = [[Δ²/2, 0], [0, Δ²/2],
    /// [Δ, 0], [0, Δ]] (TAC 2009 §V); over a gap the authors rebuild G with Δ = k·T_s.
    Discrete {
        /// Σ, the covariance of the 2-D acceleration noise w (rows in files, see
        /// [`crate::matrix_rows`]).
        #[serde(with = "crate::matrix_rows")]
        acceleration_covariance: Matrix2<f64>,
    },
}

/// Nearly constant velocity in 2-D, state [x, y, ẋ, ẏ].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawCv", into = "RawCv")]
pub struct ConstantVelocity2 {
    dt_s: f64,
    noise: CvNoise,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCv {
    dt_s: f64,
    noise: CvNoise,
}

impl TryFrom<RawCv> for ConstantVelocity2 {
    type Error = Error;
    fn try_from(raw: RawCv) -> Result<Self> {
        ConstantVelocity2::new(raw.dt_s, raw.noise)
    }
}

impl From<ConstantVelocity2> for RawCv {
    fn from(m: ConstantVelocity2) -> Self {
        RawCv {
            dt_s: m.dt_s,
            noise: m.noise,
        }
    }
}

impl ConstantVelocity2 {
    /// A model with sampling period `dt_s`; the noise parameters are checked.
    pub fn new(dt_s: f64, noise: CvNoise) -> Result<Self> {
        ensure_positive(dt_s, "dt_s")?;
        match noise {
            CvNoise::WhiteAcceleration { q } => {
                ensure_non_negative(q, "q")?;
            }
            CvNoise::Discrete {
                acceleration_covariance,
            } => check_positive_semidefinite(&acceleration_covariance, "acceleration covariance")?,
        }
        Ok(Self { dt_s, noise })
    }

    /// The MCMCDA paper's model: Q = G diag(σ², σ²) Gᵀ.
    pub fn mcmcda(dt_s: f64, accel_variance: f64) -> Result<Self> {
        Self::new(
            dt_s,
            CvNoise::Discrete {
                acceleration_covariance: Matrix2::identity() * accel_variance,
            },
        )
    }

    /// The sampling period.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// The noise form.
    pub fn noise(&self) -> CvNoise {
        self.noise
    }

    /// F(k) P F(k)ᵀ without the process noise. With P in 2×2 blocks [[A, B], [Bᵀ, C]] and
    /// F = [[I, Δ I], [0, I]]: [[A + Δ(B + Bᵀ) + Δ² C, B + Δ C], [Bᵀ + Δ C, C]]; a few dozen
    /// flops instead of two dense 4×4 products.
    pub fn transport_covariance(&self, p: &SMatrix<f64, 4, 4>, steps: u32) -> SMatrix<f64, 4, 4> {
        let dt = self.dt_s * f64::from(steps);
        let mut out = *p;
        for i in 0..2 {
            for j in 0..2 {
                let c = p[(i + 2, j + 2)];
                let b = p[(i, j + 2)];
                let bt = p[(i + 2, j)];
                out[(i, j)] = p[(i, j)] + dt * (b + bt) + dt * dt * c;
                out[(i, j + 2)] = b + dt * c;
                out[(i + 2, j)] = bt + dt * c;
            }
        }
        out
    }

    /// G(Δ) of the discrete form.
    pub fn noise_gain(dt: f64) -> SMatrix<f64, 4, 2> {
        let h = 0.5 * dt * dt;
        SMatrix::<f64, 4, 2>::new(h, 0.0, 0.0, h, dt, 0.0, 0.0, dt)
    }
}

impl TransitionModel<4> for ConstantVelocity2 {
    fn transition_matrix(&self, steps: u32) -> SMatrix<f64, 4, 4> {
        let dt = self.dt_s * f64::from(steps);
        let mut f = SMatrix::<f64, 4, 4>::identity();
        f[(0, 2)] = dt;
        f[(1, 3)] = dt;
        f
    }

    fn propagate_covariance(&self, p: &SMatrix<f64, 4, 4>, steps: u32) -> SMatrix<f64, 4, 4> {
        self.transport_covariance(p, steps) + self.process_noise(steps)
    }

    fn process_noise(&self, steps: u32) -> SMatrix<f64, 4, 4> {
        let dt = self.dt_s * f64::from(steps);
        match self.noise {
            CvNoise::WhiteAcceleration { q } => {
                let (a, b, c) = (q * dt.powi(3) / 3.0, q * dt.powi(2) / 2.0, q * dt);
                SMatrix::<f64, 4, 4>::new(
                    a, 0.0, b, 0.0, //
                    0.0, a, 0.0, b, //
                    b, 0.0, c, 0.0, //
                    0.0, b, 0.0, c,
                )
            }
            CvNoise::Discrete {
                acceleration_covariance,
            } => {
                let g = Self::noise_gain(dt);
                symmetrise(&(g * acceleration_covariance * g.transpose()))
            }
        }
    }
}

/// Random walk x_{t+1} = x_t + w, w ~ N(0, Q), in any dimension; Q(k) = k Q.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomWalk<const N: usize> {
    step_covariance: SMatrix<f64, N, N>,
}

impl<const N: usize> RandomWalk<N> {
    /// A random walk whose per-step covariance must be positive semi-definite.
    pub fn new(step_covariance: SMatrix<f64, N, N>) -> Result<Self> {
        check_positive_semidefinite(&step_covariance, "random-walk step covariance")?;
        Ok(Self { step_covariance })
    }
}

impl<const N: usize> TransitionModel<N> for RandomWalk<N> {
    fn transition_matrix(&self, _steps: u32) -> SMatrix<f64, N, N> {
        SMatrix::identity()
    }

    fn process_noise(&self, steps: u32) -> SMatrix<f64, N, N> {
        self.step_covariance * f64::from(steps)
    }
}

/// Any linear-Gaussian transition given by its one-step F and Q; over k steps
/// F(k) = Fᵏ and Q(k) = Σ_{i<k} Fⁱ Q Fⁱᵀ.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearTransition<const N: usize> {
    f: SMatrix<f64, N, N>,
    q: SMatrix<f64, N, N>,
}

impl<const N: usize> LinearTransition<N> {
    /// Checks F for finiteness and Q for positive semi-definiteness.
    pub fn new(f: SMatrix<f64, N, N>, q: SMatrix<f64, N, N>) -> Result<Self> {
        check_finite_matrix(&f, "transition matrix")?;
        check_positive_semidefinite(&q, "process noise")?;
        Ok(Self { f, q })
    }
}

impl<const N: usize> TransitionModel<N> for LinearTransition<N> {
    fn transition_matrix(&self, steps: u32) -> SMatrix<f64, N, N> {
        (0..steps).fold(SMatrix::identity(), |acc, _| self.f * acc)
    }

    fn process_noise(&self, steps: u32) -> SMatrix<f64, N, N> {
        (0..steps).fold(SMatrix::zeros(), |acc, _| {
            symmetrise(&(self.f * acc * self.f.transpose() + self.q))
        })
    }
}

/// A general linear measurement z = H x + v.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearObservation<const N: usize, const M: usize> {
    h: SMatrix<f64, M, N>,
    r: SMatrix<f64, M, M>,
}

impl<const N: usize, const M: usize> LinearObservation<N, M> {
    /// Checks H for finiteness and R for positive definiteness.
    pub fn new(h: SMatrix<f64, M, N>, r: SMatrix<f64, M, M>) -> Result<Self> {
        check_finite_matrix(&h, "observation matrix")?;
        cholesky_checked(&r, "measurement noise")?;
        Ok(Self { h, r })
    }

    /// Observes the first `M` state components directly (H = [I 0]): position-only
    /// measurements of a constant-velocity state.
    pub fn leading_components(r: SMatrix<f64, M, M>) -> Result<Self> {
        if M > N {
            return Err(Error::ShapeMismatch(format!(
                "cannot observe {M} leading components of a {N}-D state"
            )));
        }
        Self::new(SMatrix::<f64, M, N>::identity(), r)
    }
}

impl<const N: usize, const M: usize> ObservationModel<N, M> for LinearObservation<N, M> {
    fn observation_matrix(&self) -> SMatrix<f64, M, N> {
        self.h
    }

    fn measurement_noise(&self) -> SMatrix<f64, M, M> {
        self.r
    }
}

/// Position-only measurement of a 2-D constant-velocity state, H = [I₂ 0].
pub type PositionMeasurement2 = LinearObservation<4, 2>;

/// Full-state measurement, H = I.
pub type FullStateMeasurement<const N: usize> = LinearObservation<N, N>;

/// The MCMCDA paper's position measurement with noise `r_variance · I₂`.
pub fn position_measurement(r_variance: f64) -> Result<PositionMeasurement2> {
    LinearObservation::leading_components(Matrix2::identity() * r_variance)
}

/// Full-state measurement with noise covariance `r`.
pub fn full_state_measurement<const N: usize>(
    r: SMatrix<f64, N, N>,
) -> Result<FullStateMeasurement<N>> {
    LinearObservation::new(SMatrix::identity(), r)
}
