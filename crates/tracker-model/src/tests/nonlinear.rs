//! The EKF, UKF, turn models, radar models and IMM against closed forms, numerical integration,
//! finite differences, quadrature and hand-worked mixing; filterpy's outputs are checked in
//! `tests/filterpy_reference.rs`.

use approx::assert_relative_eq;
use nalgebra::{Matrix1, Matrix4, SMatrix, SVector, Vector1, Vector2, Vector4};

use crate::*;

fn cv(q: f64) -> ConstantVelocity2 {
    ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q }).unwrap()
}

fn cv_prior() -> Gaussian<4> {
    let cov = Matrix4::new(
        4.0, 0.5, 0.3, 0.0, //
        0.5, 3.0, 0.0, 0.2, //
        0.3, 0.0, 1.0, 0.1, //
        0.0, 0.2, 0.1, 0.8,
    );
    Gaussian::new(Vector4::new(1.0, -2.0, 0.5, 0.25), cov).unwrap()
}

fn assert_gaussians_close<const N: usize>(a: &Gaussian<N>, b: &Gaussian<N>, eps: f64) {
    assert_relative_eq!(a.mean(), b.mean(), epsilon = eps, max_relative = eps);
    assert_relative_eq!(
        a.covariance(),
        b.covariance(),
        epsilon = eps,
        max_relative = eps
    );
}

// ---------------------------------------------------------------------------------------------
// EKF and UKF on linear models are the Kalman filter

#[test]
fn ekf_on_linear_models_is_the_kalman_filter() {
    let motion = cv(0.3);
    let sensor = position_measurement(0.5).unwrap();
    let z = Vector2::new(1.7, -1.1);
    let kf_pred = TransitionModel::predict(&motion, &cv_prior());
    let ekf_pred = GaussianFilter::Extended
        .predict(&motion, &cv_prior(), 1.0)
        .unwrap();
    assert_gaussians_close(&ekf_pred, &kf_pred, 1e-13);
    let kf = ObservationModel::update(&sensor, &kf_pred, &z).unwrap();
    let ekf = GaussianFilter::Extended
        .update(&sensor, &kf_pred, &z)
        .unwrap();
    assert_gaussians_close(&ekf.state, &kf.state, 1e-13);
    assert_relative_eq!(
        ekf.innovation.log_likelihood,
        kf.innovation.log_likelihood,
        max_relative = 1e-13
    );
}

/// The unscented transform is exact for linear maps (its points match the first two moments),
/// whatever α, β and κ.
#[test]
fn ukf_on_linear_models_is_the_kalman_filter() {
    let motion = cv(0.3);
    let sensor = position_measurement(0.5).unwrap();
    let z = Vector2::new(1.7, -1.1);
    let kf_pred = TransitionModel::predict(&motion, &cv_prior());
    let kf = ObservationModel::update(&sensor, &kf_pred, &z).unwrap();
    for (alpha, beta, kappa) in [(1.0, 2.0, 0.0), (0.1, 2.0, -1.0), (0.5, 0.0, 3.0)] {
        let ukf = GaussianFilter::Unscented(SigmaPoints::new(alpha, beta, kappa).unwrap());
        let pred = ukf.predict(&motion, &cv_prior(), 1.0).unwrap();
        assert_gaussians_close(&pred, &kf_pred, 1e-9);
        let up = ukf.update(&sensor, &kf_pred, &z).unwrap();
        assert_gaussians_close(&up.state, &kf.state, 1e-9);
        assert_relative_eq!(
            up.innovation.log_likelihood,
            kf.innovation.log_likelihood,
            max_relative = 1e-9
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Turn models

/// RK4 on ẋ = v, v̇ = ω × v (ω about the vertical), 20 000 steps.
fn integrate_turn(x: [f64; 4], omega: f64, dt: f64) -> [f64; 4] {
    let deriv = |s: [f64; 4]| [s[2], s[3], -omega * s[3], omega * s[2]];
    let steps = 20_000;
    let h = dt / steps as f64;
    let add = |a: [f64; 4], b: [f64; 4], k: f64| std::array::from_fn(|i| a[i] + k * b[i]);
    (0..steps).fold(x, |s, _| {
        let k1 = deriv(s);
        let k2 = deriv(add(s, k1, h / 2.0));
        let k3 = deriv(add(s, k2, h / 2.0));
        let k4 = deriv(add(s, k3, h));
        std::array::from_fn(|i| s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
    })
}

#[test]
fn coordinated_turns_match_the_integrated_dynamics() {
    let start = [100.0, -50.0, 120.0, 40.0];
    for (omega, dt) in [
        (0.05, 10.0),
        (-0.2, 3.0),
        (1e-6, 7.0),
        (0.0, 5.0),
        (1.5, 4.0),
    ] {
        let want = integrate_turn(start, omega, dt);
        let known = CoordinatedTurn::new(omega, 0.1).unwrap();
        let got4 = known.propagate(&Vector4::from(start), dt);
        let x5 = SVector::<f64, 5>::new(start[0], start[1], start[2], start[3], omega);
        let noise = TurnNoise {
            q_accel: 0.1,
            q_turn: 1e-4,
        };
        let got5 = CoordinatedTurnRate::new(noise).unwrap().propagate(&x5, dt);
        for i in 0..4 {
            assert_relative_eq!(got4[i], want[i], epsilon = 1e-8, max_relative = 1e-10);
            assert_relative_eq!(got5[i], want[i], epsilon = 1e-8, max_relative = 1e-10);
        }
        assert_eq!(got5[4].to_bits(), omega.to_bits());
    }
}

/// A full circle (ωΔ = 2π) comes back to its start with its velocity.
#[test]
fn a_full_turn_returns_to_its_start() {
    let omega = 0.1;
    let m = CoordinatedTurn::new(omega, 0.0).unwrap();
    let x = Vector4::new(3.0, 4.0, 50.0, -20.0);
    let back = m.propagate(&x, std::f64::consts::TAU / omega);
    assert_relative_eq!(back, x, epsilon = 1e-9);
}

fn central_difference<const N: usize, const M: usize>(
    f: impl Fn(&SVector<f64, N>) -> SVector<f64, M>,
    x: &SVector<f64, N>,
    h: &SVector<f64, N>,
) -> SMatrix<f64, M, N> {
    let mut j = SMatrix::<f64, M, N>::zeros();
    for k in 0..N {
        let mut up = *x;
        let mut down = *x;
        up[k] += h[k];
        down[k] -= h[k];
        j.set_column(k, &((f(&up) - f(&down)) / (2.0 * h[k])));
    }
    j
}

#[test]
fn turn_rate_jacobian_matches_finite_differences() {
    let noise = TurnNoise {
        q_accel: 1.0,
        q_turn: 1e-5,
    };
    let models: [&dyn MotionModel<5>; 2] = [
        &CoordinatedTurnRate::new(noise).unwrap(),
        &ConstantVelocityTurnLayout::new(noise).unwrap(),
    ];
    let steps = SVector::<f64, 5>::new(1e-3, 1e-3, 1e-4, 1e-4, 1e-7);
    for model in models {
        for omega in [0.05, -0.3, 2e-6, 0.0, 0.0416, 0.0417] {
            let x = SVector::<f64, 5>::new(-800.0, 300.0, 150.0, -40.0, omega);
            for dt in [4.0, 12.0] {
                let numeric = central_difference(|s| model.propagate(s, dt), &x, &steps);
                let analytic = model.jacobian(&x, dt);
                assert_relative_eq!(analytic, numeric, epsilon = 1e-5, max_relative = 1e-6);
            }
        }
    }
}

/// The series branch of the turn terms and the direct one agree where they meet (the
/// Jacobians either side are checked against finite differences above).
#[test]
fn turn_terms_are_continuous_at_the_series_threshold() {
    let noise = TurnNoise {
        q_accel: 1.0,
        q_turn: 1e-5,
    };
    let model = CoordinatedTurnRate::new(noise).unwrap();
    let dt = 10.0;
    let at = |omega: f64| {
        let x = SVector::<f64, 5>::new(0.0, 0.0, 200.0, 30.0, omega);
        (model.propagate(&x, dt), model.jacobian(&x, dt))
    };
    // ωΔ = 0.5 is the switch; step across it and undo the step to first order with the
    // Jacobian's ω column (the second-order remainder is ~1e-15 m here).
    let (w_below, w_above) = (0.049_999_999, 0.050_000_001);
    let (below, j_below) = at(w_below);
    let (above, _) = at(w_above);
    let moved = below + j_below.column(4) * (w_above - w_below);
    assert_relative_eq!(moved, above, epsilon = 1e-12, max_relative = 1e-13);
}

// ---------------------------------------------------------------------------------------------
// Radar models

#[test]
fn radar_jacobians_match_finite_differences() {
    let rb = RangeBearing::<5>::at([100.0, -200.0], 10.0, 0.01).unwrap();
    let x = SVector::<f64, 5>::new(-3000.0, 1200.0, 100.0, 20.0, 0.01);
    let h = SVector::<f64, 5>::repeat(1e-3);
    let numeric = central_difference(|s| rb.measure(s), &x, &h);
    assert_relative_eq!(
        rb.jacobian(&x),
        numeric,
        epsilon = 1e-9,
        max_relative = 1e-6
    );

    let site = RadarSite {
        position: SVector::<f64, 3>::new(5.0, 6.0, 7.0),
        state_indices: SVector::<usize, 3>::new(0, 1, 2),
    };
    let rbe = RangeBearingElevation::<6>::new(site, [10.0, 0.01, 0.01]).unwrap();
    let x6 = SVector::<f64, 6>::new(-3000.0, 1200.0, 4000.0, 100.0, 20.0, 5.0);
    let numeric = central_difference(|s| rbe.measure(s), &x6, &SVector::repeat(1e-3));
    assert_relative_eq!(
        rbe.jacobian(&x6),
        numeric,
        epsilon = 1e-9,
        max_relative = 1e-6
    );
}

/// Bearings either side of ±π: the residual is the short way round and their mean is ±π, not 0.
#[test]
fn bearings_are_wrapped_and_averaged_on_the_circle() {
    use std::f64::consts::PI;
    let rb = RangeBearing::<4>::at([0.0, 0.0], 1.0, 0.01).unwrap();
    let a = Vector2::new(100.0, PI - 0.01);
    let b = Vector2::new(100.0, -PI + 0.01);
    assert_relative_eq!(rb.residual(&b, &a)[1], 0.02, epsilon = 1e-12);
    let mean = rb.weighted_mean(&[a, b], &[0.5, 0.5]);
    assert_relative_eq!(mean[1].abs(), PI, epsilon = 1e-12);
    assert_relative_eq!(mean[0], 100.0, epsilon = 1e-12);
}

/// A target due west of the radar, its bearings straddling ±π: both filters' updates move the
/// estimate by a few metres, not across the sensor.
#[test]
fn filters_track_through_the_bearing_cut() {
    let rb = RangeBearing::<4>::at([0.0, 0.0], 5.0, 0.002).unwrap();
    let prior = Gaussian::new(
        Vector4::new(-1000.0, 1.0, 0.0, 0.0),
        Matrix4::from_diagonal(&Vector4::new(100.0, 100.0, 1.0, 1.0)),
    )
    .unwrap();
    let z = Vector2::new(1000.0, -std::f64::consts::PI + 0.001);
    for filter in [
        GaussianFilter::Extended,
        GaussianFilter::Unscented(SigmaPoints::gaussian()),
    ] {
        let up = filter.update(&rb, &prior, &z).unwrap();
        let m = up.state.mean();
        assert!(
            (m[0] + 1000.0).abs() < 5.0 && m[1].abs() < 5.0,
            "{filter:?}: {m}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// IMM

/// x' = a x + w, w ~ N(0, q): a 1-D mode for checks by quadrature.
struct Scalar {
    a: f64,
    q: f64,
}

impl MotionModel<1> for Scalar {
    fn propagate(&self, x: &Vector1<f64>, _dt: f64) -> Vector1<f64> {
        x * self.a
    }
    fn jacobian(&self, _x: &Vector1<f64>, _dt: f64) -> Matrix1<f64> {
        Matrix1::new(self.a)
    }
    fn noise_covariance(&self, _x: &Vector1<f64>, dt: f64) -> Matrix1<f64> {
        Matrix1::new(self.q * dt)
    }
}

fn normal(x: f64, mean: f64, var: f64) -> f64 {
    (-(x - mean).powi(2) / (2.0 * var)).exp() / (std::f64::consts::TAU * var).sqrt()
}

/// From one Gaussian, one IMM cycle is exact: the posterior is the two-component mixture
/// Σ_j c̄_j N(x'; a_j m, a_j² p + q_j) N(z; x', r), here integrated on a fine grid.
#[test]
fn one_imm_cycle_equals_the_exact_posterior_by_quadrature() {
    let (m, p, r, z) = (2.0, 1.5, 0.7, 3.1);
    let modes = [Scalar { a: 1.0, q: 0.2 }, Scalar { a: 1.4, q: 1.0 }];
    let mu = [0.6, 0.4];
    let switching = vec![vec![0.8, 0.2], vec![0.3, 0.7]];
    let c_bar = [0.6 * 0.8 + 0.4 * 0.3, 0.6 * 0.2 + 0.4 * 0.7];
    let (lo, hi, n) = (-20.0, 25.0, 450_000);
    let h = (hi - lo) / n as f64;
    let (mut mass, mut first, mut second, mut by_mode) = (0.0, 0.0, 0.0, [0.0; 2]);
    for k in 0..=n {
        let x = lo + h * k as f64;
        let w = if k == 0 || k == n { 0.5 } else { 1.0 };
        let lik = normal(z, x, r);
        for (j, md) in modes.iter().enumerate() {
            let d = w * c_bar[j] * normal(x, md.a * m, md.a * md.a * p + md.q) * lik;
            by_mode[j] += d;
            mass += d;
            first += d * x;
            second += d * x * x;
        }
    }
    let mean = first / mass;
    let var = second / mass - mean * mean;

    let boxed: Vec<Mode<1>> = vec![
        Box::new(Scalar { a: 1.0, q: 0.2 }),
        Box::new(Scalar { a: 1.4, q: 1.0 }),
    ];
    let imm = Imm::new(boxed, &switching, GaussianFilter::Extended).unwrap();
    let start = imm
        .start(
            Gaussian::new(Vector1::new(m), Matrix1::new(p)).unwrap(),
            &mu,
        )
        .unwrap();
    let predicted = imm.predict(&start, 1.0).unwrap();
    assert_relative_eq!(predicted.probabilities()[0], c_bar[0], epsilon = 1e-15);
    let sensor = full_state_measurement(Matrix1::new(r)).unwrap();
    let up = imm.update(&sensor, &predicted, &Vector1::new(z)).unwrap();
    let combined = up.state.combined();
    assert_relative_eq!(combined.mean()[0], mean, epsilon = 1e-8);
    assert_relative_eq!(combined.covariance()[(0, 0)], var, epsilon = 1e-8);
    assert_relative_eq!(
        up.state.probabilities()[0],
        by_mode[0] / mass,
        epsilon = 1e-9
    );
    assert_relative_eq!(up.log_likelihood, (mass * h).ln(), epsilon = 1e-8);
}

/// The mixing step by hand: μ = [0.7, 0.3], π = [[0.9, 0.1], [0.2, 0.8]], modes N(1, 1) and
/// N(3, 2). c̄ = [0.69, 0.31]; mode 1 mixes with weights [0.63, 0.06] / 0.69, mode 2 with
/// [0.07, 0.24] / 0.31. With Δ = 0 and no noise the predictions are the mixtures themselves.
#[test]
fn imm_mixing_equals_the_hand_computation() {
    let boxed: Vec<Mode<1>> = vec![
        Box::new(Scalar { a: 1.0, q: 0.0 }),
        Box::new(Scalar { a: 1.0, q: 0.0 }),
    ];
    let imm = Imm::new(
        boxed,
        &[vec![0.9, 0.1], vec![0.2, 0.8]],
        GaussianFilter::Extended,
    )
    .unwrap();
    let g = |m: f64, v: f64| Gaussian::new(Vector1::new(m), Matrix1::new(v)).unwrap();
    let state = imm
        .start_from_modes(vec![g(1.0, 1.0), g(3.0, 2.0)], &[0.7, 0.3])
        .unwrap();
    let predicted = imm.predict(&state, 0.0).unwrap();
    let p = predicted.probabilities();
    assert_relative_eq!(p[0], 0.69, epsilon = 1e-15);
    assert_relative_eq!(p[1], 0.31, epsilon = 1e-15);
    let mix = |w1: f64, w2: f64| {
        let mean = w1 * 1.0 + w2 * 3.0;
        let var = w1 * (1.0 + (1.0 - mean).powi(2)) + w2 * (2.0 + (3.0 - mean).powi(2));
        (mean, var)
    };
    for (j, (w1, w2)) in [(0.63 / 0.69, 0.06 / 0.69), (0.07 / 0.31, 0.24 / 0.31)]
        .into_iter()
        .enumerate()
    {
        let (mean, var) = mix(w1, w2);
        assert_relative_eq!(predicted.modes()[j].mean()[0], mean, epsilon = 1e-14);
        assert_relative_eq!(
            predicted.modes()[j].covariance()[(0, 0)],
            var,
            epsilon = 1e-14
        );
    }
}

#[test]
fn an_imm_of_one_mode_is_that_filter() {
    let motion = cv(0.3);
    let sensor = position_measurement(0.5).unwrap();
    let ukf = GaussianFilter::Unscented(SigmaPoints::new(0.5, 2.0, 0.0).unwrap());
    let imm = Imm::new(vec![Box::new(motion) as Mode<4>], &[vec![1.0]], ukf).unwrap();
    let mut single = cv_prior();
    let mut state = imm.start(cv_prior(), &[1.0]).unwrap();
    for k in 0..5 {
        let z = Vector2::new(k as f64, -0.5 * k as f64);
        single = ukf.predict(&motion, &single, 2.0).unwrap();
        let one = ukf.update(&sensor, &single, &z).unwrap();
        single = one.state;
        let up = imm
            .update(&sensor, &imm.predict(&state, 2.0).unwrap(), &z)
            .unwrap();
        state = up.state;
        assert_eq!(state.combined(), single);
        assert_eq!(
            up.log_likelihood.to_bits(),
            one.innovation.log_likelihood.to_bits()
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Errors, not panics

#[test]
fn bad_filter_and_model_parameters_are_typed_errors() {
    assert!(SigmaPoints::new(0.0, 2.0, 0.0).is_err());
    assert!(SigmaPoints::new(1.5, 2.0, 0.0).is_err());
    assert!(SigmaPoints::new(0.5, -1.0, 0.0).is_err());
    assert!(SigmaPoints::new(0.5, 2.0, f64::NAN).is_err());
    // n + κ ≤ 0 is found where n is known.
    let ukf = GaussianFilter::Unscented(SigmaPoints::new(0.5, 2.0, -4.0).unwrap());
    let err = ukf.predict(&cv(0.1), &cv_prior(), 1.0).unwrap_err();
    assert!(err.to_string().contains("n + kappa"), "{err}");
    assert!(CoordinatedTurn::new(3.0, 0.1).is_err());
    assert!(CoordinatedTurn::new(0.1, -0.1).is_err());
    let noise = TurnNoise {
        q_accel: -1.0,
        q_turn: 0.0,
    };
    assert!(CoordinatedTurnRate::new(noise).is_err());
    assert!(ConstantVelocity3::new(f64::INFINITY).is_err());
    assert!(RangeBearing::<4>::at([0.0, 0.0], 0.0, 0.01).is_err());
    let site = RadarSite {
        position: SVector::<f64, 2>::new(0.0, 0.0),
        state_indices: SVector::<usize, 2>::new(0, 4),
    };
    assert!(RangeBearing::<4>::new(site, 1.0, 0.01).is_err());
    let twice = RadarSite {
        state_indices: SVector::<usize, 2>::new(1, 1),
        ..site
    };
    assert!(RangeBearing::<4>::new(twice, 1.0, 0.01).is_err());
    for dt in [-1.0, f64::NAN] {
        let err = GaussianFilter::Extended.predict(&cv(0.1), &cv_prior(), dt);
        assert!(err.is_err());
    }
}

#[test]
fn a_target_at_the_radar_or_a_nan_measurement_is_an_error() {
    let rb = RangeBearing::<4>::at([1.0, -2.0], 1.0, 0.01).unwrap();
    let at_sensor = cv_prior(); // mean (1, −2): on the radar
    let z = Vector2::new(10.0, 0.3);
    assert!(
        GaussianFilter::Extended
            .update(&rb, &at_sensor, &z)
            .is_err()
    );
    let nan = Vector2::new(f64::NAN, 0.3);
    for filter in [
        GaussianFilter::Extended,
        GaussianFilter::Unscented(SigmaPoints::gaussian()),
    ] {
        assert!(
            filter
                .update(&position_measurement(1.0).unwrap(), &cv_prior(), &nan)
                .is_err()
        );
    }
}

#[test]
fn bad_imm_shapes_are_typed_errors() {
    let one = || vec![Box::new(cv(0.1)) as Mode<4>, Box::new(cv(0.2)) as Mode<4>];
    let ekf = GaussianFilter::Extended;
    assert!(Imm::<4>::new(Vec::new(), &[], ekf).is_err());
    assert!(Imm::new(one(), &[vec![1.0, 0.0]], ekf).is_err());
    assert!(Imm::new(one(), &[vec![0.5, 0.6], vec![0.5, 0.5]], ekf).is_err());
    assert!(Imm::new(one(), &[vec![1.5, -0.5], vec![0.5, 0.5]], ekf).is_err());
    let imm = Imm::new(one(), &[vec![0.9, 0.1], vec![0.1, 0.9]], ekf).unwrap();
    assert!(imm.start(cv_prior(), &[1.0]).is_err());
    assert!(imm.start(cv_prior(), &[0.7, 0.7]).is_err());
    let too_many: Vec<Mode<4>> = (0..=MAX_IMM_MODES)
        .map(|_| Box::new(cv(0.1)) as Mode<4>)
        .collect();
    let n = too_many.len();
    let uniform = vec![vec![1.0 / n as f64; n]; n];
    assert!(Imm::new(too_many, &uniform, ekf).is_err());
}

#[test]
fn filter_and_model_settings_round_trip_and_are_checked_when_read() {
    let ukf = GaussianFilter::Unscented(SigmaPoints::new(0.5, 2.0, -1.0).unwrap());
    let text = serde_json::to_string(&ukf).unwrap();
    assert_eq!(serde_json::from_str::<GaussianFilter>(&text).unwrap(), ukf);
    assert!(
        serde_json::from_str::<GaussianFilter>(
            r#"{"kind":"unscented","alpha":0.0,"beta":2.0,"kappa":0.0}"#
        )
        .is_err()
    );
    let turn = CoordinatedTurn::new(0.05, 0.5).unwrap();
    let text = serde_json::to_string(&turn).unwrap();
    assert_eq!(
        serde_json::from_str::<CoordinatedTurn>(&text).unwrap(),
        turn
    );
    let rb = RangeBearing::<5>::at([1.0, 2.0], 3.0, 0.01).unwrap();
    let text = serde_json::to_string(&rb).unwrap();
    assert_eq!(serde_json::from_str::<RangeBearing<5>>(&text).unwrap(), rb);
    assert!(serde_json::from_str::<RangeBearing<1>>(&text).is_err());
}
