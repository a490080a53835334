use std::sync::Arc;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::{BoundingBox, LocalDetector};

use crate::hog::{BINS, BlockGrid, CellGrid, Plane};
use crate::scene::{background, draw_sprite, noisy_frame as frame, wandering_path};
use crate::{
    BoostConfig, ColourHistogram, DetectorConfig, FrameFeed, ImageDetectors, OnlineBooster,
};

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

/// A grey plane from a function of (x, y).
fn plane(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Plane {
    let data = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| f(x, y))
        .collect();
    Plane::new(w, h, 1, data).unwrap()
}

#[test]
fn horizontal_edge_puts_all_mass_in_the_90_degree_bin() {
    // Dark above row 12, bright below: gradients point down (θ = 90°), bin 4 (80°-100°).
    let p = plane(32, 32, |_, y| if y >= 12 { 200.0 } else { 20.0 });
    let g = CellGrid::compute(&p).unwrap();
    let h = g.cell(1, 1);
    // Rows 11 and 12 see the step: 2 rows × 8 pixels × 180.
    assert!(close(h[4], 2.0 * 8.0 * 180.0, 1e-3), "{h:?}");
    for (b, v) in h.iter().enumerate() {
        if b != 4 {
            assert!(close(*v, 0.0, 1e-6), "bin {b}: {v}");
        }
    }
    // Cells away from the edge are empty.
    assert!(g.cell(1, 3).iter().all(|v| *v == 0.0));
}

#[test]
fn diagonal_edge_splits_between_the_30_and_50_degree_bins() {
    // A step along x + y = 30: θ = 45°, 15° past bin 1's centre (30°) and 5° short of bin 2's
    // (50°): weights 1/4 and 3/4.
    let p = plane(48, 48, |x, y| if x + y >= 30 { 255.0 } else { 0.0 });
    let g = CellGrid::compute(&p).unwrap();
    let (mut b1, mut b2, mut other) = (0.0, 0.0, 0.0);
    for cy in 0..g.cells_y() {
        for cx in 0..g.cells_x() {
            let h = g.cell(cx, cy);
            b1 += h[1];
            b2 += h[2];
            other += h.iter().sum::<f32>() - h[1] - h[2];
        }
    }
    assert!(b1 > 0.0 && close(b2 / b1, 3.0, 1e-4), "{b1} {b2}");
    // Only the image border (reflected) adds other directions.
    assert!(other < 0.05 * (b1 + b2), "{other}");
}

#[test]
fn l2_hys_block_normalisation_matches_the_hand_calculation() {
    // A ramp at 35°: every interior pixel has magnitude 2g and splits 0.75 / 0.25 between bins
    // 1 and 2. A block of four equal cells: v = (0.75, 0.25) m in each cell, ‖v‖ = m √2.5;
    // L2: 0.474342, 0.158114; clip: 0.2, 0.158114; L2 again (norm √0.26): 0.392232, 0.310087.
    let (c, s) = (35f32.to_radians().cos(), 35f32.to_radians().sin());
    let p = plane(48, 48, |x, y| 3.0 * (c * x as f32 + s * y as f32));
    let cells = CellGrid::compute(&p).unwrap();
    let h = cells.cell(2, 2);
    let m = 64.0 * 2.0 * 3.0;
    assert!(
        close(h[1], 0.75 * m, 1e-2) && close(h[2], 0.25 * m, 1e-2),
        "{h:?}"
    );
    let blocks = BlockGrid::from_cells(&cells);
    let b = blocks.block(1, 1);
    for cell in 0..4 {
        let v = &b[cell * BINS..(cell + 1) * BINS];
        assert!(close(v[1], 0.392_232, 1e-5), "{v:?}");
        assert!(close(v[2], 0.310_087, 1e-5), "{v:?}");
        assert!(
            v.iter()
                .enumerate()
                .all(|(k, x)| k == 1 || k == 2 || *x == 0.0)
        );
    }
    // A window's descriptor is its blocks read row by row.
    let d = blocks.window_descriptor(1, 1, 3, 3).unwrap();
    assert_eq!(d.len(), 4 * 36);
    assert_eq!(&d[36..72], blocks.block(2, 1));
    assert!(blocks.window_descriptor(4, 0, 3, 3).is_none());
}

#[test]
fn bad_planes_are_errors() {
    assert!(Plane::new(4, 4, 2, vec![0.0; 32]).is_err());
    assert!(Plane::new(4, 4, 1, vec![0.0; 15]).is_err());
    assert!(CellGrid::compute(&plane(15, 40, |_, _| 0.0)).is_err());
}

#[test]
fn bhattacharyya_by_hand() {
    let mut p = ColourHistogram::empty(8);
    p.add([10.0, 10.0, 10.0], 1.0);
    p.add([250.0, 10.0, 10.0], 1.0);
    p.normalise();
    let mut q = ColourHistogram::empty(8);
    q.add([20.0, 20.0, 20.0], 1.0); // same bin as (10, 10, 10)
    q.normalise();
    assert!((p.bhattacharyya(&q) - 0.5f64.sqrt()).abs() < 1e-6);
    assert!((p.bhattacharyya(&p) - 1.0).abs() < 1e-6);
    let mut r = ColourHistogram::empty(8);
    r.add([10.0, 250.0, 10.0], 1.0);
    r.normalise();
    assert!(p.bhattacharyya(&r).abs() < 1e-12);
}

/// A separable toy problem: feature 3 is N(0.7, 0.05²) for positives and N(0.3, 0.05²) for
/// negatives; the 19 others are uniform noise.
fn toy(rng: &mut ChaCha8Rng, positive: bool) -> Vec<f64> {
    let mut x: Vec<f64> = (0..20).map(|_| rng.random::<f64>()).collect();
    let z: f64 = (0..12).map(|_| rng.random::<f64>()).sum::<f64>() - 6.0;
    x[3] = if positive { 0.7 } else { 0.3 } + 0.05 * z;
    x
}

fn toy_error(b: &OnlineBooster, rng: &mut ChaCha8Rng) -> f64 {
    let wrong = (0..1000)
        .filter(|i| {
            let y = i % 2 == 0;
            let x = toy(rng, y);
            b.classify(|f| x[f]) != y
        })
        .count();
    wrong as f64 / 1000.0
}

#[test]
fn online_boosting_learns_a_separable_problem_within_200_updates() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let config = BoostConfig {
        selectors: 10,
        pool: 40,
        window: 100.0,
    };
    let mut b = OnlineBooster::new(config, 20, &mut rng).unwrap();
    let mut test_rng = ChaCha8Rng::seed_from_u64(99);
    // Untrained, it calls everything negative: half wrong.
    assert!(toy_error(&b, &mut test_rng) > 0.4);
    for i in 0..200 {
        let y = i % 2 == 0;
        let x = toy(&mut rng, y);
        b.update(|f| x[f], y, &mut rng);
    }
    let e = toy_error(&b, &mut test_rng);
    assert!(e < 0.05, "error {e}");
}

#[test]
fn bad_configs_are_errors() {
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let c = BoostConfig {
        selectors: 10,
        pool: 10,
        window: 10.0,
    };
    assert!(OnlineBooster::new(c, 5, &mut rng).is_err());
    assert!(OnlineBooster::new(BoostConfig::default(), 0, &mut rng).is_err());
    let d = DetectorConfig {
        scales: vec![],
        ..DetectorConfig::default()
    };
    assert!(ImageDetectors::new(d, FrameFeed::new(), 0).is_err());
    let d = DetectorConfig {
        colour_weight: 1.5,
        ..DetectorConfig::default()
    };
    assert!(ImageDetectors::new(d, FrameFeed::new(), 0).is_err());
}

/// Runs a detector alone (confirmed where it finds itself) for `n` frames along `path`;
/// returns the boxes it reported.
fn follow(path: &[BoundingBox], seed: u64) -> Vec<Option<BoundingBox>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let bg = background(320, 240, &mut rng);
    let feed = FrameFeed::new();
    let mut factory = ImageDetectors::new(DetectorConfig::default(), feed.clone(), seed).unwrap();
    feed.set(0, Arc::new(frame(&bg, &path[0], &mut rng)));
    let mut d = factory.detector(0, &path[0]).unwrap();
    let mut last = path[0];
    let mut out = vec![Some(path[0])];
    for (k, truth) in path.iter().enumerate().skip(1) {
        let k = k as u32;
        feed.set(k, Arc::new(frame(&bg, truth, &mut rng)));
        let found = d.detect(k, &last);
        if let Some(b) = found {
            d.confirm(k, &b);
            last = b;
        }
        out.push(found);
    }
    out
}

#[test]
fn follows_a_textured_sprite_on_clutter_for_200_frames() {
    let path = wandering_path(200).unwrap();
    let found = follow(&path, 11);
    let good = found
        .iter()
        .zip(&path)
        .filter(|(f, t)| f.is_some_and(|b| b.iou(t) >= 0.5))
        .count();
    assert!(
        good as f64 >= 0.95 * 200.0,
        "{good} of 200 frames with IoU >= 0.5"
    );
}

#[test]
fn identical_with_one_and_two_threads() {
    let path = wandering_path(40).unwrap();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| follow(&path, 5))
    };
    assert_eq!(run(1), run(2));
}

/// Ten detectors on sprites drawn side by side, searched with `detect_all` and updated with
/// `confirm_all` for 15 frames at `threads` threads; the boxes of every frame.
fn ten_in_parallel(threads: usize) -> Vec<Vec<Option<BoundingBox>>> {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let bg = background(320, 240, &mut rng);
    let at = |i: usize, k: usize| {
        BoundingBox::new(
            4.0 + 31.0 * i as f64 + 0.5 * k as f64,
            20.0 + 12.0 * (i % 4) as f64,
            18.0,
            44.0,
        )
        .unwrap()
    };
    let draw = |k: usize, rng: &mut ChaCha8Rng| {
        let mut im = bg.clone();
        for i in 0..10 {
            draw_sprite(&mut im, &at(i, k));
        }
        for p in im.pixels_mut() {
            for c in &mut p.0 {
                *c = (f64::from(*c) + rng.random_range(-8.0..8.0)).clamp(0.0, 255.0) as u8;
            }
        }
        Arc::new(im)
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let feed = FrameFeed::new();
        let mut factory = ImageDetectors::new(DetectorConfig::default(), feed.clone(), 9).unwrap();
        feed.set(0, draw(0, &mut rng));
        let mut detectors: Vec<_> = (0..10)
            .map(|i| factory.detector(0, &at(i, 0)).unwrap())
            .collect();
        let mut last: Vec<BoundingBox> = (0..10).map(|i| at(i, 0)).collect();
        let mut out = Vec::new();
        for k in 1..15u32 {
            feed.set(k, draw(k as usize, &mut rng));
            let found = crate::detect_all(&mut detectors, k, &last).unwrap();
            for (l, f) in last.iter_mut().zip(&found) {
                if let Some(b) = f {
                    *l = *b;
                }
            }
            crate::confirm_all(&mut detectors, k, &last).unwrap();
            out.push(found);
        }
        out
    })
}

#[test]
fn detect_all_and_confirm_all_are_identical_with_one_and_two_threads() {
    let one = ten_in_parallel(1);
    assert_eq!(one, ten_in_parallel(2));
    // They found something (the comparison is not of ten empty lists).
    assert!(one.iter().flatten().filter(|f| f.is_some()).count() > 100);
}

#[test]
fn detect_all_and_confirm_all_need_one_box_per_detector() {
    let feed = FrameFeed::new();
    let mut factory = ImageDetectors::new(DetectorConfig::default(), feed, 1).unwrap();
    let b = BoundingBox::new(10.0, 10.0, 24.0, 60.0).unwrap();
    let mut detectors = vec![factory.detector(0, &b).unwrap()];
    for boxes in [vec![], vec![b, b]] {
        let want = crate::Error::BoxCount {
            detectors: 1,
            boxes: boxes.len(),
        };
        assert_eq!(
            crate::detect_all(&mut detectors, 1, &boxes)
                .unwrap_err()
                .to_string(),
            want.to_string()
        );
        assert_eq!(
            crate::confirm_all(&mut detectors, 1, &boxes)
                .unwrap_err()
                .to_string(),
            want.to_string()
        );
    }
}

#[test]
fn a_sprite_that_leaves_the_image_is_lost_and_its_detector_removed() {
    use phd_filter::{DetectorBank, FusionConfig};
    // Walks right at 3 px/frame from x = 260 and leaves the 320-pixel image around frame 20.
    // (Kept short in view: after about 19 confirmations phd-filter's confidence rounds to
    // exactly 1.0 in f64 and eq. 10 can no longer lower it.)
    let path: Vec<BoundingBox> = (0..150)
        .map(|k| BoundingBox::new(260.0 + 3.0 * k as f64, 100.0, 24.0, 60.0).unwrap())
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let bg = background(320, 240, &mut rng);
    let feed = FrameFeed::new();
    let mut factory = ImageDetectors::new(DetectorConfig::default(), feed.clone(), 1).unwrap();
    feed.set(0, Arc::new(frame(&bg, &path[0], &mut rng)));
    let fusion = FusionConfig::default();
    let mut bank = DetectorBank::default();
    bank.add(
        1,
        Box::new(factory.detector(0, &path[0]).unwrap()),
        path[0],
        &fusion,
    );
    let mut removed_at = None;
    let mut last_found = 0;
    let mut confirmations = 0u32;
    for (k, truth) in path.iter().enumerate().skip(1) {
        let k32 = k as u32;
        feed.set(k32, Arc::new(frame(&bg, truth, &mut rng)));
        // The global detector sees the person while at least half of it is in the image.
        let global: Vec<BoundingBox> = if truth.left + truth.width / 2.0 < 320.0 {
            vec![*truth]
        } else {
            Vec::new()
        };
        let found = bank.detect(k32);
        if found
            .iter()
            .any(|(_, b)| global.iter().any(|g| g.iou(b) >= fusion.confirm_iou))
        {
            confirmations += 1;
        }
        if let Some((_, b)) = found.first() {
            last_found = k;
            bank.confirm(1, k32, b);
        }
        bank.update_confidence(&found, &global, &fusion);
        if bank.detectors().is_empty() {
            removed_at = Some(k);
            break;
        }
    }
    // Half of the box leaves at frame (320 − 12 − 260) / 3 = 16. Eqs. 9-10 with p_D = 0.7 and
    // p_FA = 0.1 multiply the odds by 7 per confirmation and by 1/3 per miss; from odds 1 the
    // detector goes when the odds reach 1/9, i.e. after (n ln 7 + ln 9) / ln 3 misses following
    // n confirmations (fewer if some frames in view were missed).
    let removed = removed_at.expect("the detector is removed");
    let n = f64::from(confirmations);
    let misses = ((n * 7f64.ln() + 9f64.ln()) / 3f64.ln()).ceil() as usize;
    assert!(
        confirmations >= 12,
        "confirmed only {confirmations} times while in view"
    );
    assert!(
        removed > 16,
        "removed at {removed}, while the person was in view"
    );
    assert!(
        removed <= 1 + 16 + misses,
        "removed only at {removed} ({misses} misses allowed)"
    );
    assert!(last_found <= 20, "still finding something at {last_found}");
}

#[test]
fn integral_cells_equal_direct_cells_at_every_offset() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let im = background(40, 36, &mut rng);
    let p = Plane::from_rgb(&im).unwrap();
    let integral = crate::hog::OrientedIntegral::compute(&p);
    let direct = CellGrid::compute(&p).unwrap();
    let via = integral.cells(0, 0).unwrap();
    assert_eq!((via.cells_x(), via.cells_y()), (5, 4));
    for cy in 0..4 {
        for cx in 0..5 {
            for (a, b) in via.cell(cx, cy).iter().zip(direct.cell(cx, cy)) {
                assert!(close(*a, *b, 1e-2 * b.abs().max(1.0)), "{a} {b}");
            }
        }
    }
    // At offset (3, 2): cell (0, 0) covers pixels 3..11 × 2..10, summed by brute force from
    // one-pixel cells of the integral.
    let shifted = integral.cells(3, 2).unwrap();
    assert_eq!((shifted.cells_x(), shifted.cells_y()), (4, 4));
    let mut brute = [0.0f64; BINS];
    for y in 2..10 {
        for x in 3..11 {
            // A 1 × 1 rectangle = one pixel's votes.
            for (b, v) in brute.iter_mut().enumerate() {
                let s = crate::hog::pixel_votes(&integral, x, y)[b];
                *v += s;
            }
        }
    }
    for (a, b) in shifted.cell(0, 0).iter().zip(brute) {
        assert!(
            close(*a, b as f32, 1e-2 * (b as f32).abs().max(1.0)),
            "{a} {b}"
        );
    }
}

#[test]
fn the_fast_angle_matches_atan2() {
    for k in 0..3600 {
        let a = k as f64 * std::f64::consts::TAU / 3600.0 + 1e-3;
        let (gx, gy) = (a.cos() as f32 * 37.0, a.sin() as f32 * 37.0);
        let mut want = gy.atan2(gx);
        if want < 0.0 {
            want += std::f32::consts::PI;
        }
        let got = crate::hog::unsigned_angle(gx, gy);
        let d = (got - want).abs();
        let d = d.min(std::f32::consts::PI - d);
        assert!(d < 2e-6, "{a}: {got} vs {want}");
    }
    assert!(close(crate::hog::unsigned_angle(0.0, 0.0), 0.0, 0.0));
    assert!(close(
        crate::hog::unsigned_angle(0.0, -3.0),
        std::f32::consts::FRAC_PI_2,
        1e-7
    ));
    assert!(close(crate::hog::unsigned_angle(-3.0, 0.0), 0.0, 1e-7));
}
