//! SORT, ByteTrack and OC-SORT over 30 frames of 10, 100 and 1,000 walkers (boxes 20 × 50
//! on a grid, moving 1-3 px a frame, a tenth of them low-scoring each frame): the whole step
//! per frame, prediction, IoU, assignment, updates and track management.

use std::hint::black_box;

use box_trackers::{ByteTrackConfig, OcSortConfig, SortConfig};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use tracker_model::{BoundingBox, Detection, Tracker};

const FRAMES: u32 = 30;

fn scene(n: usize) -> Vec<Vec<Detection>> {
    let side = (n as f64).sqrt().ceil() as usize;
    (1..=FRAMES)
        .map(|f| {
            (0..n)
                .map(|i| {
                    let (row, col) = ((i / side) as f64, (i % side) as f64);
                    let speed = 1.0 + (i % 3) as f64;
                    let jitter = (0.7 * f64::from(f) + i as f64).sin();
                    let left = 40.0 * col + speed * f64::from(f) + jitter;
                    let b = BoundingBox::new(left, 80.0 * row + jitter, 20.0, 50.0)
                        .expect("a valid box");
                    let score = if (i + f as usize).is_multiple_of(10) {
                        0.4
                    } else {
                        0.9
                    };
                    Detection::boxed((i + n * f as usize) as u64, f, b).with_score(score)
                })
                .collect()
        })
        .collect()
}

fn run<T: Tracker>(mut tracker: T, frames: &[Vec<Detection>]) -> usize {
    let mut n = 0;
    for (f, detections) in frames.iter().enumerate() {
        let states = tracker.step(f as u32 + 1, detections).expect("step");
        n += states.len();
    }
    n
}

fn trackers(c: &mut Criterion) {
    let mut group = c.benchmark_group("box_trackers_30_frames");
    group.sample_size(10);
    for n in [10, 100, 1000] {
        let frames = scene(n);
        group.bench_with_input(BenchmarkId::new("sort", n), &frames, |b, frames| {
            b.iter(|| {
                run(
                    SortConfig::default().build().expect("defaults"),
                    black_box(frames),
                )
            })
        });
        group.bench_with_input(BenchmarkId::new("bytetrack", n), &frames, |b, frames| {
            b.iter(|| {
                run(
                    ByteTrackConfig::default().build().expect("defaults"),
                    black_box(frames),
                )
            })
        });
        group.bench_with_input(BenchmarkId::new("ocsort", n), &frames, |b, frames| {
            b.iter(|| {
                run(
                    OcSortConfig::default().build().expect("defaults"),
                    black_box(frames),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, trackers);
criterion_main!(benches);
