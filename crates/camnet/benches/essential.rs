//! Essential matrix in LO-RANSAC (no refinement) on 500 correspondences with 30 % outliers
//! and 0.5 px noise at f = 1000 (the issue's ≤ 5 ms target).

use camnet::{EssentialConfig, Pose, project, ransac_essential};
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Rotation3, Vector2, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn data() -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let pose = Pose {
        rotation: Rotation3::from_euler_angles(0.2, -0.4, 0.1),
        translation: Vector3::new(-1.0, 0.3, 0.2).normalize(),
    };
    let (mut x1, mut x2) = (Vec::new(), Vec::new());
    while x1.len() < 500 {
        let p = Vector3::new(
            rng.random_range(-3.0..3.0),
            rng.random_range(-3.0..3.0),
            rng.random_range(4.0..10.0),
        );
        if let (Some(a), Some(b)) = (project(&p), project(&pose.apply(&p))) {
            let i = x1.len();
            let n = |rng: &mut ChaCha8Rng| {
                Vector2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5)) / 1000.0
            };
            x1.push(a + n(&mut rng));
            if i % 10 < 3 {
                x2.push(Vector2::new(
                    rng.random_range(-0.6..0.6),
                    rng.random_range(-0.6..0.6),
                ));
            } else {
                x2.push(b + n(&mut rng));
            }
        }
    }
    (x1, x2)
}

fn bench(c: &mut Criterion) {
    let (x1, x2) = data();
    let config = EssentialConfig {
        refine: None,
        ..EssentialConfig::default()
    };
    c.bench_function("ransac_essential_500_30pct_outliers", |b| {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        b.iter(|| ransac_essential(std::hint::black_box(&x1), &x2, &config, &mut rng))
    });
    let full = EssentialConfig::default();
    c.bench_function("estimate_relative_pose_500_30pct_outliers_with_lm", |b| {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        b.iter(|| camnet::estimate_relative_pose(std::hint::black_box(&x1), &x2, &full, &mut rng))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
