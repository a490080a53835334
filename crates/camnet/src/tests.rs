//! Tests: synthetic two-view and network geometry with known answers.

use nalgebra::{Matrix3, Rotation3, SVector, Vector2, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::{Frame, Vec2};

use crate::refine::{jacobians, step_pose};
use crate::*;

fn truth_pose() -> Pose {
    Pose {
        rotation: Rotation3::from_euler_angles(0.2, -0.4, 0.1),
        translation: Vector3::new(-1.0, 0.3, 0.2).normalize(),
    }
}

/// Points and their two images.
type Views = (Vec<Vector3<f64>>, Vec<Vector2<f64>>, Vec<Vector2<f64>>);

/// `n` random points in front of both cameras, projected exactly.
fn scene(pose: &Pose, n: usize, rng: &mut ChaCha8Rng) -> Views {
    let (mut xs, mut x1, mut x2) = (Vec::new(), Vec::new(), Vec::new());
    while xs.len() < n {
        let p = Vector3::new(
            rng.random_range(-3.0..3.0),
            rng.random_range(-3.0..3.0),
            rng.random_range(4.0..10.0),
        );
        if let (Some(a), Some(b)) = (project(&p), project(&pose.apply(&p))) {
            xs.push(p);
            x1.push(a);
            x2.push(b);
        }
    }
    (xs, x1, x2)
}

fn unit(m: &Matrix3<f64>) -> Matrix3<f64> {
    m / m.norm()
}

fn same_up_to_sign(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    let (a, b) = (unit(a), unit(b));
    (a - b).norm().min((a + b).norm())
}

#[test]
fn noise_free_eight_point_is_exact() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let pose = truth_pose();
    for n in [8, 9, 20, 200] {
        let (_, x1, x2) = scene(&pose, n, &mut rng);
        let e = eight_point(&x1, &x2).unwrap();
        // Independent route: E = [t]× R from the known pose.
        assert!(same_up_to_sign(&e, &pose.essential()) < 1e-9, "n = {n}");
        let (est, front) = select_pose(&e, &x1, &x2, &(0..n).collect::<Vec<_>>()).unwrap();
        assert_eq!(front, n);
        assert!((est.rotation.matrix() - pose.rotation.matrix()).norm() < 1e-9);
        assert!((est.translation - pose.translation).norm() < 1e-9);
    }
}

#[test]
fn essential_projection_has_equal_singular_values() {
    let m = Matrix3::new(3.0, 1.0, 0.5, -1.0, 2.0, 0.3, 0.2, 0.1, 0.4);
    let e = project_to_essential(&m).unwrap();
    let s = e.singular_values();
    let mut s: Vec<f64> = s.iter().copied().collect();
    s.sort_by(|a, b| b.total_cmp(a));
    assert!((s[0] - s[1]).abs() < 1e-12 && s[2].abs() < 1e-12);
    // The essential-matrix identity 2 E Eᵀ E − tr(E Eᵀ) E = 0.
    let c = 2.0 * e * e.transpose() * e - (e * e.transpose()).trace() * e;
    assert!(c.norm() < 1e-12);
}

#[test]
fn decomposition_picks_the_candidate_with_points_in_front() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    // Several poses, including a backward translation and a large rotation.
    let poses = [
        truth_pose(),
        Pose {
            rotation: Rotation3::from_euler_angles(-0.1, 0.9, 0.3),
            translation: Vector3::new(0.2, -0.1, -1.0).normalize(),
        },
        Pose {
            rotation: Rotation3::from_euler_angles(0.0, -0.7, 0.0),
            translation: Vector3::new(1.0, 0.0, 0.4).normalize(),
        },
    ];
    for pose in poses {
        let (_, x1, x2) = scene(&pose, 40, &mut rng);
        let idx: Vec<usize> = (0..40).collect();
        let cands = decompose_essential(&pose.essential()).unwrap();
        // Exactly one candidate puts every point in front; it is the truth.
        let counts: Vec<usize> = cands
            .iter()
            .map(|c| count_in_front(c, &x1, &x2, &idx))
            .collect();
        assert_eq!(counts.iter().filter(|&&c| c == 40).count(), 1, "{counts:?}");
        let (best, _) = select_pose(&pose.essential(), &x1, &x2, &idx).unwrap();
        assert!(rotation_error_deg(&best.rotation, &pose.rotation) < 1e-9);
        assert!((best.translation - pose.translation).norm() < 1e-9);
    }
}

#[test]
fn sampson_distance_matches_geometric_distance_to_first_order() {
    // For a point displaced by δ perpendicular to its epipolar line in view 2 only, the
    // Sampson distance is |δ| · |l₂| / ‖(l₁ part, l₂ part)‖ which tends to δ when view 1's term
    // is small; check the exact formula by hand on E = [t]× with R = I, t = x̂.
    let e = skew(&Vector3::x()); // x₂ᵀ E x₁ = y₁ − y₂ (rows: 0; -1·(x)… )
    let x1 = Vector2::new(0.3, 0.2);
    let x2 = Vector2::new(0.5, 0.2 + 0.01);
    // E x₁ = (0, -1, 0.2), Eᵀ x₂ = (0, 1, -0.21); x₂ᵀ E x₁ = -0.21 + 0.2 = -0.01.
    let expected = 0.01 / (1.0f64 + 1.0).sqrt();
    assert!((sampson_distance(&e, &x1, &x2) - expected).abs() < 1e-15);
}

#[test]
fn ransac_with_thirty_percent_outliers_recovers_the_pose() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let pose = truth_pose();
    let f = 1000.0;
    let (_, mut x1, mut x2) = scene(&pose, 500, &mut rng);
    let mut is_outlier = vec![false; 500];
    for i in 0..500 {
        x1[i] += Vector2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * 0.5 / f;
        x2[i] += Vector2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * 0.5 / f;
        if i % 10 < 3 {
            is_outlier[i] = true;
            x2[i] = Vector2::new(rng.random_range(-0.6..0.6), rng.random_range(-0.6..0.6));
        }
    }
    let est = estimate_relative_pose(&x1, &x2, &EssentialConfig::default(), &mut rng).unwrap();
    assert!(rotation_error_deg(&est.pose.rotation, &pose.rotation) < 0.2);
    assert!(angle_between_deg(&est.pose.translation, &pose.translation) < 0.5);
    let wrong = (0..500)
        .filter(|&i| est.inliers[i] == is_outlier[i])
        .count();
    // An outlier can land on its epipolar line by chance; a handful at most.
    assert!(wrong <= 5, "{wrong} misclassified");
    assert!(est.refined.as_ref().unwrap().rms_reprojection * f < 0.5);
}

#[test]
fn degenerate_inputs_get_typed_errors() {
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let pose = truth_pose();
    let (_, x1, x2) = scene(&pose, 7, &mut rng);
    assert!(matches!(
        eight_point(&x1, &x2),
        Err(Error::TooFewCorrespondences {
            found: 7,
            needed: 8
        })
    ));
    assert!(matches!(
        estimate_relative_pose(&x1, &x2, &EssentialConfig::default(), &mut rng),
        Err(Error::TooFewCorrespondences { .. })
    ));
    // All 3-D points on one line: both images on a line.
    let line: Vec<Vector3<f64>> = (0..20)
        .map(|k| Vector3::new(-1.0, 0.5, 5.0) + Vector3::new(0.3, -0.1, 0.4) * f64::from(k) * 0.2)
        .collect();
    let l1: Vec<Vector2<f64>> = line.iter().map(|p| project(p).unwrap()).collect();
    let l2: Vec<Vector2<f64>> = line
        .iter()
        .map(|p| project(&pose.apply(p)).unwrap())
        .collect();
    assert!(matches!(
        eight_point(&l1, &l2),
        Err(Error::Collinear { view: 1, .. })
    ));
    assert!(matches!(
        estimate_relative_pose(&l1, &l2, &EssentialConfig::default(), &mut rng),
        Err(Error::Collinear { .. })
    ));
    // Coincident centres: a pure rotation.
    let rot = Pose {
        rotation: pose.rotation,
        translation: Vector3::zeros(),
    };
    let (_, r1, r2) = scene(&rot, 100, &mut rng);
    assert!(matches!(
        estimate_relative_pose(&r1, &r2, &EssentialConfig::default(), &mut rng),
        Err(Error::ZeroBaseline { .. })
    ));
    // Mismatched lengths and non-finite points.
    assert!(matches!(
        eight_point(&x1, &x2[..6]),
        Err(Error::LengthMismatch { .. })
    ));
    let (_, mut y1, y2) = scene(&pose, 10, &mut rng);
    y1[3].x = f64::NAN;
    assert!(matches!(
        eight_point(&y1, &y2),
        Err(Error::NonFinitePoint { view: 1, index: 3 })
    ));
}

#[test]
fn refinement_jacobians_match_finite_differences() {
    let pose = truth_pose();
    let x = Vector3::new(0.4, -0.3, 6.0);
    let (j1x, j2x, j2c) = jacobians(&pose, &x);
    let r = |p: &Pose, x: &Vector3<f64>| {
        let y = p.apply(x);
        (
            Vector2::new(x.x / x.z, x.y / x.z),
            Vector2::new(y.x / y.z, y.y / y.z),
        )
    };
    let h = 1e-6;
    for k in 0..3 {
        let mut d = Vector3::zeros();
        d[k] = h;
        let (p1, p2) = r(&pose, &(x + d));
        let (m1, m2) = r(&pose, &(x - d));
        assert!(((p1 - m1) / (2.0 * h) - j1x.column(k)).norm() < 1e-7);
        assert!(((p2 - m2) / (2.0 * h) - j2x.column(k)).norm() < 1e-7);
    }
    for k in 0..5 {
        let mut d = SVector::<f64, 5>::zeros();
        d[k] = h;
        let (_, p2) = r(&step_pose(&pose, &d), &x);
        let (_, m2) = r(&step_pose(&pose, &(-d)), &x);
        assert!(
            ((p2 - m2) / (2.0 * h) - j2c.column(k)).norm() < 1e-7,
            "column {k}"
        );
    }
}

#[test]
fn refinement_converges_from_a_perturbed_start() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let pose = truth_pose();
    let (_, x1, x2) = scene(&pose, 60, &mut rng);
    let start = Pose {
        rotation: Rotation3::from_euler_angles(0.02, -0.01, 0.015) * pose.rotation,
        translation: (pose.translation + Vector3::new(0.05, -0.04, 0.02)).normalize(),
    };
    let r = refine_two_view(&start, &x1, &x2, &RefineConfig::default()).unwrap();
    assert!(r.final_cost < 1e-20 && r.initial_cost > 1e-6);
    assert!(rotation_error_deg(&r.pose.rotation, &pose.rotation) < 1e-7);
    assert!((r.pose.translation - pose.translation).norm() < 1e-9);
    // With noise, starting from the truth and from the perturbed pose reach one minimum,
    // no worse than the truth's.
    let noisy2: Vec<Vector2<f64>> = x2
        .iter()
        .map(|p| p + Vector2::new(rng.random_range(-1e-3..1e-3), rng.random_range(-1e-3..1e-3)))
        .collect();
    let a = refine_two_view(&start, &x1, &noisy2, &RefineConfig::default()).unwrap();
    let b = refine_two_view(&pose, &x1, &noisy2, &RefineConfig::default()).unwrap();
    assert!(a.final_cost <= b.initial_cost);
    assert!((a.final_cost - b.final_cost).abs() < 1e-9 * b.final_cost.max(1e-30) + 1e-18);
    assert!(rotation_error_deg(&a.pose.rotation, &b.pose.rotation) < 1e-6);
}

#[test]
fn umeyama_recovers_a_known_similarity() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let sim = Similarity {
        scale: 2.5,
        rotation: Rotation3::from_euler_angles(0.3, -1.1, 2.0),
        translation: Vector3::new(1.0, -2.0, 0.5),
    };
    let from: Vec<Vector3<f64>> = (0..6)
        .map(|_| {
            Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
        })
        .collect();
    let to: Vec<Vector3<f64>> = from.iter().map(|x| sim.apply(x)).collect();
    let est = umeyama(&from, &to).unwrap();
    assert!((est.scale - 2.5).abs() < 1e-12);
    assert!(rotation_error_deg(&est.rotation, &sim.rotation) < 1e-9);
    assert!((est.translation - sim.translation).norm() < 1e-12);
}

// ---- Walkers seen by several cameras (no tracker: tracks built from the truth). ----

const HEIGHT_M: f64 = 1.7;

/// Person k's ground position at frame t: a curving walk through a 20 m square.
fn walker(k: usize, t: f64) -> Vector3<f64> {
    let phase = k as f64 * 1.3;
    let c = Vector3::new(
        -3.0 + (2.0 * k as f64) % 6.0,
        -2.5 + (1.5 * k as f64) % 5.0,
        0.0,
    );
    let v = Vector3::new(phase.cos(), phase.sin(), 0.0) * 0.04;
    let bend = Vector3::new(-phase.sin(), phase.cos(), 0.0) * 1.5 * (0.05 * t + phase).sin();
    c + v * t + bend
}

fn cameras() -> Vec<(Intrinsics, Pose)> {
    let k = Intrinsics {
        fx: 800.0,
        fy: 800.0,
        cx: 640.0,
        cy: 360.0,
    };
    let centres = [
        Vector3::new(-9.0, -7.0, 5.0),
        Vector3::new(10.0, -6.0, 6.0),
        Vector3::new(8.0, 9.0, 4.0),
    ];
    centres
        .iter()
        .map(|c| (k, Pose::look_at(c, &Vector3::new(0.0, 0.0, 0.5)).unwrap()))
        .collect()
}

/// Camera `cam`'s image track of person k over `frames`, with pixel noise `sigma_px`.
fn track_of(
    cam: &(Intrinsics, Pose),
    k: usize,
    frames: std::ops::Range<Frame>,
    sigma_px: f64,
    rng: &mut ChaCha8Rng,
) -> ImageTrack {
    let (intr, pose) = cam;
    let mut t = ImageTrack {
        id: k as u64,
        frames: Vec::new(),
        blobs: Vec::new(),
        sources: Vec::new(),
    };
    for f in frames {
        let g = walker(k, f64::from(f));
        let px = |p: Vector3<f64>, rng: &mut ChaCha8Rng| {
            let x = intr.to_pixel(&project(&pose.apply(&p)).unwrap());
            x + Vector2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * sigma_px
        };
        let top: Vec2 = px(g + Vector3::z() * HEIGHT_M, rng);
        let bottom: Vec2 = px(g, rng);
        let centre: Vec2 = px(g + Vector3::z() * HEIGHT_M * 0.5, rng);
        t.frames.push(f);
        t.blobs.push(Blob {
            centre,
            top,
            bottom,
        });
        t.sources.push((f as usize, k));
    }
    t
}

#[test]
fn track_correspondence_finds_true_pairs_among_overlapping_decoys() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let cams = cameras();
    let features = |cam: usize, tracks: &[ImageTrack]| -> Vec<FeatureTrack> {
        tracks
            .iter()
            .map(|t| FeatureTrack {
                frames: t.frames.clone(),
                points: t.normalised(&cams[cam].0, Features::TopBottom),
            })
            .collect()
    };
    // Camera 0 sees persons 0..4; camera 1 sees 2..7 (shared: 2, 3), all over the same
    // frames, so every pair of tracks overlaps in time.
    let a: Vec<ImageTrack> = (0..4)
        .map(|k| track_of(&cams[0], k, 0..120, 1.7, &mut rng))
        .collect();
    let b: Vec<ImageTrack> = (2..7)
        .map(|k| track_of(&cams[1], k, 10..130, 1.7, &mut rng))
        .collect();
    let m = match_tracks(
        &features(0, &a),
        &features(1, &b),
        800.0,
        // Seeds from every point of the 110 shared frames.
        &CorrespondenceConfig {
            seed_points: 240,
            ..CorrespondenceConfig::default()
        },
        &mut rng,
    )
    .unwrap()
    .expect("a matching");
    let mut found: Vec<(u64, u64)> = m
        .matches
        .iter()
        .map(|t| (a[t.track_a].id, b[t.track_b].id))
        .collect();
    found.sort_unstable();
    assert_eq!(found, vec![(2, 2), (3, 3)]);
    assert!(m.matches.iter().all(|t| t.inlier_fraction > 0.9));
    let truth = cams[1].1.compose(&cams[0].1.inverse());
    assert!(rotation_error_deg(&m.estimate.pose.rotation, &truth.rotation) < 0.5);
    assert!(angle_between_deg(&m.estimate.pose.translation, &truth.translation) < 1.0);
}

fn network_tracks(rng: &mut ChaCha8Rng, sigma_px: f64) -> Vec<CameraTracks> {
    let cams = cameras();
    // Persons 0..5 walk; camera c sees a different subset, each shared by at least two.
    let seen: [&[usize]; 3] = [&[0, 1, 2, 3], &[1, 2, 3, 4], &[0, 2, 3, 4]];
    cams.iter()
        .zip(seen)
        .map(|(cam, who)| CameraTracks {
            intrinsics: cam.0,
            tracks: who
                .iter()
                .map(|&k| track_of(cam, k, 0..100, sigma_px, rng))
                .collect(),
        })
        .collect()
}

#[test]
fn three_cameras_chained_give_consistent_scale() {
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let cams = cameras();
    let input = network_tracks(&mut rng, 0.3);
    let net = localise(&input, &NetworkConfig::default(), 11).unwrap();
    assert_eq!(net.tree.len(), 2);
    let poses: Vec<Pose> = net.poses.iter().map(|p| p.unwrap()).collect();
    // Truth in camera 0's frame.
    let world_to_0 = cams[0].1;
    let true_centres: Vec<Vector3<f64>> = cams
        .iter()
        .map(|c| world_to_0.apply(&c.1.centre()))
        .collect();
    let est_centres: Vec<Vector3<f64>> = poses.iter().map(Pose::centre).collect();
    // Fix the global scale by the distance 0–1; then camera 2's position must agree.
    let s = true_centres[1].norm() / est_centres[1].norm();
    let scene = (true_centres[1] - true_centres[2]).norm();
    for c in 1..3 {
        let err = (est_centres[c] * s - true_centres[c]).norm() / scene;
        assert!(err < 0.01, "camera {c}: {err}");
        let rel = poses[c].rotation;
        let truth = cams[c].1.compose(&world_to_0.inverse()).rotation;
        assert!(rotation_error_deg(&rel, &truth) < 0.5);
    }
    // The scale ratio of the two baselines is right, whichever edge set it.
    let ratio_est = (est_centres[2] - est_centres[1]).norm() / est_centres[1].norm();
    let ratio_true = (true_centres[2] - true_centres[1]).norm() / true_centres[1].norm();
    assert!((ratio_est / ratio_true - 1.0).abs() < 0.01);
    assert!(net.scale_points.iter().skip(1).all(|&n| n >= 5));
}

#[test]
fn network_is_identical_at_one_and_two_threads() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let input = network_tracks(&mut rng, 1.0);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let config = NetworkConfig {
                    bundle: Some(RefineConfig::default()),
                    ..NetworkConfig::default()
                };
                localise(&input, &config, 13).unwrap()
            })
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.tree, two.tree);
    assert_eq!(one.bundle, two.bundle);
    for (p, q) in one.pairs.iter().zip(&two.pairs) {
        assert_eq!((p.route, p.pose), (q.route, q.pose));
    }
    for (p, q) in one.poses.iter().zip(&two.poses) {
        assert_eq!(p, q);
    }
}

#[test]
fn mcmcda_image_tracks_follow_two_blobs() {
    // Two blobs moving in straight lines with one false blob; the tracker's model in pixels.
    let scans: Vec<(Frame, Vec<Blob>)> = (0..12u32)
        .map(|f| {
            let t = f64::from(f);
            let mut blobs = vec![
                Blob::point(Vec2::new(100.0 + 5.0 * t, 200.0)),
                Blob::point(Vec2::new(600.0 - 4.0 * t, 300.0 + 2.0 * t)),
            ];
            if f == 5 {
                blobs.push(Blob::point(Vec2::new(900.0, 50.0)));
            }
            (f, blobs)
        })
        .collect();
    let mut config = ImageTrackConfig::default();
    config.model.volume = 1280.0 * 720.0;
    config.model.measurement_noise = nalgebra::Matrix2::identity() * 4.0;
    config.model.max_speed = 20.0;
    config.model.motion = tracker_model::ConstantVelocity2::mcmcda(1.0, 1.0).unwrap();
    let tracks = image_tracks(&scans, &config, 1).unwrap();
    assert_eq!(tracks.len(), 2);
    for t in &tracks {
        assert_eq!(t.frames, (0..12).collect::<Vec<Frame>>());
        let k = t.sources[0].1;
        assert!(t.sources.iter().all(|&(s, kk)| kk == k && s < 12));
    }
}

/// Camera `cam`'s tracks as normalised top/bottom feature tracks.
fn feature_tracks(cam: &(Intrinsics, Pose), tracks: &[ImageTrack]) -> Vec<FeatureTrack> {
    tracks
        .iter()
        .map(|t| FeatureTrack {
            frames: t.frames.clone(),
            points: t.normalised(&cam.0, Features::TopBottom),
        })
        .collect()
}

#[test]
fn guided_matching_finds_true_pairs_and_fragments_from_an_approximate_pose() {
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    let cams = cameras();
    // Camera 0 sees persons 0..4 over frames 0..120; camera 1 sees 2..7 over 10..130, with
    // person 2's track broken in two (frames 10..60 and 66..130), as MCMCDA does.
    let a: Vec<ImageTrack> = (0..4)
        .map(|k| track_of(&cams[0], k, 0..120, 1.0, &mut rng))
        .collect();
    let mut b: Vec<ImageTrack> = vec![
        track_of(&cams[1], 2, 10..60, 1.0, &mut rng),
        track_of(&cams[1], 2, 66..130, 1.0, &mut rng),
    ];
    b.extend((3..7).map(|k| track_of(&cams[1], k, 10..130, 1.0, &mut rng)));
    let truth = cams[1].1.compose(&cams[0].1.inverse());
    // The guide is off by 0.09° in rotation and 0.16° in translation direction, about what
    // the network's composition gives at 1 px (the threshold, 3 px at f = 800, is 0.2°).
    let guess = Pose {
        rotation: Rotation3::from_euler_angles(0.001, -0.001, 0.0007) * truth.rotation,
        translation: (Rotation3::from_euler_angles(0.0, 0.002, 0.002) * truth.translation)
            .normalize(),
    };
    let config = CorrespondenceConfig {
        threshold_px: 3.0,
        ..CorrespondenceConfig::default()
    };
    let (fa, fb) = (feature_tracks(&cams[0], &a), feature_tracks(&cams[1], &b));
    let m = match_tracks_guided(&fa, &fb, &guess.essential(), 800.0, &config, &mut rng)
        .unwrap()
        .expect("a guided matching");
    let mut found: Vec<(usize, usize)> = m.matches.iter().map(|t| (t.track_a, t.track_b)).collect();
    found.sort_unstable();
    // Track 2 of camera 0 pairs with both fragments (b\[0\], b\[1\]); track 3 with b\[2\].
    assert_eq!(found, vec![(2, 0), (2, 1), (3, 2)]);
    // The pose is the pair's own (two walkers' tracks: about 0.2°, not better than the guide
    // here; the guide only selects the points).
    let rot = rotation_error_deg(&m.estimate.pose.rotation, &truth.rotation);
    let dir = angle_between_deg(&m.estimate.pose.translation, &truth.translation);
    assert!(rot < 0.5 && dir < 1.0, "rotation {rot}°, direction {dir}°");
    // A guide far from the truth finds nothing (the decoys do not fit a wrong E either).
    let wrong = Pose {
        rotation: Rotation3::from_euler_angles(0.2, 0.1, -0.1) * truth.rotation,
        translation: truth.translation,
    };
    let none = match_tracks_guided(&fa, &fb, &wrong.essential(), 800.0, &config, &mut rng).unwrap();
    assert!(none.is_none());
    // A zero guide is a typed error, not a panic.
    assert!(match_tracks_guided(&fa, &fb, &Matrix3::zeros(), 800.0, &config, &mut rng).is_err());
}

#[test]
fn pair_with_one_shared_track_gets_its_pose_guided_by_the_network() {
    // Cameras 1 and 2 share only person 2: no two-track seed exists, so their own search
    // finds nothing; the pose composed through camera 0 guides the match of that one track,
    // and the pose comes from its points. Without the guided pass the pair's pose is the
    // composed one.
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let cams = cameras();
    let seen: [&[usize]; 3] = [&[0, 1, 2, 3], &[0, 1, 2, 5], &[2, 3, 4]];
    let input: Vec<CameraTracks> = cams
        .iter()
        .zip(seen)
        .map(|(cam, who)| CameraTracks {
            intrinsics: cam.0,
            tracks: who
                .iter()
                .map(|&k| track_of(cam, k, 0..100, 0.3, &mut rng))
                .collect(),
        })
        .collect();
    let truth = cams[2].1.compose(&cams[1].1.inverse());
    let net = localise(&input, &NetworkConfig::default(), 16).unwrap();
    assert!(net.poses.iter().all(Option::is_some));
    let p12 = net.pair(1, 2).unwrap();
    assert_eq!(p12.route, Some(PoseRoute::Guided));
    let m = p12.matching.as_ref().unwrap();
    assert_eq!(
        m.matches
            .iter()
            .map(|t| (t.track_a, t.track_b))
            .collect::<Vec<_>>(),
        vec![(2, 0)]
    );
    let pose = p12.pose.unwrap();
    assert_eq!(pose, m.estimate.pose);
    let rot = rotation_error_deg(&pose.rotation, &truth.rotation);
    let dir = angle_between_deg(&pose.translation, &truth.translation);
    assert!(
        rot < 0.5 && dir < 1.0,
        "guided: rotation {rot}°, direction {dir}°"
    );
    for (a, b) in [(0, 1), (0, 2)] {
        assert_eq!(net.pair(a, b).unwrap().route, Some(PoseRoute::Direct));
    }
    let plain = localise(
        &input,
        &NetworkConfig {
            guided: false,
            ..NetworkConfig::default()
        },
        16,
    )
    .unwrap();
    let p12 = plain.pair(1, 2).unwrap();
    assert!(p12.matching.is_none());
    assert_eq!(p12.route, Some(PoseRoute::Composed));
    let pose = p12.pose.unwrap();
    // Composed: pose_2 ∘ pose_1⁻¹ of the network's poses, unit translation.
    let (p1, p2) = (plain.poses[1].unwrap(), plain.poses[2].unwrap());
    let direct = p2.compose(&p1.inverse());
    assert!(rotation_error_deg(&pose.rotation, &direct.rotation) < 1e-9);
    assert!(angle_between_deg(&pose.translation, &direct.translation) < 1e-9);
    assert!((pose.translation.norm() - 1.0).abs() < 1e-12);
    assert!(rotation_error_deg(&pose.rotation, &truth.rotation) < 0.5);
    assert!(angle_between_deg(&pose.translation, &truth.translation) < 1.0);
}

/// Four cameras around the scene in camera 0's frame and 80 points seen by all, as a
/// bundle-adjustment problem (poses `camera_from_camera0`, points in camera 0's frame).
fn bundle_problem(
    rng: &mut ChaCha8Rng,
    sigma_px: f64,
) -> (Vec<Pose>, Vec<Vector3<f64>>, Vec<BundleObservation>) {
    let mut cams: Vec<Pose> = cameras().iter().map(|c| c.1).collect();
    cams.push(Pose::look_at(&Vector3::new(-8.0, 8.0, 7.0), &Vector3::new(0.0, 0.0, 0.5)).unwrap());
    let to0 = cams[0].inverse();
    let poses: Vec<Pose> = cams.iter().map(|c| c.compose(&to0)).collect();
    let points: Vec<Vector3<f64>> = (0..80)
        .map(|_| {
            let w = Vector3::new(
                rng.random_range(-4.0..4.0),
                rng.random_range(-4.0..4.0),
                rng.random_range(0.0..2.0),
            );
            cams[0].apply(&w)
        })
        .collect();
    let mut obs = Vec::new();
    for (p, x) in points.iter().enumerate() {
        for (c, pose) in poses.iter().enumerate() {
            let noise = Vector2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
                * (sigma_px / 800.0);
            obs.push(BundleObservation {
                camera: c,
                point: p,
                x: project(&pose.apply(x)).unwrap() + noise,
            });
        }
    }
    (poses, points, obs)
}

/// Camera centres over their mean distance from camera 0 (the gauge the bundle holds).
fn normalised_centres(poses: &[Pose]) -> Vec<Vector3<f64>> {
    let c0 = poses[0].centre();
    let mean = poses.iter().map(|p| (p.centre() - c0).norm()).sum::<f64>() / poses.len() as f64;
    poses.iter().map(|p| (p.centre() - c0) / mean).collect()
}

#[test]
fn bundle_adjustment_keeps_noise_free_input_exact() {
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let (poses, points, obs) = bundle_problem(&mut rng, 0.0);
    let b = bundle_adjust(&poses, &points, &obs, &RefineConfig::default()).unwrap();
    assert!(b.initial_rms < 1e-12 && b.final_rms < 1e-12);
    for (p, q) in b.poses.iter().zip(&poses) {
        assert!(rotation_error_deg(&p.rotation, &q.rotation) < 1e-9);
        assert!((p.translation - q.translation).norm() < 1e-9);
    }
    for (x, y) in b.points.iter().zip(&points) {
        assert!((x - y).norm() < 1e-9);
    }
}

#[test]
fn bundle_adjustment_converges_from_a_perturbed_start() {
    let mut rng = ChaCha8Rng::seed_from_u64(18);
    let (truth, points, obs) = bundle_problem(&mut rng, 0.0);
    // Rotations off by ~0.6°, centres by ~2 %, points by ~5 cm; camera 0 exact.
    let start: Vec<Pose> = truth
        .iter()
        .enumerate()
        .map(|(c, p)| {
            if c == 0 {
                return *p;
            }
            let r = Rotation3::from_euler_angles(0.006, -0.005, 0.004) * p.rotation;
            let centre = p.centre() * 1.02 + Vector3::new(0.1, -0.1, 0.05);
            Pose {
                rotation: r,
                translation: -(r * centre),
            }
        })
        .collect();
    let start_points: Vec<Vector3<f64>> = points
        .iter()
        .map(|x| x + Vector3::new(0.05, -0.03, 0.04))
        .collect();
    let b = bundle_adjust(&start, &start_points, &obs, &RefineConfig::default()).unwrap();
    assert!(b.initial_rms > 1e-4, "start rms {}", b.initial_rms);
    assert!(b.final_rms < 1e-10, "final rms {}", b.final_rms);
    for (p, q) in b.poses.iter().zip(&truth) {
        assert!(rotation_error_deg(&p.rotation, &q.rotation) < 1e-6);
    }
    // Positions are right up to the global scale, which the bundle holds at the start's.
    for (p, q) in normalised_centres(&b.poses)
        .iter()
        .zip(&normalised_centres(&truth))
    {
        assert!((p - q).norm() < 1e-7, "{p} vs {q}");
    }
    let mean = |ps: &[Pose]| {
        let c0 = ps[0].centre();
        ps.iter().map(|p| (p.centre() - c0).norm()).sum::<f64>()
    };
    assert!((mean(&b.poses) / mean(&start) - 1.0).abs() < 1e-12);
}

#[test]
fn bundle_adjustment_does_not_increase_the_noisy_reprojection_error() {
    let mut rng = ChaCha8Rng::seed_from_u64(19);
    let (truth, points, obs) = bundle_problem(&mut rng, 1.0);
    let b = bundle_adjust(&truth, &points, &obs, &RefineConfig::default()).unwrap();
    assert!(b.final_rms <= b.initial_rms);
    // Uniform ±1 px noise has σ = 1/√3 px. At the least-squares optimum the RMS residual is
    // σ √(1 − parameters / residuals) = 0.577 √(1 − 258/640) = 0.446 px (18 camera and 240
    // point parameters, 640 residuals); from the truth the fit must get there.
    let px = b.final_rms * 800.0;
    assert!((px - 0.446).abs() < 0.03, "final rms {px} px");
    assert!(b.initial_rms * 800.0 > 0.5);
    // Poses stay near the truth (narrow fields of view couple rotation with translation, so
    // the noise moves them by about a tenth of a degree).
    for (p, q) in b.poses.iter().zip(&truth) {
        let e = rotation_error_deg(&p.rotation, &q.rotation);
        assert!(e < 0.5, "rotation error {e}°");
    }
    // From a perturbed start the same optimum is reached.
    let start: Vec<Pose> = b
        .poses
        .iter()
        .enumerate()
        .map(|(c, p)| Pose {
            rotation: if c == 0 {
                p.rotation
            } else {
                Rotation3::from_euler_angles(0.003, 0.002, -0.002) * p.rotation
            },
            translation: p.translation,
        })
        .collect();
    let again = bundle_adjust(&start, &points, &obs, &RefineConfig::default()).unwrap();
    assert!(again.final_rms <= again.initial_rms);
    assert!((again.final_rms / b.final_rms - 1.0).abs() < 1e-3);
}

#[test]
fn bundle_adjustment_rejects_bad_input() {
    let mut rng = ChaCha8Rng::seed_from_u64(20);
    let (poses, points, mut obs) = bundle_problem(&mut rng, 0.0);
    let cfg = RefineConfig::default();
    assert!(bundle_adjust(&poses[..1], &points, &obs, &cfg).is_err());
    let mut bad = obs.clone();
    bad[0].camera = 9;
    assert!(bundle_adjust(&poses, &points, &bad, &cfg).is_err());
    // Point 0 seen by one camera only.
    obs.retain(|o| o.point != 0 || o.camera == 0);
    assert!(bundle_adjust(&poses, &points, &obs, &cfg).is_err());
    // All centres at camera 0's: no scale.
    let same = vec![poses[0]; 4];
    let (_, _, obs) = bundle_problem(&mut rng, 0.0);
    assert!(bundle_adjust(&same, &points, &obs, &cfg).is_err());
}

#[test]
fn network_bundle_adjustment_lowers_the_reprojection_error() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let cams = cameras();
    let input = network_tracks(&mut rng, 1.0);
    let mut config = NetworkConfig {
        bundle: Some(RefineConfig::default()),
        ..NetworkConfig::default()
    };
    // The scenario's rule: the threshold at ~3σ of the pixel noise.
    config.correspondence.threshold_px = 3.0;
    let net = localise(&input, &config, 22).unwrap();
    let b = net.bundle.as_ref().expect("a bundle");
    // Persons 0..5 over 100 frames, top and bottom, each seen by two or three cameras.
    assert!(
        b.points > 800 && b.observations >= 2 * b.points,
        "{} points, {} observations",
        b.points,
        b.observations
    );
    assert!(b.final_rms <= b.initial_rms);
    // Uniform ±1 px noise: σ = 0.577 px; the optimum's RMS is a little below it.
    let px = b.final_rms * 800.0;
    assert!(px < 0.577 && px > 0.35, "final rms {px} px");
    // Positions after similarity alignment, before and after: both close to the truth.
    let truth: Vec<Vector3<f64>> = cams.iter().map(|c| c.1.centre()).collect();
    let err = |poses: &[Option<Pose>]| {
        let from: Vec<Vector3<f64>> = poses.iter().map(|p| p.unwrap().centre()).collect();
        let sim = umeyama(&from, &truth).unwrap();
        from.iter()
            .zip(&truth)
            .map(|(f, t)| (sim.apply(f) - t).norm())
            .fold(0.0, f64::max)
    };
    let (before, after) = (err(&b.poses_before), err(&net.poses));
    assert!(
        before < 0.2 && after < 0.2,
        "before {before} m, after {after} m"
    );
    let p12 = net.pair(1, 2).unwrap();
    assert_eq!(p12.route, Some(PoseRoute::Direct));
}
