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

    /// One Rauch-Tung-Striebel step of [`smooth`](crate::smooth): the smoothed state at step
    /// k from the filtered state at k, the prediction for k + 1 and the smoothed state at
    /// k + 1; `f` is [`TransitionModel::transition_matrix`]`(1)`. The default is the general
    /// Cholesky route [`rts_step`](crate::rts_step); models with structure override it, and
    /// the result must equal the default's within rounding.
    fn smooth_step(
        &self,
        f: &SMatrix<f64, N, N>,
        filtered: &Gaussian<N>,
        next_predicted: &Gaussian<N>,
        next_smoothed: &Gaussian<N>,
    ) -> Result<Gaussian<N>> {
        crate::kalman::rts_step(f, filtered, next_predicted, next_smoothed)
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
        let innovated = innovate(self, predicted, z)?;
        let h = self.observation_matrix();
        Ok(joseph_update(
            innovated,
            predicted,
            &self.measurement_noise(),
            |a| a * h.transpose(),
        ))
    }
}

/// H P⁻, H P⁻ Hᵀ and H x⁻: what an update needs of the prediction seen through H.
#[derive(Clone, Copy)]
struct Projected<const N: usize, const M: usize> {
    hp: SMatrix<f64, M, N>,
    hpht: SMatrix<f64, M, M>,
    hx: SVector<f64, M>,
}

/// The innovation with what the update reuses: the factor of S and H P.
pub(crate) struct Innovated<const N: usize, const M: usize> {
    pub(crate) innovation: Innovation<M>,
    pub(crate) chol: CholeskyFactor<M>,
    pub(crate) hp: SMatrix<f64, M, N>,
}

fn innovate<O, const N: usize, const M: usize>(
    model: &O,
    predicted: &Gaussian<N>,
    z: &SVector<f64, M>,
) -> Result<Innovated<N, M>>
where
    O: ObservationModel<N, M> + ?Sized,
{
    let h = model.observation_matrix();
    let hp = h * predicted.covariance();
    let projected = Projected {
        hpht: hp * h.transpose(),
        hp,
        hx: h * predicted.mean(),
    };
    innovate_projected(projected, &model.measurement_noise(), z)
}

fn innovate_projected<const N: usize, const M: usize>(
    projected: Projected<N, M>,
    r: &SMatrix<f64, M, M>,
    z: &SVector<f64, M>,
) -> Result<Innovated<N, M>> {
    check_finite_matrix(z, "measurement")?;
    let Projected { hp, hpht, hx } = projected;
    innovation_from_residual(hp, hpht, r, z - hx)
}

/// The innovation of a residual z − h(x⁻) already formed (wrapped, for angles) with H P⁻ and
/// H P⁻ Hᵀ: S = H P⁻ Hᵀ + R, its factor, the Mahalanobis distance and log N(residual; 0, S).
pub(crate) fn innovation_from_residual<const N: usize, const M: usize>(
    hp: SMatrix<f64, M, N>,
    hpht: SMatrix<f64, M, M>,
    r: &SMatrix<f64, M, M>,
    residual: SVector<f64, M>,
) -> Result<Innovated<N, M>> {
    let s = symmetrise(&(hpht + r));
    // S is symmetric by construction; the factorisation itself rejects non-finite values.
    let chol = CholeskyFactor::new(&s, "innovation covariance")?;
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
        hp,
    })
}

/// The Joseph-form update from an innovation; `times_ht(A)` is A Hᵀ.
pub(crate) fn joseph_update<const N: usize, const M: usize>(
    innovated: Innovated<N, M>,
    predicted: &Gaussian<N>,
    r: &SMatrix<f64, M, M>,
    times_ht: impl Fn(&SMatrix<f64, N, N>) -> SMatrix<f64, N, M>,
) -> Updated<N, M> {
    let Innovated {
        innovation,
        chol,
        hp,
    } = innovated;
    let p = predicted.covariance();
    // K = P Hᵀ S⁻¹, computed as (S⁻¹ H P)ᵀ because S and P are symmetric.
    let gain = chol.solve(&hp).transpose();
    // (I − KH) P (I − KH)ᵀ = A − (A Hᵀ) Kᵀ with A = (I − KH) P = P − K (H P): the same
    // Joseph form with fewer multiplications than forming I − KH.
    let a = p - gain * hp;
    let cov = a - times_ht(&a) * gain.transpose() + gain * r * gain.transpose();
    let mean = predicted.mean() + gain * innovation.residual;
    Updated {
        state: Gaussian::from_parts(mean, symmetrise(&cov)),
        innovation,
    }
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

    /// The RTS step of [`rts_step`](crate::rts_step) for covariances without x–y coupling
    /// (see [`axes_uncoupled`]), done on each axis's 2 × 2 (position, velocity) block. On such
    /// covariances every entry that couples the axes of the Cholesky factor, the gain and the
    /// products is an exact zero, so each remaining entry is the same sum of the same products
    /// as in the 4 × 4 route (at most two non-zero terms, whose order does not change a
    /// floating-point sum): the result is the general route's, at a fraction of the
    /// operations and with the two axes' square roots and divisions independent.
    fn smooth_step_by_axis(
        &self,
        filtered: &Gaussian<4>,
        next_predicted: &Gaussian<4>,
        next_smoothed: &Gaussian<4>,
    ) -> Result<Gaussian<4>> {
        let dt = self.dt_s;
        let (p, m, s) = (
            filtered.covariance(),
            next_predicted.covariance(),
            next_smoothed.covariance(),
        );
        let mut mean = *filtered.mean();
        let mut cov = SMatrix::<f64, 4, 4>::zeros();
        for idx in [[0, 2], [1, 3]] {
            // Cholesky factor of the predicted block (lower triangle), as CholeskyFactor::new.
            let d0 = m[(idx[0], idx[0])];
            if d0.is_nan() || d0 <= 0.0 {
                return Err(Error::NotPositiveDefinite {
                    what: "predicted covariance",
                });
            }
            let l00 = d0.sqrt();
            let inv0 = 1.0 / l00;
            let l10 = m[(idx[1], idx[0])] * inv0;
            let d1 = m[(idx[1], idx[1])] - l10 * l10;
            if d1.is_nan() || d1 <= 0.0 {
                return Err(Error::NotPositiveDefinite {
                    what: "predicted covariance",
                });
            }
            let inv1 = 1.0 / d1.sqrt();
            // B = F P on the block: [[P_pp + Δ P_vp, P_pv + Δ P_vv], [P_vp, P_vv]].
            let pb = |a: usize, b: usize| p[(idx[a], idx[b])];
            let b = [
                [pb(0, 0) + dt * pb(1, 0), pb(0, 1) + dt * pb(1, 1)],
                [pb(1, 0), pb(1, 1)],
            ];
            // X = M⁻¹ B: forward then back substitution, column by column; gain C = Xᵀ.
            let mut x = [[0.0; 2]; 2];
            for c in 0..2 {
                let y0 = b[0][c] * inv0;
                let y1 = (b[1][c] - l10 * y0) * inv1;
                let x1 = y1 * inv1;
                x[1][c] = x1;
                x[0][c] = (y0 - l10 * x1) * inv0;
            }
            let g = [[x[0][0], x[1][0]], [x[0][1], x[1][1]]];
            // Mean: x_k + C (x^s_{k+1} − x⁻_{k+1}).
            let dm = [
                next_smoothed.mean()[idx[0]] - next_predicted.mean()[idx[0]],
                next_smoothed.mean()[idx[1]] - next_predicted.mean()[idx[1]],
            ];
            for a in 0..2 {
                mean[idx[a]] += g[a][0] * dm[0] + g[a][1] * dm[1];
            }
            // Covariance: P_k + (C D) Cᵀ with D = P^s_{k+1} − P⁻_{k+1}, then symmetrised.
            let d = |a: usize, b: usize| s[(idx[a], idx[b])] - m[(idx[a], idx[b])];
            let mut gd = [[0.0; 2]; 2];
            for (a, row) in gd.iter_mut().enumerate() {
                for (b, v) in row.iter_mut().enumerate() {
                    *v = g[a][0] * d(0, b) + g[a][1] * d(1, b);
                }
            }
            let mut sum = [[0.0; 2]; 2];
            for (a, row) in sum.iter_mut().enumerate() {
                for (b, v) in row.iter_mut().enumerate() {
                    *v = pb(a, b) + (gd[a][0] * g[b][0] + gd[a][1] * g[b][1]);
                }
            }
            for a in 0..2 {
                for b in 0..2 {
                    cov[(idx[a], idx[b])] = (sum[a][b] + sum[b][a]) * 0.5;
                }
            }
        }
        Ok(Gaussian::from_parts(mean, cov))
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

    /// The general step when the covariances couple the axes; otherwise the same arithmetic
    /// on the two 2 × 2 (position, velocity) blocks, see `ConstantVelocity2::smooth_step_by_axis`.
    fn smooth_step(
        &self,
        f: &SMatrix<f64, 4, 4>,
        filtered: &Gaussian<4>,
        next_predicted: &Gaussian<4>,
        next_smoothed: &Gaussian<4>,
    ) -> Result<Gaussian<4>> {
        if axes_uncoupled(filtered.covariance())
            && axes_uncoupled(next_predicted.covariance())
            && axes_uncoupled(next_smoothed.covariance())
        {
            self.smooth_step_by_axis(filtered, next_predicted, next_smoothed)
        } else {
            crate::kalman::rts_step(f, filtered, next_predicted, next_smoothed)
        }
    }

    /// The default prediction with F x written out (x + Δ ẋ per axis: the same numbers as the
    /// product with F, whose other terms are exact zeros).
    fn predict_steps(&self, state: &Gaussian<4>, steps: u32) -> Gaussian<4> {
        let dt = self.dt_s * f64::from(steps);
        let m = state.mean();
        let mean = CvState::new(m[0] + dt * m[2], m[1] + dt * m[3], m[2], m[3]);
        let cov = symmetrise(&self.propagate_covariance(state.covariance(), steps));
        Gaussian::from_parts(mean, cov)
    }

    fn process_noise(&self, steps: u32) -> SMatrix<f64, 4, 4> {
        self.noise_over(self.dt_s * f64::from(steps))
    }
}

impl ConstantVelocity2 {
    /// Q(Δ) for an interval of `dt` seconds, in either noise form.
    pub fn noise_over(&self, dt: f64) -> SMatrix<f64, 4, 4> {
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

/// Whether a [x, y, ẋ, ẏ] covariance has no x–y coupling: the entries linking (x, ẋ) with
/// (y, ẏ) are exact zeros. A constant-velocity filter keeps it so when the prior, Q and R
/// have none (diagonal R with position measurements, for example).
pub fn axes_uncoupled(p: &SMatrix<f64, 4, 4>) -> bool {
    axes_uncoupled_in(p, 2)
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

impl<const N: usize, const M: usize> LinearObservation<N, M> {
    /// Whether H = [I 0] (the first M state components observed directly).
    fn observes_leading_components(&self) -> bool {
        M <= N && self.h == SMatrix::<f64, M, N>::identity()
    }

    /// H P⁻, H P⁻ Hᵀ and H x⁻ for H = [I 0] read off P⁻ and x⁻ instead of multiplied: the
    /// products only add exact zeros to these entries, so the results are the same.
    fn project_leading(predicted: &Gaussian<N>) -> Projected<N, M> {
        let p = predicted.covariance();
        Projected {
            hp: p.fixed_rows::<M>(0).into_owned(),
            hpht: p.fixed_view::<M, M>(0, 0).into_owned(),
            hx: predicted.mean().fixed_rows::<M>(0).into_owned(),
        }
    }
}

impl<const N: usize, const M: usize> LinearObservation<N, M> {
    /// The Joseph-form update for H = [I 0], N = 2M (state [position (M), velocity (M)]),
    /// diagonal R and a predicted covariance without coupling between the M axes (see
    /// [`axes_uncoupled_in`]). Then S is diagonal and every entry of the gain and the products
    /// that couples two axes is an exact zero, so each remaining entry is the same product or
    /// sum of the same two products as in the general route: the result is the general
    /// route's, computed axis by axis on 2 × 2 (position, velocity) blocks.
    fn update_by_axis(
        &self,
        predicted: &Gaussian<N>,
        z: &SVector<f64, M>,
    ) -> Result<Updated<N, M>> {
        check_finite_matrix(z, "measurement")?;
        let p = predicted.covariance();
        let x = predicted.mean();
        let s = symmetrise(&(p.fixed_view::<M, M>(0, 0).into_owned() + self.r));
        let chol = CholeskyFactor::new(&s, "innovation covariance")?;
        let residual = z - x.fixed_rows::<M>(0);
        let mahalanobis_sq = chol.mahalanobis_sq(&residual);
        let mut mean = *x;
        let mut cov = SMatrix::<f64, N, N>::zeros();
        for i in 0..M {
            let idx = [i, i + M];
            // K = (S⁻¹ H P)ᵀ on this axis: S is diagonal, so a forward and a back substitution
            // each multiply by 1 / √s_ii.
            let inv = chol.inv_diag(i);
            let gain = [(p[(i, i)] * inv) * inv, (p[(i, i + M)] * inv) * inv];
            let r = self.r[(i, i)];
            let mut block = [[0.0; 2]; 2];
            for (a, row) in block.iter_mut().enumerate() {
                for (b, v) in row.iter_mut().enumerate() {
                    // A = P − K (H P), then A − (A Hᵀ) Kᵀ + (K R) Kᵀ.
                    let a_rc = p[(idx[a], idx[b])] - gain[a] * p[(i, idx[b])];
                    let a_ri = p[(idx[a], i)] - gain[a] * p[(i, i)];
                    *v = (a_rc - a_ri * gain[b]) + (gain[a] * r) * gain[b];
                }
            }
            for a in 0..2 {
                for b in 0..2 {
                    cov[(idx[a], idx[b])] = (block[a][b] + block[b][a]) * 0.5;
                }
                mean[idx[a]] += gain[a] * residual[i];
            }
        }
        let innovation = Innovation {
            residual,
            covariance: s,
            mahalanobis_sq,
            log_likelihood: chol.log_normal_given(mahalanobis_sq),
        };
        Ok(Updated {
            state: Gaussian::from_parts(mean, cov),
            innovation,
        })
    }
}

/// Whether a covariance over [position (m), velocity (m)] has no coupling between axes: every
/// entry (r, c) with r ≠ c mod m is an exact zero.
fn axes_uncoupled_in<const N: usize>(p: &SMatrix<f64, N, N>, m: usize) -> bool {
    (0..N).all(|r| (0..N).all(|c| r % m == c % m || p[(r, c)] == 0.0))
}

/// Whether every off-diagonal entry is an exact zero.
fn is_diagonal<const M: usize>(r: &SMatrix<f64, M, M>) -> bool {
    (0..M).all(|i| (0..M).all(|j| i == j || r[(i, j)] == 0.0))
}

impl<const N: usize, const M: usize> ObservationModel<N, M> for LinearObservation<N, M> {
    fn observation_matrix(&self) -> SMatrix<f64, M, N> {
        self.h
    }

    fn measurement_noise(&self) -> SMatrix<f64, M, M> {
        self.r
    }

    fn innovation(&self, predicted: &Gaussian<N>, z: &SVector<f64, M>) -> Result<Innovation<M>> {
        if self.observes_leading_components() {
            innovate_projected(Self::project_leading(predicted), &self.r, z).map(|i| i.innovation)
        } else {
            innovate(self, predicted, z).map(|i| i.innovation)
        }
    }

    /// The default Joseph-form update; with H = [I 0] the products with H are replaced by
    /// reading rows and columns, which gives the same numbers with a third fewer operations,
    /// and when moreover the axes are uncoupled (see `LinearObservation::update_by_axis`) the
    /// update runs axis by axis.
    fn update(&self, predicted: &Gaussian<N>, z: &SVector<f64, M>) -> Result<Updated<N, M>> {
        if self.observes_leading_components() {
            if M > 0
                && N == 2 * M
                && axes_uncoupled_in(predicted.covariance(), M)
                && is_diagonal(&self.r)
            {
                return self.update_by_axis(predicted, z);
            }
            let innovated = innovate_projected(Self::project_leading(predicted), &self.r, z)?;
            Ok(joseph_update(innovated, predicted, &self.r, |a| {
                a.fixed_columns::<M>(0).into_owned()
            }))
        } else {
            let innovated = innovate(self, predicted, z)?;
            let h = self.h;
            Ok(joseph_update(innovated, predicted, &self.r, |a| {
                a * h.transpose()
            }))
        }
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
