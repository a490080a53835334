//! Tests of tracker-model against closed forms, an independent batch solution, statistics of
//! seeded runs and hand-worked edge cases.

use approx::assert_relative_eq;
use nalgebra::{DMatrix, DVector, Matrix1, Matrix2, Matrix4, SMatrix, Vector1, Vector2, Vector4};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::*;

mod nonlinear;

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn white_cv(q: f64) -> ConstantVelocity2 {
    ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q }).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Kalman filter

/// Scalar random walk x' = x + w (var q), z = x + v (var r). The steady-state prediction variance
/// solves P⁻ = P⁻ r / (P⁻ + r) + q, i.e. P⁻ = (q + √(q² + 4qr)) / 2, with gain K = P⁻/(P⁻ + r)
/// and filtered variance K r.
#[test]
fn scalar_random_walk_reaches_closed_form_steady_state() {
    let check = |q: f64, r: f64| {
        let walk = RandomWalk::new(Matrix1::new(q)).unwrap();
        let sensor = full_state_measurement(Matrix1::new(r)).unwrap();
        let prior = Gaussian::new(Vector1::new(0.0), Matrix1::new(1e4)).unwrap();
        let zs: Vec<Option<Vector1<f64>>> = (0..400)
            .map(|k| Some(Vector1::new(k as f64 * 0.1)))
            .collect();
        let run = filter(&walk, &sensor, &prior, &zs).unwrap();
        let last = run.steps.last().unwrap();
        let p_pred = (q + (q * q + 4.0 * q * r).sqrt()) / 2.0;
        let gain = p_pred / (p_pred + r);
        assert_relative_eq!(
            last.predicted.covariance()[(0, 0)],
            p_pred,
            max_relative = 1e-12
        );
        assert_relative_eq!(
            last.filtered.covariance()[(0, 0)],
            gain * r,
            max_relative = 1e-12
        );
    };
    check(1.0, 1.0);
    check(0.01, 4.0);
    check(25.0, 0.5);
}

/// A measurement update of N(0, 1) with z = 2, r = 1 gives mean 1, variance 1/2, and
/// log-likelihood log N(2; 0, 2) — worked by hand.
#[test]
fn scalar_update_by_hand() {
    let sensor = full_state_measurement(Matrix1::new(1.0)).unwrap();
    let prior = Gaussian::new(Vector1::new(0.0), Matrix1::new(1.0)).unwrap();
    let up = sensor.update(&prior, &Vector1::new(2.0)).unwrap();
    assert_relative_eq!(up.state.mean()[0], 1.0, epsilon = 1e-15);
    assert_relative_eq!(up.state.covariance()[(0, 0)], 0.5, epsilon = 1e-15);
    let expected = -0.5 * (4.0 / 2.0) - 0.5 * (2.0 * std::f64::consts::PI * 2.0).ln();
    assert_relative_eq!(up.innovation.log_likelihood, expected, epsilon = 1e-14);
    assert_relative_eq!(up.innovation.mahalanobis_sq, 2.0, epsilon = 1e-14);
}

/// Solves the whole 20-step smoothing problem at once: the MAP of the joint Gaussian
/// p(x_0..x_19 | z) via its information matrix, and the marginal covariances from its inverse.
fn batch_smoother(
    motion: &ConstantVelocity2,
    sensor: &PositionMeasurement2,
    prior: &Gaussian<4>,
    zs: &[Option<Vector2<f64>>],
) -> (Vec<Vector4<f64>>, Vec<Matrix4<f64>>) {
    let n = zs.len();
    let dim = 4 * n;
    let mut lambda = DMatrix::<f64>::zeros(dim, dim);
    let mut eta = DVector::<f64>::zeros(dim);
    let add_block = |lambda: &mut DMatrix<f64>, i: usize, j: usize, m: &Matrix4<f64>| {
        let mut view = lambda.view_mut((4 * i, 4 * j), (4, 4));
        view += m;
    };
    let p0_inv = prior.covariance().try_inverse().unwrap();
    add_block(&mut lambda, 0, 0, &p0_inv);
    eta.rows_mut(0, 4).add_assign(&(p0_inv * prior.mean()));
    let f = motion.transition_matrix(1);
    let q_inv = motion.process_noise(1).try_inverse().unwrap();
    for k in 0..n - 1 {
        // (x_{k+1} − F x_k)ᵀ Q⁻¹ (x_{k+1} − F x_k)
        add_block(&mut lambda, k, k, &(f.transpose() * q_inv * f));
        add_block(&mut lambda, k + 1, k + 1, &q_inv);
        add_block(&mut lambda, k, k + 1, &(-f.transpose() * q_inv));
        add_block(&mut lambda, k + 1, k, &(-q_inv * f));
    }
    let h = sensor.observation_matrix();
    let r_inv = sensor.measurement_noise().try_inverse().unwrap();
    for (k, z) in zs.iter().enumerate() {
        if let Some(z) = z {
            add_block(&mut lambda, k, k, &(h.transpose() * r_inv * h));
            eta.rows_mut(4 * k, 4)
                .add_assign(&(h.transpose() * r_inv * z));
        }
    }
    let chol = lambda.cholesky().unwrap();
    let x = chol.solve(&eta);
    let cov = chol.inverse();
    let means = (0..n)
        .map(|k| Vector4::from_iterator(x.rows(4 * k, 4).iter().copied()))
        .collect();
    let covs = (0..n)
        .map(|k| Matrix4::from_iterator(cov.view((4 * k, 4 * k), (4, 4)).iter().copied()))
        .collect();
    (means, covs)
}

use std::ops::AddAssign;

#[test]
fn rts_smoother_matches_batch_information_form_solution() {
    let motion = white_cv(0.5);
    let sensor = position_measurement(2.0).unwrap();
    let prior =
        Gaussian::new(Vector4::new(0.0, 0.0, 1.0, 0.5), Matrix4::identity() * 10.0).unwrap();
    let mut g = rng(11);
    let mut zs: Vec<Option<Vector2<f64>>> = (0..20)
        .map(|k| {
            let t = k as f64;
            let noise: f64 = StandardNormal.sample(&mut g);
            Some(Vector2::new(
                t + noise,
                0.5 * t - noise * 0.3 + 0.02 * t * t,
            ))
        })
        .collect();
    zs[7] = None; // the missing step
    let run = filter(&motion, &sensor, &prior, &zs).unwrap();
    let smoothed = smooth(&motion, &run).unwrap();
    let (means, covs) = batch_smoother(&motion, &sensor, &prior, &zs);
    for k in 0..20 {
        for i in 0..4 {
            assert!(
                (smoothed[k].mean()[i] - means[k][i]).abs() < 1e-9,
                "step {k} mean {i}"
            );
            for j in 0..4 {
                let d = (smoothed[k].covariance()[(i, j)] - covs[k][(i, j)]).abs();
                assert!(d < 1e-9, "step {k} cov ({i},{j}) differs by {d}");
            }
        }
    }
    // The last smoothed state is the last filtered one.
    assert_eq!(smoothed[19], run.steps[19].filtered);
}

/// A model seen only through F and Q: every other method is the trait's general default
/// (4 × 4 products, Cholesky RTS step).
struct GeneralTransition(ConstantVelocity2);

impl TransitionModel<4> for GeneralTransition {
    fn transition_matrix(&self, steps: u32) -> Matrix4<f64> {
        self.0.transition_matrix(steps)
    }
    fn process_noise(&self, steps: u32) -> Matrix4<f64> {
        self.0.process_noise(steps)
    }
}

/// A sensor seen only through H and R: the trait's general Joseph-form update.
struct GeneralObservation(PositionMeasurement2);

impl ObservationModel<4, 2> for GeneralObservation {
    fn observation_matrix(&self) -> SMatrix<f64, 2, 4> {
        self.0.observation_matrix()
    }
    fn measurement_noise(&self) -> Matrix2<f64> {
        self.0.measurement_noise()
    }
}

/// A random symmetric positive-definite matrix B Bᵀ + εI.
fn random_spd<const N: usize>(g: &mut ChaCha8Rng, scale: f64) -> SMatrix<f64, N, N> {
    let b = SMatrix::<f64, N, N>::from_fn(|_, _| StandardNormal.sample(g));
    (b * b.transpose() + SMatrix::identity() * 0.1) * scale
}

/// The constant-velocity fast paths (closed-form prediction, the update with H = [I 0] read
/// off P and, for uncoupled axes, done axis by axis; the RTS step on 2 × 2 blocks) against
/// the general route on random models: random Δ, both noise forms, diagonal and full R,
/// uncoupled and full priors, missing scans. The general route is the trait defaults, an
/// independent computation of the same formulas with full 4 × 4 products and Cholesky solves.
#[test]
fn constant_velocity_fast_paths_match_the_general_route() {
    let mut g = rng(21);
    let mut by_axis = 0;
    for case in 0..60 {
        let uniform = |g: &mut ChaCha8Rng, lo: f64, hi: f64| {
            let u: f64 = rand::RngExt::random(g);
            lo + (hi - lo) * u
        };
        let dt = uniform(&mut g, 0.05, 3.0);
        let noise = if case % 3 == 0 {
            CvNoise::WhiteAcceleration {
                q: uniform(&mut g, 0.01, 5.0),
            }
        } else if case % 3 == 1 {
            CvNoise::Discrete {
                acceleration_covariance: Matrix2::new(
                    uniform(&mut g, 0.01, 5.0),
                    0.0,
                    0.0,
                    uniform(&mut g, 0.01, 5.0),
                ),
            }
        } else {
            CvNoise::Discrete {
                acceleration_covariance: random_spd::<2>(&mut g, 1.0),
            }
        };
        let motion = ConstantVelocity2::new(dt, noise).unwrap();
        let uncoupled = case % 2 == 0 && case % 3 != 2;
        let r = if uncoupled || case % 5 == 1 {
            Matrix2::new(
                uniform(&mut g, 0.1, 9.0),
                0.0,
                0.0,
                uniform(&mut g, 0.1, 9.0),
            )
        } else {
            random_spd::<2>(&mut g, 2.0)
        };
        let sensor = LinearObservation::leading_components(r).unwrap();
        let prior_cov = if uncoupled {
            let (x, y) = (random_spd::<2>(&mut g, 5.0), random_spd::<2>(&mut g, 5.0));
            let mut p = Matrix4::zeros();
            for (block, axis) in [(x, 0), (y, 1)] {
                for a in 0..2 {
                    for b in 0..2 {
                        p[(axis + 2 * a, axis + 2 * b)] = block[(a, b)];
                    }
                }
            }
            p
        } else {
            random_spd::<4>(&mut g, 5.0)
        };
        let prior_mean = Vector4::from_fn(|_, _| StandardNormal.sample(&mut g));
        let prior = Gaussian::new(prior_mean, prior_cov).unwrap();
        let zs: Vec<Option<Vector2<f64>>> = (0..150)
            .map(|k| {
                let t = k as f64 * dt;
                let n: [f64; 2] = [StandardNormal.sample(&mut g), StandardNormal.sample(&mut g)];
                (uniform(&mut g, 0.0, 1.0) > 0.15).then(|| Vector2::new(t + n[0], 2.0 * t + n[1]))
            })
            .collect();
        let fast = filter(&motion, &sensor, &prior, &zs).unwrap();
        let general = filter(
            &GeneralTransition(motion),
            &GeneralObservation(sensor),
            &prior,
            &zs,
        )
        .unwrap();
        let close = |a: f64, b: f64, what: &str| {
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0),
                "case {case}: {what}: {a} vs {b}"
            );
        };
        let close_gaussian = |a: &Gaussian<4>, b: &Gaussian<4>, what: &str| {
            for i in 0..4 {
                close(a.mean()[i], b.mean()[i], what);
                for j in 0..4 {
                    close(a.covariance()[(i, j)], b.covariance()[(i, j)], what);
                }
            }
        };
        for (f, gs) in fast.steps.iter().zip(&general.steps) {
            close_gaussian(&f.predicted, &gs.predicted, "predicted");
            close_gaussian(&f.filtered, &gs.filtered, "filtered");
            assert_eq!(f.log_likelihood.is_some(), gs.log_likelihood.is_some());
            if let (Some(a), Some(b)) = (f.log_likelihood, gs.log_likelihood) {
                close(a, b, "log-likelihood");
            }
            if let (Some(a), Some(b)) = (f.innovation_mahalanobis_sq, gs.innovation_mahalanobis_sq)
            {
                close(a, b, "innovation Mahalanobis distance");
            }
        }
        let (smoothed_fast, smoothed_general) = (
            smooth(&motion, &fast).unwrap(),
            smooth(&GeneralTransition(motion), &general).unwrap(),
        );
        for (a, b) in smoothed_fast.iter().zip(&smoothed_general) {
            close_gaussian(a, b, "smoothed");
        }
        if fast
            .steps
            .iter()
            .all(|s| axes_uncoupled(s.filtered.covariance()))
        {
            by_axis += 1;
        }
        assert_eq!(
            uncoupled,
            axes_uncoupled(fast.steps[149].filtered.covariance()),
            "case {case}"
        );
    }
    // Both branches were exercised.
    assert!((10..50).contains(&by_axis), "{by_axis} uncoupled cases");
}

/// Published χ² table values (e.g. NIST/SEMATECH e-Handbook, table 1.3.6.7.4): the
/// approximation must be within 0.1 %.
#[test]
fn chi_square_quantiles_match_tables() {
    let z = 1.959_963_984_540_054;
    for (dof, lower, upper) in [(100.0, 74.222, 129.561), (50.0, 32.357, 71.420)] {
        assert_relative_eq!(chi_square_quantile_wh(dof, -z), lower, max_relative = 1e-3);
        assert_relative_eq!(chi_square_quantile_wh(dof, z), upper, max_relative = 1e-3);
    }
}

#[test]
fn filter_is_consistent_average_nees_in_chi2_interval() {
    let motion = white_cv(0.2);
    let sensor = position_measurement(4.0).unwrap();
    let runs = 500;
    let steps = 30;
    let l_q = motion.process_noise(1).cholesky().unwrap().l();
    let f = motion.transition_matrix(1);
    let mut g = rng(2024);
    let p0 = Matrix4::from_diagonal(&Vector4::new(25.0, 25.0, 4.0, 4.0));
    let l_p0 = p0.cholesky().unwrap().l();
    let checked_steps = [0usize, 5, 29];
    let mut nees_sum = [0.0; 3];
    for _ in 0..runs {
        let normal4 = |g: &mut ChaCha8Rng| Vector4::from_fn(|_, _| StandardNormal.sample(g));
        let normal2 = |g: &mut ChaCha8Rng| Vector2::from_fn(|_, _| StandardNormal.sample(g));
        let prior_mean = Vector4::new(10.0, -5.0, 1.0, 2.0);
        let mut x = prior_mean + l_p0 * normal4(&mut g);
        let mut truth = Vec::with_capacity(steps);
        let mut zs = Vec::with_capacity(steps);
        for k in 0..steps {
            if k > 0 {
                x = f * x + l_q * normal4(&mut g);
            }
            truth.push(x);
            zs.push(Some(x.fixed_rows::<2>(0) + 2.0 * normal2(&mut g)));
        }
        let prior = Gaussian::new(prior_mean, p0).unwrap();
        let run = filter(&motion, &sensor, &prior, &zs).unwrap();
        for (slot, &k) in checked_steps.iter().enumerate() {
            nees_sum[slot] += run.steps[k].filtered.mahalanobis_sq(&truth[k]).unwrap();
        }
    }
    let (lo, hi) = anees_interval_95(4, runs);
    for (slot, &k) in checked_steps.iter().enumerate() {
        let anees = nees_sum[slot] / runs as f64;
        assert!(
            lo <= anees && anees <= hi,
            "step {k}: ANEES {anees} outside [{lo}, {hi}]"
        );
    }
}

#[test]
fn predicting_k_steps_at_once_equals_k_single_steps_for_white_acceleration() {
    let motion = white_cv(0.7);
    let start =
        Gaussian::new(Vector4::new(1.0, 2.0, 3.0, -1.0), Matrix4::identity() * 2.0).unwrap();
    let once = motion.predict_steps(&start, 5);
    let stepwise = (0..5).fold(start.clone(), |g, _| motion.predict(&g));
    assert!((once.mean() - stepwise.mean()).amax() < 1e-12);
    assert!((once.covariance() - stepwise.covariance()).amax() < 1e-10);
    // A general linear transition built from the same F, Q composes identically.
    let general =
        LinearTransition::new(motion.transition_matrix(1), motion.process_noise(1)).unwrap();
    assert!((general.process_noise(5) - motion.process_noise(5)).amax() < 1e-10);
    assert_eq!(motion.predict_steps(&start, 0), start);
}

/// The constant-velocity closed form of F P Fᵀ + Q agrees with the dense default.
#[test]
fn cv_covariance_propagation_matches_dense_product() {
    let motion = ConstantVelocity2::mcmcda(0.7, 2.0).unwrap();
    let a = SMatrix::<f64, 4, 4>::from_fn(|i, j| ((i * 7 + j * 3) % 5) as f64 - 1.5);
    let p = a * a.transpose() + Matrix4::identity();
    for steps in [0, 1, 3] {
        let f = motion.transition_matrix(steps);
        let dense = f * p * f.transpose() + motion.process_noise(steps);
        assert!((motion.propagate_covariance(&p, steps) - dense).amax() < 1e-12);
    }
}

#[test]
fn mcmcda_noise_is_g_sigma_g_transpose() {
    let motion = ConstantVelocity2::mcmcda(2.0, 3.0).unwrap();
    let q = motion.process_noise(1);
    // G = [[2,0],[0,2],[2,0],[0,2]] for Δ = 2, so Q = 3·[[4,0,4,0],[0,4,0,4],[4,0,4,0],[0,4,0,4]].
    let expected = SMatrix::<f64, 4, 4>::new(
        12.0, 0.0, 12.0, 0.0, 0.0, 12.0, 0.0, 12.0, 12.0, 0.0, 12.0, 0.0, 0.0, 12.0, 0.0, 12.0,
    );
    assert!((q - expected).amax() < 1e-12);
}

#[test]
fn invalid_covariances_and_values_are_errors() {
    let bad = Matrix2::new(1.0, 2.0, 2.0, 1.0); // eigenvalues 3 and −1
    assert_eq!(
        Gaussian::new(Vector2::zeros(), bad),
        Err(Error::NotPositiveDefinite {
            what: "state covariance"
        })
    );
    assert!(matches!(
        Gaussian::new(Vector2::zeros(), Matrix2::new(1.0, 0.5, 0.0, 1.0)),
        Err(Error::NotSymmetric { .. })
    ));
    assert!(matches!(
        Gaussian::new(Vector2::new(f64::NAN, 0.0), Matrix2::identity()),
        Err(Error::NonFinite { .. })
    ));
    assert!(position_measurement(0.0).is_err());
    assert!(position_measurement(-1.0).is_err());
    assert!(RandomWalk::new(bad).is_err());
    assert!(ConstantVelocity2::new(0.0, CvNoise::WhiteAcceleration { q: 1.0 }).is_err());
    assert!(ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q: f64::NAN }).is_err());
    let sensor = position_measurement(1.0).unwrap();
    let g = Gaussian::new(Vector4::zeros(), Matrix4::identity()).unwrap();
    assert!(matches!(
        sensor.update(&g, &Vector2::new(f64::INFINITY, 0.0)),
        Err(Error::NonFinite { .. })
    ));
    assert_eq!(
        smooth(&white_cv(1.0), &FilterRun::<4> { steps: vec![] }),
        Err(Error::Empty { what: "filter run" })
    );
}

proptest::proptest! {
    /// Covariances stay symmetric positive definite through any sequence of predictions and
    /// updates, even with tiny or huge noise.
    #[test]
    fn covariances_stay_symmetric_positive_definite(
        q in 1e-6f64..1e3, r in 1e-6f64..1e3,
        zs in proptest::collection::vec(proptest::option::of((-1e3f64..1e3, -1e3f64..1e3)), 1..40),
    ) {
        let motion = white_cv(q);
        let sensor = position_measurement(r).unwrap();
        let prior = Gaussian::new(Vector4::zeros(), Matrix4::identity() * 1e4).unwrap();
        let zs: Vec<_> = zs.into_iter().map(|o| o.map(|(a, b)| Vector2::new(a, b))).collect();
        let run = filter(&motion, &sensor, &prior, &zs).unwrap();
        for s in run.filtered() {
            proptest::prop_assert!(check_symmetric(s.covariance(), "p").is_ok());
            proptest::prop_assert!(s.covariance().cholesky().is_some());
        }
        let smoothed = smooth(&motion, &run).unwrap();
        for s in &smoothed {
            proptest::prop_assert!(s.covariance().cholesky().is_some());
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Geometry

#[test]
fn iou_edge_cases() {
    let b = |l, t, w, h| BoundingBox::new(l, t, w, h).unwrap();
    let check = |a: BoundingBox, c: BoundingBox, expected: f64| {
        assert_relative_eq!(a.iou(&c), expected, epsilon = 1e-15);
        assert_relative_eq!(c.iou(&a), expected, epsilon = 1e-15);
    };
    check(b(0.0, 0.0, 2.0, 2.0), b(5.0, 5.0, 1.0, 1.0), 0.0); // disjoint
    check(b(0.0, 0.0, 2.0, 2.0), b(2.0, 0.0, 2.0, 2.0), 0.0); // touching edges
    check(b(0.0, 0.0, 4.0, 4.0), b(1.0, 1.0, 2.0, 2.0), 4.0 / 16.0); // contained
    check(b(1.0, 1.0, 3.0, 2.0), b(1.0, 1.0, 3.0, 2.0), 1.0); // identical
    check(b(0.0, 0.0, 2.0, 2.0), b(1.0, 0.0, 2.0, 2.0), 2.0 / 6.0); // half overlap
    check(b(1.0, 1.0, 0.0, 0.0), b(1.0, 1.0, 0.0, 0.0), 0.0); // zero area, identical
    check(b(1.0, 1.0, 0.0, 3.0), b(0.0, 0.0, 4.0, 4.0), 0.0); // zero area inside another
    assert!(BoundingBox::new(0.0, 0.0, -1.0, 1.0).is_err());
    assert!(BoundingBox::new(f64::NAN, 0.0, 1.0, 1.0).is_err());
    assert_eq!(b(1.0, 2.0, 4.0, 6.0).centre(), Vector2::new(3.0, 5.0));
}

#[test]
fn region_bearing_and_angles() {
    let r = Region2::new(Vector2::new(-1.0, 2.0), Vector2::new(3.0, 7.0)).unwrap();
    assert_relative_eq!(r.volume(), 20.0);
    assert!(r.contains(&Vector2::new(0.0, 3.0)));
    assert!(!r.contains(&Vector2::new(0.0, 8.0)));
    assert!(Region2::new(Vector2::new(1.0, 0.0), Vector2::new(1.0, 1.0)).is_err());
    let mut g = rng(1);
    assert!((0..1000).all(|_| r.contains(&r.sample_uniform(&mut g))));
    use std::f64::consts::{FRAC_PI_2, PI};
    assert_relative_eq!(
        bearing_rad(&Vector2::new(1.0, 1.0), &Vector2::new(1.0, 3.0)),
        FRAC_PI_2
    );
    assert_relative_eq!(
        bearing_rad(&Vector2::new(0.0, 0.0), &Vector2::new(-1.0, 0.0)),
        PI
    );
    assert_relative_eq!(wrap_angle_rad(3.0 * PI), PI, epsilon = 1e-12);
    assert_relative_eq!(wrap_angle_rad(-PI), PI, epsilon = 1e-12);
    assert_relative_eq!(
        wrap_angle_rad(-FRAC_PI_2 - 4.0 * PI),
        -FRAC_PI_2,
        epsilon = 1e-12
    );
}

// ---------------------------------------------------------------------------------------------
// Likelihood grids

fn bump(centre: Vector2<f64>, width: f64) -> impl Fn(Vector2<f64>) -> f64 {
    move |p| (-(p - centre).norm_squared() / (2.0 * width * width)).exp()
}

#[test]
fn grid_fusion_and_peaks() {
    let region = Region2::square(10.0).unwrap();
    let a = LikelihoodGrid::from_fn(region, 1.0, |p| {
        bump(Vector2::new(2.5, 2.5), 1.0)(p) + bump(Vector2::new(7.5, 6.5), 1.0)(p)
    })
    .unwrap();
    let b = LikelihoodGrid::from_fn(region, 1.0, bump(Vector2::new(7.5, 6.5), 1.5)).unwrap();
    assert_eq!(a.shape(), (10, 10));
    let sum = LikelihoodGrid::fuse_weighted_sum(&[(&a, 0.5), (&b, 0.5)]).unwrap();
    assert_relative_eq!(sum.values().iter().sum::<f64>(), 1.0, epsilon = 1e-12);
    let peaks = sum
        .peaks(&PeakConfig {
            relative_threshold: 0.3,
            suppression_radius: 2.0,
        })
        .unwrap();
    assert_eq!(peaks.len(), 2);
    assert_eq!(peaks[0].position, Vector2::new(7.5, 6.5)); // both sensors agree there
    assert_eq!(peaks[1].position, Vector2::new(2.5, 2.5));
    // The product vetoes what only one sensor sees.
    let prod = LikelihoodGrid::fuse_product(&[(&a, 1.0), (&b, 1.0)]).unwrap();
    let peaks = prod
        .peaks(&PeakConfig {
            relative_threshold: 0.3,
            suppression_radius: 2.0,
        })
        .unwrap();
    assert_eq!(peaks.len(), 1);
    // Product by hand at one cell: normalised a·b.
    let total: f64 = a.values().iter().zip(b.values()).map(|(x, y)| x * y).sum();
    assert_relative_eq!(
        prod.value(3, 4),
        a.value(3, 4) * b.value(3, 4) / total,
        max_relative = 1e-12
    );
    assert_eq!(sum.cell_of(&Vector2::new(7.9, 6.1)), Some((7, 6)));
    assert_eq!(sum.cell_of(&Vector2::new(-0.1, 6.1)), None);
}

#[test]
fn grid_errors() {
    let region = Region2::square(4.0).unwrap();
    let small = LikelihoodGrid::zeros(region, 1.0).unwrap();
    let coarse = LikelihoodGrid::zeros(region, 2.0).unwrap();
    assert!(matches!(
        LikelihoodGrid::fuse_weighted_sum(&[(&small, 1.0), (&coarse, 1.0)]),
        Err(Error::ShapeMismatch(_))
    ));
    assert!(LikelihoodGrid::fuse_weighted_sum(&[]).is_err());
    assert!(small.clone().normalise().is_err());
    assert!(LikelihoodGrid::from_fn(region, 1.0, |_| f64::NAN).is_err());
    assert!(LikelihoodGrid::zeros(region, 0.0).is_err());
    assert!(
        small
            .peaks(&PeakConfig {
                relative_threshold: 0.0,
                suppression_radius: 1.0
            })
            .is_err()
    );
    assert!(small.peaks(&PeakConfig::default()).unwrap().is_empty());
}

// ---------------------------------------------------------------------------------------------
// Simulator

fn stats_config() -> SimulationConfig {
    SimulationConfig {
        region: Region2::square(100.0).unwrap(),
        n_scans: 4000,
        births_per_scan: 0.8,
        p_disappear: 0.05,
        p_detect: 0.7,
        clutter_per_scan: 3.0,
        motion: ConstantVelocity2::mcmcda(1.0, 0.5).unwrap(),
        measurement_noise: Matrix2::identity() * 0.1,
        initial_speed_max: 2.0,
        max_speed: Some(2.5),
    }
}

#[test]
fn simulator_counts_match_their_expectations() {
    let cfg = stats_config();
    let sim = cfg.check().unwrap().simulate(&mut rng(99)).unwrap();
    let n = f64::from(cfg.n_scans);
    let within = |name: &str, mean: f64, expected: f64, var: f64, count: f64| {
        let se = (var / count).sqrt();
        assert!(
            (mean - expected).abs() < 4.0 * se,
            "{name}: mean {mean}, expected {expected} ± 4·{se}"
        );
    };
    // Births: Poisson(λ_b V) per scan, so variance = mean.
    let births = sim.truth.len() as f64 / n;
    within(
        "births per scan",
        births,
        cfg.births_per_scan,
        cfg.births_per_scan,
        n,
    );
    // Clutter: Poisson(λ_f V) per scan.
    let clutter: usize = sim
        .scans
        .iter()
        .map(|s| {
            s.measurements
                .iter()
                .filter(|m| m.origin == Origin::Clutter)
                .count()
        })
        .sum();
    within(
        "clutter per scan",
        clutter as f64 / n,
        cfg.clutter_per_scan,
        cfg.clutter_per_scan,
        n,
    );
    // Detections: Bernoulli(p_d) per target-scan.
    let target_scans = sim.truth.n_points() as f64;
    let detections = sim
        .scans
        .iter()
        .flat_map(|s| &s.measurements)
        .filter(|m| matches!(m.origin, Origin::Target(_)))
        .count() as f64;
    within(
        "detection rate",
        detections / target_scans,
        cfg.p_detect,
        cfg.p_detect * (1.0 - cfg.p_detect),
        target_scans,
    );
    // Disappearances: Bernoulli(p_z) per transition of a target that could still move on.
    let deaths = sim
        .truth
        .tracks()
        .iter()
        .filter(|t| t.last_frame() < Some(cfg.n_scans - 1))
        .count() as f64;
    let transitions = sim
        .truth
        .tracks()
        .iter()
        .map(|t| {
            (t.len() - 1) as f64
                + if t.last_frame() < Some(cfg.n_scans - 1) {
                    1.0
                } else {
                    0.0
                }
        })
        .sum::<f64>();
    within(
        "disappearance rate",
        deaths / transitions,
        cfg.p_disappear,
        cfg.p_disappear * (1.0 - cfg.p_disappear),
        transitions,
    );
    // Every detection belongs to a target that exists at that frame.
    for scan in &sim.scans {
        for m in &scan.measurements {
            if let Origin::Target(id) = m.origin {
                assert!(sim.truth.get(id).unwrap().at(scan.frame).is_some());
            }
        }
    }
}

#[test]
fn simulator_respects_speed_bound_and_region_for_births() {
    let cfg = stats_config();
    let sim = cfg.check().unwrap().simulate(&mut rng(5)).unwrap();
    let v_max = cfg.max_speed.unwrap();
    for t in sim.truth.tracks() {
        assert!(cfg.region.contains(&t.points()[0].location.position()));
        for p in t.points() {
            assert!(p.velocity.unwrap().norm() <= v_max);
        }
    }
}

#[test]
fn simulator_is_reproducible_and_rejects_bad_configs() {
    let cfg = SimulationConfig {
        n_scans: 50,
        ..stats_config()
    };
    let sim = cfg.check().unwrap();
    assert!(sim.simulate(&mut rng(3)).unwrap() == sim.simulate(&mut rng(3)).unwrap());
    assert!(sim.simulate(&mut rng(3)).unwrap() != sim.simulate(&mut rng(4)).unwrap());
    assert!(
        SimulationConfig {
            p_detect: 1.5,
            ..stats_config()
        }
        .check()
        .is_err()
    );
    assert!(
        SimulationConfig {
            births_per_scan: -1.0,
            ..stats_config()
        }
        .check()
        .is_err()
    );
    assert!(
        SimulationConfig {
            clutter_per_scan: f64::NAN,
            ..stats_config()
        }
        .check()
        .is_err()
    );
    assert!(
        SimulationConfig {
            n_scans: 0,
            ..stats_config()
        }
        .check()
        .is_err()
    );
    assert!(
        SimulationConfig {
            max_speed: Some(0.0),
            ..stats_config()
        }
        .check()
        .is_err()
    );
    assert!(
        SimulationConfig {
            measurement_noise: Matrix2::zeros(),
            ..stats_config()
        }
        .check()
        .is_err()
    );
}

#[test]
fn scenario_round_trips_through_json_and_bincode() {
    let cfg = SimulationConfig {
        n_scans: 20,
        ..stats_config()
    };
    let sim = cfg.check().unwrap().simulate(&mut rng(8)).unwrap();

    let json = serde_json::to_string(&cfg).unwrap();
    assert_eq!(
        serde_json::from_str::<SimulationConfig>(&json).unwrap(),
        cfg
    );
    let json = serde_json::to_string(&sim).unwrap();
    assert!(
        serde_json::from_str::<Simulation>(&json).unwrap() == sim,
        "JSON round trip changed the simulation"
    );

    let config = bincode::config::standard();
    let bytes = bincode::serde::encode_to_vec(&sim, config).unwrap();
    let (back, used): (Simulation, usize) =
        bincode::serde::decode_from_slice(&bytes, config).unwrap();
    assert_eq!(used, bytes.len());
    assert!(back == sim, "bincode round trip changed the simulation");
    let bytes = bincode::serde::encode_to_vec(&cfg, config).unwrap();
    let (back, _): (SimulationConfig, usize) =
        bincode::serde::decode_from_slice(&bytes, config).unwrap();
    assert_eq!(back, cfg);

    // Deserialisation re-checks invariants: a region with lower > upper is rejected.
    let bad = json_region_swapped();
    assert!(serde_json::from_str::<Region2>(&bad).is_err());
}

fn json_region_swapped() -> String {
    r#"{"lower":[5.0,0.0],"upper":[1.0,1.0]}"#.to_string()
}

// ---------------------------------------------------------------------------------------------
// Tracks and MOTChallenge rows

#[test]
fn tracks_reject_bad_frames_and_duplicate_ids() {
    let mut t = Track::new(TrackId(1));
    t.push(TrackPoint::at(3, Vector2::new(0.0, 0.0))).unwrap();
    assert!(t.push(TrackPoint::at(3, Vector2::new(1.0, 0.0))).is_err());
    assert!(
        t.push(TrackPoint::at(4, Vector2::new(f64::NAN, 0.0)))
            .is_err()
    );
    t.push(TrackPoint::at(6, Vector2::new(1.0, 0.0))).unwrap();
    assert_eq!(t.at(6).unwrap().location.position(), Vector2::new(1.0, 0.0));
    assert!(t.at(5).is_none());
    let mut set = TrackSet::new();
    set.push(t.clone()).unwrap();
    assert!(set.push(t).is_err());
    assert_eq!(set.frame_range(), Some((3, 6)));
}

#[test]
fn mot_parse_and_format_round_trip() {
    let text = "1,1,10,20,30,40,1,-1,-1,-1\n\n1,2,0.5,1.5,2,3,0.9,-1,-1,-1\n2,1,12,21,30,40\n";
    let rows = parse_mot(text.as_bytes()).unwrap();
    assert_eq!(rows.len(), 3);
    assert!((rows[2].confidence - 1.0).abs() < f64::EPSILON); // default for a 6-column row
    assert_eq!(rows[1].bbox, BoundingBox::new(0.5, 1.5, 2.0, 3.0).unwrap());
    let set = TrackSet::from_mot_rows(&rows).unwrap();
    assert_eq!(set.len(), 2);
    assert_eq!(set.get(TrackId(1)).unwrap().len(), 2);
    let again = parse_mot(format_mot(&set.to_mot_rows(1.0)).as_bytes()).unwrap();
    assert_eq!(TrackSet::from_mot_rows(&again).unwrap(), set);
}

#[test]
fn mot_parse_errors_carry_line_numbers() {
    let check = |text: &str, line: usize, needle: &str| match parse_mot(text.as_bytes()) {
        Err(Error::Parse { line: l, reason }) => {
            assert_eq!(l, line, "{reason}");
            assert!(reason.contains(needle), "{reason:?} lacks {needle:?}");
        }
        other => panic!("expected a parse error, got {other:?}"),
    };
    check("1,1,0,0,1,1\n1,2,0,0,1\n", 2, "found 5");
    check("1,1,0,0,1,1\n\n2,x,0,0,1,1\n", 3, "column 2 (id)");
    check("1.5,1,0,0,1,1\n", 1, "frame");
    check("1,1,0,0,nan,1\n", 1, "not finite");
    check("1,1,0,0,-2,1\n", 1, "must be >= 0");
    check("1,1,0,0,1,1,1,1,1,1,1\n", 1, "found 11");
    let rows = parse_mot("1,3,0,0,1,1\n1,3,5,5,1,1\n".as_bytes()).unwrap();
    assert!(TrackSet::from_mot_rows(&rows).is_err()); // the same id twice in one frame
}

#[test]
fn frame_clock_maps_frames_and_times_both_ways() {
    // 25 frames per second starting at 2 s: frame 10 is at 2.4 s.
    let clock = FrameClock::new(2.0, 0.04).unwrap();
    assert_relative_eq!(clock.time_s(10), 2.4, epsilon = 1e-12);
    assert_eq!(clock.frame_at(2.4).unwrap(), 10);
    // An audio block stamped 2.419 s belongs to frame 10, one at 2.421 s to frame 11.
    assert_eq!(clock.frame_at(2.419).unwrap(), 10);
    assert_eq!(clock.frame_at(2.421).unwrap(), 11);
    // Before the first frame's half-period, outside the range, or not a number: errors.
    assert!(clock.frame_at(1.9).is_err());
    assert!(clock.frame_at(f64::NAN).is_err());
    assert!(clock.frame_at(1e12).is_err());
    assert!(FrameClock::new(0.0, 0.0).is_err());
    assert!(FrameClock::new(f64::INFINITY, 1.0).is_err());
    // Deserialisation goes through the same checks.
    assert!(serde_json::from_str::<FrameClock>(r#"{"start_s":0.0,"period_s":-1.0}"#).is_err());
    let back: FrameClock = serde_json::from_str(&serde_json::to_string(&clock).unwrap()).unwrap();
    assert_eq!(back, clock);
}

#[test]
fn non_negative_check_accepts_zero_only_from_the_boundary() {
    assert!(ensure_non_negative(0.0, "x").is_ok());
    assert!(ensure_non_negative(2.5, "x").is_ok());
    for bad in [-1e-300, f64::NAN, f64::INFINITY] {
        let err = ensure_non_negative(bad, "gap_cost").unwrap_err();
        assert!(err.to_string().contains("gap_cost"), "{err}");
    }
}

#[test]
fn misspelt_fields_in_model_configs_are_errors() {
    let good = r#"{"dt_s":1.0,"noise":{"white_acceleration":{"q":0.5}}}"#;
    assert!(serde_json::from_str::<ConstantVelocity2>(good).is_ok());
    for bad in [
        r#"{"dt_s":1.0,"noise":{"white_acceleration":{"q":0.5}},"dts":2.0}"#,
        r#"{"dt_s":1.0,"noise":{"white_acceleration":{"q":0.5,"qq":1.0}}}"#,
    ] {
        let err = serde_json::from_str::<ConstantVelocity2>(bad).unwrap_err();
        assert!(err.to_string().contains("unknown field"), "{err}");
    }
    let region = r#"{"lower":[0.0,0.0],"upper":[1.0,1.0],"uper":[2.0,2.0]}"#;
    assert!(serde_json::from_str::<Region2>(region).is_err());
}

#[test]
fn mot_header_is_skipped_and_returned() {
    // The header of a MOTChallenge results file with column names, then rows.
    let text = "\nframe,id,bb_left,bb_top,bb_width,bb_height,conf,x,y,z\n1,1,0,0,10,10\n";
    let file = read_mot(text.as_bytes()).unwrap();
    assert_eq!(
        file.header,
        Some((
            2,
            "frame,id,bb_left,bb_top,bb_width,bb_height,conf,x,y,z".into()
        ))
    );
    assert_eq!(file.rows.len(), 1);
    assert_eq!(parse_mot(text.as_bytes()).unwrap(), file.rows);
    // A header is only the first non-blank line, and only when no field is a number: a bad
    // row is still an error, and a header-like line after a row is one too.
    assert!(matches!(
        parse_mot("1,1,0,0,ten,10\n".as_bytes()),
        Err(Error::Parse { line: 1, .. })
    ));
    assert!(matches!(
        parse_mot("1,1,0,0,1,1\nframe,id,l,t,w,h\n".as_bytes()),
        Err(Error::Parse { line: 2, .. })
    ));
    assert_eq!(read_mot("1,1,0,0,1,1\n".as_bytes()).unwrap().header, None);
}

#[test]
fn zero_area_boxes_are_a_typed_error_at_parse_time() {
    for (text, width, height) in [
        ("1,1,5,5,0,10\n", 0.0, 10.0),
        ("1,1,5,5,10,0\n", 10.0, 0.0),
        ("1,1,5,5,0,0,1,-1,-1,-1\n", 0.0, 0.0),
    ] {
        assert_eq!(
            parse_mot(format!("1,2,0,0,3,4\n{text}").as_bytes()),
            Err(Error::ZeroAreaBox {
                line: 2,
                width,
                height
            })
        );
    }
    // The smallest positive box is fine.
    assert_eq!(
        parse_mot("1,1,0,0,1e-9,1e-9\n".as_bytes()).unwrap().len(),
        1
    );
}

#[test]
fn config_matrices_are_rows_and_the_flat_form_still_loads() {
    // Rows: an asymmetric matrix shows the order.
    let noise = CvNoise::Discrete {
        acceleration_covariance: Matrix2::new(4.0, 1.0, 1.0, 9.0),
    };
    let json = serde_json::to_string(&noise).unwrap();
    assert_eq!(
        json,
        r#"{"discrete":{"acceleration_covariance":[[4.0,1.0],[1.0,9.0]]}}"#
    );
    assert_eq!(serde_json::from_str::<CvNoise>(&json).unwrap(), noise);
    // The flat form is whatever nalgebra's own serde writes (column-major): read it back
    // through the helper and get nalgebra's matrix.
    let m = Matrix2::new(1.0, 2.0, 3.0, 4.0);
    let flat = serde_json::to_string(&m).unwrap();
    assert_eq!(flat, "[1.0,3.0,2.0,4.0]");
    let cfg: SimulationConfig =
        serde_json::from_str(&format!(r#"{{"measurement_noise":{flat}}}"#)).unwrap();
    assert_eq!(cfg.measurement_noise, m);
    let cfg: SimulationConfig =
        serde_json::from_str(r#"{"measurement_noise":[[1.0,2.0],[3.0,4.0]]}"#).unwrap();
    assert_eq!(cfg.measurement_noise, m);
    // A whole config round-trips through the row form.
    let cfg = SimulationConfig {
        measurement_noise: Matrix2::new(25.0, 5.0, 5.0, 16.0),
        ..SimulationConfig::default()
    };
    let json = serde_json::to_string(&cfg).unwrap();
    assert!(
        json.contains(r#""measurement_noise":[[25.0,5.0],[5.0,16.0]]"#),
        "{json}"
    );
    assert_eq!(
        serde_json::from_str::<SimulationConfig>(&json).unwrap(),
        cfg
    );
    // Wrong shapes name the expected one.
    for bad in [
        "[[1.0,0.0],[0.0]]",
        "[1.0,0.0,1.0]",
        "[[1.0,0.0],2.0]",
        "[[1,0],[0,1],[0,0]]",
    ] {
        let err =
            serde_json::from_str::<SimulationConfig>(&format!(r#"{{"measurement_noise":{bad}}}"#))
                .unwrap_err()
                .to_string();
        assert!(err.contains("2×2"), "{bad}: {err}");
    }
}

/// A tracker that reports one track per detection, at the detection, with the detection's id:
/// enough to see what `Online` feeds a `Tracker` and in which order.
struct Echo {
    seen: Vec<(Frame, u64)>,
}

impl Tracker for Echo {
    type Error = Error;

    fn step(&mut self, frame: Frame, detections: &[Detection]) -> Result<Vec<TrackState>> {
        self.seen.extend(detections.iter().map(|d| (frame, d.id.0)));
        Ok(detections
            .iter()
            .map(|d| TrackState {
                id: TrackId(d.id.0),
                point: TrackPoint::at(frame, d.position()),
            })
            .collect())
    }

    fn finish(&mut self) -> Result<TrackSet> {
        let tracks = self
            .seen
            .iter()
            .map(|&(f, id)| Track::from_points(TrackId(id), vec![TrackPoint::at(f, Vec2::zeros())]))
            .collect::<Result<Vec<_>>>()?;
        TrackSet::from_tracks(tracks)
    }
}

#[test]
fn scans_group_by_frame_in_order_and_online_steps_each_once() {
    let d = |id, frame| Detection::point(id, frame, Vec2::new(id as f64, 0.0));
    // Out of frame order in the input; within a frame the input order is kept.
    let input = [d(1, 7), d(2, 3), d(3, 7), d(4, 4_000_000_000), d(5, 3)];
    let scans = scans_of(&input, None).unwrap();
    let frames: Vec<Frame> = scans.iter().map(|s| s.frame).collect();
    assert_eq!(frames, vec![3, 7, 4_000_000_000]);
    let ids: Vec<Vec<u64>> = scans
        .iter()
        .map(|s| s.detections.iter().map(|d| d.id.0).collect())
        .collect();
    assert_eq!(ids, vec![vec![2, 5], vec![1, 3], vec![4]]);
    let mut online = Online(Echo { seen: Vec::new() });
    let tracks = online.track(&scans).unwrap();
    assert_eq!(
        online.0.seen,
        vec![(3, 2), (3, 5), (7, 1), (7, 3), (4_000_000_000, 4)]
    );
    assert_eq!(tracks.len(), 5);
}
