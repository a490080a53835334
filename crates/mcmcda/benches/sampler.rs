//! MCMCDA throughput: proposals per second on the K = 50 batch scenario of Oh, Russell &
//! Sastry 2009 (one chain, one core), the online example per scan, and the GNN baseline on the
//! same input.
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use mcmcda::{
    McmcdaConfig, NearestNeighbourConfig, OnlineConfig, OnlineTracker, Problem,
    chain::{Chain, greedy_initial_partition},
    nearest_neighbour_tracks,
};
use nalgebra::{Matrix2, Vector2};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tracker_model::{ConstantVelocity2, Region2, SimulationConfig};

const PROPOSALS: u64 = 100_000;

fn batch(c: &mut Criterion) {
    let sim = SimulationConfig {
        births_per_scan: 5.0,
        ..SimulationConfig::default()
    }
    .check()
    .unwrap()
    .simulate(&mut ChaCha8Rng::seed_from_u64(50))
    .unwrap();
    let model = McmcdaConfig {
        births_per_scan: 5.0,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let problem = Problem::from_scans(&model, &sim.scans).unwrap();
    let window = problem.all_scans().unwrap();
    let init = greedy_initial_partition(&model, &problem, window.clone()).unwrap();
    c.bench_function("mcmcda_k50_100k_proposals", |b| {
        b.iter(|| {
            let mut chain = Chain::new(init.clone(), ChaCha8Rng::seed_from_u64(1));
            chain.run(black_box(PROPOSALS));
            chain.map().1
        })
    });
    c.bench_function("gnn_k50_10_scans", |b| {
        b.iter(|| {
            nearest_neighbour_tracks(
                &model,
                black_box(&problem),
                window.clone(),
                &NearestNeighbourConfig::default(),
            )
            .unwrap()
        })
    });
}

fn online(c: &mut Criterion) {
    let noise = Matrix2::identity() * 0.031;
    let motion = ConstantVelocity2::new(
        1.0,
        tracker_model::CvNoise::Discrete {
            acceleration_covariance: noise,
        },
    )
    .unwrap();
    let sim = SimulationConfig {
        region: Region2::new(Vector2::zeros(), Vector2::new(100.0, 100.0)).unwrap(),
        n_scans: 100,
        births_per_scan: 5.0,
        p_disappear: 0.05,
        p_detect: 0.7,
        clutter_per_scan: 30.0,
        motion,
        measurement_noise: noise,
        initial_speed_max: 2.0,
        max_speed: Some(3.0),
    }
    .check()
    .unwrap()
    .simulate(&mut ChaCha8Rng::seed_from_u64(2011))
    .unwrap();
    let model = McmcdaConfig {
        volume: 1e4,
        births_per_scan: 5.0,
        p_disappear: 0.05,
        p_detect: 0.7,
        clutter_per_scan: 30.0,
        motion,
        measurement_noise: noise,
        max_speed: 3.0,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let scans: Vec<Vec<Vector2<f64>>> = sim
        .scans
        .iter()
        .map(|s| s.measurements.iter().map(|m| m.value).collect())
        .collect();
    let mut group = c.benchmark_group("online");
    group.sample_size(10);
    group.bench_function("mcmcda_online_100_scans_2000_samples", |b| {
        b.iter(|| {
            let mut tracker =
                OnlineTracker::new(model.clone(), 0, OnlineConfig::default(), 3).unwrap();
            for (f, points) in scans.iter().enumerate() {
                tracker.push_scan(f as u32, black_box(points)).unwrap();
            }
            tracker.finish().unwrap().tracks.len()
        })
    });
    group.finish();
}

criterion_group!(benches, batch, online);
criterion_main!(benches);
