//! The spline baselines at the problem sizes of `docs/comparisons/scipy_splines.py`: the
//! least-squares cubic B-spline (SciPy's `make_lsq_spline`) on the scenario's size (180
//! samples, Oh & Jung's 8 coefficients) and on a large one (10 000 samples, 100 interior
//! knots), and the GCV smoothing spline (SciPy's `make_smoothing_spline(lam=None)`) on 180.
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use gdt_bridge::{BSpline, GcvConfig, SmoothingSpline};

/// The same deterministic samples as the SciPy script: x = 0..n, a smooth curve plus a
/// fixed pseudo-random wiggle.
fn samples(n: usize) -> (Vec<f64>, Vec<f64>) {
    let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let y = x
        .iter()
        .map(|&t| 10.0 * (t / 10.0).sin() + 0.5 * (t * 12.9898).sin().fract())
        .collect();
    (x, y)
}

/// Clamped cubic knots with `interior` uniform interior knots over [x_0, x_{n−1}].
fn knots(x: &[f64], interior: usize) -> Vec<f64> {
    let (a, b) = (x[0], x[x.len() - 1]);
    let mut t = vec![a; 4];
    t.extend((1..=interior).map(|k| a + (b - a) * k as f64 / (interior + 1) as f64));
    t.extend([b; 4]);
    t
}

fn bench_splines(c: &mut Criterion) {
    for (n, interior) in [(180, 4), (10_000, 100)] {
        let (x, y) = samples(n);
        let w = vec![1.0; n];
        let t = knots(&x, interior);
        c.bench_function(
            &format!("lsq_bspline_{n}_samples_{}_coefficients", interior + 4),
            |b| b.iter(|| BSpline::fit_lsq(black_box(&x), black_box(&y), &w, &t).unwrap()),
        );
    }
    let (x, y) = samples(180);
    let gcv = GcvConfig::default();
    c.bench_function("smoothing_spline_gcv_180_samples", |b| {
        b.iter(|| SmoothingSpline::fit_gcv(black_box(&x), black_box(&y), &gcv).unwrap())
    });
}

criterion_group!(benches, bench_splines);
criterion_main!(benches);
