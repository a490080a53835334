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
    let fit = lsq_bspline(
        &times,
        &values,
        &weights,
        (9.0, 20.0),
        &BSplineConfig::default(),
        &at,
    )
    .unwrap();
    for (got, x) in fit.iter().zip(at) {
        assert_relative_eq!(*got, cubic(x), epsilon = 1e-9);
    }
    assert!(
        lsq_bspline(
            &times,
            &values,
            &vec![0.0; times.len()],
            (9.0, 20.0),
            &BSplineConfig::default(),
            &[1.0]
        )
        .is_err()
    );
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
        Err(Error::InvalidParameter { name, .. })
        | Err(Error::Model(tracker_model::Error::InvalidParameter { name, .. })) => name,
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
