//! 1000 gaps of 21 missing frames each (segments of 10 observations at frames 0-9 and 31-40),
//! recovered by GDT and by the natural cubic spline.
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use gdt_bridge::{Baseline, GdtConfig, Observation, recover_baseline, recover_gdt};
use tracker_model::Vec2;

fn segments(k: usize) -> (Vec<Observation>, Vec<Observation>) {
    let v = 1.0 + 0.001 * k as f64;
    let obs = |f: u32| Observation {
        frame: f,
        position: Vec2::new(
            v * f64::from(f) + (f64::from(f) * 0.7).sin(),
            0.5 * f64::from(f),
        ),
    };
    ((0..10).map(obs).collect(), (31..41).map(obs).collect())
}

fn bench_gaps(c: &mut Criterion) {
    let gaps: Vec<_> = (0..1000).map(segments).collect();
    assert_eq!(
        recover_gdt(
            &gaps[0].0,
            &gaps[0].1,
            &GdtConfig::default().check().unwrap()
        )
        .unwrap()
        .frames
        .len(),
        21
    );
    let model = GdtConfig::default().check().unwrap();
    c.bench_function("gdt_1000_gaps_of_21_frames", |b| {
        b.iter(|| {
            gaps.iter()
                .map(|(a, z)| recover_gdt(black_box(a), black_box(z), &model).unwrap())
                .collect::<Vec<_>>()
        })
    });
    c.bench_function("natural_spline_1000_gaps_of_21_frames", |b| {
        b.iter(|| {
            gaps.iter()
                .map(|(a, z)| {
                    recover_baseline(black_box(a), black_box(z), &Baseline::NaturalCubicSpline)
                        .unwrap()
                })
                .collect::<Vec<_>>()
        })
    });
}

criterion_group!(benches, bench_gaps);
criterion_main!(benches);
