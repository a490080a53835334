//! One PHD frame with 10 targets and 20 clutter boxes: SMC-PHD at 1000 particles per target,
//! and GM-PHD on the same input. Filters are warmed up for 20 frames first; each iteration
//! steps a copy of the warmed-up filter through one more frame.
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use phd_filter::{GmConfig, GmPhd, PhdConfig, SmcPhd};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::BoundingBox;

fn frames(n: usize) -> Vec<Vec<BoundingBox>> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let people: Vec<(f64, f64)> = (0..10)
        .map(|i| (40.0 + 60.0 * i as f64, 200.0 + 10.0 * (i % 3) as f64))
        .collect();
    (0..n)
        .map(|t| {
            let mut boxes: Vec<BoundingBox> = people
                .iter()
                .map(|&(x, y)| BoundingBox {
                    left: x + 0.5 * t as f64 + rng.random_range(-2.0..2.0),
                    top: y + rng.random_range(-2.0..2.0),
                    width: 40.0,
                    height: 100.0,
                })
                .collect();
            boxes.extend((0..20).map(|_| BoundingBox {
                left: rng.random_range(0.0..600.0),
                top: rng.random_range(0.0..380.0),
                width: 40.0,
                height: 100.0,
            }));
            boxes
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let input = frames(21);
    let config = PhdConfig {
        clutter_rate: 20.0,
        ..PhdConfig::default()
    };
    let mut smc = SmcPhd::new(config, 1).unwrap();
    let mut gm = GmPhd::new(config, GmConfig::default()).unwrap();
    for f in &input[..20] {
        smc.step(f).unwrap();
        gm.step(f).unwrap();
    }
    let last = &input[20];
    let n = smc.particles().len();
    assert!((10_000..=25_000).contains(&n), "{n} particles");
    c.bench_function("smc_phd_frame_10_targets_20_clutter_1000_per_target", |b| {
        b.iter_batched(
            || smc.clone(),
            |mut f| f.step(black_box(last)).unwrap().estimates.len(),
            BatchSize::LargeInput,
        )
    });
    c.bench_function("gm_phd_frame_10_targets_20_clutter", |b| {
        b.iter_batched(
            || gm.clone(),
            |mut f| f.step(black_box(last)).unwrap().estimates.len(),
            BatchSize::SmallInput,
        )
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
