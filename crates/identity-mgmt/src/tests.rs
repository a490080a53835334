//! Tests. Every expected value comes from an independent route: a closed form, a hand
//! calculation, brute force over permutations or a grid, or the other scalability route.

use proptest::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::TrackId;

use crate::*;

const T: f64 = 1.0 / 3.0;

fn ids(n: u64) -> Vec<IdentityId> {
    (0..n).map(IdentityId).collect()
}

fn tracks(n: u64) -> Vec<TrackId> {
    (0..n).map(TrackId).collect()
}

fn tight() -> ScalingConfig {
    ScalingConfig {
        sinkhorn: SinkhornConfig {
            tolerance: 1e-14,
            max_iterations: 100_000,
        },
        ..ScalingConfig::default()
    }
}

fn assert_close(got: &[f64], want: &[f64], tol: f64) {
    assert_eq!(got.len(), want.len());
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= tol,
            "entry {k}: got {g}, want {w} (tol {tol})"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Scaling and scalability

/// The CDC-2004 example: "object 3 is definitely Z" replaces column 3 of the uniform 3 × 3
/// matrix; the result by hand: rows 1-2 share columns 1-2 equally, identity 3 is on track 3.
#[test]
fn three_by_three_example_scales_and_is_almost_scalable() {
    let input = vec![T, T, 0.0, T, T, 0.0, T, T, 1.0];
    let want = [0.5, 0.5, 0.0, 0.5, 0.5, 0.0, 0.0, 0.0, 1.0];
    let ones = [1.0; 3];
    for method in [ScalabilityMethod::Auto, ScalabilityMethod::MaxFlow] {
        let config = ScalingConfig { method, ..tight() };
        let mut a = input.clone();
        let report = scale_to_marginals(&mut a, 3, 3, &ones, &ones, &config).unwrap();
        assert_eq!(
            report.scalability,
            Scalability::Almost {
                forced_zero: vec![(2, 0), (2, 1)]
            }
        );
        assert!(report.sinkhorn.converged);
        assert_close(&a, &want, 1e-12);
    }
    // Plain Sinkhorn on the raw input heads to the same limit, but only like 1/k.
    let config = ScalingConfig {
        almost_scalable: AlmostScalableRule::IterateRaw,
        sinkhorn: SinkhornConfig {
            tolerance: 1e-9,
            max_iterations: 20_000,
        },
        ..ScalingConfig::default()
    };
    let mut a = input.clone();
    let report = scale_to_marginals(&mut a, 3, 3, &ones, &ones, &config).unwrap();
    assert!(!report.sinkhorn.converged);
    assert_close(&a, &want, 1e-3);
    // The same through the belief matrix: uniform beliefs, then local information on track 3.
    let mut b = BeliefMatrix::from_row_major(ids(3), tracks(3), vec![T; 9]).unwrap();
    let report = b
        .incorporate_local_information(TrackId(2), &[0.0, 0.0, 1.0], &tight())
        .unwrap();
    assert_close(b.as_row_major(), &want, 1e-12);
    assert_eq!(
        report.forced_zero,
        vec![(IdentityId(2), TrackId(0)), (IdentityId(2), TrackId(1))]
    );
    assert!((report.entropy_before_nats - 3.0 * 3f64.ln()).abs() < 1e-12);
    assert!((report.entropy_after_nats - 2.0 * 2f64.ln()).abs() < 1e-9);
}

/// For a positive 2 × 2 matrix the doubly stochastic limit [[a, 1−a], [1−a, a]] keeps the
/// cross ratio: a² / (1−a)² = p11·p22 / (p12·p21).
#[test]
fn two_by_two_limit_matches_closed_form() {
    let cases = [
        [0.2, 0.5, 0.1, 0.9],
        [1.0, 1.0, 1.0, 1.0],
        [3.0, 0.01, 0.7, 2.0],
        [1e-3, 5.0, 2.0, 1e-2],
    ];
    for p in cases {
        let mut a = p.to_vec();
        let report = sinkhorn(&mut a, 2, 2, &[1.0; 2], &[1.0; 2], &tight().sinkhorn).unwrap();
        assert!(report.converged);
        let ratio = a[0] / (1.0 - a[0]);
        let want = (p[0] * p[3] / (p[1] * p[2])).sqrt();
        assert!(
            (ratio - want).abs() <= 1e-12 * want.max(1.0),
            "{p:?}: {ratio} vs {want}"
        );
    }
}

/// Brute force over all n! permutations: a positive entry lies on a positive diagonal iff
/// some positive permutation uses it; no positive permutation means not scalable.
fn brute_force_scalability(a: &[f64], n: usize) -> Scalability {
    fn permutations(n: usize) -> Vec<Vec<usize>> {
        if n == 0 {
            return vec![vec![]];
        }
        let mut out = Vec::new();
        for p in permutations(n - 1) {
            for k in 0..n {
                let mut q = p.clone();
                q.insert(k, n - 1);
                out.push(q);
            }
        }
        out
    }
    let mut on_diagonal = vec![false; n * n];
    let mut any = false;
    for p in permutations(n) {
        if p.iter().enumerate().all(|(i, &j)| a[i * n + j] > 0.0) {
            any = true;
            for (i, &j) in p.iter().enumerate() {
                on_diagonal[i * n + j] = true;
            }
        }
    }
    if !any {
        return Scalability::NotScalable {
            carried: f64::NAN,
            required: n as f64,
        };
    }
    let forced_zero: Vec<_> = (0..n * n)
        .filter(|&k| a[k] > 0.0 && !on_diagonal[k])
        .map(|k| (k / n, k % n))
        .collect();
    if forced_zero.is_empty() {
        Scalability::Exact
    } else {
        Scalability::Almost { forced_zero }
    }
}

fn same_class(got: &Scalability, want: &Scalability) -> bool {
    match (got, want) {
        (Scalability::NotScalable { .. }, Scalability::NotScalable { .. }) => true,
        _ => got == want,
    }
}

#[test]
fn no_perfect_matching_is_not_scalable() {
    // Rows 0 and 1 both have their only positive entry in column 0.
    let a = vec![1.0, 0.0, 0.0, 0.5, 0.0, 0.0, 1.0, 1.0, 1.0];
    let ones = [1.0; 3];
    for method in [ScalabilityMethod::Auto, ScalabilityMethod::MaxFlow] {
        let config = ScalingConfig {
            method,
            ..ScalingConfig::default()
        };
        let s = scalability(&a, 3, 3, &ones, &ones, &config).unwrap();
        let Scalability::NotScalable { carried, required } = s else {
            panic!("{s:?}")
        };
        assert!((carried - 2.0).abs() < 1e-9 && (required - 3.0).abs() < 1e-12);
        let mut m = a.clone();
        assert!(matches!(
            scale_to_marginals(&mut m, 3, 3, &ones, &ones, &config),
            Err(Error::NotScalable { .. })
        ));
        assert_eq!(m, a, "a failed scaling leaves the input unchanged");
    }
    assert!(matches!(
        brute_force_scalability(&a, 3),
        Scalability::NotScalable { .. }
    ));
    // Plain Sinkhorn rejects an empty line before touching the matrix: column 1's only
    // positive entry is in row 2, whose target is 0.
    let mut m = vec![1.0, 0.0, 1.0, 0.0, 0.0, 1.0];
    let err = sinkhorn(
        &mut m,
        3,
        2,
        &[1.0, 1.0, 0.0],
        &[1.0, 1.0],
        &SinkhornConfig::default(),
    );
    assert_eq!(
        err,
        Err(Error::NotScalable {
            carried: 0.0,
            required: 1.0
        })
    );
    assert_eq!(m, vec![1.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
}

#[test]
fn impossible_local_information_is_an_error_or_softened() {
    // Identity 0 is surely on track 0; information that track 1 is identity 0 contradicts it
    // once the column is replaced (rows 0 and 1 then both need column 1... see below).
    let mut b = BeliefMatrix::from_rows(
        ids(3),
        tracks(3),
        &[
            vec![1.0, 0.0, 0.0],
            vec![0.0, 0.5, 0.5],
            vec![0.0, 0.5, 0.5],
        ],
    )
    .unwrap();
    let before = b.clone();
    // Column 0 becomes e_1: row 0 then has no positive entry.
    let info = [0.0, 1.0, 0.0];
    let err = b.incorporate_local_information(TrackId(0), &info, &ScalingConfig::default());
    assert!(matches!(err, Err(Error::NotScalable { .. })), "{err:?}");
    assert_eq!(b, before);
    let soften = ScalingConfig {
        not_scalable: NotScalableRule::Soften { old_weight: 0.1 },
        ..tight()
    };
    let report = b
        .incorporate_local_information(TrackId(0), &info, &soften)
        .unwrap();
    assert!(report.softened && report.scalability.is_scalable());
    // The softened column 0.9·e_1 + 0.1·e_0 can only keep identity 0 on track 0 (row 0 has
    // no other entry), so the old belief comes back exactly.
    assert_close(b.as_row_major(), before.as_row_major(), 1e-12);
}

proptest! {
    /// The square route (assignment + alternating-graph components), the flow route and brute
    /// force over permutations agree on random zero patterns.
    #[test]
    fn scalability_routes_agree_with_brute_force(n in 1usize..6, bits in proptest::collection::vec(0u8..10, 36)) {
        let a: Vec<f64> = bits.iter().take(n * n).map(|&b| if b < 6 { 1.0 + f64::from(b) } else { 0.0 }).collect();
        let ones = vec![1.0; n];
        let want = brute_force_scalability(&a, n);
        let square = square_scalability(&a, n).unwrap();
        let flow = flow_scalability(&a, n, n, &ones, &ones).unwrap();
        prop_assert!(same_class(&square, &want), "square {:?} vs {:?}", square, want);
        prop_assert!(same_class(&flow, &want), "flow {:?} vs {:?}", flow, want);
    }

    /// General targets, against the definition: entry (i, j) can stay positive iff the
    /// targets minus δ at row i and column j can still be met on the pattern (δ = 1/2 is exact
    /// here: the targets are integers, so the feasible set has integer vertices and the largest
    /// possible x_ij is an integer). Targets come from a random integer matrix on part of the
    /// pattern, so the problem is feasible.
    #[test]
    fn flow_route_matches_the_definition(seed in 0u64..1_000_000, n_rows in 1usize..5, n_cols in 1usize..5) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut a = vec![0.0; n_rows * n_cols];
        let mut x = vec![0.0; n_rows * n_cols];
        for k in 0..n_rows * n_cols {
            if rng.random_bool(0.6) {
                a[k] = rng.random_range(0.1..1.0);
                if rng.random_bool(0.5) {
                    x[k] = f64::from(rng.random_range(1u8..4));
                }
            }
        }
        let rows: Vec<f64> = (0..n_rows).map(|i| x[i * n_cols..(i + 1) * n_cols].iter().sum()).collect();
        let cols: Vec<f64> = (0..n_cols).map(|j| (0..n_rows).map(|i| x[i * n_cols + j]).sum()).collect();
        prop_assume!(rows.iter().sum::<f64>() > 0.0);
        let s = flow_scalability(&a, n_rows, n_cols, &rows, &cols).unwrap();
        prop_assert!(s.is_scalable());
        let forced = match &s { Scalability::Almost { forced_zero } => forced_zero.clone(), _ => vec![] };
        for i in 0..n_rows {
            for j in 0..n_cols {
                if a[i * n_cols + j] == 0.0 {
                    continue;
                }
                let (mut r, mut c) = (rows.clone(), cols.clone());
                r[i] -= 0.5;
                c[j] -= 0.5;
                let possible = r[i] >= 0.0 && c[j] >= 0.0
                    && flow_scalability(&a, n_rows, n_cols, &r, &c).unwrap().is_scalable();
                prop_assert_eq!(possible, !forced.contains(&(i, j)), "entry ({}, {}) of {:?}", i, j, a);
            }
        }
    }

    /// Mixing by a doubly stochastic M (a random convex combination of permutation matrices,
    /// Birkhoff) never lowers H(B), also on a rectangular matrix and a subset of tracks.
    #[test]
    fn doubly_stochastic_mixing_never_lowers_entropy(seed in 0u64..1_000_000, n_ids in 1usize..6, n_tracks in 1usize..6, n_perm in 1usize..4) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut data = vec![0.0; n_ids * n_tracks];
        for j in 0..n_tracks {
            // Some columns certain, some spread.
            let col: Vec<f64> = (0..n_ids).map(|_| if rng.random_bool(0.3) { 0.0 } else { rng.random_range(0.0..1.0) }).collect();
            let s: f64 = col.iter().sum();
            for i in 0..n_ids {
                data[i * n_tracks + j] = if s > 0.0 { col[i] / s } else if i == 0 { 1.0 } else { 0.0 };
            }
        }
        let mut b = BeliefMatrix::from_row_major(ids(n_ids as u64), tracks(n_tracks as u64), data).unwrap();
        let subset: Vec<TrackId> = tracks(n_tracks as u64).into_iter().filter(|_| rng.random_bool(0.7)).collect();
        let k = subset.len();
        let mut m = vec![0.0; k * k];
        let weights: Vec<f64> = (0..n_perm).map(|_| rng.random_range(0.0..1.0) + 1e-3).collect();
        let total: f64 = weights.iter().sum();
        for w in weights {
            let mut perm: Vec<usize> = (0..k).collect();
            for i in (1..k).rev() {
                perm.swap(i, rng.random_range(0..=i));
            }
            for (i, &j) in perm.iter().enumerate() {
                m[i * k + j] += w / total;
            }
        }
        let m = Continuation::new(k, m).unwrap();
        let before = b.entropy(EntropyUnit::Nats);
        b.mix(&subset, &m).unwrap();
        prop_assert!(b.entropy(EntropyUnit::Nats) >= before - 1e-12);
    }
}

/// The Sinkhorn limit is the I-projection: among 2 × 3 matrices with the given marginals it
/// minimises KL(X‖A). The feasible set has two free entries (x11, x12); a brute-force grid,
/// refined twice around its best point, must not beat Sinkhorn and must land next to it.
#[test]
fn sinkhorn_limit_minimises_kl_on_a_grid() {
    let a = [0.3, 1.2, 0.5, 0.8, 0.1, 0.9];
    let rows = [1.3, 1.7];
    let cols = [0.9, 1.1, 1.0];
    let mut x = a.to_vec();
    let report = sinkhorn(&mut x, 2, 3, &rows, &cols, &tight().sinkhorn).unwrap();
    assert!(report.converged);
    let kl = |m: &[f64]| -> f64 {
        m.iter()
            .zip(&a)
            .map(|(&v, &w)| if v > 0.0 { v * (v / w).ln() } else { 0.0 })
            .sum()
    };
    let from_free = |x11: f64, x12: f64| -> Option<[f64; 6]> {
        let m = [
            x11,
            x12,
            rows[0] - x11 - x12,
            cols[0] - x11,
            cols[1] - x12,
            cols[2] - (rows[0] - x11 - x12),
        ];
        m.iter().all(|&v| v >= 0.0).then_some(m)
    };
    let (mut c11, mut c12, mut half) = (cols[0] / 2.0, cols[1] / 2.0, cols[0].max(cols[1]) / 2.0);
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let steps = 400;
        let (mut b11, mut b12) = (c11, c12);
        for s in 0..=steps {
            for t in 0..=steps {
                let x11 = c11 - half + 2.0 * half * s as f64 / steps as f64;
                let x12 = c12 - half + 2.0 * half * t as f64 / steps as f64;
                if let Some(m) = from_free(x11, x12) {
                    let v = kl(&m);
                    if v < best {
                        (best, b11, b12) = (v, x11, x12);
                    }
                }
            }
        }
        (c11, c12, half) = (b11, b12, 4.0 * half / steps as f64);
    }
    assert!(
        kl(&x) <= best + 1e-12,
        "Sinkhorn KL {} above grid {}",
        kl(&x),
        best
    );
    assert!(
        (c11 - x[0]).abs() < 1e-4 && (c12 - x[1]).abs() < 1e-4,
        "grid ({c11}, {c12}) vs {:?}",
        &x[..2]
    );
}

/// General targets through the flow route: a sensor's 5 × 2 matrix whose rows hold unequal
/// identity mass; local information keeps every row's mass and every column's unit sum.
#[test]
fn rectangular_local_information_keeps_the_marginals() {
    let data = vec![0.3, 0.1, 0.3, 0.1, 0.2, 0.2, 0.1, 0.3, 0.1, 0.3];
    let mut b = BeliefMatrix::from_row_major(ids(5), tracks(2), data).unwrap();
    let rows = b.row_sums();
    let report = b
        .incorporate_local_information(TrackId(1), &[0.0, 0.9, 0.05, 0.05, 0.0], &tight())
        .unwrap();
    assert!(report.sinkhorn.converged);
    assert_close(&b.row_sums(), &rows, 1e-12);
    for t in b.tracks().to_vec() {
        assert!((b.column(t).unwrap().iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
    assert!(report.entropy_after_nats < report.entropy_before_nats);
    // Rows 0 and 4 hold mass 0.4 and 0.4 but track 1 now gives them nothing, so track 0 must
    // carry 0.4 of each: column 0 is forced, by hand, to [.4, x, y, z, .4].
    assert!((b.probability(IdentityId(0), TrackId(0)).unwrap() - 0.4).abs() < 1e-12);
    assert!((b.probability(IdentityId(4), TrackId(0)).unwrap() - 0.4).abs() < 1e-12);
}

#[test]
fn flow_route_finds_forced_zeros_with_general_targets() {
    // Row 0 must put its whole 0.5 on column 0 (its only entry), column 0 needs only 0.5, so
    // row 1's entry in column 0 is forced to 0.
    let a = [1.0, 0.0, 1.0, 1.0];
    let s = flow_scalability(&a, 2, 2, &[0.5, 1.0], &[0.5, 1.0]).unwrap();
    assert_eq!(
        s,
        Scalability::Almost {
            forced_zero: vec![(1, 0)]
        }
    );
    let s = flow_scalability(&a, 2, 2, &[0.5, 1.0], &[0.6, 0.9]).unwrap();
    assert_eq!(s, Scalability::Exact);
    let s = flow_scalability(&a, 2, 2, &[0.6, 0.9], &[0.5, 1.0]).unwrap();
    assert!(matches!(s, Scalability::NotScalable { .. }));
    assert!(matches!(
        flow_scalability(&a, 2, 2, &[0.5, 1.0], &[0.5, 2.0]),
        Err(Error::MarginalMismatch { .. })
    ));
}

// ---------------------------------------------------------------------------------------------
// Mixing

#[test]
fn continuation_from_samples() {
    // 4 samples over 3 pieces: pieces 0 and 1 swap in one sample; piece 2 is unjoined in one.
    let samples = vec![
        vec![(0, 0), (1, 1), (2, 2)],
        vec![(0, 1), (1, 0), (2, 2)],
        vec![(0, 0), (1, 1), (2, 2)],
        vec![(0, 0), (1, 1)],
    ];
    let (m, _) = Continuation::from_samples(3, &samples, &FromSamplesConfig::default()).unwrap();
    // By hand: the fractions [[3/4,1/4,0],[1/4,3/4,0],[1/12,1/12,3/4+1/12]] are not yet doubly
    // stochastic; Sinkhorn keeps the 0/1 symmetry, so m00 = m11, m01 = m10, m20 = m21, m02 = m12.
    let d = m.as_row_major();
    assert!(
        (d[0] - d[4]).abs() < 1e-12 && (d[1] - d[3]).abs() < 1e-12 && (d[6] - d[7]).abs() < 1e-12
    );
    assert!(d[2] == 0.0 && d[5] == 0.0);
    assert!(Continuation::new(3, d.to_vec()).is_ok());
    let (stay, _) = Continuation::from_samples(
        3,
        &samples,
        &FromSamplesConfig {
            unjoined: UnjoinedRule::Stay,
            ..Default::default()
        },
    )
    .unwrap();
    assert_close(
        stay.as_row_major(),
        &[0.75, 0.25, 0.0, 0.25, 0.75, 0.0, 0.0, 0.0, 1.0],
        1e-12,
    );
    let bad = vec![vec![(0, 0), (0, 1)]];
    assert!(matches!(
        Continuation::from_samples(3, &bad, &FromSamplesConfig::default()),
        Err(Error::BadSample { sample: 0, .. })
    ));
    assert!(matches!(
        Continuation::new(2, vec![0.9, 0.2, 0.1, 0.8]),
        Err(Error::NotDoublyStochastic { .. })
    ));
}

#[test]
fn belief_matrix_bookkeeping() {
    let mut b = BeliefMatrix::new();
    b.add_new_target(IdentityId(7), TrackId(1)).unwrap();
    b.add_new_target(IdentityId(8), TrackId(2)).unwrap();
    assert_eq!(b.as_row_major(), &[1.0, 0.0, 0.0, 1.0]);
    b.add_identity(IdentityId(9)).unwrap();
    b.add_track(TrackId(3), &[0.0, 0.5, 0.5]).unwrap();
    assert_eq!(b.row_sums(), vec![1.0, 1.5, 0.5]);
    assert_eq!(b.remove_track(TrackId(2)).unwrap(), vec![0.0, 1.0, 0.0]);
    assert_eq!(b.tracks(), &[TrackId(1), TrackId(3)]);
    assert_eq!(
        b.column_over(TrackId(3), &[IdentityId(9), IdentityId(8), IdentityId(5)])
            .unwrap(),
        vec![0.5, 0.5, 0.0]
    );
    assert_eq!(
        b.column_over(TrackId(3), &[IdentityId(9)]),
        Err(Error::UnknownIdentity {
            identity: IdentityId(8)
        })
    );
    assert_eq!(
        b.add_identity(IdentityId(7)),
        Err(Error::DuplicateIdentity {
            identity: IdentityId(7)
        })
    );
    assert_eq!(
        b.add_track(TrackId(1), &[1.0, 0.0, 0.0]),
        Err(Error::DuplicateTrack { track: TrackId(1) })
    );
    assert!(matches!(
        b.add_track(TrackId(4), &[0.5, 0.0, 0.0]),
        Err(Error::NotProbability { .. })
    ));
    assert_eq!(
        b.remove_track(TrackId(2)),
        Err(Error::UnknownTrack { track: TrackId(2) })
    );
    let top = b.argmax();
    assert_eq!(top[0].identity, Some(IdentityId(7)));
    assert_eq!(
        top[1].identity,
        Some(IdentityId(8)),
        "ties go to the first identity"
    );
    assert!((top[1].probability - 0.5).abs() < 1e-15);
    // Entropy: track 3 is a fair coin, 1 bit = ln 2 nats.
    assert!((b.column_entropy(TrackId(3), EntropyUnit::Bits).unwrap() - 1.0).abs() < 1e-15);
    assert!((b.entropy(EntropyUnit::Nats) - 2f64.ln()).abs() < 1e-15);
    assert!((entropy(&[0.2; 5], EntropyUnit::Nats) - 5f64.ln()).abs() < 1e-15);
}

#[test]
fn serde_checks_and_rejects_unknown_fields() {
    let b = BeliefMatrix::known(&[(IdentityId(1), TrackId(1))]).unwrap();
    let json = serde_json::to_string(&b).unwrap();
    assert_eq!(serde_json::from_str::<BeliefMatrix>(&json).unwrap(), b);
    let bad = r#"{"identities":[1],"tracks":[1],"data":[0.5]}"#;
    assert!(serde_json::from_str::<BeliefMatrix>(bad).is_err());
    let config: ScalingConfig = toml::from_str(
        "almost_scalable = 'iterate-raw'\n[sinkhorn]\ntolerance = 1e-6\n[not_scalable.soften]\nold_weight = 0.2\n",
    )
    .unwrap();
    assert_eq!(
        config.not_scalable,
        NotScalableRule::Soften { old_weight: 0.2 }
    );
    assert!(toml::from_str::<ScalingConfig>("tolerence = 1.0").is_err());
    assert_eq!(
        toml::from_str::<FusionConfig>("criterion = 'kl-sum-geometric'")
            .unwrap()
            .criterion,
        FusionCriterion::KlSumGeometric
    );
    assert!(toml::from_str::<FusionConfig>("[criterion.bayesian]\nprior = [0.5, 0.5]\n").is_ok());
    assert!(toml::from_str::<FusionConfig>("[criterion.bayesian]\npriors = [0.5, 0.5]\n").is_err());
    let config = ScalingConfig {
        not_scalable: NotScalableRule::Soften { old_weight: 0.0 },
        ..Default::default()
    };
    assert!(matches!(config.check(), Err(Error::Model(_))));
    let bad_sinkhorn = SinkhornConfig {
        tolerance: -1.0,
        ..Default::default()
    };
    assert!(matches!(
        sinkhorn(&mut [1.0], 1, 1, &[1.0], &[1.0], &bad_sinkhorn),
        Err(Error::Model(_))
    ));
    assert!(matches!(
        sinkhorn(
            &mut [1.0, f64::NAN],
            1,
            2,
            &[1.0],
            &[0.5, 0.5],
            &SinkhornConfig::default()
        ),
        Err(Error::InvalidEntry { row: 0, col: 1, .. })
    ));
}

// ---------------------------------------------------------------------------------------------
// Fusion

fn config(criterion: FusionCriterion) -> FusionConfig {
    FusionConfig {
        criterion,
        ..FusionConfig::default()
    }
}

fn random_simplex(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
    let v: Vec<f64> = (0..n)
        .map(|_| -rng.random_range(1e-12..1.0f64).ln())
        .collect();
    let s: f64 = v.iter().sum();
    v.into_iter().map(|x| x / s).collect()
}

const P: [f64; 4] = [0.6, 0.25, 0.1, 0.05];
const Q: [f64; 4] = [0.15, 0.5, 0.3, 0.05];

#[test]
fn kl_sum_geometric_is_the_normalised_geometric_mean_and_a_minimum() {
    let r = fuse(&P, &Q, &config(FusionCriterion::KlSumGeometric)).unwrap();
    let g: Vec<f64> = P.iter().zip(&Q).map(|(a, b)| (a * b).sqrt()).collect();
    let s: f64 = g.iter().sum();
    assert_close(
        &r.distribution,
        &g.iter().map(|x| x / s).collect::<Vec<_>>(),
        1e-15,
    );
    let objective = |x: &[f64]| kl_divergence(x, &P) + kl_divergence(x, &Q);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for _ in 0..20_000 {
        // Random points, and small perturbations of the optimum.
        let mut x = random_simplex(&mut rng, 4);
        if rng.random_bool(0.5) {
            x = r
                .distribution
                .iter()
                .zip(&x)
                .map(|(a, b)| 0.99 * a + 0.01 * b)
                .collect();
        }
        assert!(objective(&x) >= objective(&r.distribution) - 1e-14);
    }
}

#[test]
fn kl_sum_arithmetic_is_the_mean_and_a_minimum() {
    let r = fuse(&P, &Q, &config(FusionCriterion::KlSumArithmetic)).unwrap();
    assert_close(&r.distribution, &[0.375, 0.375, 0.2, 0.05], 1e-15);
    let objective = |x: &[f64]| kl_divergence(&P, x) + kl_divergence(&Q, x);
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    for _ in 0..20_000 {
        let mut x = random_simplex(&mut rng, 4);
        if rng.random_bool(0.5) {
            x = r
                .distribution
                .iter()
                .zip(&x)
                .map(|(a, b)| 0.99 * a + 0.01 * b)
                .collect();
        }
        assert!(objective(&x) >= objective(&r.distribution) - 1e-14);
    }
}

/// Chernoff: equal divergences to both inputs, and ω* = argmin_ω Σ p^ω q^{1−ω} (the Chernoff
/// coefficient), which a fine grid finds independently.
#[test]
fn chernoff_gives_equal_divergences() {
    let r = fuse(&P, &Q, &config(FusionCriterion::Chernoff)).unwrap();
    let d_p = kl_divergence(&r.distribution, &P);
    let d_q = kl_divergence(&r.distribution, &Q);
    assert!((d_p - d_q).abs() < 1e-10, "{d_p} vs {d_q}");
    let coefficient = |w: f64| {
        P.iter()
            .zip(&Q)
            .map(|(a, b)| a.powf(w) * b.powf(1.0 - w))
            .sum::<f64>()
    };
    let steps = 200_000;
    let grid_best = (0..=steps)
        .map(|k| k as f64 / steps as f64)
        .min_by(|x, y| coefficient(*x).total_cmp(&coefficient(*y)))
        .unwrap();
    let omega = r.omega.unwrap();
    assert!(
        (omega - grid_best).abs() < 1e-4,
        "ω {omega} vs grid {grid_best}"
    );
    // A zero in one input: on the common support D(r‖q) ≥ −ln q(common) = ln 2 while D(r‖p)
    // stays below it, so no interior point equalises them; ω* then goes to the end where the
    // Chernoff coefficient (on the common support) is least, here ω → 0 (r = q restricted).
    let (p, q) = ([0.5, 0.5, 0.0], [0.2, 0.3, 0.5]);
    let r = fuse(&p, &q, &config(FusionCriterion::Chernoff)).unwrap();
    assert!(r.omega.unwrap() < 1e-9);
    assert_close(&r.distribution, &[0.4, 0.6, 0.0], 1e-9);
}

#[test]
fn shannon_picks_the_least_entropy_member() {
    let r = fuse(&P, &Q, &config(FusionCriterion::Shannon)).unwrap();
    let h = entropy(&r.distribution, EntropyUnit::Nats);
    let steps = 100_000;
    for k in 0..=steps {
        let m = geometric_mixture(&P, &Q, k as f64 / steps as f64).unwrap();
        assert!(h <= entropy(&m, EntropyUnit::Nats) + 1e-12);
    }
    assert_close(
        &r.distribution,
        &geometric_mixture(&P, &Q, r.omega.unwrap()).unwrap(),
        1e-15,
    );
}

/// Bayesian: two sensors' posteriors from independent likelihoods L1, L2 and a shared prior
/// π combine to the posterior from both, π·L1·L2 normalised.
#[test]
fn bayesian_fusion_is_the_joint_posterior() {
    let prior = [0.5, 0.3, 0.15, 0.05];
    let l1 = [0.2, 0.9, 0.4, 0.1];
    let l2 = [0.7, 0.1, 0.6, 0.3];
    let post = |l: &[f64]| {
        let v: Vec<f64> = prior.iter().zip(l).map(|(a, b)| a * b).collect();
        let s: f64 = v.iter().sum();
        v.into_iter().map(|x| x / s).collect::<Vec<f64>>()
    };
    let joint: Vec<f64> = {
        let v: Vec<f64> = (0..4).map(|k| prior[k] * l1[k] * l2[k]).collect();
        let s: f64 = v.iter().sum();
        v.into_iter().map(|x| x / s).collect()
    };
    let r = fuse(
        &post(&l1),
        &post(&l2),
        &config(FusionCriterion::Bayesian {
            prior: Some(prior.to_vec()),
        }),
    )
    .unwrap();
    assert_close(&r.distribution, &joint, 1e-15);
    // Uniform prior: p·q normalised.
    let r = fuse(&P, &Q, &config(FusionCriterion::Bayesian { prior: None })).unwrap();
    let pq: Vec<f64> = P.iter().zip(&Q).map(|(a, b)| a * b).collect();
    let s: f64 = pq.iter().sum();
    assert_close(
        &r.distribution,
        &pq.iter().map(|x| x / s).collect::<Vec<_>>(),
        1e-15,
    );
}

#[test]
fn fusion_errors() {
    assert_eq!(
        fuse(&[1.0, 0.0], &[0.0, 1.0], &FusionConfig::default()),
        Err(Error::DisjointSupports)
    );
    assert!(matches!(
        fuse(&[1.0, 0.0], &[0.5], &FusionConfig::default()),
        Err(Error::Shape { .. })
    ));
    assert!(matches!(
        fuse(&[0.7, 0.0], &[0.5, 0.5], &FusionConfig::default()),
        Err(Error::NotProbability { .. })
    ));
    let zero_prior = config(FusionCriterion::Bayesian {
        prior: Some(vec![0.0, 1.0]),
    });
    assert!(matches!(
        fuse(&[0.5, 0.5], &[0.5, 0.5], &zero_prior),
        Err(Error::InvalidEntry { row: 0, .. })
    ));
}

/// Fusing into a belief matrix writes the fused column back and rescales: two sensors that
/// both lean towards identity 0 on track 0 end up more certain than either.
#[test]
fn fusion_writes_back_and_rescales() {
    let own =
        BeliefMatrix::from_rows(ids(2), tracks(2), &[vec![0.7, 0.3], vec![0.3, 0.7]]).unwrap();
    for criterion in [
        FusionCriterion::Shannon,
        FusionCriterion::Chernoff,
        FusionCriterion::KlSumGeometric,
        FusionCriterion::Bayesian { prior: None },
    ] {
        let mut b = own.clone();
        let report = b
            .fuse_track(
                TrackId(0),
                &[0.8, 0.2],
                &config(criterion.clone()),
                &tight(),
            )
            .unwrap();
        let p00 = b.probability(IdentityId(0), TrackId(0)).unwrap();
        assert!(p00 > 0.7, "{criterion:?}: {p00}");
        assert_close(&b.row_sums(), &[1.0, 1.0], 1e-12);
        assert!(report.entropy_after_nats < report.entropy_before_nats);
    }
    // The arithmetic mean of 0.7 and 0.8 is 0.75; rescaling [[.75, .3], [.25, .7]] gives
    // [[a, 1−a], [1−a, a]] with a/(1−a) = sqrt(.75·.7 / (.3·.25)) (the 2 × 2 closed form):
    // the written-back column itself moves.
    let mut b = own.clone();
    b.fuse_track(
        TrackId(0),
        &[0.8, 0.2],
        &config(FusionCriterion::KlSumArithmetic),
        &tight(),
    )
    .unwrap();
    let k = (0.75f64 * 0.7 / (0.3 * 0.25)).sqrt();
    let a = k / (1.0 + k);
    assert_close(b.as_row_major(), &[a, 1.0 - a, 1.0 - a, a], 1e-12);
}
