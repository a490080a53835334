//! Brute-force enumeration of every state path on tiny models, agreement between the scaled,
//! log-space, dense and sparse formulations, Baum-Welch monotonicity and freezing, a very long
//! sequence, and error cases.
#![expect(clippy::float_cmp, reason = "structural zeros are exactly zero")]

use approx::assert_relative_eq;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::{TrackId, TrackPoint, Vec2};

use crate::*;

fn random_row(len: usize, zeros: &[usize], rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mut row: Vec<f64> = (0..len)
        .map(|j| {
            if zeros.contains(&j) {
                0.0
            } else {
                rng.random_range(0.05..1.0)
            }
        })
        .collect();
    let s: f64 = row.iter().sum();
    row.iter_mut().for_each(|v| *v /= s);
    row
}

/// A random model; `sparse` zeroes one transition per row so both storages are exercised.
fn random_hmm(n: usize, m: usize, sparse: bool, seed: u64) -> Hmm {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let a: Vec<f64> = (0..n)
        .flat_map(|i| {
            let zeros = if sparse { vec![(i + 1) % n] } else { vec![] };
            random_row(n, &zeros, &mut rng)
        })
        .collect();
    let b: Vec<f64> = (0..n).flat_map(|_| random_row(m, &[], &mut rng)).collect();
    let pi = random_row(n, &[], &mut rng);
    Hmm::new(pi, Transitions::dense(n, a).unwrap(), b, m).unwrap()
}

/// P(Q, O | λ) for every path Q, by enumeration.
fn all_paths(hmm: &Hmm, obs: &[usize]) -> Vec<(Vec<usize>, f64)> {
    let n = hmm.n_states();
    let len = obs.len();
    let mut out = Vec::new();
    for code in 0..n.pow(len as u32) {
        let path: Vec<usize> = (0..len).map(|t| (code / n.pow(t as u32)) % n).collect();
        let mut p = hmm.initial()[path[0]] * hmm.emission(path[0], obs[0]);
        for t in 1..len {
            p *= hmm.transitions().get(path[t - 1], path[t]) * hmm.emission(path[t], obs[t]);
        }
        out.push((path, p));
    }
    out
}

#[test]
fn forward_posterior_viterbi_and_xi_match_brute_force() {
    for (seed, sparse) in [(1, false), (2, true), (3, false), (4, true)] {
        let hmm = random_hmm(3, 2, sparse, seed);
        let obs = [0, 1, 1, 0, 1, 0];
        let paths = all_paths(&hmm, &obs);
        let total: f64 = paths.iter().map(|p| p.1).sum();
        let f = forward(&hmm, &obs).unwrap();
        assert!(
            (f.log_likelihood - total.ln()).abs() < 1e-12,
            "log-likelihood"
        );
        let post = posterior(&hmm, &obs).unwrap();
        for t in 0..obs.len() {
            for i in 0..3 {
                let brute: f64 = paths
                    .iter()
                    .filter(|p| p.0[t] == i)
                    .map(|p| p.1)
                    .sum::<f64>()
                    / total;
                assert!((post.at(t)[i] - brute).abs() < 1e-12, "gamma t={t} i={i}");
            }
        }
        let (best_path, best_p) = paths.iter().fold((vec![], 0.0), |acc, p| {
            if p.1 > acc.1 { (p.0.clone(), p.1) } else { acc }
        });
        let (path, log_p) = viterbi(&hmm, &obs).unwrap();
        assert_eq!(path, best_path);
        assert!((log_p - best_p.ln()).abs() < 1e-12);
        let xi = expected_transitions(&hmm, &obs).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let brute: f64 = paths
                    .iter()
                    .map(|p| p.0.windows(2).filter(|w| w[0] == i && w[1] == j).count() as f64 * p.1)
                    .sum::<f64>()
                    / total;
                assert!((xi[i * 3 + j] - brute).abs() < 1e-12, "xi {i}->{j}");
            }
        }
        // Posterior decoding picks the per-step argmax of the brute-force marginals.
        let decoded = posterior_decode(&hmm, &obs).unwrap();
        for (t, &s) in decoded.iter().enumerate() {
            let g = post.at(t);
            assert!(g.iter().all(|&v| v <= g[s]));
        }
    }
}

#[test]
fn scaled_and_log_space_forward_agree() {
    let hmm = random_hmm(5, 4, false, 9);
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let (_, obs) = hmm.sample(200, &mut rng);
    let f = forward(&hmm, &obs).unwrap();
    let (log_alpha, ll) = forward_log(&hmm, &obs).unwrap();
    assert_relative_eq!(f.log_likelihood, ll, max_relative = 1e-12);
    for t in 0..obs.len() {
        let row = &log_alpha[t * 5..(t + 1) * 5];
        let max = row.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let norm: f64 = row.iter().map(|v| (v - max).exp()).sum();
        for (la, a) in row.iter().zip(&f.alpha[t * 5..(t + 1) * 5]) {
            assert!(((la - max).exp() / norm - a).abs() < 1e-12);
        }
    }
}

#[test]
fn sparse_and_dense_paths_agree() {
    let grid = CellGrid {
        n_cols: 6,
        n_rows: 5,
        cell_size: 1.0,
        blocked: vec![(2, 2), (3, 2)],
    };
    let space = StateSpace::from_grid(&grid).unwrap();
    let a = space
        .transitions(&SpeedDistribution::new(vec![0.3, 0.6, 0.1]).unwrap())
        .unwrap();
    let sensors = SensorModel {
        sensors: vec![Vec2::new(0.0, 0.0)],
        base_sigma: 0.7,
        sigma_per_distance: 0.1,
    };
    let n = space.n_states();
    let mut pi = vec![0.0; n];
    pi[0] = 1.0;
    let sparse = Hmm::new(pi, a, space.sensor_emissions(&sensors).unwrap(), n).unwrap();
    assert!(sparse.transitions().is_sparse());
    let dense = sparse.with_transition_storage(StorageChoice::Dense);
    assert!(!dense.transitions().is_sparse());
    let (_, obs) = sparse.sample(300, &mut ChaCha8Rng::seed_from_u64(3));
    let (fs, fd) = (
        forward(&sparse, &obs).unwrap(),
        forward(&dense, &obs).unwrap(),
    );
    assert!((fs.log_likelihood - fd.log_likelihood).abs() < 1e-12 * fs.log_likelihood.abs());
    let (ps, pd) = (
        posterior(&sparse, &obs).unwrap(),
        posterior(&dense, &obs).unwrap(),
    );
    assert!(
        ps.gamma
            .iter()
            .zip(&pd.gamma)
            .all(|(a, b)| (a - b).abs() < 1e-12)
    );
    let (xs, xd) = (
        expected_transitions(&sparse, &obs).unwrap(),
        expected_transitions(&dense, &obs).unwrap(),
    );
    assert!(xs.iter().zip(&xd).all(|(a, b)| (a - b).abs() < 1e-12));
    let (vs, vd) = (
        viterbi(&sparse, &obs).unwrap(),
        viterbi(&dense, &obs).unwrap(),
    );
    assert_eq!(vs.0, vd.0);
    assert!((vs.1 - vd.1).abs() < 1e-12 * vs.1.abs());
    // Automatic choice: a 20×20 grid's stay-or-step matrix (≤ 5 of 400 entries per row) given
    // densely is stored sparse; a full matrix stays dense.
    let big = StateSpace::from_grid(&CellGrid {
        n_cols: 20,
        n_rows: 20,
        cell_size: 1.0,
        blocked: vec![],
    })
    .unwrap();
    let values = big
        .transitions(&SpeedDistribution::new(vec![0.2, 0.8]).unwrap())
        .unwrap()
        .dense_values();
    let auto = Transitions::from_row_major(400, values.clone(), StorageChoice::Auto).unwrap();
    assert!(auto.is_sparse());
    assert_eq!(auto.dense_values(), values);
    let forced = Transitions::from_row_major(400, values, StorageChoice::Dense).unwrap();
    assert!(!forced.is_sparse());
    assert_eq!(forced.to_storage(StorageChoice::Auto), auto);
    let full = vec![0.5, 0.5, 0.5, 0.5];
    assert!(
        !Transitions::from_row_major(2, full.clone(), StorageChoice::Auto)
            .unwrap()
            .is_sparse()
    );
    let forced = Transitions::from_row_major(2, full.clone(), StorageChoice::Sparse).unwrap();
    assert!(forced.is_sparse());
    assert_eq!(forced.dense_values(), full);
    assert_eq!(
        forced.to_storage(StorageChoice::Dense),
        Transitions::dense(2, full).unwrap()
    );
}

fn training_data(truth: &Hmm, k: usize, len: usize, seed: u64) -> Vec<Vec<usize>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..k).map(|_| truth.sample(len, &mut rng).1).collect()
}

#[test]
fn baum_welch_never_decreases_the_likelihood() {
    let truth = random_hmm(4, 3, true, 21);
    let start = random_hmm(4, 3, true, 22);
    let data = training_data(&truth, 8, 120, 5);
    let cfg = BaumWelchConfig {
        max_iterations: 60,
        tolerance: 0.0,
        ..BaumWelchConfig::default()
    };
    let (_, report) = baum_welch(&start, &data, &cfg).unwrap();
    assert_eq!(report.log_likelihoods.len(), 61);
    for w in report.log_likelihoods.windows(2) {
        assert!(
            w[1] >= w[0] - 1e-9 * w[0].abs(),
            "log-likelihood fell from {} to {}",
            w[0],
            w[1]
        );
    }
    assert!(report.log_likelihoods.last().unwrap() > &report.log_likelihoods[0]);
}

#[test]
fn frozen_components_stay_bit_identical() {
    let start = random_hmm(4, 3, false, 30);
    let data = training_data(&random_hmm(4, 3, false, 31), 5, 80, 6);
    for freeze in [
        Freeze {
            initial: true,
            ..Freeze::default()
        },
        Freeze {
            transitions: true,
            ..Freeze::default()
        },
        Freeze {
            emissions: true,
            ..Freeze::default()
        },
    ] {
        let cfg = BaumWelchConfig {
            max_iterations: 10,
            freeze,
            pseudo_counts: PseudoCounts {
                initial: 0.5,
                transitions: 0.5,
                emissions: 0.5,
            },
            ..BaumWelchConfig::default()
        };
        let (trained, _) = baum_welch(&start, &data, &cfg).unwrap();
        assert_eq!(freeze.initial, trained.initial() == start.initial());
        assert_eq!(
            freeze.transitions,
            trained.transitions() == start.transitions()
        );
        assert_eq!(freeze.emissions, trained.emissions() == start.emissions());
    }
}

#[test]
fn structural_zeros_survive_training_with_pseudo_counts() {
    let start = random_hmm(4, 3, true, 40);
    let data = training_data(&random_hmm(4, 3, false, 41), 5, 80, 7);
    let cfg = BaumWelchConfig {
        max_iterations: 5,
        pseudo_counts: PseudoCounts {
            transitions: 1.0,
            ..PseudoCounts::default()
        },
        ..BaumWelchConfig::default()
    };
    let (trained, _) = baum_welch(&start, &data, &cfg).unwrap();
    for i in 0..4 {
        assert_eq!(trained.transitions().get(i, (i + 1) % 4), 0.0);
    }
}

#[test]
fn baum_welch_is_independent_of_thread_count() {
    let start = random_hmm(5, 4, false, 50);
    let data = training_data(&random_hmm(5, 4, false, 51), 12, 60, 8);
    let cfg = BaumWelchConfig {
        max_iterations: 5,
        ..BaumWelchConfig::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| baum_welch(&start, &data, &cfg).unwrap())
    };
    let (one, two) = (run(1), run(2));
    assert!(one.0 == two.0 && one.1 == two.1);
}

#[test]
fn a_million_steps_neither_underflow_nor_overflow() {
    let hmm = random_hmm(3, 2, false, 60);
    let (states, obs) = hmm.sample(1_000_000, &mut ChaCha8Rng::seed_from_u64(61));
    let f = forward(&hmm, &obs).unwrap();
    assert!(f.log_likelihood.is_finite() && f.log_likelihood < -1e5);
    let post = posterior(&hmm, &obs).unwrap();
    assert!(post.gamma.iter().all(|g| g.is_finite() && *g >= 0.0));
    assert!((post.at(999_999).iter().sum::<f64>() - 1.0).abs() < 1e-9);
    let (path, log_p) = viterbi(&hmm, &obs).unwrap();
    assert!(log_p.is_finite() && log_p < f.log_likelihood);
    // The Viterbi score is the joint log-probability of its path, recomputed here by the plain
    // product of the model's entries, and no smaller than that of the true path (it is the max).
    let joint = |p: &[usize]| {
        let mut lp = hmm.initial()[p[0]].ln() + hmm.emission(p[0], obs[0]).ln();
        for t in 1..p.len() {
            lp += hmm.transitions().get(p[t - 1], p[t]).ln() + hmm.emission(p[t], obs[t]).ln();
        }
        lp
    };
    assert_relative_eq!(joint(&path), log_p, max_relative = 1e-9);
    assert!(log_p >= joint(&states));
    // Given the observations, the truth at step t is in state i with probability γ_t(i), so the
    // number of steps on which a decoded path agrees with the truth has expectation
    // Σ_t γ_t(path_t) and variance Σ_t p_t(1 − p_t) ≤ T/4 (times a small factor for the
    // correlation between neighbouring steps of this fast-mixing 3-state chain): σ ≤ ~1000 at
    // T = 10⁶. A tolerance of T/100 = 10 000 is ≥ 10σ, yet a decoder wrong on 1 % of the steps,
    // or a posterior off by 0.01 on average, fails it; chance agreement (~T/3) is far outside.
    for (decoder, decoded) in [
        ("viterbi", path),
        ("posterior", posterior_decode(&hmm, &obs).unwrap()),
    ] {
        let agree = decoded.iter().zip(&states).filter(|(a, b)| a == b).count() as f64;
        let expected: f64 = decoded
            .iter()
            .enumerate()
            .map(|(t, &s)| post.at(t)[s])
            .sum();
        assert!(
            (agree - expected).abs() <= 1e4,
            "{decoder}: {agree} steps agree, the posterior expects {expected}"
        );
    }
}

/// Baum-Welch recovers a known model from long simulated data, within a tolerance derived from
/// the data size.
///
/// Complete data: a row i visited n_i ≈ T·s_i times (T steps in all, s the stationary
/// distribution of A) gives a maximum-likelihood a_ij that is a multinomial proportion with
/// standard error √(a_ij (1 − a_ij) / n_i); likewise b_i(m) over the n_i visits of state i.
/// Hidden states: the observed-data information is the complete-data one less the missing
/// information (Louis 1982), so the standard errors grow by at most 1/√(1 − λ), λ the largest
/// fraction of missing information, which is also EM's linear rate of convergence
/// (Dempster, Laird & Rubin 1977, §3): late in the run θ_k − θ* shrinks by λ per step and the
/// log-likelihood gains by λ². So λ is read off the run's own gains, and every entry must lie
/// within 5 such inflated standard errors of the truth (here λ ≈ 0.92, an inflation ≈ 3.5; the
/// complete-data errors of the same samples are all below 2 s.e.). A Baum-Welch that did not
/// learn would stay at the start, > 15 inflated s.e. away.
#[test]
fn baum_welch_recovers_a_known_model_from_long_data() {
    let a = [0.8, 0.15, 0.05, 0.1, 0.7, 0.2, 0.2, 0.1, 0.7];
    let b = [
        0.85, 0.1, 0.03, 0.02, //
        0.05, 0.85, 0.05, 0.05, //
        0.02, 0.03, 0.1, 0.85,
    ];
    let truth = Hmm::new(
        vec![1.0 / 3.0; 3],
        Transitions::dense(3, a.to_vec()).unwrap(),
        b.to_vec(),
        4,
    )
    .unwrap();
    // Start away from the truth but with the same labelling (EM finds a local maximum; a start
    // this close keeps it in the truth's basin and rules out a permutation of the states).
    let perturb = |v: &[f64], cols: usize, sign: f64| -> Vec<f64> {
        v.chunks(cols)
            .enumerate()
            .flat_map(|(i, row)| {
                let mut r: Vec<f64> = row
                    .iter()
                    .enumerate()
                    .map(|(j, x)| x + if (i + j) % 2 == 0 { sign * 0.1 } else { 0.0 })
                    .map(|x: f64| x.max(0.02))
                    .collect();
                let s: f64 = r.iter().sum();
                r.iter_mut().for_each(|x| *x /= s);
                r
            })
            .collect()
    };
    let start = Hmm::new(
        vec![1.0 / 3.0; 3],
        Transitions::dense(3, perturb(&a, 3, 1.0)).unwrap(),
        perturb(&b, 4, -1.0),
        4,
    )
    .unwrap();
    let (k, len) = (40, 5_000);
    let data = training_data(&truth, k, len, 77);
    let cfg = BaumWelchConfig {
        max_iterations: 1000,
        tolerance: 0.0,
        // |LL| ≈ 1.5·10⁵, so this stops at |ΔLL| ≈ 10⁻⁸, far above rounding (≈ 10⁻¹¹).
        relative_tolerance: 1e-13,
        freeze: Freeze {
            initial: true,
            ..Freeze::default()
        },
        ..BaumWelchConfig::default()
    };
    let (learned, report) = baum_welch(&start, &data, &cfg).unwrap();
    assert!(report.converged, "{} iterations", report.iterations());
    // λ² from the geometric mean ratio of successive gains while they fall from 10⁻⁴ to 10⁻⁷.
    let gains: Vec<f64> = report
        .log_likelihoods
        .windows(2)
        .map(|w| w[1] - w[0])
        .collect();
    let first = gains.iter().position(|&g| g < 1e-4).unwrap();
    let last = gains.iter().position(|&g| g < 1e-7).unwrap();
    assert!(last > first + 5 && gains[first..=last].iter().all(|&g| g > 0.0));
    let lambda = (gains[last] / gains[first])
        .powf(1.0 / (last - first) as f64)
        .sqrt();
    assert!((0.0..0.99).contains(&lambda), "{lambda}");
    let inflation = 1.0 / (1.0 - lambda).sqrt();
    // Stationary distribution of A by power iteration.
    let mut s = [1.0 / 3.0; 3];
    for _ in 0..1000 {
        let mut next = [0.0; 3];
        for i in 0..3 {
            for j in 0..3 {
                next[j] += s[i] * a[i * 3 + j];
            }
        }
        s = next;
    }
    let steps = (k * len) as f64;
    let z = |truth: f64, est: f64, visits: f64| {
        (est - truth).abs() / ((truth * (1.0 - truth) / visits).sqrt() * inflation)
    };
    // The largest error of a model's entries in inflated standard errors, and where.
    let worst = |model: &Hmm| {
        let mut out = (0.0, String::new());
        for i in 0..3 {
            // Transitions out of i are counted on every step but the last of each sequence.
            let visits = (steps - k as f64) * s[i];
            for j in 0..3 {
                let zz = z(a[i * 3 + j], model.transitions().get(i, j), visits);
                if zz > out.0 {
                    out = (zz, format!("a[{i}][{j}]"));
                }
            }
            for m in 0..4 {
                let zz = z(b[i * 4 + m], model.emission(i, m), steps * s[i]);
                if zz > out.0 {
                    out = (zz, format!("b[{i}][{m}]"));
                }
            }
        }
        out
    };
    let (learned_z, at) = worst(&learned);
    assert!(
        learned_z <= 5.0,
        "{at} is {learned_z:.1} s.e. from the truth"
    );
    let (start_z, _) = worst(&start);
    assert!(start_z > 15.0, "{start_z}");
}

#[test]
fn relative_tolerance_stops_where_the_absolute_one_does_not() {
    let truth = random_hmm(4, 3, false, 81);
    let start = random_hmm(4, 3, false, 82);
    let data = training_data(&truth, 20, 200, 83);
    let absolute = BaumWelchConfig {
        max_iterations: 40,
        tolerance: 1e-12,
        ..BaumWelchConfig::default()
    };
    let (_, slow) = baum_welch(&start, &data, &absolute).unwrap();
    assert!(!slow.converged && slow.iterations() == 40);
    let relative = BaumWelchConfig {
        relative_tolerance: 1e-4,
        ..absolute
    };
    let (_, fast) = baum_welch(&start, &data, &relative).unwrap();
    assert!(fast.converged && fast.iterations() < 40);
    // It stopped at the first step whose change met |ΔLL| ≤ rel·|LL|, and not before.
    let ll = &fast.log_likelihoods;
    let met = |w: &[f64]| (w[1] - w[0]).abs() <= 1e-4 * w[1].abs();
    assert!(met(&ll[ll.len() - 2..]));
    assert!(ll.windows(2).rev().skip(1).all(|w| !met(w)));
    // Up to that step both runs are the same computation.
    assert_eq!(ll[..], slow.log_likelihoods[..ll.len()]);
}

#[test]
fn invalid_models_and_observations_are_clear_errors() {
    let a = || Transitions::dense(2, vec![0.5, 0.5, 0.5, 0.5]).unwrap();
    assert!(matches!(
        Transitions::dense(2, vec![0.5, 0.5, 0.4, 0.5]),
        Err(Error::InvalidRow {
            what: "transition matrix",
            row: 1,
            ..
        })
    ));
    assert!(matches!(
        Transitions::dense(2, vec![1.5, -0.5, 0.5, 0.5]),
        Err(Error::InvalidRow { row: 0, .. })
    ));
    assert!(matches!(
        Transitions::dense(2, vec![f64::NAN, 1.0, 0.5, 0.5]),
        Err(Error::InvalidRow { row: 0, .. })
    ));
    assert!(matches!(
        Transitions::dense(2, vec![1.0; 3]),
        Err(Error::ShapeMismatch {
            expected: 4,
            got: 3,
            ..
        })
    ));
    assert!(matches!(
        Transitions::sparse(vec![vec![(0, 1.0)], vec![(5, 1.0)]]),
        Err(Error::InvalidRow { row: 1, .. })
    ));
    assert!(matches!(
        Hmm::new(vec![0.5, 0.6], a(), vec![1.0, 0.0, 0.0, 1.0], 2),
        Err(Error::InvalidRow {
            what: "initial distribution",
            ..
        })
    ));
    assert!(matches!(
        Hmm::new(vec![0.5, 0.5], a(), vec![1.0, 0.0, 0.3, 0.3], 2),
        Err(Error::InvalidRow {
            what: "emission matrix",
            row: 1,
            ..
        })
    ));
    assert!(matches!(
        Hmm::new(vec![1.0], a(), vec![1.0, 0.0, 0.0, 1.0], 2),
        Err(Error::ShapeMismatch {
            expected: 2,
            got: 1,
            ..
        })
    ));
    let hmm = Hmm::new(vec![1.0, 0.0], a(), vec![1.0, 0.0, 1.0, 0.0], 2).unwrap();
    assert_eq!(
        forward(&hmm, &[0, 2]).unwrap_err(),
        Error::SymbolOutOfRange {
            sequence: 0,
            index: 1,
            symbol: 2,
            n_symbols: 2
        }
    );
    assert_eq!(
        forward(&hmm, &[]).unwrap_err(),
        Error::Empty("observation sequence")
    );
    // Symbol 1 can never be emitted.
    assert_eq!(
        forward(&hmm, &[0, 1]).unwrap_err(),
        Error::ImpossibleObservation {
            sequence: 0,
            index: 1
        }
    );
    assert!(matches!(
        viterbi(&hmm, &[1]),
        Err(Error::ImpossibleObservation { .. })
    ));
    assert!(matches!(
        baum_welch(&hmm, &[vec![0], vec![0, 3]], &BaumWelchConfig::default()),
        Err(Error::SymbolOutOfRange { sequence: 1, .. })
    ));
    assert!(baum_welch(&hmm, &[], &BaumWelchConfig::default()).is_err());
    let bad = BaumWelchConfig {
        pseudo_counts: PseudoCounts {
            emissions: -1.0,
            ..PseudoCounts::default()
        },
        ..BaumWelchConfig::default()
    };
    assert!(baum_welch(&hmm, &[vec![0]], &bad).is_err());
}

#[test]
fn models_round_trip_through_serde_and_reject_corrupt_input() {
    for hmm in [
        random_hmm(4, 3, false, 70),
        random_hmm(4, 3, true, 71).with_transition_storage(StorageChoice::Sparse),
    ] {
        let json = serde_json::to_string(&hmm).unwrap();
        assert_eq!(serde_json::from_str::<Hmm>(&json).unwrap(), hmm);
    }
    let bad = r#"{"initial":[1.0],"transitions":{"sparse":{"rows":[[[3,1.0]]]}},"emissions":[1.0],"n_symbols":1}"#;
    assert!(serde_json::from_str::<Hmm>(bad).is_err());
}

#[test]
fn maps_build_valid_models() {
    let grid = CellGrid {
        n_cols: 3,
        n_rows: 3,
        cell_size: 10.0,
        blocked: vec![(1, 1)],
    };
    let space = StateSpace::from_grid(&grid).unwrap();
    assert_eq!(space.n_states(), 8);
    assert_eq!(space.state_of_cell(1, 1).unwrap(), None);
    let corner = space.state_of_cell(0, 0).unwrap().unwrap();
    assert_eq!(space.neighbours(corner).len(), 2);
    assert_eq!(space.position(corner), Vec2::new(5.0, 5.0));
    // Stay 0.2, one hop 0.8 split over the two neighbours.
    let a = space
        .transitions(&SpeedDistribution::new(vec![0.2, 0.8]).unwrap())
        .unwrap();
    assert_relative_eq!(a.get(corner, corner), 0.2);
    let cell = |col, row| space.state_of_cell(col, row).unwrap().unwrap();
    assert_relative_eq!(a.get(corner, cell(1, 0)), 0.4);
    assert_eq!(a.get(corner, cell(2, 2)), 0.0);
    let road = StateSpace::from_road_graph(
        vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(2.0, 0.0),
        ],
        &[(0, 1), (1, 2)],
    )
    .unwrap();
    // A dead end cannot move two hops: that speed's share goes to the possible ones.
    let a = road
        .transitions(&SpeedDistribution::new(vec![0.5, 0.25, 0.25]).unwrap())
        .unwrap();
    assert_relative_eq!(a.get(1, 1), 0.5 / 0.75);
    assert_relative_eq!(a.get(0, 2), 0.25);
    let b = road
        .sensor_emissions(&SensorModel {
            sensors: vec![Vec2::new(0.0, 0.0)],
            base_sigma: 0.5,
            sigma_per_distance: 0.5,
        })
        .unwrap();
    for i in 0..3 {
        assert!(
            (0..3).all(|m| b[i * 3 + m] <= b[i * 3 + i]),
            "diagonal dominates row {i}"
        );
    }
    // Accuracy falls with distance from the sensor.
    assert!(b[0] > b[2 * 3 + 2]);
    assert!(StateSpace::from_road_graph(vec![Vec2::new(0.0, 0.0)], &[(0, 1)]).is_err());
    assert_eq!(
        StateSpace::from_grid(&CellGrid {
            n_cols: 2,
            n_rows: 2,
            cell_size: 1.0,
            blocked: vec![(5, 0)]
        })
        .unwrap_err(),
        Error::CellOutsideGrid {
            col: 5,
            row: 0,
            n_cols: 2,
            n_rows: 2
        }
    );
    assert!(SpeedDistribution::new(vec![0.5, 0.6]).is_err());
}

#[test]
fn cells_outside_the_grid_are_typed_errors() {
    // A 3-wide, 2-high grid: column 3 of row 0 would alias cell (0, 1) in row-major order.
    let space = StateSpace::from_grid(&CellGrid {
        n_cols: 3,
        n_rows: 2,
        cell_size: 1.0,
        blocked: vec![],
    })
    .unwrap();
    assert_eq!(space.state_of_cell(2, 1).unwrap(), Some(5));
    let outside = |col, row| Error::CellOutsideGrid {
        col,
        row,
        n_cols: 3,
        n_rows: 2,
    };
    assert_eq!(space.state_of_cell(3, 0).unwrap_err(), outside(3, 0));
    assert_eq!(space.state_of_cell(0, 2).unwrap_err(), outside(0, 2));
    assert_eq!(
        space.state_of_cell(usize::MAX, usize::MAX).unwrap_err(),
        outside(usize::MAX, usize::MAX)
    );
    let road = StateSpace::from_road_graph(vec![Vec2::new(0.0, 0.0)], &[]).unwrap();
    assert_eq!(road.state_of_cell(0, 0).unwrap_err(), Error::NotAGrid);
}

#[test]
fn configs_are_checked_once_and_reject_unknown_fields() {
    let checked = BaumWelchConfig::default().check().unwrap();
    assert_eq!(checked.config(), &BaumWelchConfig::default());
    for (config, name) in [
        (
            BaumWelchConfig {
                tolerance: f64::NAN,
                ..BaumWelchConfig::default()
            },
            "tolerance",
        ),
        (
            BaumWelchConfig {
                relative_tolerance: -1e-6,
                ..BaumWelchConfig::default()
            },
            "relative_tolerance",
        ),
        (
            BaumWelchConfig {
                pseudo_counts: PseudoCounts {
                    transitions: -0.5,
                    ..PseudoCounts::default()
                },
                ..BaumWelchConfig::default()
            },
            "pseudo_counts.transitions",
        ),
    ] {
        assert!(
            matches!(
                config.check(),
                Err(Error::Model(tracker_model::Error::InvalidParameter { name: n, .. })) if n == name
            ),
            "{name}"
        );
    }
    // Partial configs take the defaults; misspelt fields are refused.
    let partial: BaumWelchConfig =
        serde_json::from_str(r#"{"max_iterations": 3, "freeze": {"initial": true}}"#).unwrap();
    assert_eq!(partial.max_iterations, 3);
    assert!(partial.freeze.initial && !partial.freeze.emissions);
    assert_eq!(partial.tolerance, BaumWelchConfig::default().tolerance);
    for bad in [
        r#"{"max_iteration": 3}"#,
        r#"{"freeze": {"emission": true}}"#,
        r#"{"pseudo_counts": {"transition": 1.0}}"#,
    ] {
        assert!(
            serde_json::from_str::<BaumWelchConfig>(bad).is_err(),
            "{bad}"
        );
    }
    assert!(
        serde_json::from_str::<CellGrid>(
            r#"{"n_cols": 2, "n_rows": 2, "cell_size": 1.0, "blocked": [], "wrap": true}"#
        )
        .is_err()
    );
    assert!(
        serde_json::from_str::<SensorModel>(
            r#"{"sensors": [], "base_sigma": 1.0, "sigma_per_distance": 0.0, "gain": 2.0}"#
        )
        .is_err()
    );
    let sensors = |base_sigma, sigma_per_distance| SensorModel {
        sensors: vec![Vec2::new(0.0, 0.0)],
        base_sigma,
        sigma_per_distance,
    };
    assert!(sensors(1.0, 0.0).check().is_ok());
    assert!(sensors(0.0, 0.0).check().is_err());
    assert!(sensors(1.0, -0.1).check().is_err());
    // A speed distribution is re-checked when read.
    let speed = SpeedDistribution::new(vec![0.25, 0.75]).unwrap();
    let json = serde_json::to_string(&speed).unwrap();
    assert_eq!(
        serde_json::from_str::<SpeedDistribution>(&json).unwrap(),
        speed
    );
    assert!(serde_json::from_str::<SpeedDistribution>(r#"{"probabilities": [0.5, 0.6]}"#).is_err());
}

#[test]
fn state_spaces_round_trip_through_serde_and_reject_corrupt_input() {
    let grid = StateSpace::from_grid(&CellGrid {
        n_cols: 3,
        n_rows: 2,
        cell_size: 1.0,
        blocked: vec![(1, 0)],
    })
    .unwrap();
    let road =
        StateSpace::from_road_graph(vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)], &[(0, 1)])
            .unwrap();
    for space in [grid, road] {
        let json = serde_json::to_string(&space).unwrap();
        assert_eq!(serde_json::from_str::<StateSpace>(&json).unwrap(), space);
    }
    for bad in [
        // A neighbour outside the states.
        r#"{"positions": [[0.0, 0.0]], "neighbours": [[1]], "cells": null}"#,
        // One neighbour list for two states.
        r#"{"positions": [[0.0, 0.0], [1.0, 0.0]], "neighbours": [[1]], "cells": null}"#,
        // A cell pointing at a missing state.
        r#"{"positions": [[0.0, 0.0]], "neighbours": [[]], "cells": {"n_cols": 1, "n_rows": 1, "states": [3]}}"#,
        // Fewer cells than the grid has.
        r#"{"positions": [[0.0, 0.0]], "neighbours": [[]], "cells": {"n_cols": 2, "n_rows": 1, "states": [0]}}"#,
        // No states at all.
        r#"{"positions": [], "neighbours": [], "cells": null}"#,
    ] {
        assert!(serde_json::from_str::<StateSpace>(bad).is_err(), "{bad}");
    }
}

#[test]
fn state_paths_become_tracks() {
    // Free cells of a 2×2 grid with (1, 0) blocked: state 0 = (0, 0) at (5, 5),
    // state 1 = (0, 1) at (5, 15), state 2 = (1, 1) at (15, 15).
    let space = StateSpace::from_grid(&CellGrid {
        n_cols: 2,
        n_rows: 2,
        cell_size: 10.0,
        blocked: vec![(1, 0)],
    })
    .unwrap();
    let track = space.path_to_track(&[0, 1, 2, 2], 7, TrackId(3)).unwrap();
    assert_eq!(track.id(), TrackId(3));
    assert_eq!(
        track.points(),
        &[
            TrackPoint::at(7, Vec2::new(5.0, 5.0)),
            TrackPoint::at(8, Vec2::new(5.0, 15.0)),
            TrackPoint::at(9, Vec2::new(15.0, 15.0)),
            TrackPoint::at(10, Vec2::new(15.0, 15.0)),
        ]
    );
    assert!(space.path_to_track(&[], 0, TrackId(0)).unwrap().is_empty());
    let err = space.path_to_track(&[0, 3], 0, TrackId(0)).unwrap_err();
    assert!(
        matches!(&err, Error::Model(tracker_model::Error::InvalidParameter { name: "state path", reason }) if reason.contains("step 1 is state 3")),
        "{err}"
    );
    assert!(space.path_to_track(&[0, 0], u32::MAX, TrackId(0)).is_err());
}

#[test]
fn sizes_that_overflow_are_typed_errors() {
    // N × N and N × M entry counts past usize::MAX: an error, not a wrapped product (which
    // could even match the length given) or a panic.
    let n = 1usize << (usize::BITS / 2);
    assert!(matches!(
        Transitions::dense(n, vec![]),
        Err(Error::SizeOverflow { rows, cols, .. }) if rows == n && cols == n
    ));
    assert!(matches!(
        Transitions::from_row_major(usize::MAX, vec![1.0], StorageChoice::Auto),
        Err(Error::SizeOverflow { .. })
    ));
    let a = Transitions::dense(2, vec![0.5, 0.5, 0.5, 0.5]).unwrap();
    assert!(matches!(
        Hmm::new(vec![0.5, 0.5], a, vec![1.0], usize::MAX),
        Err(Error::SizeOverflow {
            rows: 2,
            cols: usize::MAX,
            ..
        })
    ));
}
