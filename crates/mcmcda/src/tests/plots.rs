//! PlotGnn on simulated radar plots: identities through a crossing, clutter left unconfirmed,
//! the IMM against constant velocity through a turn, view and order rules.

use nalgebra::{SMatrix, SVector, Vector2, Vector4};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, Uniform};
use tracker_model::{
    ConstantVelocity2, CoordinatedTurn, CvNoise, Gaussian, GaussianFilter, Imm, Mode, RangeBearing,
    SingleModel, StateEstimator, TrackId,
};

use crate::{Dwell, PlotGnn, PlotGnnConfig, PlotTrackState, View};

const SCAN_S: f64 = 5.0;

fn config() -> PlotGnnConfig {
    PlotGnnConfig {
        gate_chi2: 16.0,
        // One false alarm per 10 km of range per radian: ln(1e-4).
        clutter_log_density: (1e-4f64).ln(),
        confirm_hits: 3,
        confirm_window: 4,
        max_misses: 3,
        max_tracks: 1000,
    }
}

fn cv(q: f64) -> ConstantVelocity2 {
    ConstantVelocity2::new(SCAN_S, CvNoise::WhiteAcceleration { q }).unwrap()
}

/// A 4-D start from one plot: the converted position, velocity unknown to ±300 m/s.
fn birth(radar: &RangeBearing<4>, z: &SVector<f64, 2>) -> tracker_model::Result<Gaussian<4>> {
    let (p, pc) = radar.position_of(z);
    let mut cov = SMatrix::<f64, 4, 4>::zeros();
    cov.fixed_view_mut::<2, 2>(0, 0).copy_from(&pc);
    cov[(2, 2)] = 300.0f64.powi(2);
    cov[(3, 3)] = 300.0f64.powi(2);
    Gaussian::new(Vector4::new(p[0], p[1], 0.0, 0.0), cov)
}

/// Runs `tracker` over dwells of the truth `paths` (positions per scan, `None` when the target
/// is absent), with clutter uniform in range 1-30 km and all bearings.
fn run<E: StateEstimator<4>>(
    tracker: &mut PlotGnn<E, 4>,
    radar: &RangeBearing<4>,
    paths: &[Vec<Option<Vector2<f64>>>],
    clutter_per_scan: usize,
    seed: u64,
) -> Vec<Vec<PlotTrackState<4>>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise_r = Normal::new(0.0, 30.0).unwrap();
    let noise_b = Normal::new(0.0, 0.002).unwrap();
    let range = Uniform::new(1000.0, 30_000.0).unwrap();
    let angle = Uniform::new(-std::f64::consts::PI, std::f64::consts::PI).unwrap();
    let scans = paths[0].len();
    let mut out = Vec::new();
    for k in 0..scans {
        let mut plots = Vec::new();
        for path in paths {
            if let Some(p) = path[k] {
                let z = tracker_model::MeasurementModel::<4, 2>::measure(
                    radar,
                    &Vector4::new(p.x, p.y, 0.0, 0.0),
                );
                plots.push(SVector::<f64, 2>::new(
                    z[0] + noise_r.sample(&mut rng),
                    tracker_model::wrap_angle_rad(z[1] + noise_b.sample(&mut rng)),
                ));
            }
        }
        for _ in 0..clutter_per_scan {
            plots.push(SVector::<f64, 2>::new(
                range.sample(&mut rng),
                angle.sample(&mut rng),
            ));
        }
        let dwell = Dwell {
            time_s: k as f64 * SCAN_S,
            sensor: radar,
            plots: &plots,
            in_view: &|_| View::In,
            birth: &|z| birth(radar, z),
        };
        out.push(tracker.step(&dwell).unwrap());
    }
    out
}

fn straight(
    start: Vector2<f64>,
    velocity: Vector2<f64>,
    scans: usize,
) -> Vec<Option<Vector2<f64>>> {
    (0..scans)
        .map(|k| Some(start + velocity * (k as f64 * SCAN_S)))
        .collect()
}

fn radar() -> RangeBearing<4> {
    RangeBearing::at([0.0, -30_000.0], 30.0, 0.002).unwrap()
}

fn kalman(q: f64) -> SingleModel<ConstantVelocity2> {
    SingleModel {
        motion: cv(q),
        filter: GaussianFilter::Extended,
    }
}

/// Two aircraft crossing at 90° without clutter: two confirmed tracks, each following one
/// aircraft from confirmation to the end.
#[test]
fn crossing_aircraft_keep_their_tracks() {
    let a = straight(
        Vector2::new(-10_000.0, 10_000.0),
        Vector2::new(200.0, 0.0),
        21,
    );
    let b = straight(Vector2::new(0.0, 0.0), Vector2::new(0.0, 200.0), 21);
    let paths = [a, b];
    let mut gnn = PlotGnn::new(kalman(1.0), config()).unwrap();
    let steps = run(&mut gnn, &radar(), &paths, 0, 1);
    let ids: std::collections::BTreeSet<TrackId> = steps.iter().flatten().map(|s| s.id).collect();
    assert_eq!(ids.len(), 2, "{ids:?}");
    for (k, step) in steps.iter().enumerate().skip(3) {
        assert_eq!(step.len(), 2, "scan {k}");
        for state in step {
            let m = state.estimate.mean();
            let which = usize::from(state.id != TrackId(1));
            let truth = paths[which][k].unwrap();
            let err = (Vector2::new(m[0], m[1]) - truth).norm();
            assert!(err < 150.0, "scan {k}: track {:?} is {err} m off", state.id);
        }
    }
}

/// Five false alarms per scan over 30 km for 40 scans: with a 3-of-4 rule and a 16 gate no
/// false track is confirmed (a clutter plot falls in a 4σ gate of about 240 m × 0.016 rad with
/// probability ≈ 5 × 4.2e-5 per scan).
#[test]
fn clutter_alone_confirms_no_track() {
    let paths = [vec![None; 40]];
    let mut gnn = PlotGnn::new(kalman(1.0), config()).unwrap();
    let steps = run(&mut gnn, &radar(), &paths, 5, 2);
    assert!(steps.iter().all(Vec::is_empty));
    // Tentative tracks die within the window: no more than two scans' births are held.
    assert!(gnn.track_count() <= 15, "{} tracks held", gnn.track_count());
}

/// A 3°/s turn at 200 m/s between two straight legs.
fn turning_path(scans: usize) -> Vec<Option<Vector2<f64>>> {
    let omega = 3f64.to_radians();
    let turn = CoordinatedTurn::new(omega, 0.0).unwrap();
    let straight_leg = cv(0.0);
    let mut x = Vector4::new(-15_000.0, 0.0, 200.0, 0.0);
    (0..scans)
        .map(|k| {
            let p = Some(Vector2::new(x[0], x[1]));
            let in_turn = (8..20).contains(&k);
            x = if in_turn {
                tracker_model::MotionModel::propagate(&turn, &x, SCAN_S)
            } else {
                tracker_model::MotionModel::propagate(&straight_leg, &x, SCAN_S)
            };
            p
        })
        .collect()
}

fn imm() -> Imm<4> {
    let omega = 3f64.to_radians();
    let modes: Vec<Mode<4>> = vec![
        Box::new(cv(1.0)),
        Box::new(CoordinatedTurn::new(omega, 1.0).unwrap()),
        Box::new(CoordinatedTurn::new(-omega, 1.0).unwrap()),
    ];
    let switching = [
        vec![0.90, 0.05, 0.05],
        vec![0.10, 0.85, 0.05],
        vec![0.10, 0.05, 0.85],
    ];
    Imm::new(modes, &switching, GaussianFilter::Extended)
        .unwrap()
        .with_start_probabilities(&[0.8, 0.1, 0.1])
        .unwrap()
}

/// RMS position error over the turn's scans (9-22) of the nearest confirmed track, cut off at
/// 1 km, a scan without a track counting 1 km (single-target OSPA with c = 1 km).
fn turn_rmse(steps: &[Vec<PlotTrackState<4>>], path: &[Option<Vector2<f64>>]) -> f64 {
    const CUTOFF: f64 = 1000.0;
    let mut sum = 0.0;
    for k in 9..23 {
        let truth = path[k].unwrap();
        let nearest = steps[k]
            .iter()
            .map(|s| (Vector2::new(s.estimate.mean()[0], s.estimate.mean()[1]) - truth).norm())
            .fold(CUTOFF, f64::min);
        sum += nearest * nearest;
    }
    (sum / 14.0).sqrt()
}

/// Through a 3°/s turn the CV/CT IMM's position error is at most 0.8 of the best CV filter's
/// (q chosen among 1, 10 and 100 on seeds 100-104, then both scored on seeds 1-20); the
/// margin was fixed before the test was run.
#[test]
fn the_imm_beats_constant_velocity_through_a_turn() {
    let path = turning_path(30);
    let paths = [path.clone()];
    let score = |make: &dyn Fn() -> PlotGnn<SingleModel<ConstantVelocity2>, 4>,
                 seeds: std::ops::Range<u64>| {
        seeds
            .map(|s| turn_rmse(&run(&mut make(), &radar(), &paths, 0, s), &path))
            .sum::<f64>()
    };
    let best_q = [1.0, 10.0, 100.0]
        .into_iter()
        .min_by(|a, b| {
            let sa = score(&|| PlotGnn::new(kalman(*a), config()).unwrap(), 100..105);
            let sb = score(&|| PlotGnn::new(kalman(*b), config()).unwrap(), 100..105);
            sa.total_cmp(&sb)
        })
        .unwrap();
    let cv_mean = score(&|| PlotGnn::new(kalman(best_q), config()).unwrap(), 1..21) / 20.0;
    let imm_mean = (1..21)
        .map(|s| {
            let mut gnn = PlotGnn::new(imm(), config()).unwrap();
            turn_rmse(&run(&mut gnn, &radar(), &paths, 0, s), &path)
        })
        .sum::<f64>()
        / 20.0;
    assert!(
        imm_mean <= 0.8 * cv_mean,
        "IMM {imm_mean:.1} m against CV (q = {best_q}) {cv_mean:.1} m"
    );
}

/// A track out of view is neither predicted nor missed; in view again, it is still there.
#[test]
fn tracks_out_of_view_are_left_alone() {
    let paths = [straight(
        Vector2::new(5000.0, 5000.0),
        Vector2::new(100.0, 0.0),
        6,
    )];
    let mut gnn = PlotGnn::new(kalman(1.0), config()).unwrap();
    let steps = run(&mut gnn, &radar(), &paths, 0, 3);
    let id = steps[5][0].id;
    let r = radar();
    for k in 6..20 {
        let dwell = Dwell {
            time_s: k as f64 * SCAN_S,
            sensor: &r,
            plots: &[],
            in_view: &|_| View::Out,
            birth: &|z| birth(&r, z),
        };
        assert!(gnn.step(&dwell).unwrap().is_empty());
    }
    assert_eq!(gnn.track_count(), 1);
    let back = Dwell {
        time_s: 20.0 * SCAN_S,
        sensor: &r,
        plots: &[],
        in_view: &|_| View::In,
        birth: &|z| birth(&r, z),
    };
    let seen = gnn.step(&back).unwrap();
    assert_eq!(seen.len(), 1);
    assert_eq!(seen[0].id, id);
    assert!(!seen[0].hit);
}

#[test]
fn bad_dwells_and_settings_are_errors() {
    let r = radar();
    let mut gnn = PlotGnn::new(kalman(1.0), config()).unwrap();
    let view = |_: &SVector<f64, 2>| View::In;
    let start = |z: &SVector<f64, 2>| birth(&r, z);
    let mut step_at = |t: f64| {
        gnn.step(&Dwell {
            time_s: t,
            sensor: &r,
            plots: &[],
            in_view: &view,
            birth: &start,
        })
    };
    step_at(10.0).unwrap();
    assert!(step_at(5.0).is_err());
    assert!(step_at(f64::NAN).is_err());
    for bad in [
        PlotGnnConfig {
            gate_chi2: 0.0,
            ..config()
        },
        PlotGnnConfig {
            confirm_hits: 5,
            ..config()
        },
        PlotGnnConfig {
            confirm_hits: 0,
            ..config()
        },
        PlotGnnConfig {
            max_misses: 0,
            ..config()
        },
        PlotGnnConfig {
            max_tracks: 0,
            ..config()
        },
        PlotGnnConfig {
            clutter_log_density: f64::NAN,
            ..config()
        },
    ] {
        assert!(PlotGnn::new(kalman(1.0), bad).is_err(), "{bad:?}");
    }
}

/// PointGnn behind the one interface: the turning aircraft as point detections each frame
/// (5 s apart, σ 30 m), through the IMM and through a CV Kalman filter, as the `Tracker` trait
/// drives them; the IMM keeps one track from confirmation to the end.
#[test]
fn point_gnn_runs_any_estimator_behind_the_tracker_interface() {
    use rand_distr::StandardNormal;
    use tracker_model::{Detection, Tracker, Vec2};
    let path = turning_path(30);
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let frames: Vec<Vec<Detection>> = path
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let p = p.unwrap();
            let n: [f64; 2] = [
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            ];
            vec![Detection::point(
                k as u64,
                k as u32,
                Vec2::new(p.x + 30.0 * n[0], p.y + 30.0 * n[1]),
            )]
        })
        .collect();
    let birth = crate::BirthPrior {
        sigma_speed_m_s: 300.0,
        sigma_turn_rad_s: 0.03,
    };
    let r = nalgebra::Matrix2::identity() * 900.0;
    // Position plots: the clutter density is per square metre (one false alarm per 100 km²).
    let config = || PlotGnnConfig {
        clutter_log_density: (1e-10f64).ln(),
        ..config()
    };
    let mut imm_tracker =
        crate::PointGnn::new(PlotGnn::new(imm(), config()).unwrap(), SCAN_S, r, birth).unwrap();
    for (k, dets) in frames.iter().enumerate() {
        let states = imm_tracker.step(k as u32, dets).unwrap();
        assert_eq!(states.len(), usize::from(k >= 2), "frame {k}");
    }
    let set = imm_tracker.finish().unwrap();
    assert_eq!(set.tracks().len(), 1);
    assert_eq!(set.tracks()[0].points().len(), 28);
    let mut kf = crate::PointGnn::new(
        PlotGnn::new(kalman(100.0), config()).unwrap(),
        SCAN_S,
        r,
        birth,
    )
    .unwrap();
    for (k, dets) in frames.iter().enumerate() {
        kf.step(k as u32, dets).unwrap();
    }
    assert!(!kf.finish().unwrap().tracks().is_empty());
    assert!(crate::PointGnn::new(PlotGnn::new(imm(), config()).unwrap(), 0.0, r, birth).is_err());
}

/// A track at a sector's edge without a plot is not missed: ten edge dwells leave it, three
/// inside dwells without a plot delete it.
#[test]
fn edge_dwells_count_no_miss() {
    let paths = [straight(
        Vector2::new(5000.0, 5000.0),
        Vector2::new(100.0, 0.0),
        6,
    )];
    let r = radar();
    let start = |z: &SVector<f64, 2>| birth(&r, z);
    let edge = |_: &SVector<f64, 2>| View::Edge;
    let inside = |_: &SVector<f64, 2>| View::In;
    let mut gnn = PlotGnn::new(kalman(1.0), config()).unwrap();
    run(&mut gnn, &r, &paths, 0, 3);
    for k in 6..16u32 {
        let d = Dwell {
            time_s: f64::from(k) * SCAN_S,
            sensor: &r,
            plots: &[],
            in_view: &edge,
            birth: &start,
        };
        assert!(gnn.step(&d).unwrap().is_empty());
    }
    assert_eq!(gnn.track_count(), 1);
    for k in 16..19u32 {
        let d = Dwell {
            time_s: f64::from(k) * SCAN_S,
            sensor: &r,
            plots: &[],
            in_view: &inside,
            birth: &start,
        };
        gnn.step(&d).unwrap();
    }
    assert_eq!(gnn.track_count(), 0);
}
