//! The whole fusion pipeline for Table 1's nine sensors (six 36-beam audio nodes, three
//! 160-angle cameras) on a 35 × 20 m grid of 0.5 m cells, at 10 Hz: buffering, scheduling,
//! projection, fusion, peaks and online MCMCDA. The sensor simulation is excluded: the
//! profiles (a bump towards one vehicle on a noisy floor) are built before timing. One
//! iteration is a 4 s pass (40 ticks); real time is 4 s.

use std::f64::consts::TAU;
use std::hint::black_box;

use av_fusion::{
    AvConfig, FusionConfig, FusionRule, Modalities, PeakExtraction, ProfileShape, RangeFade,
    Report, SchedulerConfig, SensorKind, SensorNode, SumScaling, TrackerConfig, track_reports,
};
use criterion::{Criterion, criterion_group, criterion_main};
use mcmcda::{McmcdaConfig, OnlineConfig};
use nalgebra::Matrix2;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::{ConstantVelocity2, Region2, SensorPose, Vec2, wrap_angle_rad};

fn sensors() -> Vec<SensorNode> {
    let mut out: Vec<SensorNode> = av_fusion::scene::audio_poses()
        .into_iter()
        .enumerate()
        .map(|(i, pose)| SensorNode::audio(format!("a{i}"), pose, 36))
        .collect();
    for (i, (x, y, h)) in [(1.0, 1.0, 35.0f64), (34.0, 1.0, 145.0), (8.0, 19.5, -55.0)]
        .into_iter()
        .enumerate()
    {
        out.push(SensorNode {
            name: format!("v{i}"),
            kind: SensorKind::Video,
            pose: SensorPose {
                position: Vec2::new(x, y),
                heading_rad: h.to_radians(),
            },
            shape: ProfileShape::Sector {
                start_rad: -38f64.to_radians(),
                step_rad: 76f64.to_radians() / 160.0,
                n_bins: 160,
            },
            clock_offset_s: 0.0,
            weight: 1.0,
            exponent: 1.0,
            lobes: None,
        });
    }
    out
}

fn reports(sensors: &[SensorNode], rng: &mut ChaCha8Rng) -> Vec<Report> {
    let vehicle = |t: f64| Vec2::new(-3.0 + 10.0 * t, 8.5);
    let mut out = Vec::new();
    for (i, s) in sensors.iter().enumerate() {
        let (period, width) = match s.kind {
            SensorKind::Audio => (0.05, 15f64.to_radians()),
            SensorKind::Video => (1.0 / 15.0, 1.5f64.to_radians()),
        };
        let mut k = 0u32;
        loop {
            let t = f64::from(k) * period;
            if t > 4.0 {
                break;
            }
            let d = vehicle(t) - s.pose.position;
            let bearing = d.y.atan2(d.x);
            let n = s.shape.n_bins();
            let values = (0..n)
                .map(|b| {
                    let rel = match s.shape {
                        ProfileShape::FullCircle { n_bins } => TAU * b as f64 / n_bins as f64,
                        ProfileShape::Sector {
                            start_rad,
                            step_rad,
                            ..
                        } => start_rad + b as f64 * step_rad,
                    };
                    let off = wrap_angle_rad(s.pose.heading_rad + rel - bearing);
                    (-0.5 * (off / width).powi(2)).exp() + 0.1 * rng.random::<f64>()
                })
                .collect();
            out.push(Report {
                sensor: i,
                local_time_s: t,
                values,
            });
            k += 1;
        }
    }
    out
}

fn config(rule: FusionRule) -> AvConfig {
    AvConfig {
        scheduler: SchedulerConfig {
            rate_hz: 10.0,
            start_s: 0.0,
            staleness_s: 0.05,
            buffer_capacity: 16,
        },
        fusion: FusionConfig {
            region: Region2::new(Vec2::zeros(), Vec2::new(35.0, 20.0)).expect("region"),
            cell_size_m: 0.5,
            max_range_m: None,
            min_range_m: 0.5,
            range_fade: None,
            rule,
            modalities: Modalities::Both,
            peaks: PeakExtraction {
                relative_threshold: if matches!(rule, FusionRule::Product { .. }) {
                    0.3
                } else {
                    0.85
                },
                ..PeakExtraction::default()
            },
        },
        tracker: TrackerConfig {
            mcmcda: McmcdaConfig {
                volume: 700.0,
                births_per_scan: 0.05,
                clutter_per_scan: 0.5,
                p_disappear: 0.01,
                p_detect: 0.8,
                motion: ConstantVelocity2::mcmcda(0.1, 4.0).expect("motion"),
                measurement_noise: Matrix2::identity() * 0.5,
                max_speed: 20.0,
                ..McmcdaConfig::default()
            },
            online: OnlineConfig {
                window: 10,
                samples_per_scan: 300,
                ..OnlineConfig::default()
            },
            seed: 1,
            peak_scores: None,
        },
    }
}

fn bench(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(18);
    let nodes = sensors();
    let reps = reports(&nodes, &mut rng);
    let mut group = c.benchmark_group("av_fusion_pass_4s_9_sensors");
    // The range fade (the multi-vehicle scenario's audio+video product: r₀ = 8 m, q = ½)
    // adds a per-sensor subtraction per cell; its maps are computed once per pipeline.
    let fade = Some(RangeFade {
        full_weight_m: 8.0,
        power: 0.5,
    });
    for (name, rule, range_fade) in [
        ("product", FusionRule::Product { floor: 0.05 }, None),
        (
            "weighted_sum",
            FusionRule::WeightedSum {
                scaling: SumScaling::Max,
            },
            None,
        ),
        (
            "product_range_fade",
            FusionRule::Product { floor: 0.05 },
            fade,
        ),
    ] {
        let mut cfg = config(rule);
        cfg.fusion.range_fade = range_fade;
        group.bench_function(name, |b| {
            b.iter(|| {
                let run = track_reports(nodes.clone(), reps.clone(), 40, &cfg).expect("runs");
                black_box(run.tracks.len())
            });
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
