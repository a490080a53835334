//! HMM benchmarks: a 20×20 grid (400 states, stay + 4 neighbours, sparse), M = 400 symbols,
//! T = 1000; the same grid model stored dense (what hmmlearn computes with, so the like-for-like
//! comparison with docs/comparisons/hmmlearn_grid400.py); and a dense N = 400 model of the same
//! size with every transition possible.
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use hmm_grid::{
    BaumWelchConfig, CellGrid, Hmm, SensorModel, SpeedDistribution, StateSpace, StorageChoice,
    Transitions, baum_welch, posterior, viterbi,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::Vec2;

fn grid_model() -> Hmm {
    let grid = CellGrid {
        n_cols: 20,
        n_rows: 20,
        cell_size: 1.0,
        blocked: vec![],
    };
    let space = StateSpace::from_grid(&grid).unwrap();
    let a = space
        .transitions(&SpeedDistribution::new(vec![0.3, 0.7]).unwrap())
        .unwrap();
    let sensors = SensorModel {
        sensors: vec![Vec2::new(5.0, 5.0), Vec2::new(15.0, 15.0)],
        base_sigma: 0.8,
        sigma_per_distance: 0.1,
    };
    let b = space.sensor_emissions(&sensors).unwrap();
    Hmm::new(vec![1.0 / 400.0; 400], a, b, 400).unwrap()
}

fn dense_model(rng: &mut ChaCha8Rng) -> Hmm {
    let row = |rng: &mut ChaCha8Rng| {
        let r: Vec<f64> = (0..400).map(|_| rng.random_range(0.01..1.0)).collect();
        let s: f64 = r.iter().sum();
        r.into_iter().map(|v| v / s).collect::<Vec<f64>>()
    };
    let a: Vec<f64> = (0..400).flat_map(|_| row(rng)).collect();
    let b: Vec<f64> = (0..400).flat_map(|_| row(rng)).collect();
    Hmm::new(
        vec![1.0 / 400.0; 400],
        Transitions::from_row_major(400, a, StorageChoice::Auto).unwrap(),
        b,
        400,
    )
    .unwrap()
}

fn bench_hmm(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let grid = grid_model();
    assert!(grid.transitions().is_sparse());
    let (_, obs) = grid.sample(1000, &mut rng);
    let runs = BaumWelchRuns::new();
    bench_grid_sparse(c, &grid, &obs, &runs);
    bench_grid_dense(c, &grid, &obs, &runs);
    bench_dense(c, &mut rng, &runs);
}

/// The Baum-Welch configurations the benchmarks run. `baum_welch(max_iterations = k)` runs
/// k + 1 E-steps (forward-backward, Rabiner 1989) and k M-steps, so one iteration costs the
/// difference between the k = 3 and k = 2 runs.
struct BaumWelchRuns {
    one: BaumWelchConfig,
    two: BaumWelchConfig,
    three: BaumWelchConfig,
}

impl BaumWelchRuns {
    fn new() -> Self {
        let run = |max_iterations| BaumWelchConfig {
            max_iterations,
            tolerance: 0.0,
            ..BaumWelchConfig::default()
        };
        Self {
            one: run(1),
            two: run(2),
            three: run(3),
        }
    }
}

/// The 20×20 grid model with its sparse transitions (stay + 4 neighbours): forward-backward,
/// Viterbi and Baum-Welch on `obs`.
fn bench_grid_sparse(c: &mut Criterion, grid: &Hmm, obs: &[usize], runs: &BaumWelchRuns) {
    c.bench_function("grid400_forward_backward_T1000", |b| {
        b.iter(|| posterior(grid, black_box(obs)).unwrap())
    });
    c.bench_function("grid400_viterbi_T1000", |b| {
        b.iter(|| viterbi(grid, black_box(obs)).unwrap())
    });
    let seqs = vec![obs.to_vec()];
    c.bench_function("grid400_baum_welch_2_iterations_T1000", |b| {
        b.iter(|| baum_welch(grid, black_box(&seqs), &runs.two).unwrap())
    });
    c.bench_function("grid400_baum_welch_3_iterations_T1000", |b| {
        b.iter(|| baum_welch(grid, black_box(&seqs), &runs.three).unwrap())
    });
    c.bench_function("grid400_baum_welch_iteration_T1000", |b| {
        b.iter(|| baum_welch(grid, black_box(&seqs), &runs.one).unwrap())
    });
}

/// The same grid model with A stored dense: N² work per step, like hmmlearn's (the
/// like-for-like comparison with docs/comparisons/hmmlearn_grid400.py).
fn bench_grid_dense(c: &mut Criterion, grid: &Hmm, obs: &[usize], runs: &BaumWelchRuns) {
    let grid_dense = Hmm::new(
        grid.initial().to_vec(),
        grid.transitions().to_storage(StorageChoice::Dense),
        grid.emissions().to_vec(),
        400,
    )
    .unwrap();
    assert!(!grid_dense.transitions().is_sparse());
    let seqs = vec![obs.to_vec()];
    c.bench_function("grid400_dense_forward_backward_T1000", |b| {
        b.iter(|| posterior(&grid_dense, black_box(obs)).unwrap())
    });
    c.bench_function("grid400_dense_viterbi_T1000", |b| {
        b.iter(|| viterbi(&grid_dense, black_box(obs)).unwrap())
    });
    c.bench_function("grid400_dense_baum_welch_iteration_T1000", |b| {
        b.iter(|| baum_welch(&grid_dense, black_box(&seqs), &runs.one).unwrap())
    });
    c.bench_function("grid400_dense_baum_welch_2_iterations_T1000", |b| {
        b.iter(|| baum_welch(&grid_dense, black_box(&seqs), &runs.two).unwrap())
    });
    c.bench_function("grid400_dense_baum_welch_3_iterations_T1000", |b| {
        b.iter(|| baum_welch(&grid_dense, black_box(&seqs), &runs.three).unwrap())
    });
}

/// A dense N = 400 model with every transition possible (drawn from `rng`, after the grid's
/// observations) and its own observations; its Baum-Welch runs in a group of 10 samples.
fn bench_dense(c: &mut Criterion, rng: &mut ChaCha8Rng, runs: &BaumWelchRuns) {
    let dense = dense_model(rng);
    assert!(!dense.transitions().is_sparse());
    let (_, obs) = dense.sample(1000, rng);
    c.bench_function("dense400_forward_backward_T1000", |b| {
        b.iter(|| posterior(&dense, black_box(&obs)).unwrap())
    });
    c.bench_function("dense400_viterbi_T1000", |b| {
        b.iter(|| viterbi(&dense, black_box(&obs)).unwrap())
    });
    // One Baum-Welch iteration on the dense model: the difference between these two.
    let dense_seqs = vec![obs.clone()];
    let mut slow = c.benchmark_group("dense400_baum_welch");
    slow.sample_size(10);
    slow.bench_function("dense400_baum_welch_2_iterations_T1000", |b| {
        b.iter(|| baum_welch(&dense, black_box(&dense_seqs), &runs.two).unwrap())
    });
    slow.bench_function("dense400_baum_welch_3_iterations_T1000", |b| {
        b.iter(|| baum_welch(&dense, black_box(&dense_seqs), &runs.three).unwrap())
    });
    slow.finish();
}

criterion_group!(benches, bench_hmm);
criterion_main!(benches);
