//! Kalman benchmarks: one constant-velocity predict + update, and a 1000-step filter followed
//! by the RTS smoother (filterpy needs ≈ 26 ms for the latter on this machine:
//! docs/comparisons/filterpy_cv2d_1000.py, docs/benchmarks.md).
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix4, Vector2, Vector4};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use tracker_model::{
    ConstantVelocity2, CvNoise, Gaussian, ObservationModel, TransitionModel, filter,
    position_measurement, smooth,
};

fn bench_kalman(c: &mut Criterion) {
    let motion = ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q: 0.1 }).unwrap();
    let sensor = position_measurement(4.0).unwrap();
    let prior =
        Gaussian::new(Vector4::new(0.0, 0.0, 1.0, 1.0), Matrix4::identity() * 10.0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let measurements: Vec<Option<Vector2<f64>>> = (0..1000)
        .map(|k| {
            let t = k as f64;
            let n: [f64; 2] = [
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            ];
            (k % 10 != 3).then(|| Vector2::new(t + 2.0 * n[0], t + 2.0 * n[1]))
        })
        .collect();

    c.bench_function("cv2d_predict_update", |b| {
        let z = Vector2::new(1.0, 1.2);
        b.iter(|| {
            let predicted = motion.predict(black_box(&prior));
            sensor.update(&predicted, black_box(&z)).unwrap()
        })
    });
    c.bench_function("cv2d_filter_1000_steps", |b| {
        b.iter(|| filter(&motion, &sensor, &prior, black_box(&measurements)).unwrap())
    });
    let run = filter(&motion, &sensor, &prior, &measurements).unwrap();
    c.bench_function("cv2d_rts_1000_steps", |b| {
        b.iter(|| smooth(&motion, black_box(&run)).unwrap())
    });
    c.bench_function("cv2d_filter_and_rts_1000_steps", |b| {
        b.iter(|| {
            let run = filter(&motion, &sensor, &prior, black_box(&measurements)).unwrap();
            smooth(&motion, &run).unwrap()
        })
    });
}

criterion_group!(benches, bench_kalman);
criterion_main!(benches);
