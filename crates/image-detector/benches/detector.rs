//! One local detector's search and update on a 768 × 576 frame (search window twice the
//! object; one scale, the default, and three), and ten detectors on one frame: one after
//! another (as phd-filter's detector bank runs them), searches in parallel with `detect_all`
//! then updates one after another, and both in parallel (`detect_all`, `confirm_all`).
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use image::{Rgb, RgbImage};
use image_detector::{
    DetectorConfig, FrameFeed, ImageDetector, ImageDetectors, confirm_all, detect_all,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::{BoundingBox, LocalDetector};

/// A cluttered 768 × 576 frame with ten striped 48 × 120 figures in a row.
fn scene() -> (RgbImage, Vec<BoundingBox>) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (w, h) = (768u32, 576u32);
    let mut im = RgbImage::from_fn(w, h, |_, _| Rgb([rng.random(), rng.random(), rng.random()]));
    let boxes: Vec<BoundingBox> = (0..10)
        .map(|i| BoundingBox {
            left: 20.0 + 74.0 * f64::from(i),
            top: 100.0 + 30.0 * f64::from(i % 3),
            width: 48.0,
            height: 120.0,
        })
        .collect();
    for (i, b) in boxes.iter().enumerate() {
        let c = Rgb([40 + 20 * i as u8, 200 - 15 * i as u8, 90]);
        for y in b.top as u32..b.bottom() as u32 {
            for x in b.left as u32..b.right() as u32 {
                if (y / 6) % 2 == 0 {
                    im.put_pixel(x, y, c);
                }
            }
        }
    }
    (im, boxes)
}

fn bench(c: &mut Criterion) {
    let (im, boxes) = scene();
    let feed = FrameFeed::new();
    feed.set(0, Arc::new(im));
    let mut factory = ImageDetectors::new(DetectorConfig::default(), feed.clone(), 3).unwrap();
    let mut detectors: Vec<ImageDetector> = boxes
        .iter()
        .map(|b| factory.detector(0, b).unwrap())
        .collect();
    let shifted: Vec<BoundingBox> = boxes
        .iter()
        .map(|b| BoundingBox {
            left: b.left + 3.0,
            ..*b
        })
        .collect();
    c.bench_function("image_detector/one_search_and_update_768x576", |bch| {
        let d = &mut detectors[0];
        bch.iter(|| {
            let found = d.detect(0, black_box(&shifted[0]));
            d.confirm(0, &boxes[0]);
            black_box(found)
        });
    });
    let three = DetectorConfig {
        scales: vec![0.95, 1.0, 1.05],
        ..DetectorConfig::default()
    };
    let mut d3 = ImageDetectors::new(three, feed.clone(), 3)
        .unwrap()
        .detector(0, &boxes[0])
        .unwrap();
    c.bench_function("image_detector/one_search_and_update_3_scales", |bch| {
        bch.iter(|| {
            let found = d3.detect(0, black_box(&shifted[0]));
            d3.confirm(0, &boxes[0]);
            black_box(found)
        });
    });
    c.bench_function("image_detector/ten_search_and_update_sequential", |bch| {
        bch.iter(|| {
            for (d, (a, b)) in detectors.iter_mut().zip(shifted.iter().zip(&boxes)) {
                black_box(d.detect(0, a));
                d.confirm(0, b);
            }
        });
    });
    c.bench_function("image_detector/ten_search_parallel_then_update", |bch| {
        bch.iter(|| {
            let found = detect_all(&mut detectors, 0, black_box(&shifted)).unwrap();
            for (d, b) in detectors.iter_mut().zip(&boxes) {
                d.confirm(0, b);
            }
            black_box(found)
        });
    });
    c.bench_function("image_detector/ten_search_and_update_parallel", |bch| {
        bch.iter(|| {
            let found = detect_all(&mut detectors, 0, black_box(&shifted)).unwrap();
            confirm_all(&mut detectors, 0, &boxes).unwrap();
            black_box(found)
        });
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
