//! GDT against an independent RTS smoother, and the baselines against hand-worked cases and
//! exactly representable functions.

use approx::assert_relative_eq;
use nalgebra::{Matrix2, Matrix2x4, Matrix4, SMatrix, Vector2, Vector4};
use tracker_model::{
    ConstantVelocity2, CvNoise, Gaussian, LinearObservation, TransitionModel, Vec2, filter, smooth,
};

use crate::error::Error;
use crate::*;

/// Conditioning on the goal is the same as smoothing the free model with the goal as a
/// terminal measurement: every marginal mean and covariance must agree.
#[test]
fn goal_directed_prediction_equals_rts_smoothing() {
    let motion = ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q: 0.3 }).unwrap();
    let prior = Gaussian::new(
        Vector4::new(1.0, -2.0, 0.5, 0.2),
        Matrix4::from_diagonal(&Vector4::new(2.0, 3.0, 0.5, 0.4)),
    )
    .unwrap();
    let horizon = 12;
    for (h, value, pi) in [
        // Position-only goal.
        (
            Matrix2x4::identity(),
            Vector2::new(9.0, 4.0),
            Matrix2::new(0.5, 0.1, 0.1, 0.8),
        ),
    ] {
        let goal = Goal {
            observation: h,
            value,
            covariance: pi,
        };
        let f = motion.transition_matrix(1);
        let q = motion.process_noise(1);
        let gdt = GoalDirected::new(&vec![f; horizon], &vec![q; horizon], &goal, &prior).unwrap();
        let moments = gdt.predict();
        let sensor = LinearObservation::new(h, pi).unwrap();
        let mut zs: Vec<Option<Vector2<f64>>> = vec![None; horizon + 1];
        zs[horizon] = Some(value);
        let smoothed = smooth(&motion, &filter(&motion, &sensor, &prior, &zs).unwrap()).unwrap();
        for (t, (m, s)) in moments.iter().zip(&smoothed).enumerate() {
            assert!((m.mean - s.mean()).amax() < 1e-9, "mean at t = {t}");
            assert!(
                (m.covariance - s.covariance()).amax() < 1e-9,
                "covariance at t = {t}"
            );
        }
    }
}

#[test]
fn full_state_goal_with_time_varying_model_equals_smoothing() {
    // Time-varying A_t, Q_t: check by brute force with the joint Gaussian of (x_0..x_T).
    let horizon = 5;
    let a: Vec<SMatrix<f64, 2, 2>> = (0..horizon)
        .map(|t| SMatrix::<f64, 2, 2>::new(1.0, 0.5 + 0.1 * t as f64, 0.0, 0.9))
        .collect();
    let q: Vec<SMatrix<f64, 2, 2>> = (0..horizon)
        .map(|t| SMatrix::<f64, 2, 2>::new(0.2 + 0.05 * t as f64, 0.02, 0.02, 0.1))
        .collect();
    let prior = Gaussian::new(Vector2::new(0.5, 1.0), Matrix2::new(1.0, 0.2, 0.2, 0.5)).unwrap();
    let goal = Goal {
        observation: Matrix2::identity(),
        value: Vector2::new(3.0, -1.0),
        covariance: Matrix2::identity() * 0.3,
    };
    let moments = GoalDirected::new(&a, &q, &goal, &prior).unwrap().predict();
    // Joint moments of z = (x_0, …, x_T, y_T) from the free model, then condition on y_T.
    let dim = 2 * (horizon + 2);
    let mut mean = nalgebra::DVector::<f64>::zeros(dim);
    let mut cov = nalgebra::DMatrix::<f64>::zeros(dim, dim);
    // x_t = Φ(t,0) x_0 + Σ_{s≤t} Φ(t,s) w_s: cross-covariances via transition products.
    let phi =
        |t: usize, s: usize| (s..t).fold(SMatrix::<f64, 2, 2>::identity(), |acc, k| a[k] * acc);
    for t in 0..=horizon {
        mean.rows_mut(2 * t, 2)
            .copy_from(&(phi(t, 0) * prior.mean()));
        for u in 0..=horizon {
            let mut c = phi(t, 0) * prior.covariance() * phi(u, 0).transpose();
            for s in 1..=t.min(u) {
                c += phi(t, s) * q[s - 1] * phi(u, s).transpose();
            }
            cov.view_mut((2 * t, 2 * u), (2, 2)).copy_from(&c);
        }
    }
    let y = 2 * (horizon + 1);
    let last_mean = mean.rows(2 * horizon, 2).clone_owned();
    mean.rows_mut(y, 2).copy_from(&last_mean);
    for t in 0..=horizon {
        let c = cov.view((2 * t, 2 * horizon), (2, 2)).clone_owned();
        cov.view_mut((2 * t, y), (2, 2)).copy_from(&c);
        cov.view_mut((y, 2 * t), (2, 2)).copy_from(&c.transpose());
    }
    let xx = cov.view((2 * horizon, 2 * horizon), (2, 2)).clone_owned();
    cov.view_mut((y, y), (2, 2))
        .copy_from(&(xx + goal.covariance));
    let syy_inv = cov
        .view((y, y), (2, 2))
        .clone_owned()
        .try_inverse()
        .unwrap();
    for (t, moment) in moments.iter().enumerate() {
        let sxy = cov.view((2 * t, y), (2, 2)).clone_owned();
        let m = mean.rows(2 * t, 2) + &sxy * &syy_inv * (goal.value - mean.rows(y, 2));
        let c = cov.view((2 * t, 2 * t), (2, 2)) - &sxy * &syy_inv * sxy.transpose();
        assert!((moment.mean - m).amax() < 1e-10, "mean at t = {t}");
        assert!(
            (moment.covariance - c).amax() < 1e-10,
            "covariance at t = {t}"
        );
    }
}

#[test]
fn an_exact_goal_is_reached() {
    let motion = ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q: 1.0 }).unwrap();
    let prior = Gaussian::new(Vector4::zeros(), Matrix4::identity()).unwrap();
    let goal = Goal {
        observation: Matrix2x4::identity(),
        value: Vector2::new(50.0, -20.0),
        covariance: Matrix2::identity() * 1e-10,
    };
    let m = GoalDirected::new(
        &[motion.transition_matrix(1); 8],
        &[motion.process_noise(1); 8],
        &goal,
        &prior,
    )
    .unwrap()
    .predict();
    assert!((m[8].mean.fixed_rows::<2>(0) - goal.value).amax() < 1e-6);
    assert!(m[8].covariance[(0, 0)] < 1e-6);
    assert!(GoalDirected::<4>::new(&[], &[], &goal, &prior).is_err());
}

#[test]
fn baselines_by_hand() {
    assert_eq!(
        linear(&[0.0, 2.0], &[1.0, 5.0], &[0.5, 1.0]).unwrap(),
        vec![2.0, 3.0]
    );
    // Natural spline through (0,0), (1,1), (2,0): M_1 = −3, so S(0.5) = −3·0.125/6 + 1.5·0.5.
    let s = natural_cubic_spline(&[0.0, 1.0, 2.0], &[0.0, 1.0, 0.0], &[0.5, 1.0, 1.5]).unwrap();
    assert_relative_eq!(s[0], 0.6875, epsilon = 1e-12);
    assert_relative_eq!(s[1], 1.0, epsilon = 1e-12);
    assert_relative_eq!(s[2], 0.6875, epsilon = 1e-12);
    // A natural spline reproduces straight lines and interpolates its samples.
    let t = [0.0, 1.0, 2.5, 4.0, 7.0];
    let line: Vec<f64> = t.iter().map(|x| 3.0 - 2.0 * x).collect();
    let at = [0.3, 3.3, 6.0];
    for (got, x) in natural_cubic_spline(&t, &line, &at).unwrap().iter().zip(at) {
        assert_relative_eq!(*got, 3.0 - 2.0 * x, epsilon = 1e-12);
    }
    let wiggle = [0.0, 2.0, -1.0, 3.0, 0.5];
    assert!(
        natural_cubic_spline(&t, &wiggle, &t)
            .unwrap()
            .iter()
            .zip(wiggle)
            .all(|(a, b)| (a - b).abs() < 1e-12)
    );
    assert!(natural_cubic_spline(&[0.0, 0.0], &[1.0, 2.0], &[0.0]).is_err());
    assert!(linear(&[0.0], &[1.0], &[0.0]).is_err());
}

#[test]
fn least_squares_bspline_reproduces_a_cubic() {
    // A cubic polynomial lies in the spline space, so the fit is exact whatever the weights.
    let times: Vec<f64> = (0..10).chain(20..30).map(f64::from).collect();
    let cubic = |x: f64| 0.01 * x.powi(3) - 0.3 * x * x + 2.0 * x - 5.0;
    let values: Vec<f64> = times.iter().map(|&x| cubic(x)).collect();
    let weights: Vec<f64> = times.iter().map(|x| 1.0 + 0.1 * x).collect();
    let at: Vec<f64> = (10..20).map(f64::from).collect();
    let knots = gap_knots(&times, (9.0, 20.0), 2);
    assert_eq!(
        knots,
        [
            0.0, 0.0, 0.0, 0.0, 3.0, 6.0, 23.0, 26.0, 29.0, 29.0, 29.0, 29.0
        ]
    );
    let fit = lsq_bspline(&times, &values, &weights, &knots, &at).unwrap();
    for (got, x) in fit.iter().zip(at) {
        assert_relative_eq!(*got, cubic(x), epsilon = 1e-9);
    }
    assert!(lsq_bspline(&times, &values, &vec![0.0; times.len()], &knots, &[1.0]).is_err());
}

#[test]
fn gaps_on_a_straight_path_are_recovered_by_every_method() {
    let obs = |f: u32| Observation {
        frame: f,
        position: Vec2::new(3.0 * f64::from(f), 100.0 - 0.5 * f64::from(f)),
    };
    let a: Vec<Observation> = (0..15).map(obs).collect();
    let b: Vec<Observation> = (25..40).map(obs).collect();
    let gdt = recover_gdt(&a, &b, &default_model()).unwrap();
    assert_eq!(gdt.frames, (15..25).collect::<Vec<_>>());
    for (f, p) in gdt.frames.iter().zip(&gdt.positions) {
        assert!(
            (p - obs(*f).position).norm() < 0.5,
            "GDT at frame {f}: {p:?}"
        );
    }
    // Conditioning on the goal can only shrink the uncertainty of the free prediction from the
    // end of segment A (filtered with the prior recover_gdt documents).
    let cfg = GdtConfig::default();
    let motion =
        ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q: cfg.accel_psd }).unwrap();
    let sensor = tracker_model::position_measurement(cfg.measurement_variance).unwrap();
    let prior = Gaussian::new(
        Vector4::new(a[0].position.x, a[0].position.y, 0.0, 0.0),
        Matrix4::from_diagonal(&Vector4::new(
            cfg.measurement_variance,
            cfg.measurement_variance,
            cfg.initial_velocity_variance,
            cfg.initial_velocity_variance,
        )),
    )
    .unwrap();
    let zs: Vec<_> = a.iter().map(|o| Some(o.position)).collect();
    let start = filter(&motion, &sensor, &prior, &zs)
        .unwrap()
        .steps
        .last()
        .unwrap()
        .filtered
        .clone();
    for (k, c) in gdt.covariances.iter().enumerate() {
        let free = motion.predict_steps(&start, k as u32 + 1);
        assert!(
            c[(0, 0)] > 0.0 && c[(0, 0)] < free.covariance()[(0, 0)],
            "frame {}",
            gdt.frames[k]
        );
    }
    for method in [
        Baseline::Linear,
        Baseline::NaturalCubicSpline,
        Baseline::LeastSquaresBSpline(BSplineConfig::default()),
        Baseline::SmoothingSpline(GcvConfig::default()),
        Baseline::WindowCubic(WindowConfig::default()),
        Baseline::WindowBSpline(WindowConfig::default()),
    ] {
        let r = recover_baseline(&a, &b, &method).unwrap();
        for (f, p) in r.frames.iter().zip(&r.positions) {
            assert!(
                (p - obs(*f).position).norm() < 1e-6,
                "{method:?} at frame {f}"
            );
        }
    }
    assert!(recover_gdt(&b, &a, &default_model()).is_err());
    assert!(recover_gdt(&a, &[], &default_model()).is_err());
}

// ---------------------------------------------------------------------------------------------
// Segment linking

fn walker(x0: f64, y0: f64, vx: f64, vy: f64, frames: std::ops::Range<u32>) -> Vec<Observation> {
    frames
        .map(|f| Observation {
            frame: f,
            position: Vec2::new(x0 + vx * f64::from(f), y0 + vy * f64::from(f)),
        })
        .collect()
}

fn default_model() -> GdtModel {
    GdtConfig::default().check().unwrap()
}

fn link_config() -> LinkConfig {
    LinkConfig {
        model: GdtConfig::default(),
        max_gap_frames: 30,
        max_speed: 10.0,
        new_track_cost: 30.0,
    }
}

#[test]
fn crossing_walkers_are_linked_to_their_own_continuations() {
    // Two walkers cross during their gaps; each is seen in two segments.
    let segments = vec![
        walker(0.0, 0.0, 3.0, 2.0, 0..20),
        walker(0.0, 80.0, 3.0, -2.0, 0..20),
        walker(0.0, 80.0, 3.0, -2.0, 32..50),
        walker(0.0, 0.0, 3.0, 2.0, 30..50),
    ];
    let links = link_segments(&segments, &link_config().check().unwrap()).unwrap();
    let pairs: Vec<(usize, usize)> = links.iter().map(|l| (l.from, l.to)).collect();
    assert_eq!(pairs, vec![(0, 3), (1, 2)]);
}

#[test]
fn gating_drops_impossible_pairs() {
    let segments = vec![
        walker(0.0, 0.0, 1.0, 0.0, 0..10),
        walker(500.0, 0.0, 1.0, 0.0, 12..20),
        walker(9.0, 0.0, 1.0, 0.0, 100..110),
    ];
    let linking = link_config().check().unwrap();
    let costs = link_costs(&segments, &linking).unwrap();
    // 0 → 1 is too fast (491 px in 3 frames), 0 → 2 too late (91 frames); 1 → 2 too late.
    assert!(costs.is_empty(), "{costs:?}");
    assert!(link_segments(&segments, &linking).unwrap().is_empty());
    assert!(matches!(
        LinkConfig {
            max_speed: 0.0,
            ..link_config()
        }
        .check(),
        Err(Error::Model(tracker_model::Error::InvalidParameter {
            name: "max_speed",
            ..
        }))
    ));
}

#[test]
fn linking_is_the_optimal_assignment() {
    // Segments of three walkers in several pieces; brute force over every one-to-one set of
    // gated links must not beat the assignment.
    let segments = vec![
        walker(0.0, 0.0, 2.0, 1.0, 0..10),
        walker(10.0, 30.0, 2.0, 0.0, 0..10),
        walker(5.0, 15.0, 2.0, 0.5, 0..10),
        walker(0.0, 0.0, 2.0, 1.0, 14..20),
        walker(10.0, 30.0, 2.0, 0.0, 13..20),
        walker(5.0, 15.0, 2.1, 0.5, 15..25),
    ];
    let cfg = link_config();
    let linking = cfg.check().unwrap();
    let costs = link_costs(&segments, &linking).unwrap();
    let weight = |c: f64| (cfg.new_track_cost - c).max(0.0);
    fn best(
        costs: &[(usize, usize, f64)],
        k: usize,
        used_from: u32,
        used_to: u32,
        w: &dyn Fn(f64) -> f64,
    ) -> f64 {
        if k == costs.len() {
            return 0.0;
        }
        let skip = best(costs, k + 1, used_from, used_to, w);
        let (i, j, c) = costs[k];
        if used_from & (1 << i) != 0 || used_to & (1 << j) != 0 {
            return skip;
        }
        skip.max(w(c) + best(costs, k + 1, used_from | (1 << i), used_to | (1 << j), w))
    }
    let optimum = best(&costs, 0, 0, 0, &weight);
    let chosen: f64 = link_segments(&segments, &linking)
        .unwrap()
        .iter()
        .map(|l| weight(l.cost))
        .sum();
    assert!(optimum > 0.0);
    assert!(
        (chosen - optimum).abs() < 1e-9,
        "assignment {chosen} vs brute force {optimum}"
    );
}

// ---------------------------------------------------------------------------------------------
// The mask protocol

#[test]
fn mask_crossings_become_gaps_by_oh_and_jungs_rules() {
    use tracker_model::{Region2, Track, TrackId, TrackPoint, TrackSet};
    let track = |id: u64, xs: &[f64]| {
        Track::from_points(
            TrackId(id),
            xs.iter()
                .enumerate()
                .map(|(f, &x)| TrackPoint::at(f as u32, Vec2::new(x, 5.0)))
                .collect(),
        )
        .unwrap()
    };
    let mask = Region2::new(Vector2::new(10.0, 0.0), Vector2::new(20.0, 10.0)).unwrap();
    let truth = TrackSet::from_tracks(vec![
        // Crosses twice: out, in, out, in, out → two gaps.
        track(1, &[0.0, 5.0, 12.0, 15.0, 25.0, 30.0, 18.0, 26.0]),
        // Starts inside: no gap for that run.
        track(2, &[12.0, 15.0, 25.0, 30.0]),
        // Ends inside: no gap.
        track(3, &[0.0, 5.0, 12.0]),
        // Never enters.
        track(4, &[0.0, 1.0, 2.0]),
    ])
    .unwrap();
    let gaps = gaps_from_mask(&truth, &mask);
    assert_eq!(gaps.len(), 2);
    assert_eq!((gaps[0].truth_id, gaps[0].crossing), (TrackId(1), 0));
    assert_eq!(
        gaps[0].hidden.iter().map(|o| o.frame).collect::<Vec<_>>(),
        vec![2, 3]
    );
    assert_eq!(gaps[0].before.len(), 2);
    assert_eq!(
        gaps[0].after.iter().map(|o| o.frame).collect::<Vec<_>>(),
        vec![4, 5]
    );
    assert_eq!(
        (gaps[1].crossing, gaps[1].hidden.len(), gaps[1].after.len()),
        (1, 1, 1)
    );
    assert_eq!(
        gaps[1].before.iter().map(|o| o.frame).collect::<Vec<_>>(),
        vec![4, 5]
    );
}

#[test]
fn degenerate_inputs_are_clear_errors() {
    let a = walker(0.0, 0.0, 1.0, 0.0, 0..10);
    // A gap of zero length: B starts right after A.
    let b = walker(0.0, 0.0, 1.0, 0.0, 10..20);
    assert_eq!(
        recover_gdt(&a, &b, &default_model()),
        Err(Error::NoGap {
            last_a: 9,
            first_b: 10
        })
    );
    // A segment too short for the filter.
    let one = walker(0.0, 0.0, 1.0, 0.0, 0..1);
    let later = walker(0.0, 0.0, 1.0, 0.0, 15..20);
    assert_eq!(
        recover_gdt(&one, &later, &default_model()),
        Err(Error::SegmentTooShort { len: 1, min: 2 })
    );
    // A singular goal covariance Π_T.
    let motion = ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q: 1.0 }).unwrap();
    let prior = Gaussian::new(Vector4::zeros(), Matrix4::identity()).unwrap();
    let goal = Goal {
        observation: Matrix2x4::identity(),
        value: Vector2::new(1.0, 1.0),
        covariance: Matrix2::new(1.0, 1.0, 1.0, 1.0),
    };
    let r = GoalDirected::new(
        &[motion.transition_matrix(1); 3],
        &[motion.process_noise(1); 3],
        &goal,
        &prior,
    );
    assert!(matches!(
        r,
        Err(Error::Model(
            tracker_model::Error::NotPositiveDefinite { .. }
        ))
    ));
    // A NaN observation.
    let mut bad = later.clone();
    bad[2].position.x = f64::NAN;
    assert_eq!(
        recover_gdt(&a, &bad, &default_model()),
        Err(Error::NonFiniteObservation { frame: 17 })
    );
    // Frames out of order, in either segment and for either form.
    let mut shuffled = later.clone();
    // Frames 15, 18, 17, 16, 19.
    shuffled.swap(1, 3);
    assert_eq!(
        recover_gdt(&a, &shuffled, &default_model()),
        Err(Error::FramesOutOfOrder {
            frame: 17,
            last: 18
        })
    );
    assert_eq!(
        recover_gdt_goal_state(&a, &shuffled, &default_model()),
        Err(Error::FramesOutOfOrder {
            frame: 17,
            last: 18
        })
    );
    assert_eq!(
        recover_gdt(
            &shuffled,
            &walker(0.0, 0.0, 1.0, 0.0, 40..45),
            &default_model()
        ),
        Err(Error::FramesOutOfOrder {
            frame: 17,
            last: 18
        })
    );
    // Baseline samples.
    assert_eq!(
        linear(&[0.0, 1.0], &[1.0], &[0.5]),
        Err(Error::LengthMismatch {
            what: "values",
            n_times: 2,
            len: 1
        })
    );
    assert!(matches!(
        natural_cubic_spline(&[0.0], &[1.0], &[0.5]),
        Err(Error::TooFewSamples { len: 1, min: 2, .. })
    ));
    assert!(matches!(
        linear(&[0.0, f64::NAN], &[1.0, 2.0], &[0.5]),
        Err(Error::NonFiniteSample { index: 1, .. })
    ));
    assert_eq!(
        linear(&[1.0, 0.0], &[1.0, 2.0], &[0.5]),
        Err(Error::TimesOutOfOrder {
            time: 0.0,
            last: 1.0
        })
    );
}

#[test]
fn noise_free_constant_velocity_is_recovered_exactly() {
    // With almost noise-free measurements, a vague velocity prior and no process noise, the
    // filtered end state is the true state and the goal-conditioned mean is the true line.
    let a = walker(10.0, 20.0, 2.5, -1.5, 0..12);
    let b = walker(10.0, 20.0, 2.5, -1.5, 30..40);
    let cfg = GdtConfig {
        accel_psd: 1e-12,
        measurement_variance: 1e-10,
        initial_velocity_variance: 1e6,
    };
    let model = cfg.check().unwrap();
    let gdt = recover_gdt(&a, &b, &model).unwrap();
    let goal_state = recover_gdt_goal_state(&a, &b, &model).unwrap();
    let lin = recover_baseline(&a, &b, &Baseline::Linear).unwrap();
    for (k, f) in gdt.frames.iter().enumerate() {
        let truth = Vec2::new(10.0 + 2.5 * f64::from(*f), 20.0 - 1.5 * f64::from(*f));
        assert!((gdt.positions[k] - truth).norm() < 1e-6, "GDT at frame {f}");
        assert!(
            (goal_state.positions[k] - truth).norm() < 1e-6,
            "GDT goal state at frame {f}"
        );
        assert!(
            (lin.positions[k] - truth).norm() < 1e-9,
            "linear at frame {f}"
        );
    }
}

#[test]
fn oh_and_jungs_special_forms_agree_with_the_general_form() {
    let a: Vec<SMatrix<f64, 2, 2>> = (0..6)
        .map(|t| SMatrix::<f64, 2, 2>::new(1.0, 0.3 + 0.05 * t as f64, -0.1, 0.95))
        .collect();
    let q: Vec<SMatrix<f64, 2, 2>> = (0..6)
        .map(|t| SMatrix::<f64, 2, 2>::new(0.3, 0.05, 0.05, 0.2 + 0.01 * t as f64))
        .collect();
    let prior = Gaussian::new(Vector2::new(0.2, -0.4), Matrix2::new(0.8, 0.1, 0.1, 0.6)).unwrap();
    let close = |x: &GoalDirected<2>, y: &GoalDirected<2>| {
        let (mx, my) = (x.predict(), y.predict());
        mx.iter().zip(&my).all(|(p, q)| {
            (p.mean - q.mean).amax() < 1e-9 && (p.covariance - q.covariance).amax() < 1e-9
        })
    };
    // Invertible H (eqs. 11-15): exactly the general form.
    let goal = Goal {
        observation: Matrix2::new(2.0, 0.5, -0.3, 1.5),
        value: Vector2::new(4.0, 1.0),
        covariance: Matrix2::new(0.4, 0.1, 0.1, 0.3),
    };
    assert!(close(
        &GoalDirected::new(&a, &q, &goal, &prior).unwrap(),
        &GoalDirected::pseudo_inverse_form(&a, &q, &goal, &prior).unwrap()
    ));
    // Pseudo-inverse (eqs. 16-18), three readings of a 2-D state, Π = σ² I: exact.
    let h = SMatrix::<f64, 3, 2>::new(1.0, 0.0, 0.0, 1.0, 1.0, 1.0);
    let tall = Goal {
        observation: h,
        value: nalgebra::Vector3::new(3.0, 1.0, 4.2),
        covariance: nalgebra::Matrix3::identity() * 0.5,
    };
    assert!(close(
        &GoalDirected::new(&a, &q, &tall, &prior).unwrap(),
        &GoalDirected::pseudo_inverse_form(&a, &q, &tall, &prior).unwrap()
    ));
    // With correlated Π it is Oh & Jung's approximation and differs.
    let skew = Goal {
        covariance: nalgebra::Matrix3::new(0.5, 0.4, 0.0, 0.4, 0.5, 0.0, 0.0, 0.0, 2.0),
        ..tall
    };
    assert!(!close(
        &GoalDirected::new(&a, &q, &skew, &prior).unwrap(),
        &GoalDirected::pseudo_inverse_form(&a, &q, &skew, &prior).unwrap()
    ));
    // A position-only goal on a 4-D state has a singular HᵀH: the pseudo-inverse form refuses it.
    let motion = ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q: 1.0 }).unwrap();
    let p4 = Gaussian::new(Vector4::zeros(), Matrix4::identity()).unwrap();
    let pos = Goal {
        observation: Matrix2x4::identity(),
        value: Vector2::new(1.0, 1.0),
        covariance: Matrix2::identity(),
    };
    assert!(
        GoalDirected::pseudo_inverse_form(
            &[motion.transition_matrix(1); 3],
            &[motion.process_noise(1); 3],
            &pos,
            &p4
        )
        .is_err()
    );
}

#[test]
fn settings_are_checked_once_and_name_the_bad_field() {
    let name = |r: Result<()>| match r {
        Err(Error::Model(tracker_model::Error::InvalidParameter { name, .. })) => name,
        other => panic!("expected an invalid parameter, got {other:?}"),
    };
    let gdt = |c: GdtConfig| name(c.check().map(|_| ()));
    assert_eq!(
        gdt(GdtConfig {
            accel_psd: -1.0,
            ..GdtConfig::default()
        }),
        "accel_psd"
    );
    assert_eq!(
        gdt(GdtConfig {
            measurement_variance: 0.0,
            ..GdtConfig::default()
        }),
        "measurement_variance"
    );
    assert_eq!(
        gdt(GdtConfig {
            initial_velocity_variance: f64::NAN,
            ..GdtConfig::default()
        }),
        "initial_velocity_variance"
    );
    // No process noise is a valid (deterministic) motion model.
    assert!(
        GdtConfig {
            accel_psd: 0.0,
            ..GdtConfig::default()
        }
        .check()
        .is_ok()
    );
    let link = |c: LinkConfig| name(c.check().map(|_| ()));
    assert_eq!(
        link(LinkConfig {
            max_gap_frames: 0,
            ..link_config()
        }),
        "max_gap_frames"
    );
    assert_eq!(
        link(LinkConfig {
            new_track_cost: f64::INFINITY,
            ..link_config()
        }),
        "new_track_cost"
    );
    assert_eq!(
        link(LinkConfig {
            model: GdtConfig {
                measurement_variance: -4.0,
                ..GdtConfig::default()
            },
            ..link_config()
        }),
        "measurement_variance"
    );
    let checked = link_config().check().unwrap();
    assert_eq!(*checked.config(), link_config());
    assert_eq!(*checked.model().config(), GdtConfig::default());
}

// ---------------------------------------------------------------------------------------------
// Least-squares B-spline: against a dense QR fit on an independently computed basis

/// Cox-de Boor over the whole knot vector: every cubic basis function at `x` (the recursion of
/// de Boor 1978 on all functions at once, unlike the four-function one the crate uses).
fn dense_basis(knots: &[f64], x: f64) -> Vec<f64> {
    let last = knots.len() - 1;
    let span = if x >= knots[last] {
        (0..last).rev().find(|&i| knots[i] < knots[i + 1])
    } else {
        (0..last).rev().find(|&i| knots[i] <= x && x < knots[i + 1])
    };
    let mut b = vec![0.0; last];
    if let Some(i) = span {
        b[i] = 1.0;
    }
    for degree in 1..=3 {
        for i in 0..last - degree {
            let (ld, rd) = (
                knots[i + degree] - knots[i],
                knots[i + degree + 1] - knots[i + 1],
            );
            let left = if ld > 0.0 {
                (x - knots[i]) / ld * b[i]
            } else {
                0.0
            };
            let right = if rd > 0.0 {
                (knots[i + degree + 1] - x) / rd * b[i + 1]
            } else {
                0.0
            };
            b[i] = left + right;
        }
    }
    b.truncate(knots.len() - 4);
    b
}

#[test]
fn banded_least_squares_bspline_equals_a_dense_qr_fit() {
    use nalgebra::{DMatrix, DVector};
    // Uneven samples, uneven weights, a double interior knot.
    let times: Vec<f64> = (0..60)
        .map(|i| f64::from(i) + 0.3 * f64::from(i % 3))
        .collect();
    let values: Vec<f64> = times
        .iter()
        .map(|t| (0.2 * t).sin() * 10.0 + 0.05 * t * t)
        .collect();
    let weights: Vec<f64> = (0..60).map(|i| 0.5 + f64::from(i % 5) * 0.3).collect();
    let (t0, t1) = (times[0], times[59]);
    let mut knots = vec![t0; 4];
    knots.extend([7.0, 15.5, 15.5, 30.0, 41.0, 50.0]);
    knots.extend([t1; 4]);
    let n_basis = knots.len() - 4;
    let design = DMatrix::from_fn(times.len(), n_basis, |r, c| {
        weights[r] * dense_basis(&knots, times[r])[c]
    });
    let rhs = DVector::from_iterator(60, values.iter().zip(&weights).map(|(v, w)| v * w));
    let qr = design.qr();
    let dense = qr
        .r()
        .solve_upper_triangular(&(qr.q().transpose() * rhs))
        .unwrap();
    let spline = BSpline::fit_lsq(&times, &values, &weights, &knots).unwrap();
    for (got, want) in spline.coefficients().iter().zip(dense.iter()) {
        assert_relative_eq!(*got, *want, epsilon = 1e-8, max_relative = 1e-9);
    }
    for x in [0.0, 3.3, 15.5, 29.9, 44.0, t1] {
        let want: f64 = dense_basis(&knots, x)
            .iter()
            .zip(dense.iter())
            .map(|(b, c)| b * c)
            .sum();
        assert_relative_eq!(spline.value(x), want, epsilon = 1e-8);
    }
}

#[test]
fn bspline_fits_that_the_data_cannot_determine_are_typed_errors() {
    let times: Vec<f64> = (0..10).chain(20..30).map(f64::from).collect();
    let values = vec![1.0; 20];
    let ones = vec![1.0; 20];
    // Five knots inside the empty stretch (10, 20): B_4 lives on [11, 15], without data.
    let knots = [
        0.0, 0.0, 0.0, 0.0, 11.0, 12.0, 13.0, 14.0, 15.0, 29.0, 29.0, 29.0, 29.0,
    ];
    assert_eq!(
        BSpline::fit_lsq(&times, &values, &ones, &knots),
        Err(Error::RankDeficientFit)
    );
    // A sample outside the base interval.
    let short = [0.0, 0.0, 0.0, 0.0, 25.0, 25.0, 25.0, 25.0];
    assert_eq!(
        BSpline::fit_lsq(&times, &values, &ones, &short),
        Err(Error::SampleOutsideKnots {
            time: 26.0,
            lower: 0.0,
            upper: 25.0
        })
    );
    let invalid = |knots: &[f64]| {
        matches!(
            BSpline::fit_lsq(&times, &values, &ones, knots),
            Err(Error::Model(tracker_model::Error::InvalidParameter {
                name: "knots",
                ..
            }))
        )
    };
    assert!(invalid(&[0.0, 0.0, 0.0, 29.0, 29.0, 29.0]));
    assert!(invalid(&[0.0, 0.0, 0.0, 0.0, 0.0, 29.0, 29.0, 29.0, 29.0]));
    assert!(invalid(&[
        0.0, 0.0, 0.0, 0.0, 20.0, 10.0, 29.0, 29.0, 29.0, 29.0
    ]));
    assert!(invalid(&[
        0.0,
        0.0,
        0.0,
        0.0,
        f64::NAN,
        29.0,
        29.0,
        29.0,
        29.0
    ]));
    // Fewer samples than coefficients.
    assert!(matches!(
        BSpline::fit_lsq(
            &times[..3],
            &values[..3],
            &ones[..3],
            &[0.0, 0.0, 0.0, 0.0, 2.0, 2.0, 2.0, 2.0]
        ),
        Err(Error::TooFewSamples { len: 3, min: 4, .. })
    ));
}

// ---------------------------------------------------------------------------------------------
// Smoothing spline

/// The smoothing spline by dense linear algebra (Green & Silverman 1994, Theorem 2.1):
/// K = Q R⁻¹ Qᵀ, A(λ) = (I + λK)⁻¹, fitted g = A y; returns (g, tr A, GCV).
fn dense_smoothing(times: &[f64], y: &[f64], lambda: f64) -> (Vec<f64>, f64, f64) {
    use nalgebra::{DMatrix, DVector};
    let n = times.len();
    let h: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let mut q = DMatrix::zeros(n, n - 2);
    let mut r = DMatrix::zeros(n - 2, n - 2);
    for j in 1..n - 1 {
        let c = j - 1;
        q[(j - 1, c)] = 1.0 / h[j - 1];
        q[(j, c)] = -1.0 / h[j - 1] - 1.0 / h[j];
        q[(j + 1, c)] = 1.0 / h[j];
        r[(c, c)] = (h[j - 1] + h[j]) / 3.0;
        if c + 1 < n - 2 {
            r[(c, c + 1)] = h[j] / 6.0;
            r[(c + 1, c)] = h[j] / 6.0;
        }
    }
    let k = &q * r.try_inverse().unwrap() * q.transpose();
    let a = (DMatrix::identity(n, n) + k * lambda)
        .try_inverse()
        .unwrap();
    let g = &a * DVector::from_column_slice(y);
    let rss: f64 = g.iter().zip(y).map(|(g, y)| (g - y).powi(2)).sum();
    let tr = a.trace();
    let nf = n as f64;
    (
        g.iter().copied().collect(),
        tr,
        nf * rss / (nf - tr).powi(2),
    )
}

#[test]
fn smoothing_spline_equals_the_dense_solution_and_its_gcv() {
    let times = [0.0, 1.0, 2.5, 3.0, 4.5, 6.0, 7.0];
    let y = [1.0, 2.2, 1.9, 3.5, 2.8, 4.1, 3.9];
    for lambda in [1e-3, 0.1, 1.0, 30.0] {
        let s = SmoothingSpline::fit(&times, &y, lambda).unwrap();
        let (g, tr, gcv) = dense_smoothing(&times, &y, lambda);
        for (got, want) in s.fitted().iter().zip(&g) {
            assert_relative_eq!(*got, *want, epsilon = 1e-10);
        }
        assert_relative_eq!(s.edf(), tr, epsilon = 1e-10);
        assert_relative_eq!(s.gcv(), gcv, max_relative = 1e-9);
        // The spline passes through its fitted values.
        for (t, g) in times.iter().zip(s.fitted()) {
            assert_relative_eq!(s.value(*t), *g, epsilon = 1e-12);
        }
    }
    // The GCV choice is at least as good as any λ on a fine brute-force grid, on data with a
    // curve and noise (so the optimum is inside the range; the dense route loses accuracy
    // for λ/h³ beyond ≈ 10⁶, so the grid stops there).
    let times: Vec<f64> = (0..16)
        .map(|i| f64::from(i) + 0.3 * f64::from(i % 3))
        .collect();
    let y: Vec<f64> = (0..16)
        .map(|i| 3.0 * (0.5 * times[i]).sin() + 0.4 * (f64::from((i as u32 * 7) % 5) - 2.0))
        .collect();
    let chosen = SmoothingSpline::fit_gcv(&times, &y, &GcvConfig::default()).unwrap();
    let h = (times[15] - times[0]) / 15.0;
    let grid_best = (0..=1000)
        .map(|k| {
            dense_smoothing(
                &times,
                &y,
                h.powi(3) * 10f64.powf(-4.0 + 0.01 * f64::from(k)),
            )
            .2
        })
        .fold(f64::INFINITY, f64::min);
    assert!(
        chosen.edf() > 3.0 && chosen.edf() < 14.0,
        "edf {}",
        chosen.edf()
    );
    assert!(
        chosen.gcv() <= grid_best * (1.0 + 1e-9),
        "GCV {} at λ = {} against the grid's {grid_best}",
        chosen.gcv(),
        chosen.lambda()
    );
    assert!(chosen.gcv() >= grid_best * (1.0 - 1e-4));
}

#[test]
fn smoothing_spline_limits_are_interpolation_and_the_least_squares_line() {
    let times: Vec<f64> = (0..12)
        .map(|i| f64::from(i) * 1.5 + 0.2 * f64::from(i % 2))
        .collect();
    let y: Vec<f64> = times.iter().map(|t| (t * 0.7).sin() + 0.1 * t).collect();
    let at = [0.4, 3.1, 7.7, 12.0, 16.5];
    // λ = 0: the natural interpolating spline.
    let s = SmoothingSpline::fit(&times, &y, 0.0).unwrap();
    let natural = natural_cubic_spline(&times, &y, &at).unwrap();
    for (x, want) in at.iter().zip(&natural) {
        assert_relative_eq!(s.value(*x), *want, epsilon = 1e-10);
    }
    assert_relative_eq!(s.edf(), 12.0, epsilon = 1e-9);
    // λ → ∞: the least-squares line, in closed form.
    let n = times.len() as f64;
    let (mt, my) = (times.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let slope = times
        .iter()
        .zip(&y)
        .map(|(t, v)| (t - mt) * (v - my))
        .sum::<f64>()
        / times.iter().map(|t| (t - mt).powi(2)).sum::<f64>();
    let s = SmoothingSpline::fit(&times, &y, 1e12).unwrap();
    for x in at {
        assert_relative_eq!(s.value(x), my + slope * (x - mt), epsilon = 1e-5);
    }
    assert_relative_eq!(s.edf(), 2.0, epsilon = 1e-5);
    assert!(matches!(
        SmoothingSpline::fit(&times, &y, -1.0),
        Err(Error::Model(tracker_model::Error::InvalidParameter {
            name: "lambda",
            ..
        }))
    ));
    assert!(matches!(
        SmoothingSpline::fit(&times[..2], &y[..2], 1.0),
        Err(Error::TooFewSamples { min: 3, .. })
    ));
}

// ---------------------------------------------------------------------------------------------
// Window fits: n by cross-validation on the observations

#[test]
fn window_fits_choose_a_window_that_avoids_a_bend_seen_only_in_the_observations() {
    // Straight for the 10 frames next to the gap on each side, wildly curved beyond: the
    // held-out observations next to the gap expose a wide window, so cross-validation picks
    // a narrow one, and a narrow window recovers the straight path exactly.
    let line = |f: f64| Vec2::new(2.0 * f - 7.0, 0.5 * f + 3.0);
    let pos = |f: u32| {
        let x = f64::from(f);
        let bend = if (30..60).contains(&f) {
            0.0
        } else {
            40.0 * ((x - 45.0) / 8.0).sin()
        };
        line(x) + Vec2::new(bend, -bend)
    };
    let obs = |f: u32| Observation {
        frame: f,
        position: pos(f),
    };
    let a: Vec<Observation> = (0..40).map(obs).collect();
    let b: Vec<Observation> = (50..90).map(obs).collect();
    for method in [
        Baseline::WindowCubic(WindowConfig::default()),
        Baseline::WindowBSpline(WindowConfig::default()),
    ] {
        let r = recover_baseline(&a, &b, &method).unwrap();
        assert_eq!(r.frames, (40..50).collect::<Vec<_>>());
        for (f, p) in r.frames.iter().zip(&r.positions) {
            assert!(
                (p - line(f64::from(*f))).norm() < 1e-6,
                "{method:?} at frame {f}: {p:?}"
            );
        }
        // Forced to the widest window, the same fit misses the path.
        let wide = match &method {
            Baseline::WindowCubic(_) => Baseline::WindowCubic(WindowConfig {
                candidates: vec![40],
            }),
            _ => Baseline::WindowBSpline(WindowConfig {
                candidates: vec![40],
            }),
        };
        let r = recover_baseline(&a, &b, &wide).unwrap();
        assert!((r.positions[5] - line(45.0)).norm() > 1.0, "{wide:?}");
    }
    // A window B-spline reproduces a cubic path whatever n.
    let cubic = |f: f64| Vec2::new(0.001 * f.powi(3) - 0.1 * f * f + f, 0.002 * f.powi(3));
    let cobs = |f: u32| Observation {
        frame: f,
        position: cubic(f64::from(f)),
    };
    let a: Vec<Observation> = (0..30).map(cobs).collect();
    let b: Vec<Observation> = (45..70).map(cobs).collect();
    let r = recover_baseline(&a, &b, &Baseline::WindowBSpline(WindowConfig::default())).unwrap();
    for (f, p) in r.frames.iter().zip(&r.positions) {
        assert!((p - cubic(f64::from(*f))).norm() < 1e-6, "frame {f}");
    }
    assert!(matches!(
        recover_baseline(
            &a,
            &b,
            &Baseline::WindowBSpline(WindowConfig {
                candidates: vec![2]
            })
        ),
        Err(Error::Model(tracker_model::Error::InvalidParameter {
            name: "candidates",
            ..
        }))
    ));
}

// ---------------------------------------------------------------------------------------------
// Noise estimation

/// A constant-velocity walk with white-acceleration density `q` observed with variance `r`.
fn simulate_cv(q: f64, r: f64, frames: std::ops::Range<u32>, seed: u64) -> Vec<Observation> {
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let motion = ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q }).unwrap();
    let chol = motion.process_noise(1).cholesky().unwrap();
    let mut x = Vector4::new(100.0, 50.0, 2.0, -1.0);
    let mut out = Vec::new();
    for frame in frames {
        let z: Vector2<f64> = Vector2::from_fn(|_, _| StandardNormal.sample(&mut rng));
        out.push(Observation {
            frame,
            position: Vector2::new(x[0], x[1]) + z * r.sqrt(),
        });
        let w: Vector4<f64> = Vector4::from_fn(|_, _| StandardNormal.sample(&mut rng));
        x = motion.transition_matrix(1) * x + chol.l() * w;
    }
    out
}

#[test]
fn noise_likelihood_is_the_kalman_filters() {
    // Against tracker-model's filter run frame by frame, with missing frames as None.
    let mut seg = simulate_cv(0.05, 2.0, 0..40, 1);
    seg.retain(|o| o.frame % 7 != 3);
    let cfg = GdtConfig {
        accel_psd: 0.05,
        measurement_variance: 2.0,
        initial_velocity_variance: 25.0,
    };
    let model = cfg.check().unwrap();
    let first = seg[0];
    let prior = Gaussian::new(
        Vector4::new(first.position.x, first.position.y, 0.0, 0.0),
        Matrix4::from_diagonal(&Vector4::new(2.0, 2.0, 25.0, 25.0)),
    )
    .unwrap();
    let mut zs = vec![None; 40];
    for o in &seg {
        zs[o.frame as usize] = Some(o.position);
    }
    let run = filter(model.motion(), model.sensor(), &prior, &zs).unwrap();
    // Without the first observation's term, which only places the prior.
    let want = run.log_likelihood() - run.steps[0].log_likelihood.unwrap();
    let got = noise_log_likelihood(&[&seg], 2.0, 0.05, 25.0).unwrap();
    assert_relative_eq!(got, want, max_relative = 1e-10);
}

#[test]
fn noise_is_estimated_by_maximum_likelihood() {
    let (q, r) = (0.05, 2.0);
    let a = simulate_cv(q, r, 0..600, 7);
    let b = simulate_cv(q, r, 700..1300, 8);
    let est = estimate_noise(&[&a, &b], &NoiseSearch::default()).unwrap();
    // 1200 observations: the variance's standard error is ≈ r·√(2/2400)·(a few, for the
    // correlation with q) ≈ 10 %; q's is larger. Tolerances of ≈ 3 standard errors.
    let (r_hat, q_hat) = (est.config.measurement_variance, est.config.accel_psd);
    assert!((r_hat / r - 1.0).abs() < 0.2, "r̂ = {r_hat}");
    assert!((q_hat / q).ln().abs() < 0.5, "q̂ = {q_hat}");
    // No point of a brute-force grid around it has a higher likelihood.
    let mut grid_best = f64::NEG_INFINITY;
    for i in 0..=20 {
        for j in 0..=20 {
            let rr = r * 10f64.powf(-0.3 + 0.03 * f64::from(i));
            let qq = q * 10f64.powf(-0.6 + 0.06 * f64::from(j));
            grid_best = grid_best.max(noise_log_likelihood(&[&a, &b], rr, qq, 25.0).unwrap());
        }
    }
    assert!(
        est.log_likelihood >= grid_best - 1e-6,
        "{} < {grid_best}",
        est.log_likelihood
    );
    assert!(matches!(
        estimate_noise(
            &[&a],
            &NoiseSearch {
                accel_psd_range: [1.0, 0.1],
                ..NoiseSearch::default()
            }
        ),
        Err(Error::Model(tracker_model::Error::InvalidParameter {
            name: "accel_psd_range",
            ..
        }))
    ));
    assert_eq!(
        estimate_noise(&[&a[..1]], &NoiseSearch::default()),
        Err(Error::SegmentTooShort { len: 1, min: 2 })
    );
}

// ---------------------------------------------------------------------------------------------
// Frame numbers at the ends of u32

#[test]
fn frames_near_u32_max_are_typed_errors_or_correct_results() {
    let model = default_model();
    let obs = |frame: u32, x: f64| Observation {
        frame,
        position: Vec2::new(x, 0.0),
    };
    // B's frames decrease: the goal-state form must not reverse time by subtraction first.
    let a = [obs(0, 0.0), obs(1, 1.0)];
    let b_down = [obs(20, 20.0), obs(10, 10.0)];
    assert_eq!(
        recover_gdt_goal_state(&a, &b_down, &model),
        Err(Error::FramesOutOfOrder {
            frame: 10,
            last: 20
        })
    );
    // A ends at u32::MAX: nothing can follow (`last + 1` would overflow).
    let at_end = [obs(u32::MAX - 1, 0.0), obs(u32::MAX, 1.0)];
    let b = [obs(5, 0.0), obs(6, 1.0)];
    let no_gap = Err(Error::NoGap {
        last_a: u32::MAX,
        first_b: 5,
    });
    assert_eq!(recover_gdt(&at_end, &b, &model), no_gap);
    assert_eq!(recover_baseline(&at_end, &b, &Baseline::Linear), no_gap);
    // A segment spanning all of u32 and a four-frame gap at the very end: A's filter steps
    // over the span in one prediction instead of allocating a slot per frame.
    let wide = [obs(0, 0.0), obs(1, 1.0), obs(u32::MAX - 10, 2.0)];
    let end = [obs(u32::MAX - 5, 3.0), obs(u32::MAX, 4.0)];
    let gap = recover_gdt(&wide, &end, &model).unwrap();
    assert_eq!(gap.frames, (u32::MAX - 9..u32::MAX - 5).collect::<Vec<_>>());
    assert!(recover_gdt_goal_state(&wide, &end, &model).is_ok());
    // A gap of ≈ 4·10⁹ frames is refused, not allocated.
    let far = [obs(u32::MAX - 1, 0.0), obs(u32::MAX, 1.0)];
    let too_long = Err(Error::GapTooLong {
        frames: u64::from(u32::MAX - 3),
        max: MAX_GAP_FRAMES,
    });
    assert_eq!(recover_gdt(&a, &far, &model), too_long);
    assert_eq!(
        recover_baseline(&a, &far, &Baseline::NaturalCubicSpline),
        too_long
    );
    // Linking segments that span the whole frame range costs no memory per frame.
    let linking = LinkConfig {
        max_gap_frames: u32::MAX,
        max_speed: 10.0,
        ..link_config()
    }
    .check()
    .unwrap();
    let costs = link_costs(&[wide.to_vec(), end.to_vec()], &linking).unwrap();
    assert_eq!(costs.len(), 1);
    assert_eq!((costs[0].0, costs[0].1), (0, 1));
    // A truth track at the last frames of u32 crossing a mask.
    use tracker_model::{Region2, Track, TrackId, TrackPoint, TrackSet};
    let xs = [0.0, 5.0, 12.0, 15.0, 25.0];
    let track = Track::from_points(
        TrackId(1),
        xs.iter()
            .enumerate()
            .map(|(k, &x)| TrackPoint::at(u32::MAX - 4 + k as u32, Vec2::new(x, 5.0)))
            .collect(),
    )
    .unwrap();
    let mask = Region2::new(Vector2::new(10.0, 0.0), Vector2::new(20.0, 10.0)).unwrap();
    let gaps = gaps_from_mask(&TrackSet::from_tracks(vec![track]).unwrap(), &mask);
    assert_eq!(gaps.len(), 1);
    assert_eq!(gaps[0].after[0].frame, u32::MAX);
}

// ---------------------------------------------------------------------------------------------
// A peer's output: SciPy 1.17.1 on the same data (docs/comparisons has the timing script; these
// values were printed by `make_lsq_spline`, `make_smoothing_spline(lam=…)` and
// `CubicSpline(bc_type='natural')`).

#[test]
fn splines_agree_with_scipy() {
    // make_lsq_spline(times, values, knots, k=3, w=weights) on the data of the dense-QR test.
    let times: Vec<f64> = (0..60)
        .map(|i| f64::from(i) + 0.3 * f64::from(i % 3))
        .collect();
    let values: Vec<f64> = times
        .iter()
        .map(|t| (0.2 * t).sin() * 10.0 + 0.05 * t * t)
        .collect();
    let weights: Vec<f64> = (0..60).map(|i| 0.5 + f64::from(i % 5) * 0.3).collect();
    let t1 = times[59];
    let mut knots = vec![0.0; 4];
    knots.extend([7.0, 15.5, 15.5, 30.0, 41.0, 50.0]);
    knots.extend([t1; 4]);
    let got = lsq_bspline(
        &times,
        &values,
        &weights,
        &knots,
        &[0.0, 3.3, 15.5, 29.9, 44.0, t1],
    )
    .unwrap();
    let scipy = [
        -0.324_483_246_076_973_26,
        6.745_729_489_418_309,
        12.126_031_500_914_92,
        41.613_402_331_053_04,
        103.082_409_682_568_41,
        171.545_493_054_024_86,
    ];
    for (g, s) in got.iter().zip(scipy) {
        assert_relative_eq!(*g, s, epsilon = 1e-9, max_relative = 1e-10);
    }
    // make_smoothing_spline(t, y, lam=λ): the same penalised criterion Σ (y − f)² + λ ∫ f''².
    let t = [0.0, 1.0, 2.5, 3.0, 4.5, 6.0, 7.0];
    let y = [1.0, 2.2, 1.9, 3.5, 2.8, 4.1, 3.9];
    let at = [0.5, 2.0, 3.7, 6.5];
    for (lambda, scipy) in [
        (
            0.1,
            [
                1.592_467_688_562_179_4,
                2.291_231_430_940_708_7,
                3.025_283_939_776_521_4,
                3.992_574_179_402_183_6,
            ],
        ),
        (
            1.0,
            [
                1.535_638_411_784_239_7,
                2.333_644_424_494_804_2,
                2.992_738_017_491_328,
                3.914_725_362_147_692_5,
            ],
        ),
        (
            30.0,
            [
                1.597_002_234_924_774_6,
                2.229_746_717_069_529_5,
                2.909_822_650_147_231,
                3.961_525_985_835_092_6,
            ],
        ),
    ] {
        let s = SmoothingSpline::fit(&t, &y, lambda).unwrap();
        for (x, want) in at.iter().zip(scipy) {
            assert_relative_eq!(s.value(*x), want, epsilon = 1e-9);
        }
    }
    // CubicSpline(bc_type='natural') on uneven samples (the hand case above is evenly spaced).
    let t: Vec<f64> = (0..12)
        .map(|i| f64::from(i) * 1.5 + 0.2 * f64::from(i % 2))
        .collect();
    let y: Vec<f64> = t.iter().map(|x| (x * 0.7).sin() + 0.1 * x).collect();
    let got = natural_cubic_spline(&t, &y, &[0.4, 3.1, 7.7, 12.0, 16.5]).unwrap();
    let scipy = [
        0.311_719_320_192_240_13,
        1.135_479_621_086_915_4,
        -0.009_072_672_631_403_1,
        2.054_598_908_088_281_4,
        0.834_608_001_281_487,
    ];
    for (g, s) in got.iter().zip(scipy) {
        assert_relative_eq!(*g, s, epsilon = 1e-10);
    }
}
