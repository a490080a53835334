//! Tests of the multi-scan sampler against independent routes: enumeration of every
//! partition, the per-scan-count posterior with a general Kalman filter, and forced reverse
//! moves.

use std::collections::HashMap;

use nalgebra::{Matrix2, Matrix4, Vector2};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tracker_model::{ConstantVelocity2, Measurement, Origin, Scan, SimulationConfig};

mod plots;

use crate::reference::{enumerate_partitions, log_posterior_by_counts};
use crate::sampler::Chain;
use crate::{
    Error, McmcdaConfig, Model, Move, Problem, TrackEnd, TrackInit,
    chain::{Partition, run_chains},
};

fn scan(frame: u32, points: &[(f64, f64)]) -> Scan {
    Scan {
        frame,
        measurements: points
            .iter()
            .map(|&(x, y)| Measurement {
                value: Vector2::new(x, y),
                origin: Origin::Unknown,
            })
            .collect(),
    }
}

/// Three scans with two measurements each: two crossing targets, ambiguous enough that many
/// partitions carry real posterior mass.
fn tiny_config() -> McmcdaConfig {
    McmcdaConfig {
        volume: 400.0,
        births_per_scan: 0.6,
        clutter_per_scan: 0.8,
        p_disappear: 0.1,
        p_detect: 0.8,
        motion: ConstantVelocity2::mcmcda(1.0, 1.0).unwrap(),
        measurement_noise: Matrix2::identity() * 1.5,
        max_gap: 2,
        max_speed: 6.0,
        ..McmcdaConfig::default()
    }
}

fn tiny_scans() -> Vec<Scan> {
    vec![
        scan(0, &[(0.0, 0.0), (4.0, 1.0)]),
        scan(1, &[(2.0, 1.0), (2.5, 0.0)]),
        scan(2, &[(4.0, 1.5), (1.0, 3.0)]),
    ]
}

fn exact_posterior(model: &Model, problem: &Problem) -> HashMap<Vec<Vec<u32>>, f64> {
    let window = problem.all_scans().unwrap();
    let all = enumerate_partitions(model, problem, window.clone()).unwrap();
    let lps: Vec<f64> = all
        .iter()
        .map(|p| log_posterior_by_counts(model, problem, window.clone(), p).unwrap())
        .collect();
    let max = lps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let z: f64 = lps.iter().map(|l| (l - max).exp()).sum();
    all.into_iter()
        .zip(lps)
        .map(|(p, l)| (p, (l - max).exp() / z))
        .collect()
}

/// Visit frequencies of `n_chains` chains of `n_steps` steps from the empty partition, chain
/// c seeded with `seed + c` (chains run in parallel; the sum does not depend on the order).
fn chain_frequencies(
    model: &Model,
    problem: &Problem,
    n_chains: u64,
    n_steps: u64,
    seed: u64,
) -> HashMap<Vec<Vec<u32>>, f64> {
    use rayon::prelude::*;
    let per_chain: Vec<HashMap<Vec<Vec<u32>>, u64>> = (0..n_chains)
        .into_par_iter()
        .map(|c| {
            let mut counts: HashMap<Vec<Vec<u32>>, u64> = HashMap::new();
            let start = Partition::empty(model, problem, problem.all_scans().unwrap()).unwrap();
            let mut chain = Chain::new(start, ChaCha8Rng::seed_from_u64(seed + c));
            for _ in 0..n_steps {
                chain.step();
                *counts.entry(chain.state().canonical()).or_default() += 1;
            }
            counts
        })
        .collect();
    let mut counts: HashMap<Vec<Vec<u32>>, u64> = HashMap::new();
    for chain in per_chain {
        for (p, n) in chain {
            *counts.entry(p).or_default() += n;
        }
    }
    let total = (n_chains * n_steps) as f64;
    counts
        .into_iter()
        .map(|(p, n)| (p, n as f64 / total))
        .collect()
}

/// Total variation ½ Σ |p − q| over the union of both supports.
fn total_variation(p: &HashMap<Vec<Vec<u32>>, f64>, q: &HashMap<Vec<Vec<u32>>, f64>) -> f64 {
    let only_in_q: f64 = q
        .iter()
        .filter(|(k, _)| !p.contains_key(*k))
        .map(|(_, v)| v)
        .sum();
    let shared: f64 = p
        .iter()
        .map(|(k, v)| (v - q.get(k).copied().unwrap_or(0.0)).abs())
        .sum();
    (shared + only_in_q) / 2.0
}

/// The model variants every exactness test runs: both track starts, both track ends, and
/// the paper's tail-only moves as well as head moves.
fn variants() -> Vec<(TrackInit, TrackEnd, f64)> {
    let first = TrackInit::FirstMeasurement {
        velocity_variance: None,
    };
    vec![
        (first, TrackEnd::Disappeared, 0.5),
        (
            TrackInit::TwoPoint {
                initial_covariance: Matrix4::identity(),
            },
            TrackEnd::Disappeared,
            0.5,
        ),
        (first, TrackEnd::Undetected, 0.0),
    ]
}

/// The largest total variation between the chain's visit frequencies and the enumerated
/// posterior that the exactness test accepts, and the run that must keep its noise floor 3×
/// below it.
const TV_THRESHOLD: f64 = 0.02;
const CHAINS: u64 = 16;
const STEPS: u64 = 500_000;

#[test]
fn chain_matches_the_enumerated_posterior() {
    for (track_init, track_end, head_probability) in variants() {
        let model = McmcdaConfig {
            track_init,
            track_end,
            head_probability,
            ..tiny_config()
        }
        .check()
        .unwrap();
        let problem = Problem::from_scans(&model, &tiny_scans()).unwrap();
        let exact = exact_posterior(&model, &problem);
        let top = exact.values().copied().fold(0.0, f64::max);
        // The test is only meaningful if mass is spread over several partitions.
        assert!(
            exact.len() > 30 && top < 0.5,
            "{} partitions, top {top}",
            exact.len()
        );
        let empirical = chain_frequencies(&model, &problem, CHAINS, STEPS, 100);
        if let Some(p) = empirical.keys().find(|p| !exact.contains_key(*p)) {
            panic!("chain visited an infeasible partition {p:?}");
        }
        let tv = total_variation(&exact, &empirical);
        // The noise floor: an exact sampler with the chain's autocorrelation would still be
        // this far from the posterior. Two independent runs of the same size differ by about
        // √2 times it (their errors are independent), so it is measured, not assumed.
        let other = chain_frequencies(&model, &problem, CHAINS, STEPS, 100 + CHAINS);
        let floor = total_variation(&empirical, &other) / std::f64::consts::SQRT_2;
        eprintln!(
            "{track_init:?}, {track_end:?}, head {head_probability}: TV {tv:.5}, noise floor {floor:.5}"
        );
        assert!(
            3.0 * floor <= TV_THRESHOLD,
            "noise floor {floor} is not 3× below the threshold {TV_THRESHOLD}"
        );
        assert!(
            tv < TV_THRESHOLD,
            "{track_init:?}, {track_end:?}, head {head_probability}: total variation {tv}"
        );
    }
}

#[test]
fn incremental_posterior_equals_recomputation_after_every_move() {
    let sim = SimulationConfig {
        births_per_scan: 1.0,
        clutter_per_scan: 3.0,
        n_scans: 12,
        ..SimulationConfig::default()
    }
    .check()
    .unwrap()
    .simulate(&mut ChaCha8Rng::seed_from_u64(5))
    .unwrap();
    for (track_init, track_end, head_probability) in variants() {
        let model = McmcdaConfig {
            clutter_per_scan: 3.0,
            track_init,
            track_end,
            head_probability,
            ..McmcdaConfig::default()
        }
        .check()
        .unwrap();
        let problem = Problem::from_scans(&model, &sim.scans).unwrap();
        let window = problem.all_scans().unwrap();
        let start = Partition::empty(&model, &problem, window.clone()).unwrap();
        let mut chain = Chain::new(start, ChaCha8Rng::seed_from_u64(9));
        let mut accepted = [0u32; 8];
        for i in 0..20_000 {
            // Every third proposal is forced through, so that rarely accepted moves (splits)
            // and unlikely partitions are exercised too.
            chain.force_accept = i % 3 == 0;
            let (m, ok) = chain.step();
            if ok {
                accepted[m.index()] += 1;
            }
            let state = chain.state();
            state.check_invariants().unwrap();
            let tracks: Vec<Vec<u32>> = state.tracks().map(<[u32]>::to_vec).collect();
            let fresh = log_posterior_by_counts(&model, &problem, window.clone(), &tracks).unwrap();
            let incremental = state.log_posterior();
            assert!(
                (fresh - incremental).abs() < 1e-8 * fresh.abs().max(1.0),
                "after {m:?}: {incremental} vs {fresh}"
            );
        }
        assert!(
            accepted.iter().all(|&a| a > 0),
            "every move accepted some time: {accepted:?}"
        );
    }
}

/// The move that undoes `m`.
fn reverse(m: Move) -> Move {
    match m {
        Move::Birth => Move::Death,
        Move::Death => Move::Birth,
        Move::Split => Move::Merge,
        Move::Merge => Move::Split,
        Move::Extension => Move::Reduction,
        Move::Reduction => Move::Extension,
        Move::Update => Move::Update,
        Move::Switch => Move::Switch,
    }
}

#[test]
fn every_move_is_undone_by_its_reverse() {
    // Slow targets and a small neighbourhood keep candidate sets small, so that a random
    // reverse proposal regenerates the old partition often enough to find it.
    let sim = SimulationConfig {
        births_per_scan: 0.6,
        clutter_per_scan: 1.0,
        n_scans: 7,
        initial_speed_max: 20.0,
        max_speed: Some(30.0),
        ..SimulationConfig::default()
    }
    .check()
    .unwrap()
    .simulate(&mut ChaCha8Rng::seed_from_u64(3))
    .unwrap();
    let model = McmcdaConfig {
        max_speed: 40.0,
        gap_distribution: crate::GapDistribution::Uniform,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let problem = Problem::from_scans(&model, &sim.scans).unwrap();
    let start = Partition::empty(&model, &problem, problem.all_scans().unwrap()).unwrap();
    let mut chain = Chain::new(start, ChaCha8Rng::seed_from_u64(4));
    chain.force_accept = true;
    let mut undone = [0u32; 8];
    let mut rng_seed = 1000;
    for _ in 0..3000 {
        let before = chain.state().canonical();
        let (m, _) = chain.step();
        let after = chain.state().canonical();
        if after == before {
            continue;
        }
        // Propose the reverse move from ω' until it produces ω (fresh generators each try).
        let back = (0..20_000).any(|_| {
            rng_seed += 1;
            let mut probe = Chain::new(chain.state().clone(), ChaCha8Rng::seed_from_u64(rng_seed));
            probe.force_accept = true;
            probe.step_with(reverse(m));
            probe.state().canonical() == before
        });
        assert!(
            back,
            "{m:?} from {before:?} to {after:?} could not be undone"
        );
        undone[m.index()] += 1;
    }
    assert!(
        undone.iter().all(|&n| n > 0),
        "every move type exercised: {undone:?}"
    );
}

#[test]
fn best_chain_does_not_depend_on_the_thread_count() {
    let sim = SimulationConfig {
        births_per_scan: 2.0,
        ..SimulationConfig::default()
    }
    .check()
    .unwrap()
    .simulate(&mut ChaCha8Rng::seed_from_u64(11))
    .unwrap();
    let model = McmcdaConfig {
        births_per_scan: 2.0,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let problem = Problem::from_scans(&model, &sim.scans).unwrap();
    let start = Partition::empty(&model, &problem, problem.all_scans().unwrap()).unwrap();
    let run_in = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run_chains(&start, 4, 5_000, 21).unwrap())
    };
    let one = run_in(1);
    let two = run_in(2);
    assert_eq!(one, two);
    assert_eq!(one.log_posterior.to_bits(), two.log_posterior.to_bits());
}

#[test]
fn infeasible_partitions_are_rejected_with_reasons() {
    let model = tiny_config().check().unwrap();
    let problem = Problem::from_scans(&model, &tiny_scans()).unwrap();
    let err =
        |tracks: &[Vec<u32>]| Partition::from_tracks(&model, &problem, 0..=2, tracks).unwrap_err();
    let check = |tracks: &[Vec<u32>], expected: Error, message: &str| {
        let e = err(tracks);
        assert_eq!(e, expected);
        assert!(e.to_string().contains(message), "{e}");
    };
    check(
        &[vec![0]],
        Error::TrackTooShort { track: 0, len: 1 },
        "fewer than 2",
    );
    check(
        &[vec![0, 1]],
        Error::ScansNotIncreasing {
            track: 0,
            first: 0,
            second: 1,
        },
        "increasing scans",
    );
    check(
        &[vec![0, 2], vec![2, 4]],
        Error::MeasurementTaken { track: 1, id: 2 },
        "already in a track",
    );
    check(
        &[vec![0, 99]],
        Error::UnknownMeasurement { track: 0, id: 99 },
        "does not exist",
    );
    let two_scans = Partition::from_tracks(&model, &problem, 0..=1, &[vec![0, 2, 4]]);
    assert_eq!(
        two_scans.unwrap_err(),
        Error::MeasurementOutsideWindow { track: 0, id: 4 }
    );
    let far = McmcdaConfig {
        max_speed: 1.0,
        ..tiny_config()
    }
    .check()
    .unwrap();
    let problem_far = Problem::from_scans(&far, &tiny_scans()).unwrap();
    let e = Partition::from_tracks(&far, &problem_far, 0..=2, &[vec![0, 3]]).unwrap_err();
    assert_eq!(
        e,
        Error::TooFarApart {
            track: 0,
            first: 0,
            second: 3,
            gap: 1
        }
    );
    assert!(e.to_string().contains("too far apart"), "{e}");
    let short_gap = McmcdaConfig {
        max_gap: 1,
        ..tiny_config()
    }
    .check()
    .unwrap();
    let problem_short = Problem::from_scans(&short_gap, &tiny_scans()).unwrap();
    assert_eq!(
        Partition::from_tracks(&short_gap, &problem_short, 0..=2, &[vec![0, 4]]).unwrap_err(),
        Error::GapTooLong {
            track: 0,
            first: 0,
            second: 4,
            gap: 2,
            max_gap: 1
        }
    );
}

#[test]
fn single_scan_beta_matches_exact_jpda() {
    use crate::{SingleScanConfig, jpda_exact, single_scan_mcmcda};
    use nalgebra::Vector4;
    use tracker_model::{Gaussian, LinearObservation};
    // Three targets with overlapping gates and five measurements between them.
    let predicted: Vec<Gaussian<4>> = [(0.0, 0.0), (3.0, 0.5), (1.5, 2.5)]
        .iter()
        .map(|&(x, y)| {
            Gaussian::new(Vector4::new(x, y, 1.0, 0.0), Matrix4::identity() * 2.0).unwrap()
        })
        .collect();
    let sensor = LinearObservation::leading_components(Matrix2::identity()).unwrap();
    let ys: Vec<Vector2<f64>> = [(0.5, 0.3), (2.2, 0.4), (1.4, 1.6), (3.5, 1.0), (-1.0, 1.2)]
        .iter()
        .map(|&(x, y)| Vector2::new(x, y))
        .collect();
    let config = SingleScanConfig {
        clutter_density: 0.02,
        burn_in: 10_000,
        samples: 2_000_000,
        ..SingleScanConfig::default()
    };
    let exact = jpda_exact(&predicted, &sensor, &ys, &config).unwrap();
    let mcmc = single_scan_mcmcda(
        &predicted,
        &sensor,
        &ys,
        &config,
        &mut ChaCha8Rng::seed_from_u64(8),
    )
    .unwrap();
    // Ambiguity must be real for the test to mean something.
    let spread = exact.beta.iter().flatten().filter(|&&b| b > 0.05).count();
    assert!(spread >= 8, "only {spread} sizeable β");
    for k in 0..3 {
        let sum: f64 = exact.beta[k].iter().sum::<f64>() + exact.beta_missed[k];
        assert!((sum - 1.0).abs() < 1e-12);
        for j in 0..ys.len() {
            let (a, b) = (exact.beta[k][j], mcmc.beta[k][j]);
            assert!((a - b).abs() < 0.01, "β[{k}][{j}]: exact {a}, MCMC {b}");
        }
        let d = (exact.states[k].mean() - mcmc.states[k].mean()).norm();
        assert!(d < 0.02, "target {k} mean differs by {d}");
    }
}

#[test]
fn exact_jpda_of_one_target_is_the_pda_closed_form() {
    use crate::{SingleScanConfig, jpda_exact};
    use nalgebra::Vector4;
    use tracker_model::{Gaussian, LinearObservation, ObservationModel};
    // With one target, β_j ∝ p_d N(y_j) / λ_f and β_0 ∝ 1 − p_d (the PDA weights).
    let prior = Gaussian::new(Vector4::new(0.0, 0.0, 0.0, 0.0), Matrix4::identity()).unwrap();
    let sensor = LinearObservation::leading_components(Matrix2::identity() * 0.5).unwrap();
    let ys = [Vector2::new(0.3, -0.2), Vector2::new(-1.0, 0.4)];
    let config = SingleScanConfig {
        clutter_density: 0.1,
        ..SingleScanConfig::default()
    };
    let out = jpda_exact(std::slice::from_ref(&prior), &sensor, &ys, &config).unwrap();
    let w: Vec<f64> = ys
        .iter()
        .map(|y| {
            let l = sensor.innovation(&prior, y).unwrap().log_likelihood.exp();
            config.p_detect * l / config.clutter_density
        })
        .collect();
    let z = 1.0 - config.p_detect + w.iter().sum::<f64>();
    assert!((out.beta_missed[0] - (1.0 - config.p_detect) / z).abs() < 1e-12);
    for (b, wj) in out.beta[0].iter().zip(&w) {
        assert!((b - wj / z).abs() < 1e-12);
    }
}

/// Three well-separated targets moving in straight lines, every one detected except where
/// `missed` says, and no clutter.
fn three_walkers(n_scans: u32, missed: &[(u32, usize)]) -> Vec<Scan> {
    (0..n_scans)
        .map(|f| {
            let t = f64::from(f);
            let points: Vec<(f64, f64)> = [(100.0, 100.0), (500.0, 600.0), (800.0, 200.0)]
                .iter()
                .enumerate()
                .filter(|(i, _)| !missed.contains(&(f, *i)))
                .map(|(i, &(x, y))| (x + 20.0 * t, y + (i as f64 - 1.0) * 15.0 * t))
                .collect();
            scan(f, &points)
        })
        .collect()
}

#[test]
fn gnn_and_the_chain_recover_separated_targets() {
    use crate::{
        NearestNeighbourConfig, chain::greedy_initial_partition, nearest_neighbour_tracks,
    };
    let scans = three_walkers(8, &[(3, 1), (4, 1), (6, 2)]);
    let model = McmcdaConfig::default().check().unwrap();
    let problem = Problem::from_scans(&model, &scans).unwrap();
    let window = problem.all_scans().unwrap();
    // The true partition by construction: each walker's measurements in scan order.
    let mut truth: Vec<Vec<u32>> = vec![Vec::new(); 3];
    let mut id = 0;
    for (f, s) in scans.iter().enumerate() {
        let present: Vec<usize> = (0..3)
            .filter(|i| ![(3, 1), (4, 1), (6, 2)].contains(&(f as u32, *i)))
            .collect();
        for (&walker, _) in present.iter().zip(&s.measurements) {
            truth[walker].push(id);
            id += 1;
        }
    }
    truth.sort();
    let gnn = nearest_neighbour_tracks(
        &model,
        &problem,
        window.clone(),
        &NearestNeighbourConfig::default(),
    )
    .unwrap();
    assert_eq!(gnn, truth);
    let start = greedy_initial_partition(&model, &problem, window.clone()).unwrap();
    assert_eq!(start.canonical(), truth);
    // From nothing, the chain finds the same partition.
    let empty = Partition::empty(&model, &problem, window).unwrap();
    let run = run_chains(&empty, 2, 20_000, 1).unwrap();
    assert_eq!(run.tracks, truth);
}

#[test]
fn online_tracker_keeps_labels_and_takes_late_measurements() {
    use crate::{OnlineConfig, OnlineTracker};
    let scans = three_walkers(30, &[(10, 0), (11, 2), (20, 1)]);
    let model = McmcdaConfig::default().check().unwrap();
    let config = OnlineConfig {
        window: 6,
        samples_per_scan: 500,
        ..OnlineConfig::default()
    };
    let mut tracker = OnlineTracker::new(model, 0, config, 5).unwrap();
    // Walker 1's measurement of frame 20 arrives one scan late.
    let late = Vector2::new(500.0 + 400.0, 600.0);
    for s in &scans {
        let points: Vec<Vector2<f64>> = s.measurements.iter().map(|m| m.value).collect();
        let step = tracker.push_scan(s.frame, &points).unwrap();
        if s.frame >= 3 {
            assert_eq!(step.estimates.len(), 3, "frame {}", s.frame);
        }
        if s.frame == 21 {
            tracker.add_late(20, late).unwrap();
        }
    }
    // Too late: frame 5 left the window long ago.
    let err = tracker.add_late(5, late).unwrap_err();
    assert_eq!(
        err,
        Error::LateMeasurement {
            frame: 5,
            window_start: 24
        }
    );
    assert!(err.to_string().contains("left the window"), "{err}");
    let result = tracker.finish().unwrap();
    assert_eq!(result.tracks.len(), 3, "one label per walker");
    let mut lengths: Vec<usize> = result.associations.iter().map(|(_, t)| t.len()).collect();
    lengths.sort_unstable();
    // Each walker has 30 scans minus its misses; the late measurement filled walker 1's.
    assert_eq!(lengths, vec![29, 29, 30]);
    for (_, track) in &result.associations {
        let xs: Vec<f64> = track
            .iter()
            .map(|&m| result.problem.position(m).x)
            .collect();
        // One walker per label: x grows by 20 per scan along every track.
        for (pair, ids) in xs.windows(2).zip(track.windows(2)) {
            let gap = (result.problem.scan_of(ids[1]) - result.problem.scan_of(ids[0])) as f64;
            assert!((pair[1] - pair[0] - 20.0 * gap).abs() < 1e-9);
        }
    }
}

#[test]
fn bad_input_gives_errors_not_panics() {
    let model = McmcdaConfig::default().check().unwrap();
    let nan = scan(0, &[(f64::NAN, 1.0)]);
    assert!(Problem::from_scans(&model, &[nan]).is_err());
    let unordered = [scan(3, &[(1.0, 1.0)]), scan(1, &[(1.0, 1.0)])];
    let err = Problem::from_scans(&model, &unordered).unwrap_err();
    assert_eq!(err, Error::FramesOutOfOrder { frame: 1, last: 3 });
    assert!(err.to_string().contains("arrives after"), "{err}");
    let mut empty = Problem::empty(&model, 4);
    assert_eq!(empty.all_scans(), Err(Error::EmptyProblem));
    assert_eq!(
        empty.push_scan(2, &[]),
        Err(Error::FrameBeforeFirst { frame: 2, first: 4 })
    );
    assert_eq!(
        empty.add_measurement(4, Vector2::new(1.0, 1.0)),
        Err(Error::FrameNotHeld {
            frame: 4,
            first: 4,
            end: 4
        })
    );
    assert_eq!(
        crate::batch_mcmcda(&model, &empty, &crate::BatchConfig::default()).unwrap_err(),
        Error::EmptyProblem
    );
    for bad in [
        McmcdaConfig {
            p_detect: 1.0,
            ..McmcdaConfig::default()
        },
        McmcdaConfig {
            clutter_per_scan: 0.0,
            ..McmcdaConfig::default()
        },
        McmcdaConfig {
            max_gap: 0,
            ..McmcdaConfig::default()
        },
        McmcdaConfig {
            measurement_noise: Matrix2::new(1.0, 2.0, 2.0, 1.0),
            ..McmcdaConfig::default()
        },
        McmcdaConfig {
            head_probability: 1.5,
            ..McmcdaConfig::default()
        },
    ] {
        assert!(bad.check().is_err(), "{bad:?} accepted");
    }
    let problem = Problem::from_scans(&model, &[scan(0, &[(1.0, 1.0)])]).unwrap();
    assert_eq!(
        Partition::empty(&model, &problem, 0..=3).unwrap_err(),
        Error::WindowOutOfRange {
            start: 0,
            end: 3,
            n_scans: 1
        }
    );
    // A single-scan problem: nothing can be a track, and the chain just stays empty.
    let start = Partition::empty(&model, &problem, 0..=0).unwrap();
    assert!(run_chains(&start, 1, 100, 0).unwrap().tracks.is_empty());
}

#[test]
fn running_mmse_matches_the_exact_posterior_mean() {
    // f(ω) = (number of tracks, number of false alarms): its posterior mean by enumeration
    // against the chain's running mean.
    let model = tiny_config().check().unwrap();
    let problem = Problem::from_scans(&model, &tiny_scans()).unwrap();
    let exact = exact_posterior(&model, &problem);
    let n = problem.n_measurements() as f64;
    let f = |tracks: &[Vec<u32>]| {
        let held: usize = tracks.iter().map(Vec::len).sum();
        [tracks.len() as f64, n - held as f64]
    };
    let mut expected = [0.0; 2];
    for (p, q) in &exact {
        let v = f(p);
        expected[0] += q * v[0];
        expected[1] += q * v[1];
    }
    let start = Partition::empty(&model, &problem, 0..=2).unwrap();
    let mut chain = Chain::new(start, ChaCha8Rng::seed_from_u64(77));
    let mean = chain.run_mmse(1_000_000, |state| f(&state.canonical()).to_vec());
    for k in 0..2 {
        assert!(
            (mean[k] - expected[k]).abs() < 0.02,
            "component {k}: {} vs exact {}",
            mean[k],
            expected[k]
        );
    }
}

#[test]
fn proposal_frequencies_match_the_computed_q() {
    // From one fixed partition, draw many proposals (each from a fresh copy) and compare how
    // often each new partition is proposed with the q the sampler puts in the
    // Metropolis-Hastings ratio. This checks every move's q directly, including sums over
    // several ways and the switch's two ends.
    // Two targets crossing (A, B), one long straight target (C), one cut in two (D), and
    // a few false alarms; all within reach of each other's neighbourhoods where it matters.
    let points = |f: usize| -> Vec<(f64, f64)> {
        let t = f as f64;
        let mut v = vec![
            (20.0 * t, 20.0 * t),
            (20.0 * t, 80.0 - 19.0 * t),
            (200.0, 10.0 * t),
            (300.0, 12.0 * t),
        ];
        v.extend(match f {
            1 => vec![(100.0, 100.0)],
            2 => vec![(30.0, 150.0), (210.0, 60.0)],
            3 => vec![(150.0, 50.0)],
            _ => vec![],
        });
        v
    };
    let scans: Vec<Scan> = (0..5).map(|f| scan(f as u32, &points(f))).collect();
    let model = McmcdaConfig {
        max_speed: 60.0,
        max_gap: 3,
        gap_distribution: crate::GapDistribution::Uniform,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let problem = Problem::from_scans(&model, &scans).unwrap();
    // Ids: scan f's points in order; target k of scan f is problem.scan(f)[k].
    let id = |f: usize, k: usize| problem.scan(f)[k];
    let track = |k: usize, frames: std::ops::Range<usize>| -> Vec<u32> {
        frames.map(|f| id(f, k)).collect()
    };
    // C is held only up to scan 2, so its scan-3 and scan-4 measurements are free: its tail
    // can be extended, and an update can regrow it through a false alarm instead.
    let tracks = vec![
        track(0, 0..5),
        track(1, 0..5),
        track(2, 0..3),
        track(3, 0..2),
        track(3, 2..5),
    ];
    let window = problem.all_scans().unwrap();
    let start = Partition::from_tracks(&model, &problem, window, &tracks).unwrap();
    assert_eq!(start.n_tracks(), 5);
    let from = start.canonical();
    let n = 300_000u64;
    // Each new partition: how often it was proposed, its q, and which move types proposed it
    // (several can: an update that keeps the whole track and grows is also an extension).
    let mut seen: HashMap<Vec<Vec<u32>>, (u64, f64, [bool; 8])> = HashMap::new();
    for i in 0..n {
        let mut chain = Chain::new(start.clone(), ChaCha8Rng::seed_from_u64(i));
        chain.force_accept = true;
        let (m, _) = chain.step();
        let to = chain.state().canonical();
        if let (Some(q), true) = (chain.last_log_q, to != from) {
            let entry = seen.entry(to).or_insert((0, q, [false; 8]));
            entry.0 += 1;
            entry.2[m.index()] = true;
            assert!((entry.1 - q).abs() < 1e-9, "{m:?}: q differs between draws");
        }
    }
    // checked[m]: partitions proposed by move m whose frequency was tested; alone[m]: those
    // that only move m proposed.
    let (mut checked, mut alone) = ([0u32; 8], [0u32; 8]);
    for (count, log_q, moves) in seen.values() {
        let expected = n as f64 * log_q.exp();
        if expected < 30.0 {
            continue;
        }
        let z = (*count as f64 - expected) / expected.sqrt();
        assert!(
            z.abs() < 5.0,
            "{moves:?}: proposed {count} times, q predicts {expected:.0}"
        );
        for m in Move::ALL.into_iter().filter(|m| moves[m.index()]) {
            checked[m.index()] += 1;
            if moves.iter().filter(|&&b| b).count() == 1 {
                alone[m.index()] += 1;
            }
        }
    }
    for m in Move::ALL {
        assert!(
            checked[m.index()] > 0,
            "no {m:?} proposal frequent enough: {checked:?}"
        );
    }
    eprintln!("checked per move {checked:?}, proposed by that move alone {alone:?}");
    // Every partition an extension proposes is also an update's (keep the whole track, then
    // grow), so extensions are checked through that sum, with enough draws: at least two
    // such partitions. An update that regrows the tail differently is an update's alone, so
    // its own q is tested too.
    assert!(
        checked[Move::Extension.index()] >= 2,
        "extension proposals checked: {checked:?}"
    );
    assert!(
        alone[Move::Update.index()] >= 2,
        "partitions proposed by an update alone checked: {alone:?}"
    );
}

#[test]
fn online_tracker_commits_scans_skipped_by_a_jump_in_frames() {
    use crate::{OnlineConfig, OnlineTracker};
    let scans = three_walkers(30, &[]);
    let model = McmcdaConfig::default().check().unwrap();
    let config = OnlineConfig {
        window: 5,
        samples_per_scan: 300,
        ..OnlineConfig::default()
    };
    let mut tracker = OnlineTracker::new(model, 0, config, 9).unwrap();
    // Frames 12 and 13 never arrive: the window jumps by three scans at frame 14.
    for s in scans.iter().filter(|s| s.frame != 12 && s.frame != 13) {
        let points: Vec<Vector2<f64>> = s.measurements.iter().map(|m| m.value).collect();
        tracker.push_scan(s.frame, &points).unwrap();
    }
    let result = tracker.finish().unwrap();
    let mut lengths: Vec<usize> = result.associations.iter().map(|(_, t)| t.len()).collect();
    lengths.sort_unstable();
    // Every received measurement is committed to its walker (a gap of 3 scans ≤ d̄).
    assert_eq!(lengths, vec![28, 28, 28]);
}

#[test]
fn every_config_is_checked_before_it_runs() {
    use crate::{
        BatchConfig, NearestNeighbourConfig, OnlineConfig, OnlineTracker, SingleScanConfig,
        batch_mcmcda, jpda_exact, nearest_neighbour_tracks,
    };
    use tracker_model::{Gaussian, LinearObservation};
    let parameter = |e: Error| match e {
        Error::Model(tracker_model::Error::InvalidParameter { name, .. }) => name,
        other => panic!("not a parameter error: {other}"),
    };
    let model = McmcdaConfig::default().check().unwrap();
    let problem = Problem::from_scans(&model, &three_walkers(4, &[])).unwrap();
    let window = problem.all_scans().unwrap();
    for (bad, name) in [
        (
            NearestNeighbourConfig {
                gate: 0.0,
                ..NearestNeighbourConfig::default()
            },
            "gate",
        ),
        (
            NearestNeighbourConfig {
                confirm_hits: 4,
                confirm_window: 3,
                ..NearestNeighbourConfig::default()
            },
            "confirm_hits",
        ),
    ] {
        assert_eq!(parameter(bad.check().unwrap_err()), name);
        let e = nearest_neighbour_tracks(&model, &problem, window.clone(), &bad).unwrap_err();
        assert_eq!(parameter(e), name);
    }
    for (bad, name) in [
        (
            OnlineConfig {
                window: 1,
                ..OnlineConfig::default()
            },
            "window",
        ),
        (
            OnlineConfig {
                extension_gate: f64::NAN,
                ..OnlineConfig::default()
            },
            "extension_gate",
        ),
    ] {
        assert_eq!(parameter(bad.check().unwrap_err()), name);
        let e = OnlineTracker::new(model.clone(), 0, bad, 1).err().unwrap();
        assert_eq!(parameter(e), name);
    }
    let bad = SingleScanConfig {
        laziness: 1.0,
        ..SingleScanConfig::default()
    };
    assert_eq!(parameter(bad.check().unwrap_err()), "laziness");
    let prior = Gaussian::new(nalgebra::Vector4::zeros(), Matrix4::identity()).unwrap();
    let sensor = LinearObservation::leading_components(Matrix2::identity()).unwrap();
    let e = jpda_exact(&[prior], &sensor, &[Vector2::new(0.0, 0.0)], &bad).unwrap_err();
    assert_eq!(parameter(e), "laziness");
    let bad = BatchConfig {
        chains: 0,
        ..BatchConfig::default()
    };
    assert_eq!(parameter(bad.check().unwrap_err()), "chains");
    assert_eq!(
        parameter(batch_mcmcda(&model, &problem, &bad).unwrap_err()),
        "chains"
    );
    // The defaults pass their own checks.
    NearestNeighbourConfig::default().check().unwrap();
    NearestNeighbourConfig::greedy_init(&model).check().unwrap();
    OnlineConfig::default().check().unwrap();
    SingleScanConfig::default().check().unwrap();
    BatchConfig::default().check().unwrap();
}

#[test]
fn configs_written_in_toml_reject_unknown_fields() {
    use crate::{BatchConfig, NearestNeighbourConfig, OnlineConfig, SingleScanConfig};
    fn rejects<T: serde::de::DeserializeOwned>(text: &str) {
        let err = toml::from_str::<T>(text).err().map(|e| e.to_string());
        assert!(
            err.as_deref()
                .is_some_and(|e| e.contains("unknown field") || e.contains("unexpected keys")),
            "{text:?} accepted as {}: {err:?}",
            std::any::type_name::<T>()
        );
    }
    rejects::<McmcdaConfig>("p_detct = 0.8");
    rejects::<McmcdaConfig>("track_init = { first_measurement = { velocity_varience = 1.0 } }");
    rejects::<NearestNeighbourConfig>("gates = 9.2");
    rejects::<OnlineConfig>("windows = 5");
    rejects::<SingleScanConfig>("burnin = 10");
    rejects::<BatchConfig>("chain = 2");
    // The same fields spelled right are read.
    let model: McmcdaConfig = toml::from_str(
        "p_detect = 0.8\ntrack_init = { first_measurement = { velocity_variance = 1.0 } }",
    )
    .unwrap();
    assert_eq!(
        model,
        McmcdaConfig {
            p_detect: 0.8,
            track_init: TrackInit::FirstMeasurement {
                velocity_variance: Some(1.0)
            },
            ..McmcdaConfig::default()
        }
    );
    let batch: BatchConfig = toml::from_str("chains = 2").unwrap();
    assert_eq!(
        batch,
        BatchConfig {
            chains: 2,
            ..BatchConfig::default()
        }
    );
}

#[test]
fn batch_mcmcda_recovers_separated_targets() {
    use crate::{BatchConfig, batch_mcmcda};
    let scans = three_walkers(8, &[(3, 1), (6, 2)]);
    let model = McmcdaConfig::default().check().unwrap();
    let problem = Problem::from_scans(&model, &scans).unwrap();
    let run = batch_mcmcda(&model, &problem, &BatchConfig::default()).unwrap();
    let mut lengths: Vec<usize> = run.tracks.iter().map(Vec::len).collect();
    lengths.sort_unstable();
    assert_eq!(lengths, vec![7, 7, 8]);
    // The same as the greedy start and run_chains by hand.
    let start =
        crate::chain::greedy_initial_partition(&model, &problem, problem.all_scans().unwrap())
            .unwrap();
    assert_eq!(run, run_chains(&start, 1, 50_000, 0).unwrap());
}

#[test]
fn a_frame_four_billion_ahead_costs_no_more_than_the_next() {
    use crate::{
        BatchConfig, NearestNeighbourConfig, OnlineConfig, OnlineTracker, batch_mcmcda,
        nearest_neighbour_tracks, smoothed_tracks,
    };
    let model = McmcdaConfig::default().check().unwrap();
    let far = 4_000_000_000u32;
    let frames = [0, 1, 2, far, far + 1, far + 2];
    let points = |f: u32| -> Vec<Vector2<f64>> {
        let t = f64::from(f % 3);
        vec![
            Vector2::new(100.0 + 30.0 * t, 200.0),
            Vector2::new(700.0, 300.0 + 25.0 * t),
        ]
    };
    let mut problem = Problem::empty(&model, 0);
    for &f in &frames {
        problem.push_scan(f, &points(f)).unwrap();
    }
    // Scan indices are frames: four billion empty scans in between, none of them stored.
    assert_eq!(problem.n_scans(), far as usize + 3);
    assert!(problem.scan(3).is_empty() && problem.scan(far as usize - 1).is_empty());
    assert_eq!(
        problem.nonempty_scans(problem.all_scans().unwrap()).count(),
        6
    );
    // Every entry point runs: no track can span the gap (d̄ = 5), so each side keeps its two.
    let run = batch_mcmcda(
        &model,
        &problem,
        &BatchConfig {
            samples: 5_000,
            ..BatchConfig::default()
        },
    )
    .unwrap();
    assert_eq!(run.tracks.len(), 4, "{:?}", run.tracks);
    let gnn = nearest_neighbour_tracks(
        &model,
        &problem,
        problem.all_scans().unwrap(),
        &NearestNeighbourConfig::default(),
    )
    .unwrap();
    assert_eq!(gnn.len(), 4, "{gnn:?}");
    let smoothed = smoothed_tracks(&model, &problem, &run.tracks, 0).unwrap();
    assert_eq!(smoothed.len(), 4);
    let mut online = OnlineTracker::new(model.clone(), 0, OnlineConfig::default(), 1).unwrap();
    for &f in &frames {
        online.push_scan(f, &points(f)).unwrap();
    }
    assert_eq!(online.finish().unwrap().associations.len(), 4);
}

#[test]
fn empty_scans_are_scored_as_the_per_scan_counts_score_them() {
    // Frames 0, 1, 3, 4: scan 2 is empty and not stored. Every feasible partition's
    // incremental log posterior must equal the per-scan-count route, which visits scan 2.
    let scans = vec![
        scan(0, &[(0.0, 0.0), (4.0, 1.0)]),
        scan(1, &[(2.0, 1.0)]),
        scan(3, &[(5.0, 1.5), (1.0, 3.0)]),
        scan(4, &[(7.0, 2.0)]),
    ];
    for (track_init, track_end, head_probability) in variants() {
        let model = McmcdaConfig {
            track_init,
            track_end,
            head_probability,
            ..tiny_config()
        }
        .check()
        .unwrap();
        let problem = Problem::from_scans(&model, &scans).unwrap();
        assert_eq!(problem.n_scans(), 5);
        let window = problem.all_scans().unwrap();
        let all = enumerate_partitions(&model, &problem, window.clone()).unwrap();
        assert!(
            all.iter().any(|p| p.iter().any(|t| {
                t.windows(2)
                    .any(|w| problem.scan_of(w[1]) - problem.scan_of(w[0]) == 2)
            })),
            "some partition has a track across the empty scan"
        );
        for tracks in &all {
            let fast = Partition::from_tracks(&model, &problem, window.clone(), tracks)
                .unwrap()
                .log_posterior();
            let slow = log_posterior_by_counts(&model, &problem, window.clone(), tracks).unwrap();
            assert!((fast - slow).abs() < 1e-9, "{tracks:?}: {fast} vs {slow}");
        }
    }
}

#[test]
fn estimates_reject_unknown_and_unsorted_ids() {
    use crate::{measurement_labels, smoothed_tracks};
    let model = tiny_config().check().unwrap();
    let problem = Problem::from_scans(&model, &tiny_scans()).unwrap();
    // Ids 0..6; scans 0, 0, 1, 1, 2, 2.
    assert_eq!(
        smoothed_tracks(&model, &problem, &[vec![0, 2], vec![1, 9]], 0).unwrap_err(),
        Error::UnknownMeasurement { track: 1, id: 9 }
    );
    assert_eq!(
        smoothed_tracks(&model, &problem, &[vec![4, 2]], 0).unwrap_err(),
        Error::ScansNotIncreasing {
            track: 0,
            first: 4,
            second: 2
        }
    );
    assert_eq!(
        smoothed_tracks(&model, &problem, &[vec![0, 1]], 0).unwrap_err(),
        Error::ScansNotIncreasing {
            track: 0,
            first: 0,
            second: 1
        }
    );
    assert_eq!(
        measurement_labels(&problem, &[vec![0, 2], vec![7]]).unwrap_err(),
        Error::UnknownMeasurement { track: 1, id: 7 }
    );
    assert_eq!(
        measurement_labels(&problem, &[vec![0, 2], vec![2, 4]]).unwrap_err(),
        Error::MeasurementTaken { track: 1, id: 2 }
    );
    assert_eq!(
        measurement_labels(&problem, &[vec![0, 3]]).unwrap(),
        vec![vec![Some(0), None], vec![None, Some(0)], vec![None, None]]
    );
}

/// Two scans, (0, 0) then (x, 0), tracked by GNN: the second measurement continues the
/// first only if the log-likelihood ratio of Blackman 2004 favours it.
fn gnn_links(x: f64, cost: crate::AssignmentCost) -> bool {
    use crate::{NearestNeighbourConfig, nearest_neighbour_tracks};
    // R = I, newborn velocity variance 1, acceleration variance 4: the predicted innovation
    // covariance is S = (R + 1·Δ² + 4Δ⁴/4 + R) = 4 I at Δ = 1 (by hand).
    let model = McmcdaConfig {
        volume: 1.0e3,
        clutter_per_scan: 1.0,
        births_per_scan: 1.0,
        p_detect: 0.9,
        measurement_noise: Matrix2::identity(),
        motion: ConstantVelocity2::mcmcda(1.0, 4.0).unwrap(),
        track_init: TrackInit::FirstMeasurement {
            velocity_variance: Some(1.0),
        },
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let problem =
        Problem::from_scans(&model, &[scan(0, &[(0.0, 0.0)]), scan(1, &[(x, 0.0)])]).unwrap();
    let config = NearestNeighbourConfig {
        cost,
        ..NearestNeighbourConfig::default()
    };
    let tracks = nearest_neighbour_tracks(&model, &problem, 0..=1, &config).unwrap();
    !tracks.is_empty()
}

#[test]
fn gnn_leaves_a_track_unassigned_when_clutter_explains_the_measurement_better() {
    use crate::AssignmentCost;
    // Link iff p_d N(z; ẑ, S) > (1 − p_d) λ with λ = (1 + 1) / 10³ and S = 4 I:
    // x² < 2·4·ln[0.9 / (0.1 · 2·10⁻³ · 2π · 4)], i.e. |x| < 6.4422 (by hand), inside the
    // χ² gate (|x| < √(13.8·4) = 7.43).
    let boundary = (8.0 * (0.9 / (0.1 * 2.0e-3 * 2.0 * std::f64::consts::PI * 4.0)).ln()).sqrt();
    assert!((boundary - 6.4422).abs() < 1e-3, "{boundary}");
    assert!(gnn_links(
        0.99 * boundary,
        AssignmentCost::LogLikelihoodRatio
    ));
    assert!(!gnn_links(
        1.01 * boundary,
        AssignmentCost::LogLikelihoodRatio
    ));
    // Forced assignment takes every gated pair.
    assert!(gnn_links(1.01 * boundary, AssignmentCost::Forced));
    assert!(!gnn_links(7.5, AssignmentCost::Forced));
}

#[test]
fn gnn_deletes_a_track_after_its_largest_gap() {
    use crate::{NearestNeighbourConfig, nearest_neighbour_tracks};
    // One walker, missed in scan 2: with max_gap 1 the track ends at scan 1 and a new one
    // starts at scan 3; with max_gap 2 it is one track.
    let scans = three_walkers(6, &[(2, 0)]);
    let model = McmcdaConfig::default().check().unwrap();
    let problem = Problem::from_scans(&model, &scans).unwrap();
    let walker0 = |tracks: &[Vec<u32>]| -> Vec<usize> {
        tracks
            .iter()
            .filter(|t| problem.position(t[0]).x < 600.0 && problem.position(t[0]).y < 300.0)
            .map(Vec::len)
            .collect()
    };
    let run = |max_gap| {
        let config = NearestNeighbourConfig {
            max_gap,
            ..NearestNeighbourConfig::default()
        };
        nearest_neighbour_tracks(&model, &problem, problem.all_scans().unwrap(), &config).unwrap()
    };
    assert_eq!(walker0(&run(Some(2))), vec![5]);
    assert_eq!(walker0(&run(Some(1))), vec![2, 3]);
    let bad = NearestNeighbourConfig {
        max_gap: Some(0),
        ..NearestNeighbourConfig::default()
    };
    assert!(bad.check().is_err());
}

/// `sample_joins` on three well-separated walkers: in every sample each walker's earlier
/// piece is joined to its own later piece (the posterior puts essentially all mass on the
/// right partition), never to another's; pieces outside the window are an error.
#[test]
fn sample_joins_follow_separated_walkers() {
    use crate::{MeasId, OnlineConfig, OnlineTracker};
    let scans = three_walkers(12, &[]);
    let model = McmcdaConfig::default().check().unwrap();
    let config = OnlineConfig {
        window: 6,
        samples_per_scan: 300,
        ..OnlineConfig::default()
    };
    let mut tracker = OnlineTracker::new(model, 0, config, 9).unwrap();
    for s in &scans {
        let points: Vec<Vector2<f64>> = s.measurements.iter().map(|m| m.value).collect();
        tracker.push_scan(s.frame, &points).unwrap();
    }
    let window = tracker.window().unwrap();
    let p = tracker.problem();
    let pre: Vec<MeasId> = p.scan(*window.start() + 1).to_vec();
    let post: Vec<MeasId> = p.scan(*window.end()).to_vec();
    assert_eq!((pre.len(), post.len()), (3, 3));
    // The walker of each piece, from its starting x (100, 500 or 800; x grows 20 per scan).
    let walker =
        |m: MeasId| ((p.position(m).x - 20.0 * p.scan_of(m) as f64) / 100.0).round() as i64;
    let expected: Vec<(usize, usize)> = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .filter(|&(i, j)| walker(pre[i]) == walker(post[j]))
        .collect();
    assert_eq!(expected.len(), 3);
    let (pre_c, post_c) = (pre.clone(), post.clone());
    let samples = tracker.sample_joins(&pre_c, &post_c, 200).unwrap();
    assert_eq!(samples.len(), 200);
    for s in &samples {
        let mut sorted = s.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, expected);
    }
    assert_eq!(tracker.map_tracks().len(), 3);
    let old = p_scan_zero(&tracker);
    assert!(matches!(
        tracker.sample_joins(&[old], &post_c, 10),
        Err(Error::MeasurementOutsideWindow { .. })
    ));
}

fn p_scan_zero(tracker: &crate::OnlineTracker) -> crate::MeasId {
    tracker.problem().scan(0)[0]
}

/// A problem with a late measurement, built twice: once whole, once forgetting its first
/// scans. The kept part must answer every question as the whole problem does (same ids,
/// scans, positions, forward neighbourhoods, backward ones within reach); the forgotten part
/// must say so (`contains` false, typed errors, a panic that names the reason).
#[test]
fn a_problem_forgets_old_scans_and_keeps_ids_and_scan_indices() {
    let model = McmcdaConfig {
        max_gap: 2,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let mut whole = Problem::empty(&model, 100);
    for f in 100..110u32 {
        let x = f64::from(f);
        whole
            .push_scan(f, &[Vector2::new(x, 0.0), Vector2::new(x, 50.0)])
            .unwrap();
        if f == 104 {
            // Late for frame 102 (scan 2): id 10, stored after scan 4's ids.
            assert_eq!(
                whole.add_measurement(102, Vector2::new(102.0, 25.0)),
                Ok(10)
            );
        }
    }
    let mut part = whole.clone();
    part.forget_before(3);
    assert_eq!(part.first_kept_scan(), 3);
    assert_eq!(part.kept_scans().unwrap(), 3..=9);
    assert_eq!(
        part.all_scans().unwrap(),
        0..=9,
        "scan indices keep their meaning"
    );
    assert_eq!((part.n_scans(), part.first_frame()), (10, 100));
    assert_eq!(part.n_measurements(), 21, "ids keep counting");
    assert_eq!(part.n_kept_measurements(), 14);
    // Scan s ≥ 3 holds ids 2s and 2s + 1, plus 11 onwards shifted by the late one.
    let kept: Vec<u32> = (0..21).filter(|&m| part.contains(m)).collect();
    let expected: Vec<u32> = (0..21)
        .filter(|&m| m != 10 && whole.scan_of(m) >= 3)
        .collect();
    assert_eq!(kept, expected);
    for m in 0..21 {
        assert_eq!(part.is_forgotten(m), !expected.contains(&m), "id {m}");
    }
    assert!(!part.contains(21) && !part.is_forgotten(21));
    for &m in &kept {
        assert_eq!(part.scan_of(m), whole.scan_of(m));
        assert_eq!(part.position(m), whole.position(m));
        for d in 1..=2 {
            assert_eq!(part.forward(m, d), whole.forward(m, d), "forward of {m}");
            let back: &[u32] = if part.scan_of(m) >= 3 + d {
                whole.backward(m, d)
            } else {
                &[]
            };
            assert_eq!(part.backward(m, d), back, "backward of {m}, d {d}");
        }
    }
    for s in 0..3 {
        assert!(part.scan(s).is_empty());
    }
    assert_eq!(part.scan(3), whole.scan(3));
    assert_eq!(
        part.nonempty_scans(0..=9)
            .map(|(s, _)| s)
            .collect::<Vec<_>>(),
        (3..10).collect::<Vec<_>>()
    );
    // Forgotten scans refuse measurements and windows; kept ones take both.
    assert_eq!(
        part.add_measurement(101, Vector2::new(1.0, 1.0)),
        Err(Error::ScanForgotten {
            scan: 1,
            first_kept: 3
        })
    );
    assert_eq!(
        Partition::empty(&model, &part, 2..=9).err(),
        Some(Error::ScanForgotten {
            scan: 2,
            first_kept: 3
        })
    );
    assert_eq!(
        Partition::from_tracks(&model, &part, 3..=9, &[vec![0, 6]]).err(),
        Some(Error::MeasurementOutsideWindow { track: 0, id: 0 })
    );
    assert_eq!(
        crate::smoothed_tracks(&model, &part, &[vec![0, 6]], 0).err(),
        Some(Error::UnknownMeasurement { track: 0, id: 0 })
    );
    assert_eq!(part.add_measurement(103, Vector2::new(103.0, 1.0)), Ok(21));
    assert_eq!(part.forward(21, 1), whole.forward(6, 1));
    // Asking a forgotten id's data is a panic that says why, never another's data.
    for m in [0, 10] {
        let p = part.clone();
        let err = std::panic::catch_unwind(move || p.position(m)).unwrap_err();
        let msg = err.downcast_ref::<String>().cloned().unwrap_or_default();
        assert!(
            msg.contains(&format!("measurement {m} was forgotten")),
            "{msg}"
        );
    }
    // Forgetting is for good, and forgetting past the end keeps nothing.
    part.forget_before(1);
    assert_eq!(part.first_kept_scan(), 3);
    part.forget_before(1_000);
    assert_eq!(part.first_kept_scan(), 10);
    assert_eq!(part.kept_scans(), Err(Error::EmptyProblem));
    assert_eq!((part.n_kept_measurements(), part.n_measurements()), (0, 22));
    assert_eq!(part.push_scan(110, &[Vector2::new(0.0, 0.0)]), Ok(vec![22]));
    assert_eq!(part.kept_scans().unwrap(), 10..=10);
}

/// The chain over the kept scans of a problem that forgot its first ones follows exactly
/// the chain over the same window of the whole problem: same seed, same states.
#[test]
fn a_chain_over_kept_scans_is_the_chain_over_the_whole_problem() {
    let sim = SimulationConfig {
        births_per_scan: 1.0,
        clutter_per_scan: 3.0,
        n_scans: 16,
        ..SimulationConfig::default()
    }
    .check()
    .unwrap()
    .simulate(&mut ChaCha8Rng::seed_from_u64(21))
    .unwrap();
    let model = McmcdaConfig {
        clutter_per_scan: 3.0,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let whole = Problem::from_scans(&model, &sim.scans).unwrap();
    let mut part = whole.clone();
    part.forget_before(6);
    let window = part.kept_scans().unwrap();
    let a = Partition::empty(&model, &whole, window.clone()).unwrap();
    let b = Partition::empty(&model, &part, window).unwrap();
    let mut ca = Chain::new(a, ChaCha8Rng::seed_from_u64(3));
    let mut cb = Chain::new(b, ChaCha8Rng::seed_from_u64(3));
    for _ in 0..5_000 {
        assert_eq!(ca.step(), cb.step());
        assert_eq!(ca.state().canonical(), cb.state().canonical());
    }
    cb.state().check_invariants().unwrap();
    assert!(ca.state().n_tracks() > 0);
}

/// Streaming (draining after every scan, or every few) changes nothing the tracker decides:
/// the same estimates at every scan, and per label the drained pieces followed by what
/// `finish` returns are the association of a run that keeps everything.
#[test]
fn streaming_online_gives_the_same_associations() {
    use crate::{CommittedPiece, OnlineConfig, OnlineTracker};
    use std::collections::BTreeMap;
    let sim = SimulationConfig {
        births_per_scan: 0.3,
        clutter_per_scan: 4.0,
        n_scans: 60,
        ..SimulationConfig::default()
    }
    .check()
    .unwrap()
    .simulate(&mut ChaCha8Rng::seed_from_u64(8))
    .unwrap();
    let model = McmcdaConfig {
        clutter_per_scan: 4.0,
        births_per_scan: 0.3,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let config = OnlineConfig {
        window: 6,
        samples_per_scan: 300,
        ..OnlineConfig::default()
    };
    let run = |drain_every: Option<usize>| {
        let mut tracker = OnlineTracker::new(model.clone(), 0, config, 4).unwrap();
        let mut steps = Vec::new();
        let mut pieces: Vec<CommittedPiece> = Vec::new();
        let mut max_kept = 0;
        for (i, s) in sim.scans.iter().enumerate() {
            let points: Vec<Vector2<f64>> = s.measurements.iter().map(|m| m.value).collect();
            steps.push(tracker.push_scan(s.frame, &points).unwrap());
            if i == 30 {
                // A late measurement near a target's: still inside the window.
                let late = s.measurements.first().map_or(Vector2::zeros(), |m| m.value);
                tracker
                    .add_late(s.frame - 2, late + Vector2::new(1.0, 1.0))
                    .unwrap();
            }
            if drain_every.is_some_and(|k| i % k == 0) {
                pieces.extend(tracker.drain_committed());
            }
            max_kept = max_kept.max(tracker.problem().n_kept_measurements());
        }
        let result = tracker.finish().unwrap();
        let mut by_label: BTreeMap<u64, Vec<u32>> = BTreeMap::new();
        for p in &pieces {
            by_label.entry(p.label).or_default().extend(&p.measurements);
        }
        for (label, meas) in &result.associations {
            by_label.entry(*label).or_default().extend(meas);
        }
        (steps, by_label, max_kept, pieces, result.problem)
    };
    let (steps, whole, kept_all, _, all) = run(None);
    assert!(whole.len() >= 3, "{} labels", whole.len());
    assert_eq!(all.n_kept_measurements(), all.n_measurements());
    for k in [1, 4] {
        let (s, streamed, kept, pieces, _) = run(Some(k));
        assert_eq!(s, steps, "draining every {k}");
        assert_eq!(streamed, whole, "draining every {k}");
        assert!(kept * 2 < kept_all, "{kept} vs {kept_all} kept");
        assert!(!pieces.is_empty());
        for p in &pieces {
            let frames: Vec<u32> = p
                .measurements
                .iter()
                .map(|&m| all.first_frame() + all.scan_of(m) as u32)
                .collect();
            let positions: Vec<Vector2<f64>> =
                p.measurements.iter().map(|&m| all.position(m)).collect();
            assert_eq!((&p.frames, &p.positions), (&frames, &positions));
        }
    }
}

/// The model of [`gnn_links`] over two scans, (0, 0) then (x, 0), with score log ratios `r`
/// for the two measurements.
fn scored_pair(x: f64, r: [f64; 2]) -> (Model, Problem) {
    let model = McmcdaConfig {
        volume: 1.0e3,
        clutter_per_scan: 1.0,
        births_per_scan: 1.0,
        p_detect: 0.9,
        measurement_noise: Matrix2::identity(),
        motion: ConstantVelocity2::mcmcda(1.0, 4.0).unwrap(),
        track_init: TrackInit::FirstMeasurement {
            velocity_variance: Some(1.0),
        },
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let mut problem = Problem::empty(&model, 0);
    problem
        .push_scan_scored(0, &[Vector2::new(0.0, 0.0)], &[r[0]])
        .unwrap();
    problem
        .push_scan_scored(1, &[Vector2::new(x, 0.0)], &[r[1]])
        .unwrap();
    (model, problem)
}

#[test]
fn score_ratios_enter_the_posterior_and_the_gnn_cost_as_computed_by_hand() {
    use crate::{NearestNeighbourConfig, nearest_neighbour_tracks};
    // MCMCDA: the track [0, 1] against "both clutter" at x = 5, by hand (eq. 9, S = 4 I):
    // ln λ_b + ln(1 − p_z) + 2 (ln p_d − ln λ_f) − ln(2π·4) − x²/8
    // = −6.9078 − 0.0001 + 2 (−0.1054 + 6.9078) − 3.2242 − 3.125 = 0.3478;
    // the scores add r₀ + r₁ = ln 2 + ln 3 = ln 6 = 1.7918.
    for (r, by_hand) in [
        ([0.0, 0.0], 0.3478),
        ([2f64.ln(), 3f64.ln()], 0.3478 + 1.7918),
    ] {
        let (model, problem) = scored_pair(5.0, r);
        let track = Partition::from_tracks(&model, &problem, 0..=1, &[vec![0, 1]]).unwrap();
        let clutter = Partition::empty(&model, &problem, 0..=1).unwrap();
        let w = track.log_posterior() - clutter.log_posterior();
        assert!((w - by_hand).abs() < 1e-3, "{w} vs {by_hand}");
        let slow = log_posterior_by_counts(&model, &problem, 0..=1, &[vec![0, 1]]).unwrap()
            - log_posterior_by_counts(&model, &problem, 0..=1, &[]).unwrap();
        assert!((slow - w).abs() < 1e-9, "{slow} vs {w}");
    }
    // GNN links iff p_d N(z; ẑ, S) f₁/f₀ > (1 − p_d) λ: x² < 8 (ln[0.9 / (0.1 · 2·10⁻³ · 2π · 4)]
    // + r) = 8 (5.1877 + r); with r = ln 4 the boundary moves from 6.4422 to 7.2520 (by hand),
    // still inside the χ² gate (7.43).
    let links = |x: f64, r: f64| {
        let (model, problem) = scored_pair(x, [0.0, r]);
        !nearest_neighbour_tracks(&model, &problem, 0..=1, &NearestNeighbourConfig::default())
            .unwrap()
            .is_empty()
    };
    assert!(links(0.99 * 6.4422, 0.0) && !links(1.01 * 6.4422, 0.0));
    assert!(links(0.99 * 7.2520, 4f64.ln()) && !links(1.01 * 7.2520, 4f64.ln()));
    // A count of ratios that does not match the points, or a non-finite one, is an error.
    let model = McmcdaConfig::default().check().unwrap();
    let mut problem = Problem::empty(&model, 0);
    assert!(matches!(
        problem.push_scan_scored(0, &[Vector2::new(1.0, 1.0)], &[]),
        Err(Error::ScoreCount {
            points: 1,
            scores: 0
        })
    ));
    assert!(
        problem
            .push_scan_scored(0, &[Vector2::new(1.0, 1.0)], &[f64::NAN])
            .is_err()
    );
    assert_eq!(problem.n_measurements(), 0);
}

#[test]
fn a_high_score_pair_forms_a_track_where_a_low_score_pair_does_not() {
    use crate::{NearestNeighbourConfig, nearest_neighbour_tracks};
    // At x = 5 the pair is nearly a tie (0.3478 in favour of the track, above); scores of
    // ln f₁/f₀ = +1 each make it a track, −1 each clutter, for the exact MAP (enumeration)
    // and for the chain.
    for (r, track) in [(1.0, true), (-1.0, false)] {
        let (model, problem) = scored_pair(5.0, [r, r]);
        let all = enumerate_partitions(&model, &problem, 0..=1).unwrap();
        let map = all
            .iter()
            .max_by(|a, b| {
                let lp = |p: &Vec<Vec<u32>>| {
                    log_posterior_by_counts(&model, &problem, 0..=1, p).unwrap()
                };
                lp(a).total_cmp(&lp(b))
            })
            .unwrap();
        assert_eq!(!map.is_empty(), track, "r = {r}: {map:?}");
        let start = Partition::empty(&model, &problem, 0..=1).unwrap();
        let run = run_chains(&start, 1, 2_000, 3).unwrap();
        assert_eq!(!run.tracks.is_empty(), track, "r = {r}: {:?}", run.tracks);
    }
    // GNN at x = 6.8, beyond the unscored boundary 6.4422: it links iff
    // 8 (5.1877 + r) > 6.8² = 46.24, i.e. r > 0.593.
    for (r, track) in [(1.0, true), (-1.0, false), (0.0, false)] {
        let (model, problem) = scored_pair(6.8, [r, r]);
        let tracks =
            nearest_neighbour_tracks(&model, &problem, 0..=1, &NearestNeighbourConfig::default())
                .unwrap();
        assert_eq!(!tracks.is_empty(), track, "r = {r}");
    }
}

#[test]
fn scored_incremental_posterior_matches_the_counts_under_every_move() {
    // The tiny crossing problem with a score ratio on every measurement: the chain's
    // incremental log posterior stays equal to the per-scan-count route.
    let model = tiny_config().check().unwrap();
    let mut problem = Problem::empty(&model, 0);
    for (i, s) in tiny_scans().iter().enumerate() {
        let points: Vec<_> = s.measurements.iter().map(|m| m.value).collect();
        let ratios: Vec<f64> = (0..points.len())
            .map(|j| 0.7 * (i as f64) - 1.1 * (j as f64) + 0.3)
            .collect();
        problem.push_scan_scored(s.frame, &points, &ratios).unwrap();
    }
    let window = problem.all_scans().unwrap();
    let start = Partition::empty(&model, &problem, window.clone()).unwrap();
    let mut chain = Chain::new(start, ChaCha8Rng::seed_from_u64(4));
    for i in 0..3_000 {
        chain.force_accept = i % 3 == 0;
        chain.step();
        let state = chain.state();
        state.check_invariants().unwrap();
        let tracks: Vec<Vec<u32>> = state.tracks().map(<[u32]>::to_vec).collect();
        let fresh = log_posterior_by_counts(&model, &problem, window.clone(), &tracks).unwrap();
        assert!((fresh - state.log_posterior()).abs() < 1e-8 * fresh.abs().max(1.0));
    }
}

/// log q of a single-track move the long way (one growth probability per kept prefix, as
/// in the paper's definition): the route the sampler's suffix sums must equal.
fn single_track_q_by_prefixes(state: &Partition<'_>, k: usize, from: &[u32], to: &[u32]) -> f64 {
    use crate::proposal::{End, FirstStep};
    let xi = |m| state.model.move_probability(m, k);
    let head = state.model.config.head_probability;
    let mut terms = Vec::new();
    for (end, weight) in [(End::Tail, 1.0 - head), (End::Head, head)] {
        if weight <= 0.0 {
            continue;
        }
        let order = |v: &[u32]| -> Vec<u32> {
            match end {
                End::Tail => v.to_vec(),
                End::Head => v.iter().rev().copied().collect(),
            }
        };
        let (from, to) = (order(from), order(to));
        let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
        let w = weight.ln();
        if to.len() > from.len() && common == from.len() {
            terms.push(
                w + xi(Move::Extension).ln()
                    + state.log_grow_probability(
                        from[common - 1],
                        end,
                        &to[common..],
                        FirstStep::MayStop,
                    ),
            );
        }
        if from.len() >= 3 && to.len() >= 2 && to.len() < from.len() && common == to.len() {
            terms.push(w + xi(Move::Reduction).ln() - ((from.len() - 2) as f64).ln());
        }
        for r in 1..=common.min(from.len()) {
            terms.push(
                w + xi(Move::Update).ln() - (from.len() as f64).ln()
                    + state.log_grow_probability(to[r - 1], end, &to[r..], FirstStep::of_update(r)),
            );
        }
    }
    let max = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY {
        return max;
    }
    max + terms.iter().map(|t| (t - max).exp()).sum::<f64>().ln() - (k as f64).ln()
}

/// Scans of `n_walkers` walkers at `position(w, t)` over `n_scans` scans (frames 0, 1, …), each
/// detected with probability `p_detect`, plus the points `clutter` draws per scan; with the
/// walkers' measurement ids (ids count walkers' detections, then clutter, scan by scan).
fn walker_scans(
    rng: &mut ChaCha8Rng,
    (n_scans, n_walkers, p_detect): (u32, usize, f64),
    position: impl Fn(f64, f64) -> (f64, f64),
    clutter: impl Fn(&mut ChaCha8Rng) -> Vec<(f64, f64)>,
) -> (Vec<Scan>, Vec<Vec<u32>>) {
    use rand::RngExt;
    let mut truth: Vec<Vec<u32>> = vec![Vec::new(); n_walkers];
    let mut id = 0u32;
    let scans = (0..n_scans)
        .map(|f| {
            let mut points = Vec::new();
            for (w, track) in truth.iter_mut().enumerate() {
                if rng.random_bool(p_detect) {
                    points.push(position(w as f64, f64::from(f)));
                    track.push(id);
                    id += 1;
                }
            }
            let noise = clutter(rng);
            id += noise.len() as u32;
            points.extend(noise);
            scan(f, &points)
        })
        .collect();
    (scans, truth)
}

/// A single-track proposal's new track for `from` (in `state`, where it is removed): a random
/// end, a random prefix from it kept and regrown as the proposal grows it; `None` when the
/// result is shorter than two measurements.
fn regrown_track(
    state: &mut Partition<'_>,
    from: &[u32],
    rng: &mut ChaCha8Rng,
) -> Option<Vec<u32>> {
    use crate::proposal::{End, FirstStep};
    use rand::RngExt;
    let end = if rng.random_bool(0.5) {
        End::Tail
    } else {
        End::Head
    };
    let mut order = from.to_vec();
    if end == End::Head {
        order.reverse();
    }
    let r = rng.random_range(1..=order.len());
    let mut to = order[..r].to_vec();
    state.grow(
        order[r - 1],
        end,
        FirstStep::of_update(r),
        &mut to,
        &mut Vec::new(),
        rng,
    );
    if end == End::Head {
        to.reverse();
    }
    (to.len() >= 2).then_some(to)
}

/// Four walkers close together over `n_scans` scans with misses (p_d = 0.8) and 0-2 clutter
/// points per scan, so that candidate sets hold several free measurements and growth can go
/// astray; with their measurement ids.
fn four_close_walkers(rng: &mut ChaCha8Rng, n_scans: u32) -> (Vec<Scan>, Vec<Vec<u32>>) {
    use rand::RngExt;
    walker_scans(
        rng,
        (n_scans, 4, 0.8),
        |w, t| (50.0 * w + 6.0 * t, 40.0 * w + (w - 1.5) * 4.0 * t),
        |rng| {
            (0..rng.random_range(0..3))
                .map(|_| (rng.random_range(0.0..300.0), rng.random_range(0.0..300.0)))
                .collect()
        },
    )
}

/// The model for [`four_close_walkers`]: v̄ = 30, d̄ = 4, the given head probability.
fn close_walkers_model(head_probability: f64) -> Model {
    McmcdaConfig {
        max_speed: 30.0,
        max_gap: 4,
        head_probability,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap()
}

#[test]
fn single_track_q_by_suffix_sums_equals_the_sum_over_prefixes() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (scans, truth) = four_close_walkers(&mut rng, 25);
    for head_probability in [0.0, 0.3, 1.0] {
        let model = close_walkers_model(head_probability);
        let problem = Problem::from_scans(&model, &scans).unwrap();
        let window = problem.all_scans().unwrap();
        let start = Partition::from_tracks(&model, &problem, window, &truth).unwrap();
        let (mut compared, mut finite) = (0, 0);
        for k in 0..start.n_tracks() {
            let mut state = start.clone();
            let old = state.remove(k);
            let from = old.meas.clone();
            for _ in 0..60 {
                let Some(to) = regrown_track(&mut state, &from, &mut rng) else {
                    continue;
                };
                let n_tracks = start.n_tracks();
                for (a, b) in [(&from, &to), (&to, &from)] {
                    let fast = state.log_single_track_probability(n_tracks, a, b);
                    let slow = single_track_q_by_prefixes(&state, n_tracks, a, b);
                    compared += 1;
                    if slow.is_finite() {
                        finite += 1;
                        assert!(
                            (fast - slow).abs() < 1e-9 * slow.abs().max(1.0),
                            "{a:?} -> {b:?}: {fast} vs {slow}"
                        );
                    } else {
                        assert!(
                            fast == f64::NEG_INFINITY && slow == f64::NEG_INFINITY,
                            "{a:?} -> {b:?}: {fast} vs {slow}"
                        );
                    }
                }
            }
        }
        assert!(finite > 100, "{finite} of {compared} comparisons finite");
    }
}

/// The suffix sums of the single-track q stop once every remaining term is below 2⁻⁵⁴ of the
/// largest (proposal.rs, `one_end_terms`): on long tracks (two walkers over 160 scans, where
/// it stops early) the result must be bit for bit the full loop's, and agree with the
/// term-by-term sum over prefixes.
#[test]
fn single_track_q_stops_early_with_the_full_sums_bits() {
    use crate::proposal::{EARLY_STOP, EARLY_STOPS};
    use rand::RngExt;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let (scans, truth) = walker_scans(
        &mut rng,
        (160, 2, 0.85),
        |w, t| (40.0 * w + 5.0 * t, 30.0 + 25.0 * w + (w - 0.5) * 0.2 * t),
        |rng| {
            if rng.random_bool(0.5) {
                vec![(rng.random_range(0.0..900.0), rng.random_range(0.0..100.0))]
            } else {
                Vec::new()
            }
        },
    );
    let model = McmcdaConfig {
        max_speed: 30.0,
        max_gap: 4,
        head_probability: 0.5,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let problem = Problem::from_scans(&model, &scans).unwrap();
    let start =
        Partition::from_tracks(&model, &problem, problem.all_scans().unwrap(), &truth).unwrap();
    let stops_before = EARLY_STOPS.with(std::cell::Cell::get);
    let mut finite = 0;
    for k in 0..start.n_tracks() {
        let mut state = start.clone();
        let from = state.remove(k).meas;
        for _ in 0..40 {
            let Some(to) = regrown_track(&mut state, &from, &mut rng) else {
                continue;
            };
            let n = start.n_tracks();
            for (a, b) in [(&from, &to), (&to, &from)] {
                let fast = state.log_single_track_probability(n, a, b);
                EARLY_STOP.with(|e| e.set(false));
                let full = state.log_single_track_probability(n, a, b);
                EARLY_STOP.with(|e| e.set(true));
                assert_eq!(fast.to_bits(), full.to_bits(), "{fast} vs {full}");
                let slow = single_track_q_by_prefixes(&state, n, a, b);
                if slow.is_finite() {
                    finite += 1;
                    assert!(
                        (fast - slow).abs() < 1e-9 * slow.abs().max(1.0),
                        "{fast} vs {slow}"
                    );
                } else {
                    assert!(fast.is_infinite() && fast < 0.0, "{fast}");
                }
            }
        }
    }
    let stops = EARLY_STOPS.with(std::cell::Cell::get) - stops_before;
    assert!(finite > 40, "{finite} finite comparisons");
    assert!(stops > 20, "the sums stopped early only {stops} times");
}

/// Rejection against a bound of the Metropolis-Hastings ratio (sampler.rs,
/// `draw_against_bound`) is exact: on four walkers close together with clutter, at every head
/// probability, over the whole problem and over a window of its later scans, a chain that
/// rejects against the bounds takes the same path as one that evaluates every ratio (same
/// MAP, log posterior and move statistics, to the bit); each bounded move (death, split,
/// reduction, update, switch) was rejected against its bound; and with
/// the bounds off every proposal's bound was checked against its exact ratio (`check_bound`,
/// which panics if one is below).
#[test]
fn bounded_rejection_takes_the_exact_ratios_path() {
    use crate::sampler::{BOUNDED_REJECTION, BOUNDED_REJECTIONS};
    let (scans, _) = four_close_walkers(&mut ChaCha8Rng::seed_from_u64(21), 20);
    let before = BOUNDED_REJECTIONS.with(std::cell::Cell::get);
    for head_probability in [0.0, 0.3, 1.0] {
        let model = close_walkers_model(head_probability);
        let problem = Problem::from_scans(&model, &scans).unwrap();
        for window in [problem.all_scans().unwrap(), 6..=19] {
            let run = |bounded: bool| {
                BOUNDED_REJECTION.with(|b| b.set(bounded));
                let start = Partition::empty(&model, &problem, window.clone()).unwrap();
                let mut chain = Chain::new(start, ChaCha8Rng::seed_from_u64(4));
                chain.run(20_000);
                BOUNDED_REJECTION.with(|b| b.set(true));
                let (map, log_posterior) = chain.map();
                (
                    map.to_vec(),
                    log_posterior.to_bits(),
                    chain.state().log_posterior().to_bits(),
                    *chain.stats(),
                )
            };
            let bounded = run(true);
            let exact = run(false);
            assert_eq!(
                bounded, exact,
                "head probability {head_probability}, {window:?}"
            );
            assert!(
                bounded.3.accepted.iter().sum::<u64>() > 500,
                "{:?}",
                bounded.3
            );
        }
    }
    let after = BOUNDED_REJECTIONS.with(std::cell::Cell::get);
    let n = |m: Move| after[m.index()] - before[m.index()];
    // Birth's q comes from its own draws and merge's q are cheap: never bounded. An
    // extension's bound seldom decides (the way it grew is unlikely, so its forward q's bound
    // is low), and it shares the single-track code with reduction and update. Switches are
    // rare here (few partners).
    assert_eq!((n(Move::Birth), n(Move::Merge)), (0, 0));
    for m in [Move::Death, Move::Split, Move::Reduction, Move::Update] {
        assert!(
            n(m) > 1_000,
            "{m:?} rejected against its bound only {} times",
            n(m)
        );
    }
    assert!(n(Move::Switch) >= 10, "{after:?}");
}

/// Runs the online tracker over `scans` (plus `extra` points at some frames) and returns the
/// final associations as sorted position lists, with the samples drawn.
fn online_run(
    scans: &[Scan],
    extra: &[(u32, Vector2<f64>)],
    config: crate::OnlineConfig,
) -> (Vec<Vec<(f64, f64)>>, u64) {
    let model = McmcdaConfig::default().check().unwrap();
    let mut tracker = crate::OnlineTracker::new(model, 0, config, 3).unwrap();
    for s in scans {
        let mut points: Vec<Vector2<f64>> = s.measurements.iter().map(|m| m.value).collect();
        points.extend(extra.iter().filter(|(f, _)| *f == s.frame).map(|(_, p)| *p));
        tracker.push_scan(s.frame, &points).unwrap();
    }
    let samples = tracker.samples_run();
    let result = tracker.finish().unwrap();
    let mut tracks: Vec<Vec<(f64, f64)>> = result
        .associations
        .iter()
        .map(|(_, t)| {
            t.iter()
                .map(|&m| {
                    let p = result.problem.position(m);
                    (p.x, p.y)
                })
                .collect()
        })
        .collect();
    tracks.sort_by(|a, b| a[0].0.total_cmp(&b[0].0));
    (tracks, samples)
}

#[test]
fn online_patience_stops_early_with_the_full_budgets_map_and_the_cap_binds() {
    use crate::OnlineConfig;
    // Three separated walkers, two misses: after the first scans every window's start (the
    // previous MAP extended into the new scan) already is the MAP.
    let scans = three_walkers(30, &[(10, 0), (20, 1)]);
    let full = OnlineConfig {
        window: 6,
        samples_per_scan: 500,
        ..OnlineConfig::default()
    };
    let (tracks, samples) = online_run(&scans, &[], full);
    // The default draws every window's whole budget.
    assert_eq!(samples, 30 * 500);
    // Sorted by starting x: walkers 0 and 1 miss one scan each, walker 2 none.
    assert_eq!(
        tracks.iter().map(Vec::len).collect::<Vec<_>>(),
        vec![29, 29, 30]
    );
    let patient = OnlineConfig {
        patience: 50,
        ..full
    };
    let (early, early_samples) = online_run(&scans, &[], patient);
    assert_eq!(early, tracks, "the adaptive stop changed the MAP");
    // At least 50 samples per window, far fewer than the budget in all.
    assert!(early_samples >= 30 * 50, "{early_samples}");
    assert!(early_samples < 30 * 500 / 3, "{early_samples} samples");
    // A patience beyond the budget never stops a chain: the cap binds, and the draws are
    // those of the fixed budget.
    let capped = OnlineConfig {
        patience: 501,
        ..full
    };
    assert_eq!(online_run(&scans, &[], capped), (tracks, 30 * 500));
}

#[test]
fn online_skip_unambiguous_samples_only_the_ambiguous_scans() {
    use crate::OnlineConfig;
    let scans = three_walkers(30, &[(10, 0), (20, 1)]);
    let full = OnlineConfig {
        window: 6,
        samples_per_scan: 500,
        ..OnlineConfig::default()
    };
    let skip = OnlineConfig {
        skip_unambiguous: true,
        ..full
    };
    let (tracks, _) = online_run(&scans, &[], full);
    // Scans 0 and 1 hold free measurements (no track has two measurements yet); from scan 2
    // on every measurement extends the one track whose gate holds it (the misses leave a
    // track unextended, which is not ambiguous).
    let (skipped, samples) = online_run(&scans, &[], skip);
    assert_eq!(skipped, tracks);
    assert_eq!(samples, 2 * 500);
    // A false point far from every walker at frame 15 is free: that scan is sampled too, and
    // the point joins no track.
    let clutter = [(15, Vector2::new(3000.0, 3000.0))];
    let (with_clutter, samples) = online_run(&scans, &clutter, skip);
    assert_eq!(with_clutter, tracks);
    assert_eq!(samples, 3 * 500);
    // Walker 1's missed measurement of frame 20 arriving late, after frame 21: the window of
    // frame 22 is sampled for it, and the chain puts it on walker 1's track.
    let model = McmcdaConfig::default().check().unwrap();
    let mut tracker = crate::OnlineTracker::new(model, 0, skip, 3).unwrap();
    for s in &scans {
        let points: Vec<Vector2<f64>> = s.measurements.iter().map(|m| m.value).collect();
        tracker.push_scan(s.frame, &points).unwrap();
        if s.frame == 21 {
            tracker.add_late(20, Vector2::new(900.0, 600.0)).unwrap();
        }
    }
    assert_eq!(tracker.samples_run(), 3 * 500);
    let result = tracker.finish().unwrap();
    let mut lengths: Vec<usize> = result.associations.iter().map(|(_, t)| t.len()).collect();
    lengths.sort_unstable();
    assert_eq!(lengths, vec![29, 30, 30]);
}

/// The two refinements of `skip_unambiguous`. `rival_log_ratio`: two walkers 30 apart (σ = 10)
/// side by side, each measurement in both gates but far likelier on its own walker's track:
/// every gated rival makes every scan ambiguous, a ratio of 1 counts none of them, and the
/// tracks are the same. `birth_lookback`: a lone false point far from everything needs no
/// sample, but a second one next to it a scan later (they could start a track) does.
#[test]
fn online_skip_counts_close_rivals_and_free_points_that_could_start_a_track() {
    use crate::OnlineConfig;
    let side_by_side: Vec<Scan> = (0..30u32)
        .map(|f| {
            let x = 100.0 + 20.0 * f64::from(f);
            scan(f, &[(x, 300.0), (x, 330.0)])
        })
        .collect();
    let every_rival = OnlineConfig {
        window: 6,
        samples_per_scan: 500,
        skip_unambiguous: true,
        ..OnlineConfig::default()
    };
    let close_rivals = OnlineConfig {
        rival_log_ratio: 1.0,
        ..every_rival
    };
    let (tracks, samples) = online_run(&side_by_side, &[], every_rival);
    assert_eq!(tracks.len(), 2);
    assert!(tracks.iter().all(|t| t.len() == 30), "{tracks:?}");
    assert!(samples >= 25 * 500, "{samples} samples");
    // Sampled: scans 0 and 1 (no track yet) and scan 2, where the two-point tracks'
    // velocities are too uncertain to tell the walkers apart.
    assert_eq!(
        online_run(&side_by_side, &[], close_rivals),
        (tracks, 3 * 500)
    );

    let scans = three_walkers(30, &[]);
    let lookback = OnlineConfig {
        birth_lookback: 2,
        ..every_rival
    };
    // Only scan 1 is sampled: scan 0's points have nothing before them to start a track with.
    let (tracks, samples) = online_run(&scans, &[], lookback);
    assert_eq!(samples, 500);
    assert_eq!(tracks, online_run(&scans, &[], every_rival).0);
    let lone = [(15, Vector2::new(3000.0, 3000.0))];
    assert_eq!(online_run(&scans, &lone, lookback), (tracks.clone(), 500));
    assert_eq!(online_run(&scans, &lone, every_rival).1, 3 * 500);
    let pair = [
        (15, Vector2::new(3000.0, 3000.0)),
        (16, Vector2::new(3020.0, 3000.0)),
    ];
    let (with_pair, samples) = online_run(&scans, &pair, lookback);
    assert_eq!(samples, 2 * 500);
    assert!(
        tracks.iter().all(|t| with_pair.contains(t)),
        "{with_pair:?}"
    );
    // A look-back beyond d̄ (5 here) looks at d̄ scans: nothing further back can precede a
    // measurement on a track.
    let far = OnlineConfig {
        birth_lookback: 40,
        ..every_rival
    };
    let (with_pair_far, _) = online_run(&scans, &pair, far);
    assert!(
        tracks.iter().all(|t| with_pair_far.contains(t)),
        "{with_pair_far:?}"
    );
}

/// The online settings are checked: a rival ratio must be ≥ 0 (∞ allowed).
#[test]
fn online_rival_log_ratio_is_checked() {
    use crate::OnlineConfig;
    for bad in [-1.0, f64::NAN, f64::NEG_INFINITY] {
        let config = OnlineConfig {
            rival_log_ratio: bad,
            ..OnlineConfig::default()
        };
        let err = config.check().unwrap_err().to_string();
        assert!(err.contains("rival_log_ratio"), "{err}");
    }
    for good in [0.0, 4.0, f64::INFINITY] {
        let config = OnlineConfig {
            rival_log_ratio: good,
            ..OnlineConfig::default()
        };
        config.check().unwrap();
    }
}

/// Every neighbour list against brute force: `forward(m, d)` holds exactly the measurements of
/// scan s(m) + d within reach of m, and `backward(m, d)` those of scan s(m) − d, in id order,
/// on a problem with empty scans (skipped frame numbers), late measurements and gaps of up to
/// d̄ = 4; then again after the oldest scans are forgotten.
#[test]
fn neighbour_lists_equal_brute_force() {
    let model = McmcdaConfig {
        max_gap: 4,
        max_speed: 3.0,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let mut problem = Problem::empty(&model, 1);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut uniform = |scale: f64| scale * rand::RngExt::random::<f64>(&mut rng);
    for frame in [1u32, 2, 3, 5, 6, 9, 10, 11, 12, 15] {
        let n = 1 + (uniform(4.0) as usize);
        let points: Vec<Vector2<f64>> = (0..n)
            .map(|_| Vector2::new(uniform(20.0), uniform(20.0)))
            .collect();
        problem.push_scan(frame, &points).unwrap();
        if frame >= 5 {
            // Late measurements two and four frames back (existing scans or empty ones), so
            // that later scans at every gap up to d̄ already hold measurements.
            for back in [2, 4] {
                let late = Vector2::new(uniform(20.0), uniform(20.0));
                problem.add_measurement(frame - back, late).unwrap();
            }
        }
    }
    let non_empty = lists_against_brute_force(&problem, &model);
    assert!(
        non_empty > 20,
        "the case must exercise the lists: {non_empty}"
    );
    // Forgetting the scans before frame 9 drops the late measurement added to frame 8
    // (scan 7) after frame 12, whose id lies above measurements that are kept: the kept
    // lists must lose exactly the entries in forgotten scans.
    problem.forget_before(8);
    assert!((0..problem.n_measurements() as u32).any(|m| problem.is_forgotten(m)));
    let non_empty = lists_against_brute_force(&problem, &model);
    assert!(
        non_empty > 5,
        "the case must exercise the lists: {non_empty}"
    );
}

/// Checks every kept measurement's lists against brute force over the kept measurements;
/// returns how many forward lists are non-empty.
fn lists_against_brute_force(problem: &Problem, model: &Model) -> usize {
    let all: Vec<u32> = (0..problem.n_measurements() as u32)
        .filter(|&m| problem.contains(m))
        .collect();
    let mut non_empty = 0;
    for &m in &all {
        for d in 1..=4 {
            let reach = d as f64 * model.radius_per_scan;
            let within = |o: u32| {
                (problem.position(m) - problem.position(o)).norm_squared() <= reach * reach
            };
            let later: Vec<u32> = all
                .iter()
                .copied()
                .filter(|&o| problem.scan_of(o) == problem.scan_of(m) + d && within(o))
                .collect();
            let earlier: Vec<u32> = all
                .iter()
                .copied()
                .filter(|&o| problem.scan_of(o) + d == problem.scan_of(m) && within(o))
                .collect();
            // In id order, unsorted: proposals index into these lists, so their order is
            // part of what a seed reproduces.
            assert_eq!(problem.forward(m, d), later, "forward({m}, {d})");
            assert_eq!(problem.backward(m, d), earlier, "backward({m}, {d})");
            non_empty += usize::from(!later.is_empty());
        }
    }
    non_empty
}

/// A problem without neighbourhoods gives GNN the same tracks as the full problem, has empty
/// lists, and refuses to be partitioned (MCMCDA needs the lists) with a typed error.
#[test]
fn a_problem_without_neighbourhoods_serves_gnn_and_refuses_mcmcda() {
    use crate::{
        NearestNeighbourConfig, chain::greedy_initial_partition, nearest_neighbour_tracks,
    };
    let scans = three_walkers(8, &[(3, 1), (4, 1), (6, 2)]);
    let model = McmcdaConfig::default().check().unwrap();
    let full = Problem::from_scans(&model, &scans).unwrap();
    let mut bare = Problem::without_neighbourhoods(&model, scans[0].frame);
    for scan in &scans {
        let points: Vec<Vector2<f64>> = scan.measurements.iter().map(|m| m.value).collect();
        bare.push_scan(scan.frame, &points).unwrap();
    }
    assert!(full.has_neighbourhoods() && !bare.has_neighbourhoods());
    let window = full.all_scans().unwrap();
    let gnn = |p: &Problem| {
        nearest_neighbour_tracks(
            &model,
            p,
            window.clone(),
            &NearestNeighbourConfig::default(),
        )
        .unwrap()
    };
    assert_eq!(gnn(&bare), gnn(&full));
    assert!((0..full.n_measurements() as u32).any(|m| !full.forward(m, 1).is_empty()));
    for m in 0..bare.n_measurements() as u32 {
        assert_eq!(bare.position(m), full.position(m));
        assert!(
            (1..=model.max_gap() as usize)
                .all(|d| bare.forward(m, d).is_empty() && bare.backward(m, d).is_empty())
        );
    }
    assert_eq!(
        Partition::empty(&model, &bare, window.clone()).unwrap_err(),
        Error::NoNeighbourhoods
    );
    assert_eq!(
        greedy_initial_partition(&model, &bare, window.clone()).unwrap_err(),
        Error::NoNeighbourhoods
    );
    assert_eq!(
        crate::reference::enumerate_partitions(&model, &bare, window).unwrap_err(),
        Error::NoNeighbourhoods
    );
}

/// Two chains per window: the same tracks as one chain on three walkers with misses, twice
/// the samples, the same bytes with one and with two threads, and a window's log posterior
/// at least that of the one-chain tracker's first window (chain 0 draws what the one-chain
/// tracker draws, and the window keeps the better MAP). Zero chains is a typed error.
#[test]
fn online_chains_in_parallel_are_reproducible_and_no_worse() {
    use crate::{OnlineConfig, OnlineTracker};
    let scans = three_walkers(30, &[(10, 0), (20, 1)]);
    let one = OnlineConfig {
        window: 6,
        samples_per_scan: 300,
        ..OnlineConfig::default()
    };
    let two = OnlineConfig { chains: 2, ..one };
    let (tracks, samples) = online_run(&scans, &[], one);
    let in_pool = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| online_run(&scans, &[], two))
    };
    let (tracks_two, samples_two) = in_pool(1);
    for threads in [2, 3] {
        assert_eq!(in_pool(threads), (tracks_two.clone(), samples_two));
    }
    assert_eq!(tracks_two, tracks);
    assert_eq!(samples_two, 2 * samples);
    // The first window with tracks to find, scans 0-1: both trackers start it from the same
    // (empty) MAP of scan 0, and chain 0 has drawn what the one-chain tracker drew.
    let first_window = |config: OnlineConfig| {
        let model = McmcdaConfig::default().check().unwrap();
        let mut tracker = OnlineTracker::new(model, 0, config, 3).unwrap();
        let mut last = f64::NAN;
        for s in &scans[..2] {
            let points: Vec<Vector2<f64>> = s.measurements.iter().map(|m| m.value).collect();
            last = tracker.push_scan(s.frame, &points).unwrap().log_posterior;
        }
        last
    };
    assert!(first_window(two) >= first_window(one));
    let model = McmcdaConfig::default().check().unwrap();
    for chains in [0, 65] {
        let bad = OnlineConfig { chains, ..one };
        assert!(matches!(
            OnlineTracker::new(model.clone(), 0, bad, 3),
            Err(Error::Model(tracker_model::Error::InvalidParameter { .. }))
        ));
    }
}

/// A window's chains: `sample_window` returns the MAP of the chain with the highest log
/// posterior among the chains run one by one from the same start with the same generators,
/// and the samples of all of them; the case is one where chain 0 is not the best.
#[test]
fn sample_window_keeps_the_best_chain() {
    use crate::OnlineConfig;
    use crate::online::{run_window, sample_window};
    let scans = three_walkers(8, &[(3, 1), (5, 2)]);
    let model = McmcdaConfig::default().check().unwrap();
    let problem = Problem::from_scans(&model, &scans).unwrap();
    let start = Partition::empty(&model, &problem, problem.all_scans().unwrap()).unwrap();
    let config = OnlineConfig {
        samples_per_scan: 40,
        chains: 4,
        ..OnlineConfig::default()
    };
    let rngs: Vec<ChaCha8Rng> = (0..4)
        .map(|i| {
            let mut rng = ChaCha8Rng::seed_from_u64(11);
            rng.set_stream(i);
            rng
        })
        .collect();
    let alone: Vec<(Vec<Vec<u32>>, f64)> = rngs
        .iter()
        .map(|rng| {
            let mut chain = Chain::new(start.clone(), rng.clone());
            run_window(&mut chain, &config);
            let (best, lp) = chain.map();
            (best.to_vec(), lp)
        })
        .collect();
    let winner = (0..4).fold(0, |w, i| if alone[i].1 > alone[w].1 { i } else { w });
    assert_ne!(winner, 0, "the case must have a better chain than chain 0");
    let (best, lp, samples) = sample_window(start, &mut rngs.clone(), &config);
    assert_eq!((best, lp), alone[winner].clone());
    assert_eq!(samples, 4 * 40);
}
