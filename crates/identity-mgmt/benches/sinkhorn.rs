//! Sinkhorn benchmarks: a positive 100 × 100 matrix (entries uniform in [0.01, 1), fixed seed)
//! scaled to doubly stochastic to 1e-9, with and without the scalability test before it; the
//! two scalability routes on a sparse 100 × 100 pattern; and a 5 × 2 local-information update
//! of the paper's size.
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use identity_mgmt::{
    BeliefMatrix, IdentityId, ScalingConfig, SinkhornConfig, flow_scalability, scale_to_marginals,
    sinkhorn, square_scalability,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::TrackId;

fn bench(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    let n = 100;
    let a: Vec<f64> = (0..n * n).map(|_| rng.random_range(0.01..1.0)).collect();
    let ones = vec![1.0; n];
    let config = SinkhornConfig {
        tolerance: 1e-9,
        max_iterations: 10_000,
    };
    c.bench_function("sinkhorn_positive_100x100_1e-9", |b| {
        b.iter(|| {
            let mut m = a.clone();
            let r = sinkhorn(&mut m, n, n, &ones, &ones, &config).unwrap();
            assert!(r.converged);
            black_box(m)
        })
    });
    let scaling = ScalingConfig {
        sinkhorn: config,
        ..ScalingConfig::default()
    };
    c.bench_function("scale_with_test_positive_100x100_1e-9", |b| {
        b.iter(|| {
            let mut m = a.clone();
            black_box(scale_to_marginals(&mut m, n, n, &ones, &ones, &scaling).unwrap())
        })
    });
    // A sparse 100 × 100 pattern (the diagonal plus 5 % of the entries) for the cost of the
    // two scalability routes themselves.
    let sparse: Vec<f64> = (0..n * n)
        .map(|k| {
            if k / n == k % n || rng.random_bool(0.05) {
                rng.random_range(0.01..1.0)
            } else {
                0.0
            }
        })
        .collect();
    c.bench_function("scalability_square_route_100x100_sparse", |b| {
        b.iter(|| black_box(square_scalability(&sparse, n).unwrap()))
    });
    c.bench_function("scalability_flow_route_100x100_sparse", |b| {
        b.iter(|| black_box(flow_scalability(&sparse, n, n, &ones, &ones).unwrap()))
    });
    let ids: Vec<IdentityId> = (0..5).map(IdentityId).collect();
    let tracks = vec![TrackId(0), TrackId(1)];
    let belief = BeliefMatrix::from_row_major(
        ids,
        tracks,
        vec![0.3, 0.1, 0.3, 0.1, 0.2, 0.2, 0.1, 0.3, 0.1, 0.3],
    )
    .unwrap();
    c.bench_function("local_information_5x2", |b| {
        b.iter(|| {
            let mut m = belief.clone();
            let info = [0.0, 0.9, 0.05, 0.05, 0.0];
            black_box(
                m.incorporate_local_information(TrackId(1), &info, &scaling)
                    .unwrap(),
            )
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
