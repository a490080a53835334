//! Tests of sensors-video. Expected values come from hand calculation with the formulas of
//! KaewTraKulPong & Bowden (2001) as written in mog.rs, closed-form camera geometry, and the
//! renderer's truth masks.
#![expect(
    clippy::float_cmp,
    reason = "pixel counts and half-pixel centroids are exact in binary"
)]

use std::f64::consts::FRAC_PI_4;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::*;

fn grey1(v: u8) -> VideoFrame {
    VideoFrame::new(1, 1, PixelFormat::Grey, vec![v]).unwrap()
}

/// (ω, μ, σ², c) of each component, in rank order, against the hand values.
fn check_pixel(model: &BackgroundModel, expected: &[(f32, f32, f32, f32)]) {
    let got = model.components(0, 0);
    assert_eq!(got.len(), expected.len(), "components: {got:?}");
    for (g, e) in got.iter().zip(expected) {
        assert!(
            (g.weight - e.0).abs() < 1e-5,
            "weight {} vs {}",
            g.weight,
            e.0
        );
        assert!(
            (g.mean[0] - e.1).abs() < 1e-3,
            "mean {} vs {}",
            g.mean[0],
            e.1
        );
        assert!(
            (g.variance[0] - e.2).abs() < 1e-2,
            "variance {} vs {}",
            g.variance[0],
            e.2
        );
        assert!(
            (g.matches - e.3).abs() < 1e-6,
            "matches {} vs {}",
            g.matches,
            e.3
        );
    }
}

#[test]
fn one_pixel_by_hand_through_the_phase_switch() {
    // L = 3 so that the window starts at the fourth frame; K = 3 so that replacement shows.
    let cfg = MogConfig {
        history: 3,
        n_mixtures: 3,
        shadows: ShadowConfig {
            enabled: false,
            ..ShadowConfig::default()
        },
        ..MogConfig::default()
    };
    let mut m = BackgroundModel::new(&cfg, 1, 1, PixelFormat::Grey).unwrap();
    // Frame 0, x = 100: no component; a new one μ = 100, σ² = 30² = 900, ω = 0.05 → 1 after
    // renormalising; it alone exceeds T = 0.7, so the pixel is background.
    assert_eq!(m.apply(&grey1(100)).unwrap().labels[0], BACKGROUND);
    check_pixel(&m, &[(1.0, 100.0, 900.0, 1.0)]);
    // Frame 1 (N = 1 < L), x = 110: 10² < 2.5²·900, match. ω = 1 + (1 − 1)/2 = 1; c = 2;
    // μ = 100 + 10/2 = 105; σ² = 900 + (100 − 900)/2 = 500.
    assert_eq!(m.apply(&grey1(110)).unwrap().labels[0], BACKGROUND);
    check_pixel(&m, &[(1.0, 105.0, 500.0, 2.0)]);
    // Frame 2, x = 200: 95² = 9025 ≥ 6.25·500 = 3125, no match. New component ω = 0.05;
    // renormalised by 1.05: 1/1.05 = 0.952381, 0.05/1.05 = 0.047619. Ranks: 0.952/√500 >
    // 0.0476/30. B = 1 (0.952 > 0.7), the new one ranks second: foreground.
    assert_eq!(m.apply(&grey1(200)).unwrap().labels[0], FOREGROUND);
    check_pixel(
        &m,
        &[
            (0.952_381, 105.0, 500.0, 2.0),
            (0.047_619, 200.0, 900.0, 1.0),
        ],
    );
    // Frame 3: N = 3 = L, the window phase. x = 104 matches the first (1 < 3125).
    // ω₁ = 0.952381 + (1 − 0.952381)/3 = 0.968254, ω₂ = 0.047619·2/3 = 0.031746;
    // ρ = 1/(3·0.968254) = 0.344262; μ = 105 − 0.344262 = 104.655738;
    // σ² = 500 + 0.344262·(1 − 500) = 328.213115. (The first phase would have given
    // ω₁ = 0.964286 and ρ = 1/3: the switch is visible.)
    assert_eq!(m.apply(&grey1(104)).unwrap().labels[0], BACKGROUND);
    check_pixel(
        &m,
        &[
            (0.968_254, 104.655_74, 328.213_1, 3.0),
            (0.031_746, 200.0, 900.0, 1.0),
        ],
    );
    // Frame 4, x = 200: first component 95.34² = 9090.5 ≥ 6.25·328.2 = 2051.3; second matches.
    // ω₁ = 0.968254·2/3 = 0.645503, ω₂ = 0.031746 + (1 − 0.031746)/3 = 0.354497;
    // ρ = 1/(3·0.354497) = 0.940299; μ stays 200; σ² = 900 − 0.940299·900 = 53.73, floored at
    // 15² = 225. Ranks 0.6455/√328.2 = 0.0356 > 0.3545/15 = 0.0236; B = 2 (0.6455 < 0.7):
    // background.
    assert_eq!(m.apply(&grey1(200)).unwrap().labels[0], BACKGROUND);
    check_pixel(
        &m,
        &[
            (0.645_503, 104.655_74, 328.213_1, 3.0),
            (0.354_497, 200.0, 225.0, 2.0),
        ],
    );
    // Frame 5, x = 50: no match (2987 ≥ 2051, 22500 ≥ 1406), a third component, weights
    // renormalised by 1.05: 0.614764, 0.337617, 0.047619. Foreground.
    assert_eq!(m.apply(&grey1(50)).unwrap().labels[0], FOREGROUND);
    check_pixel(
        &m,
        &[
            (0.614_764, 104.655_74, 328.213_1, 3.0),
            (0.337_617, 200.0, 225.0, 2.0),
            (0.047_619, 50.0, 900.0, 1.0),
        ],
    );
    // Frame 6, x = 250: no match (21125 ≥ 2051, 2500 ≥ 1406, 40000 ≥ 5625) and K is full:
    // the lowest-ranked (μ = 50) is replaced by μ = 250, ω = 0.05; renormalised by 1.002381.
    assert_eq!(m.apply(&grey1(250)).unwrap().labels[0], FOREGROUND);
    check_pixel(
        &m,
        &[
            (0.613_304, 104.655_74, 328.213_1, 3.0),
            (0.336_815, 200.0, 225.0, 2.0),
            (0.049_881, 250.0, 900.0, 1.0),
        ],
    );
    assert_eq!(m.n_frames(), 7);
}

fn static_config(format: PixelFormat, w: usize, h: usize) -> SceneConfig {
    let mut cfg = SceneConfig::small();
    cfg.format = format;
    cfg.camera.width = w;
    cfg.camera.height = h;
    cfg.camera.cx = (w as f64 - 1.0) / 2.0;
    cfg.camera.cy = (h as f64 - 1.0) / 2.0;
    cfg.camera.fx = w as f64 * 150.0 / 160.0;
    cfg.camera.fy = cfg.camera.fx;
    cfg.drift_amplitude = 0.0;
    cfg.n_sway_patches = 0;
    cfg.glints_per_frame = 0.0;
    cfg
}

#[test]
fn static_background_gives_no_foreground_after_learning() {
    for format in [PixelFormat::Grey, PixelFormat::Rgb] {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let scene = Scene::new(static_config(format, 64, 48), vec![], &mut rng).unwrap();
        let mut m = BackgroundModel::new(&MogConfig::default(), 64, 48, format).unwrap();
        let mut late = 0;
        for k in 0..150 {
            let mask = m.apply(&scene.render(k, &mut rng).unwrap().frame).unwrap();
            if k >= 50 {
                late += mask.count_foreground() + mask.count_shadow();
            }
        }
        assert_eq!(late, 0, "{format:?}");
    }
}

#[test]
fn gradual_illumination_drift_is_absorbed_and_a_sudden_one_is_not() {
    // ±10 % over a 150 s period at 10 frames/s: ≤ 0.06 grey levels per frame.
    let mut cfg = static_config(PixelFormat::Grey, 32, 24);
    cfg.drift_amplitude = 0.1;
    cfg.drift_period_s = 150.0;
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let scene = Scene::new(cfg, vec![], &mut rng).unwrap();
    let mut m = BackgroundModel::new(&MogConfig::default(), 32, 24, PixelFormat::Grey).unwrap();
    let (mut fg, mut n) = (0usize, 0usize);
    let mut last = None;
    for k in 0..1500 {
        let f = scene.render(k, &mut rng).unwrap().frame;
        let mask = m.apply(&f).unwrap();
        if k >= 200 {
            fg += mask.count_foreground();
            n += mask.labels.len();
        }
        last = Some(f);
    }
    assert!(
        (fg as f64) < 0.001 * n as f64,
        "{fg} of {n} pixels foreground under drift"
    );
    // Control: the same model sees the last frame 40 % brighter at once.
    let bright: Vec<u8> = last
        .unwrap()
        .data()
        .iter()
        .map(|&v| (f64::from(v) * 1.4).min(255.0) as u8)
        .collect();
    let mask = m
        .apply(&VideoFrame::new(32, 24, PixelFormat::Grey, bright).unwrap())
        .unwrap();
    assert!(
        mask.count_foreground() > mask.labels.len() / 2,
        "{}",
        mask.count_foreground()
    );
}

/// A 160 × 120 colour scene with people and a vehicle crossing, random colours from `rng`.
fn busy_scene(rng: &mut ChaCha8Rng, format: PixelFormat) -> Scene {
    let mut cfg = SceneConfig::small();
    cfg.format = format;
    let mut objects = Vec::new();
    for i in 0..4 {
        let kind = if i == 3 {
            ObjectKind::Vehicle
        } else {
            ObjectKind::Person
        };
        let x = rng.random_range(10.0..22.0);
        let dir = if i % 2 == 0 { 1.0 } else { -1.0 };
        let speed = if kind == ObjectKind::Vehicle {
            3.0
        } else {
            rng.random_range(1.0..1.8)
        };
        objects.push(SceneObject {
            kind,
            start_m: [x, -dir * 0.55 * x - dir * speed * (10.0 + 2.0 * i as f64)],
            velocity_mps: [0.0, dir * speed],
            colour: [rng.random(), rng.random(), rng.random()],
            appear_s: 10.0 + 2.0 * i as f64,
            vanish_s: 40.0,
        });
    }
    Scene::new(cfg, objects, rng).unwrap()
}

struct Scores {
    tp: usize,
    fp: usize,
    fn_: usize,
    shadow_hit: usize,
    shadow_total: usize,
}

fn score_scene(format: PixelFormat, seed: u64) -> Scores {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let scene = busy_scene(&mut rng, format);
    let (w, h) = (160, 120);
    let mut m = BackgroundModel::new(&MogConfig::default(), w, h, format).unwrap();
    let mut s = Scores {
        tp: 0,
        fp: 0,
        fn_: 0,
        shadow_hit: 0,
        shadow_total: 0,
    };
    for k in 0..300 {
        let r = scene.render(k, &mut rng).unwrap();
        let mask = m.apply(&r.frame).unwrap();
        if k < 100 {
            continue;
        }
        let c = clean(&mask, &PostConfig::default()).unwrap();
        for i in 0..w * h {
            match (c.foreground[i], r.truth[i]) {
                (true, true) => s.tp += 1,
                (true, false) => s.fp += 1,
                (false, true) => s.fn_ += 1,
                _ => {}
            }
            if r.shadow[i] {
                s.shadow_total += 1;
                s.shadow_hit += usize::from(mask.labels[i] == SHADOW);
            }
        }
    }
    s
}

/// Seeds 1–3 were used to choose the post-processing (closing only) and the shadow
/// chromaticity threshold (1.5σ); these seeds were not looked at before the defaults were fixed.
const REPORTED_SEEDS: [u64; 6] = [11, 12, 13, 14, 15, 16];

#[test]
fn rendered_scenes_reach_f_measure_and_shadow_rate() {
    let all: Vec<Scores> = REPORTED_SEEDS
        .iter()
        .map(|&s| score_scene(PixelFormat::Rgb, s))
        .collect();
    let per_seed: Vec<(f64, f64)> = all
        .iter()
        .map(|s| {
            let p = s.tp as f64 / (s.tp + s.fp) as f64;
            let r = s.tp as f64 / (s.tp + s.fn_) as f64;
            (
                2.0 * p * r / (p + r),
                s.shadow_hit as f64 / s.shadow_total as f64,
            )
        })
        .collect();
    let sum = |f: fn(&Scores) -> usize| all.iter().map(f).sum::<usize>() as f64;
    let (tp, fp, fn_) = (sum(|s| s.tp), sum(|s| s.fp), sum(|s| s.fn_));
    let f = 2.0 * tp / (2.0 * tp + fp + fn_);
    let shadow = sum(|s| s.shadow_hit) / sum(|s| s.shadow_total);
    assert!(
        all.iter().all(|s| s.tp > 1000 && s.shadow_total > 500),
        "a scene is nearly empty"
    );
    // Pooled over the seeds: a camouflaged object (colour within 2.5σ of the ground) is missed
    // by any per-pixel colour model, and one such seed alone would decide a per-seed minimum.
    assert!(
        f >= 0.9,
        "pooled F {f:.3}; per seed (F, shadow rate) {per_seed:.3?}"
    );
    assert!(
        shadow >= 0.8,
        "pooled shadow rate {shadow:.3}; per seed {per_seed:.3?}"
    );
}

#[test]
fn column_to_bearing_is_exact_for_a_synthetic_camera() {
    let cam = PinholeCamera {
        width: 101,
        height: 51,
        fx: 100.0,
        fy: 100.0,
        cx: 50.0,
        cy: 25.0,
        position_m: [1.0, 2.0, 3.0],
        heading_rad: 0.3,
        tilt_rad: 0.0,
    };
    // θ(u) = heading − atan((u − c_x)/f_x), for every row when there is no tilt.
    for v in [0.0, 25.0, 50.0] {
        assert!((cam.pixel_bearing_rad(150.0, v) - (0.3 - FRAC_PI_4)).abs() < 1e-14);
        assert!((cam.pixel_bearing_rad(-50.0, v) - (0.3 + FRAC_PI_4)).abs() < 1e-14);
        assert!((cam.pixel_bearing_rad(50.0, v) - 0.3).abs() < 1e-14);
        assert!((cam.pixel_bearing_rad(0.0, v) - (0.3 + 0.5f64.atan())).abs() < 1e-14);
    }
    // With tilt, back-projection agrees with forward projection of world points at known
    // bearings and heights.
    let tilted = PinholeCamera {
        tilt_rad: 0.4,
        ..cam
    };
    for (b, r, z) in [
        (0.1, 10.0, 0.0),
        (0.6, 5.0, 1.7),
        (-0.2, 30.0, 0.0),
        (0.3, 8.0, 4.0),
    ] {
        let p = [1.0 + r * f64::cos(b), 2.0 + r * f64::sin(b), z];
        let (u, v) = tilted.project(p).unwrap();
        assert!(
            (tilted.pixel_bearing_rad(u, v) - b).abs() < 1e-12,
            "bearing {b}"
        );
    }
    // Profile bins: a full column u lands in the bin of θ(u); edges are the extreme columns.
    let prof = AngleProfiler::new(cam, 10).unwrap();
    let (lo, hi) = (-(50f64 / 100.0).atan(), (50f64 / 100.0).atan());
    let step = (hi - lo) / 10.0;
    for u in [0usize, 13, 50, 77, 100] {
        let mut fg = vec![false; 101 * 51];
        for v in 0..51 {
            fg[v * 101 + u] = true;
        }
        let counts = prof.counts(&fg).unwrap();
        let rel = -((u as f64 - 50.0) / 100.0).atan();
        let bin = (((rel - lo) / step).floor() as usize).min(9);
        assert_eq!(counts[bin], 51.0, "column {u}");
        assert_eq!(counts.iter().sum::<f64>(), 51.0);
        assert!((prof.bin_angle_rad(bin) - rel).abs() <= step / 2.0 + 1e-12);
        let profile = prof.profile(counts).unwrap();
        assert!(profile.value_at(0.3 + prof.bin_angle_rad(bin)) > 50.9);
    }
    assert_eq!(DEFAULT_N_ANGLES, 160);
}

#[test]
fn output_is_identical_with_one_and_two_threads() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut rng = ChaCha8Rng::seed_from_u64(5);
            let scene = busy_scene(&mut rng, PixelFormat::Rgb);
            let mut m =
                BackgroundModel::new(&MogConfig::default(), 160, 120, PixelFormat::Rgb).unwrap();
            let mut masks = Vec::new();
            for k in 95..140 {
                masks.push(m.apply(&scene.render(k, &mut rng).unwrap().frame).unwrap());
            }
            let comps: Vec<_> = (0..120)
                .flat_map(|y| (0..160).map(move |x| (x, y)))
                .map(|(x, y)| m.components(x, y))
                .collect();
            (masks, comps)
        })
    };
    let (m1, c1) = run(1);
    let (m2, c2) = run(2);
    assert!(m1 == m2);
    assert!(c1 == c2);
    assert!(m1.iter().any(|m| m.count_foreground() > 0));
}

#[test]
fn blobs_and_mot_rows_by_hand() {
    // A 6 × 5 block at (2, 3) and one isolated pixel; the opening removes the pixel.
    let (w, h) = (16, 12);
    let mut labels = vec![BACKGROUND; w * h];
    for y in 3..8 {
        for x in 2..8 {
            labels[y * w + x] = FOREGROUND;
        }
    }
    labels[10 * w + 13] = FOREGROUND;
    labels[w + 12] = SHADOW;
    let mask = ForegroundMask {
        width: w,
        height: h,
        labels,
    };
    let opened = PostConfig {
        open_radius: 1,
        ..PostConfig::default()
    };
    let c = clean(&mask, &opened).unwrap();
    assert_eq!(c.blobs.len(), 1);
    let b = c.blobs[0];
    assert_eq!(b.area, 30);
    assert_eq!(
        (b.bbox.left, b.bbox.top, b.bbox.width, b.bbox.height),
        (2.0, 3.0, 6.0, 5.0)
    );
    assert_eq!(b.centroid, [4.5, 5.0]);
    assert_eq!(c.foreground.iter().filter(|&&f| f).count(), 30);
    let row = b.to_mot_row(7);
    assert_eq!(row.to_string(), "7,-1,2,3,6,5,1,-1,-1,-1");
    // Without opening, the pixel survives as a component but the area filter removes it.
    let raw = PostConfig {
        open_radius: 0,
        close_radius: 0,
        min_blob_area: 2,
    };
    assert_eq!(clean(&mask, &raw).unwrap().blobs.len(), 1);
    let keep_all = PostConfig {
        min_blob_area: 1,
        ..raw
    };
    assert_eq!(clean(&mask, &keep_all).unwrap().blobs.len(), 2);
}

#[test]
fn detection_filters_by_hand() {
    assert_eq!(
        post::median3(&[0.0, 9.0, 0.0, 4.0, 5.0, 6.0]),
        vec![0.0, 0.0, 4.0, 4.0, 5.0, 6.0]
    );
    let mut f = DetectionFilter::new(DetectionFilterConfig {
        persistence_frames: 2,
        remove_spikes: false,
    });
    // Bin 0 is always 3 (a swaying tree); bin 2 gets a passing object at the third frame.
    assert_eq!(f.apply(&[3.0, 0.0, 0.0]), vec![3.0, 0.0, 0.0]);
    assert_eq!(f.apply(&[3.0, 1.0, 0.0]), vec![3.0, 1.0, 0.0]);
    assert_eq!(f.apply(&[3.0, 1.0, 8.0]), vec![0.0, 1.0, 8.0]);
    assert_eq!(f.apply(&[4.0, 1.0, 8.0]), vec![1.0, 0.0, 8.0]);
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("sensors-video-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn gradient(w: usize, h: usize, format: PixelFormat) -> VideoFrame {
    let data = (0..w * h * format.channels())
        .map(|i| (i * 7 % 256) as u8)
        .collect();
    VideoFrame::new(w, h, format, data).unwrap()
}

#[test]
fn image_sequences_and_y4m_round_trip() {
    let dir = temp_dir("seq");
    let grey = vec![
        gradient(9, 7, PixelFormat::Grey),
        gradient(9, 7, PixelFormat::Grey).to_grey(),
    ];
    io::write_image_sequence(&grey, &dir, "g", "pgm").unwrap();
    assert_eq!(io::read_image_sequence(&dir).unwrap(), grey);
    let dir = temp_dir("seq-rgb");
    let rgb = vec![gradient(9, 7, PixelFormat::Rgb); 2];
    io::write_image_sequence(&rgb, &dir, "c", "png").unwrap();
    assert_eq!(io::read_image_sequence(&dir).unwrap(), rgb);

    let mut buf = Vec::new();
    io::write_y4m(&grey, 25, &mut buf, "mem").unwrap();
    assert_eq!(io::read_y4m(buf.as_slice(), "mem").unwrap(), grey);
    // Smooth colours survive the 4:4:4 BT.601 round trip within 2 levels.
    let smooth = VideoFrame::new(
        8,
        8,
        PixelFormat::Rgb,
        (0..192).map(|i| (40 + i) as u8).collect(),
    )
    .unwrap();
    let mut buf = Vec::new();
    io::write_y4m(std::slice::from_ref(&smooth), 25, &mut buf, "mem").unwrap();
    let back = io::read_y4m(buf.as_slice(), "mem").unwrap();
    assert_eq!(back.len(), 1);
    for (a, b) in back[0].data().iter().zip(smooth.data()) {
        assert!(a.abs_diff(*b) <= 2, "{a} vs {b}");
    }
}

#[test]
fn bad_input_gets_typed_errors() {
    // Zero-size frames and models.
    assert!(matches!(
        VideoFrame::new(0, 5, PixelFormat::Grey, vec![]),
        Err(Error::ZeroSize {
            width: 0,
            height: 5
        })
    ));
    assert!(matches!(
        BackgroundModel::new(&MogConfig::default(), 4, 0, PixelFormat::Rgb),
        Err(Error::ZeroSize { .. })
    ));
    assert!(matches!(
        VideoFrame::new(2, 2, PixelFormat::Rgb, vec![0; 4]),
        Err(Error::BufferSize { expected: 12, .. })
    ));
    // A frame that changes size mid-sequence: in a list, on disk and at the model.
    let frames = vec![
        gradient(8, 6, PixelFormat::Grey),
        gradient(8, 6, PixelFormat::Grey),
        gradient(6, 8, PixelFormat::Grey),
    ];
    assert!(matches!(
        check_sequence(&frames),
        Err(Error::FrameChanged {
            index: 2,
            width: 6,
            ..
        })
    ));
    let dir = temp_dir("changed");
    for (i, f) in frames.iter().enumerate() {
        io::write_image(f, &dir.join(format!("f{i}.png"))).unwrap();
    }
    assert!(matches!(
        io::read_image_sequence(&dir),
        Err(Error::SizeMismatch {
            size: (6, 8),
            expected: (8, 6),
            ..
        })
    ));
    let mut m = BackgroundModel::new(&MogConfig::default(), 8, 6, PixelFormat::Grey).unwrap();
    m.apply(&frames[0]).unwrap();
    assert!(matches!(
        m.apply(&frames[2]),
        Err(Error::FrameMismatch { width: 6, .. })
    ));
    assert!(matches!(
        m.apply(&gradient(8, 6, PixelFormat::Rgb)),
        Err(Error::FrameMismatch { channels: 3, .. })
    ));
    // Truncated files: a y4m stream cut inside its second frame, cut inside its header, and a
    // PNG cut in half.
    let mut buf = Vec::new();
    io::write_y4m(&frames[..2], 25, &mut buf, "mem").unwrap();
    let cut = &buf[..buf.len() - 10];
    assert!(matches!(
        io::read_y4m(cut, "mem"),
        Err(Error::Truncated { frame: 1, .. })
    ));
    assert!(matches!(
        io::read_y4m(&buf[..5], "mem"),
        Err(Error::Truncated { frame: 0, .. })
    ));
    let png = dir.join("f0.png");
    let bytes = std::fs::read(&png).unwrap();
    let short = dir.join("short.png");
    std::fs::write(&short, &bytes[..bytes.len() / 2]).unwrap();
    assert!(
        matches!(io::read_image(&short), Err(Error::Truncated { .. })),
        "{:?}",
        io::read_image(&short)
    );
    // Unsupported pixel formats: 16-bit grey and RGBA PNGs, a 10-bit y4m stream.
    let p16 = dir.join("deep.png");
    image::save_buffer(&p16, &[0u8; 2 * 4 * 4], 4, 4, image::ExtendedColorType::L16).unwrap();
    assert!(matches!(
        io::read_image(&p16),
        Err(Error::UnsupportedPixelFormat { .. })
    ));
    let rgba = dir.join("alpha.png");
    image::save_buffer(
        &rgba,
        &[0u8; 4 * 4 * 4],
        4,
        4,
        image::ExtendedColorType::Rgba8,
    )
    .unwrap();
    assert!(matches!(
        io::read_image(&rgba),
        Err(Error::UnsupportedPixelFormat { .. })
    ));
    // The message says how to convert.
    let message = io::read_image(&rgba).unwrap_err().to_string();
    assert!(message.contains("ffmpeg -i IN -pix_fmt rgb24"), "{message}");
    // In a folder, a truncated image is named by its frame number, not as frame 0.
    let folder = dir.join("folder");
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::write(folder.join("img_024.png"), &bytes).unwrap();
    std::fs::write(folder.join("img_025.png"), &bytes[..bytes.len() / 2]).unwrap();
    match io::FrameFolder::open(&folder).and_then(|f| f.load(25)) {
        Err(Error::Truncated { frame: 25, .. }) => {}
        other => panic!("{other:?}"),
    }
    // Renumbered, the same images are frames 1 and 2 (and the truncated one is named so).
    let renumbered = io::FrameFolder::open(&folder)
        .unwrap()
        .renumbered(1)
        .unwrap();
    assert_eq!(renumbered.frames().collect::<Vec<_>>(), [1, 2]);
    assert!(renumbered.load(1).is_ok());
    assert!(matches!(
        renumbered.load(2),
        Err(Error::Truncated { frame: 2, .. })
    ));
    assert!(
        io::FrameFolder::open(&folder)
            .unwrap()
            .renumbered(u32::MAX)
            .is_err()
    );
    let y10 = b"YUV4MPEG2 W2 H2 F25:1 C420p10\nFRAME\n".to_vec();
    assert!(matches!(
        io::read_y4m(y10.as_slice(), "mem"),
        Err(Error::UnsupportedPixelFormat { .. })
    ));
    // Declared sizes the y4m crate would multiply unchecked (found by the fuzzer): a typed
    // error naming the value, whichever of several W/H tokens is the culprit.
    for header in [
        &b"YUV4MPEG2 W100000 H12 W100000000 H10000066 H1000006666444\nFRE\n"[..],
        b"YUV4MPEG2 W4 H99999999999999999999999 C444\nFRAME\n",
        b"YUV4MPEG2 W-4 H4 C444\nFRAME\n",
    ] {
        match io::read_y4m(header, "mem") {
            Err(Error::Y4m { reason, .. }) => assert!(reason.contains("at most 32768"), "{reason}"),
            other => panic!("{other:?}"),
        }
    }
    let mut long = b"YUV4MPEG2 W4 H4".to_vec();
    long.extend(std::iter::repeat_n(b' ', 5000));
    long.extend(b"W100000000\nFRAME\n");
    match io::read_y4m(long.as_slice(), "mem") {
        Err(Error::Y4m { reason, .. }) => assert!(reason.contains("longer than"), "{reason}"),
        other => panic!("{other:?}"),
    }
    // Bad configurations are caught once, at construction.
    let bad = MogConfig {
        background_ratio: 1.5,
        ..MogConfig::default()
    };
    assert!(matches!(
        BackgroundModel::new(&bad, 4, 4, PixelFormat::Grey),
        Err(Error::Model(_))
    ));
    assert!(parse_with_unknown_field().unwrap_err().contains("bogus"));
}

/// Serde rejects unknown fields (checked through serde's own value parser, without a TOML dep).
fn parse_with_unknown_field() -> std::result::Result<MogConfig, String> {
    let value = serde::de::value::MapDeserializer::<_, serde::de::value::Error>::new(
        [("history", 100u64), ("n_mixtures", 4), ("bogus", 1)].into_iter(),
    );
    serde::Deserialize::deserialize(value).map_err(|e: serde::de::value::Error| e.to_string())
}

#[test]
fn frame_numbers_come_from_the_last_digits_of_the_name() {
    use std::path::Path;
    assert_eq!(io::frame_number(Path::new("img1/000001.png")), Some(1));
    assert_eq!(io::frame_number(Path::new("cam2_frame0042.png")), Some(42));
    assert_eq!(io::frame_number(Path::new("7-x.png")), Some(7));
    assert_eq!(io::frame_number(Path::new("frame.png")), None);
    assert_eq!(io::frame_number(Path::new("99999999999999.png")), None);
}
