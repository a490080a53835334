//! A synthetic MOT sequence of 1000 frames × 20 objects with misses, false positives and
//! identity switches, scored with CLEAR + identity + HOTA (+ SR/FAF) in one `evaluate` call.
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use eval_metrics::{EvalConfig, Sequence, clear_mot, evaluate, hota, identity};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::{BoundingBox, Track, TrackId, TrackPoint, TrackSet};

fn synthetic(n_frames: u32, n_objects: u64, seed: u64) -> (TrackSet, TrackSet) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut gt = Vec::new();
    let mut pred: Vec<Vec<TrackPoint>> = vec![Vec::new(); n_objects as usize * 2];
    for obj in 0..n_objects {
        let (x0, y0) = (rng.random_range(0.0..1500.0), rng.random_range(0.0..900.0));
        let (vx, vy) = (rng.random_range(-2.0..2.0), rng.random_range(-1.0..1.0));
        let mut points = Vec::new();
        for f in 1..=n_frames {
            let t = f64::from(f);
            let b = BoundingBox::new(x0 + vx * t, y0 + vy * t, 40.0, 90.0).unwrap();
            points.push(TrackPoint::boxed(f, b));
            if rng.random_bool(0.9) {
                // Estimates jitter by a few pixels; every 200 frames an object gets a new id
                // (an identity switch).
                let jb = BoundingBox::new(
                    b.left + rng.random_range(-3.0..3.0),
                    b.top + rng.random_range(-3.0..3.0),
                    40.0,
                    90.0,
                )
                .unwrap();
                let id = obj as usize * 2 + ((f / 200) % 2) as usize;
                pred[id].push(TrackPoint::boxed(f, jb));
            }
        }
        gt.push(Track::from_points(TrackId(obj), points).unwrap());
    }
    let mut pred_tracks: Vec<Track> = pred
        .into_iter()
        .enumerate()
        .map(|(i, pts)| Track::from_points(TrackId(i as u64), pts).unwrap())
        .collect();
    // One false positive per frame, each a short-lived track of its own.
    for f in 1..=n_frames {
        let b = BoundingBox::new(
            rng.random_range(0.0..1500.0),
            rng.random_range(0.0..900.0),
            40.0,
            90.0,
        )
        .unwrap();
        pred_tracks.push(
            Track::from_points(
                TrackId(100_000 + u64::from(f)),
                vec![TrackPoint::boxed(f, b)],
            )
            .unwrap(),
        );
    }
    (
        TrackSet::from_tracks(gt).unwrap(),
        TrackSet::from_tracks(pred_tracks).unwrap(),
    )
}

fn bench_metrics(c: &mut Criterion) {
    let (gt, pred) = synthetic(1000, 20, 7);
    let config = EvalConfig::default();
    c.bench_function("evaluate_1000x20_clear_identity_hota", |b| {
        b.iter(|| evaluate(black_box(&gt), black_box(&pred), &config).unwrap())
    });
    c.bench_function("clear_identity_hota_1000x20", |b| {
        b.iter(|| {
            let seq = Sequence::new(black_box(&gt), black_box(&pred), config.matching.similarity)
                .unwrap();
            (
                clear_mot(&seq, 0.5).unwrap(),
                identity(&seq, 0.5).unwrap(),
                hota(&seq).unwrap(),
            )
        })
    });
    let seq = Sequence::new(&gt, &pred, config.matching.similarity).unwrap();
    c.bench_function("sequence_1000x20", |b| {
        b.iter(|| {
            Sequence::new(black_box(&gt), black_box(&pred), config.matching.similarity).unwrap()
        })
    });
    c.bench_function("clear_1000x20", |b| {
        b.iter(|| clear_mot(black_box(&seq), 0.5).unwrap())
    });
    c.bench_function("identity_1000x20", |b| {
        b.iter(|| identity(black_box(&seq), 0.5).unwrap())
    });
    c.bench_function("hota_1000x20", |b| {
        b.iter(|| hota(black_box(&seq)).unwrap())
    });
}

criterion_group!(benches, bench_metrics);
criterion_main!(benches);
