//! Hand-computed cases for every metric, brute-force checks of the identity assignment,
//! property tests of OSPA/GOSPA, and box/point agreement.
#![expect(
    clippy::float_cmp,
    reason = "exact values such as 0 and the cut-off c are exact here"
)]

use approx::assert_relative_eq;
use proptest::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::{
    BoundingBox, Location, Measurement, Origin, Scan, Track, TrackId, TrackPoint, TrackSet, Vec2,
};

use crate::*;

/// A track description: (id, [(frame, x)]). Objects sit on the x axis; boxes are 10×10 so
/// positions 0 and 50 never overlap, and equal positions give IoU 1.
type Desc<'a> = &'a [(u64, &'a [(u32, f64)])];

fn boxes(desc: Desc<'_>) -> TrackSet {
    build(desc, |f, x| {
        TrackPoint::boxed(f, BoundingBox::new(x, 0.0, 10.0, 10.0).unwrap())
    })
}

fn points(desc: Desc<'_>) -> TrackSet {
    // Box centres, so the two representations describe the same scene.
    build(desc, |f, x| TrackPoint::at(f, Vec2::new(x + 5.0, 5.0)))
}

fn build(desc: Desc<'_>, point: impl Fn(u32, f64) -> TrackPoint) -> TrackSet {
    TrackSet::from_tracks(
        desc.iter()
            .map(|(id, pts)| {
                Track::from_points(
                    TrackId(*id),
                    pts.iter().map(|&(f, x)| point(f, x)).collect(),
                )
                .unwrap()
            })
            .collect(),
    )
    .unwrap()
}

fn eval_boxes(gt: Desc<'_>, pred: Desc<'_>) -> EvalReport {
    evaluate(&boxes(gt), &boxes(pred), &EvalConfig::default()).unwrap()
}

/// Expected values worked out by hand for one case.
struct Expect {
    mota: f64,
    motp: f64,
    tp: usize,
    fp: usize,
    fn_: usize,
    idsw: usize,
    frag: usize,
    idf1: f64,
    idp: f64,
    idr: f64,
    hota: f64,
    det_a: f64,
    ass_a: f64,
    loc_a: f64,
    sr: f64,
    faf: f64,
}

fn check(gt: Desc<'_>, pred: Desc<'_>, e: &Expect) {
    let r = eval_boxes(gt, pred);
    let c = &r.clear;
    assert_eq!(
        (c.true_positives, c.false_positives, c.false_negatives),
        (e.tp, e.fp, e.fn_),
        "TP/FP/FN"
    );
    assert_eq!(
        (c.id_switches, c.fragmentations),
        (e.idsw, e.frag),
        "IDSW/Frag"
    );
    for (name, got, want) in [
        ("MOTA", c.mota, e.mota),
        ("MOTP", c.motp, e.motp),
        ("IDF1", r.identity.idf1, e.idf1),
        ("IDP", r.identity.idp, e.idp),
        ("IDR", r.identity.idr, e.idr),
        ("HOTA", r.hota.hota, e.hota),
        ("DetA", r.hota.det_a, e.det_a),
        ("AssA", r.hota.ass_a, e.ass_a),
        ("LocA", r.hota.loc_a, e.loc_a),
        ("SR", r.success.success_rate, e.sr),
        ("FAF", r.success.false_alarms_per_frame, e.faf),
    ] {
        assert!(
            (got - want).abs() < 1e-12,
            "{name}: got {got}, expected {want}"
        );
    }
    // The point representation of the same scene must give the same report.
    let p = evaluate(
        &points(gt),
        &points(pred),
        &EvalConfig {
            matching: MatchConfig::within_distance(5.0),
        },
    )
    .unwrap();
    assert!(p == r, "point and box evaluations differ:\n{p:?}\n{r:?}");
}

#[test]
fn empty_truth() {
    // Three false estimates over frames 1-2: MOTA = (0 − 3)/max(1, 0) = −3 (TrackEval's floor).
    check(
        &[],
        &[(1, &[(1, 0.0), (2, 0.0)]), (2, &[(2, 50.0)])],
        &Expect {
            mota: -3.0,
            motp: 0.0,
            tp: 0,
            fp: 3,
            fn_: 0,
            idsw: 0,
            frag: 0,
            idf1: 0.0,
            idp: 0.0,
            idr: 0.0,
            hota: 0.0,
            det_a: 0.0,
            ass_a: 0.0,
            loc_a: 1.0,
            sr: 0.0,
            faf: 1.5,
        },
    );
}

#[test]
fn empty_estimates() {
    check(
        &[(1, &[(1, 0.0), (2, 0.0), (3, 0.0)])],
        &[],
        &Expect {
            mota: 0.0,
            motp: 0.0,
            tp: 0,
            fp: 0,
            fn_: 3,
            idsw: 0,
            frag: 0,
            idf1: 0.0,
            idp: 0.0,
            idr: 0.0,
            hota: 0.0,
            det_a: 0.0,
            ass_a: 0.0,
            loc_a: 1.0,
            sr: 0.0,
            faf: 0.0,
        },
    );
}

#[test]
fn all_missed() {
    // Estimates exist in the same frames but never overlap the truth: every truth detection is
    // missed and every estimate is false. MOTA = (0 − 2)/2.
    check(
        &[(1, &[(1, 0.0), (2, 0.0)])],
        &[(9, &[(1, 50.0), (2, 50.0)])],
        &Expect {
            mota: -1.0,
            motp: 0.0,
            tp: 0,
            fp: 2,
            fn_: 2,
            idsw: 0,
            frag: 0,
            idf1: 0.0,
            idp: 0.0,
            idr: 0.0,
            hota: 0.0,
            det_a: 0.0,
            ass_a: 0.0,
            loc_a: 1.0,
            sr: 0.0,
            faf: 1.0,
        },
    );
}

#[test]
fn all_false() {
    // Truth in frames 1-2, estimates only in frames 3-4. LocA is 1e-10/1e-10 = 1 at every α
    // (TrackEval's guard), SR 0, FAF = 2 false over 4 frames.
    check(
        &[(1, &[(1, 0.0), (2, 0.0)])],
        &[(9, &[(3, 0.0), (4, 0.0)])],
        &Expect {
            mota: -1.0,
            motp: 0.0,
            tp: 0,
            fp: 2,
            fn_: 2,
            idsw: 0,
            frag: 0,
            idf1: 0.0,
            idp: 0.0,
            idr: 0.0,
            hota: 0.0,
            det_a: 0.0,
            ass_a: 0.0,
            loc_a: 1.0,
            sr: 0.0,
            faf: 0.5,
        },
    );
}

#[test]
fn one_id_switch() {
    // Truth A over frames 1-4, followed by estimate 1 then estimate 2.
    // CLEAR: TP 4, IDSW 1, MOTA (4 − 0 − 1)/4. Identity: m(A,1) = m(A,2) = 2, IDTP 2,
    // IDFN 2, IDFP 2, IDF1 = 2/(2 + 1 + 1). HOTA: DetA 1; AssA = (2²/(4+2−2) + 2²/(4+2−2))/4
    // = 1/2, HOTA = √½.
    check(
        &[(1, &[(1, 0.0), (2, 0.0), (3, 0.0), (4, 0.0)])],
        &[(1, &[(1, 0.0), (2, 0.0)]), (2, &[(3, 0.0), (4, 0.0)])],
        &Expect {
            mota: 0.75,
            motp: 1.0,
            tp: 4,
            fp: 0,
            fn_: 0,
            idsw: 1,
            frag: 0,
            idf1: 0.5,
            idp: 0.5,
            idr: 0.5,
            hota: 0.5f64.sqrt(),
            det_a: 1.0,
            ass_a: 0.5,
            loc_a: 1.0,
            sr: 1.0,
            faf: 0.0,
        },
    );
}

#[test]
fn one_fragmentation() {
    // Truth over frames 1-5, the estimate misses frame 3, where a far-away false positive is
    // the only estimate. CLEAR: TP 4, FN 1, FP 1, Frag 1, MOTA 3/5. IDF1 = 2·4/(2·4 + 1 + 1).
    // HOTA: DetA = 4/6; AssA = (4²/(5+4−4))/4 = 4/5.
    check(
        &[(1, &[(1, 0.0), (2, 0.0), (3, 0.0), (4, 0.0), (5, 0.0)])],
        &[
            (3, &[(1, 0.0), (2, 0.0), (4, 0.0), (5, 0.0)]),
            (9, &[(3, 500.0)]),
        ],
        &Expect {
            mota: 0.6,
            motp: 1.0,
            tp: 4,
            fp: 1,
            fn_: 1,
            idsw: 0,
            frag: 1,
            idf1: 0.8,
            idp: 0.8,
            idr: 0.8,
            hota: (4.0f64 / 6.0 * 0.8).sqrt(),
            det_a: 4.0 / 6.0,
            ass_a: 0.8,
            loc_a: 1.0,
            sr: 0.8,
            faf: 0.2,
        },
    );
    // Without the false positive, frame 3 has no estimate at all; TrackEval's clear.py skips
    // such a frame, so the run continues across it and there is no fragmentation (the
    // reference run in testdata/gaps-* checks this convention against TrackEval itself).
    check(
        &[(1, &[(1, 0.0), (2, 0.0), (3, 0.0), (4, 0.0), (5, 0.0)])],
        &[(3, &[(1, 0.0), (2, 0.0), (4, 0.0), (5, 0.0)])],
        &Expect {
            mota: 0.8,
            motp: 1.0,
            tp: 4,
            fp: 0,
            fn_: 1,
            idsw: 0,
            frag: 0,
            idf1: 8.0 / 9.0,
            idp: 1.0,
            idr: 0.8,
            hota: 0.8,
            det_a: 0.8,
            ass_a: 0.8,
            loc_a: 1.0,
            sr: 0.8,
            faf: 0.0,
        },
    );
    let r = eval_boxes(
        &[(1, &[(1, 0.0), (2, 0.0), (3, 0.0), (4, 0.0), (5, 0.0)])],
        &[(3, &[(1, 0.0), (2, 0.0), (4, 0.0), (5, 0.0)])],
    );
    // Tracked in 4 of 5 frames: 80 % is not "more than 80 %", so partially tracked.
    assert_eq!(
        (
            r.clear.mostly_tracked,
            r.clear.partially_tracked,
            r.clear.mostly_lost
        ),
        (0, 1, 0)
    );
}

#[test]
fn perfect_tracker() {
    let gt: Desc<'_> = &[
        (1, &[(1, 0.0), (2, 1.0), (3, 2.0)]),
        (2, &[(2, 50.0), (3, 51.0)]),
    ];
    let pred: Desc<'_> = &[
        (10, &[(1, 0.0), (2, 1.0), (3, 2.0)]),
        (20, &[(2, 50.0), (3, 51.0)]),
    ];
    check(
        gt,
        pred,
        &Expect {
            mota: 1.0,
            motp: 1.0,
            tp: 5,
            fp: 0,
            fn_: 0,
            idsw: 0,
            frag: 0,
            idf1: 1.0,
            idp: 1.0,
            idr: 1.0,
            hota: 1.0,
            det_a: 1.0,
            ass_a: 1.0,
            loc_a: 1.0,
            sr: 1.0,
            faf: 0.0,
        },
    );
    assert_eq!(eval_boxes(gt, pred).clear.mostly_tracked, 2);
}

#[test]
fn perfect_detection_half_wrong_association() {
    // Estimates 1 and 2 swap targets after frame 2. CLEAR: 2 switches, MOTA (8 − 2)/8.
    // Identity: every pair matches 2 frames, IDTP 4 of 8. HOTA: every alignment is
    // 2/(4+4−2) = 1/3 and AssA = 4·(2²/6)/8 = 1/3, so HOTA = √(1/3).
    let gt: Desc<'_> = &[
        (1, &[(1, 0.0), (2, 0.0), (3, 0.0), (4, 0.0)]),
        (2, &[(1, 50.0), (2, 50.0), (3, 50.0), (4, 50.0)]),
    ];
    let pred: Desc<'_> = &[
        (1, &[(1, 0.0), (2, 0.0), (3, 50.0), (4, 50.0)]),
        (2, &[(1, 50.0), (2, 50.0), (3, 0.0), (4, 0.0)]),
    ];
    check(
        gt,
        pred,
        &Expect {
            mota: 0.75,
            motp: 1.0,
            tp: 8,
            fp: 0,
            fn_: 0,
            idsw: 2,
            frag: 0,
            idf1: 0.5,
            idp: 0.5,
            idr: 0.5,
            hota: (1.0f64 / 3.0).sqrt(),
            det_a: 1.0,
            ass_a: 1.0 / 3.0,
            loc_a: 1.0,
            sr: 1.0,
            faf: 0.0,
        },
    );
}

#[test]
fn clear_keeps_previous_partner_over_a_better_overlap() {
    // Frame 1: estimate 1 matches A exactly. Frame 2: estimate 2 overlaps A better (IoU 1)
    // than estimate 1 (IoU 8/12), but the match continues with 1: no switch, and MOTP is the
    // mean of 1 and 2/3. Estimate 2 is then a false positive.
    let r = eval_boxes(
        &[(1, &[(1, 0.0), (2, 0.0)])],
        &[(1, &[(1, 0.0), (2, 2.0)]), (2, &[(2, 0.0)])],
    );
    assert_eq!(r.clear.id_switches, 0);
    assert_eq!(r.clear.false_positives, 1);
    assert_relative_eq!(r.clear.motp, (1.0 + 80.0 / 120.0) / 2.0, epsilon = 1e-12);
}

/// IDTP by brute force: try every partial one-to-one pairing of truth tracks with estimated
/// tracks, score each by the definition IDFN + IDFP, and keep the best.
fn brute_force_idtp(counts: &[Vec<usize>], gt_len: &[usize], pred_len: &[usize]) -> usize {
    fn cost(
        pairing: &[Option<usize>],
        counts: &[Vec<usize>],
        gt_len: &[usize],
        pred_len: &[usize],
    ) -> usize {
        let mut idfn = 0;
        let mut matched_in_pred = vec![0; pred_len.len()];
        for (g, &h) in pairing.iter().enumerate() {
            let m = h.map_or(0, |h| counts[g][h]);
            idfn += gt_len[g] - m;
            if let Some(h) = h {
                matched_in_pred[h] = m;
            }
        }
        let idfp: usize = pred_len
            .iter()
            .zip(&matched_in_pred)
            .map(|(n, m)| n - m)
            .sum();
        idfn + idfp
    }
    fn search(
        pairing: &mut Vec<Option<usize>>,
        used: &mut [bool],
        ctx: (&[Vec<usize>], &[usize], &[usize]),
        best: &mut usize,
    ) {
        let (counts, gt_len, pred_len) = ctx;
        if pairing.len() == counts.len() {
            *best = (*best).min(cost(pairing, counts, gt_len, pred_len));
            return;
        }
        pairing.push(None);
        search(pairing, used, ctx, best);
        pairing.pop();
        for h in 0..used.len() {
            if !used[h] {
                used[h] = true;
                pairing.push(Some(h));
                search(pairing, used, ctx, best);
                pairing.pop();
                used[h] = false;
            }
        }
    }
    let mut best = usize::MAX;
    search(
        &mut Vec::new(),
        &mut vec![false; pred_len.len()],
        (counts, gt_len, pred_len),
        &mut best,
    );
    // IDFN + IDFP = Σ n_g + Σ n_h − 2 IDTP.
    (gt_len.iter().sum::<usize>() + pred_len.iter().sum::<usize>() - best) / 2
}

#[test]
fn identity_assignment_matches_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for _ in 0..60 {
        let n_gt = rng.random_range(1..5u64);
        let n_pred = rng.random_range(1..5u64);
        // Each track occupies random frames at one of three positions; overlaps create matches.
        let mk = |n: u64, rng: &mut ChaCha8Rng| -> TrackSet {
            let tracks = (0..n)
                .map(|id| {
                    let mut pts = Vec::new();
                    for f in 1..=8u32 {
                        if rng.random_bool(0.6) {
                            let x = 10.0 * rng.random_range(0..3) as f64;
                            pts.push(TrackPoint::at(f, Vec2::new(x, 0.0)));
                        }
                    }
                    Track::from_points(TrackId(id), pts).unwrap()
                })
                .collect();
            TrackSet::from_tracks(tracks).unwrap()
        };
        let (gt, pred) = (mk(n_gt, &mut rng), mk(n_pred, &mut rng));
        let cfg = MatchConfig::within_distance(1.0);
        let seq = Sequence::new(&gt, &pred, cfg.similarity).unwrap();
        let counts: Vec<Vec<usize>> = gt
            .tracks()
            .iter()
            .map(|g| {
                pred.tracks()
                    .iter()
                    .map(|h| {
                        g.points()
                            .iter()
                            .filter(|p| {
                                h.at(p.frame).is_some_and(|q| {
                                    (q.location.position() - p.location.position()).norm() <= 1.0
                                })
                            })
                            .count()
                    })
                    .collect()
            })
            .collect();
        let gt_len: Vec<usize> = gt.tracks().iter().map(Track::len).collect();
        let pred_len: Vec<usize> = pred.tracks().iter().map(Track::len).collect();
        let ids = identity(&seq, cfg.threshold).unwrap();
        assert_eq!(ids.idtp, brute_force_idtp(&counts, &gt_len, &pred_len));
        assert_eq!(ids.idfn, gt.n_points() - ids.idtp);
    }
}

// ---------------------------------------------------------------------------------------------
// OSPA and GOSPA

fn p(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

#[test]
fn ospa_hand_cases() {
    let c10p1 = OspaConfig {
        cutoff: 10.0,
        order: 1.0,
    };
    let c10p2 = OspaConfig {
        cutoff: 10.0,
        order: 2.0,
    };
    assert_relative_eq!(
        ospa(&[p(0.0, 0.0)], &[p(3.0, 4.0)], &c10p1)
            .unwrap()
            .distance,
        5.0
    );
    // m = 1, n = 2, p = 2: ((5² + 10²)/2)^{1/2}.
    let o = ospa(&[p(0.0, 0.0)], &[p(3.0, 4.0), p(100.0, 0.0)], &c10p2).unwrap();
    assert_relative_eq!(o.distance, 62.5f64.sqrt(), epsilon = 1e-12);
    assert_relative_eq!(o.localisation, 12.5f64.sqrt(), epsilon = 1e-12);
    assert_relative_eq!(o.cardinality, 50.0f64.sqrt(), epsilon = 1e-12);
    assert_eq!(ospa(&[], &[], &c10p1).unwrap().distance, 0.0);
    assert_eq!(ospa(&[], &[p(1.0, 1.0)], &c10p1).unwrap().distance, 10.0);
    assert_eq!(ospa(&[p(1.0, 1.0)], &[], &c10p2).unwrap().distance, 10.0);
    // Far points are cut off at c.
    assert_eq!(
        ospa(&[p(0.0, 0.0)], &[p(1e6, 0.0)], &c10p1)
            .unwrap()
            .distance,
        10.0
    );
    assert!(ospa(&[p(f64::NAN, 0.0)], &[], &c10p1).is_err());
    assert!(
        ospa(
            &[],
            &[],
            &OspaConfig {
                cutoff: 0.0,
                order: 1.0
            }
        )
        .is_err()
    );
    assert!(
        ospa(
            &[],
            &[],
            &OspaConfig {
                cutoff: 1.0,
                order: 0.5
            }
        )
        .is_err()
    );
}

#[test]
fn gospa_hand_cases() {
    let cfg = OspaConfig {
        cutoff: 5.0,
        order: 1.0,
    };
    // (0,0)↔(0,1) at distance 1; (10,0) is missed: 1 + 5/2.
    let g = gospa(&[p(0.0, 0.0), p(10.0, 0.0)], &[p(0.0, 1.0)], &cfg).unwrap();
    assert_relative_eq!(g.distance, 3.5, epsilon = 1e-12);
    assert_eq!((g.n_missed, g.n_false), (1, 0));
    // A pair farther than c is a miss plus a false target, not an assignment.
    let g = gospa(&[p(0.0, 0.0)], &[p(6.0, 0.0)], &cfg).unwrap();
    assert_eq!((g.n_missed, g.n_false), (1, 1));
    assert_relative_eq!(g.distance, 5.0, epsilon = 1e-12);
    let g = gospa(&[], &[], &cfg).unwrap();
    assert_eq!(g.distance, 0.0);
}

fn point_set() -> impl Strategy<Value = Vec<Vec2>> {
    prop::collection::vec(
        (-20.0f64..20.0, -20.0f64..20.0).prop_map(|(x, y)| p(x, y)),
        0..6,
    )
}

proptest! {
    #[test]
    fn ospa_is_a_metric(x in point_set(), y in point_set(), z in point_set(), c in 1.0f64..30.0, order in 1.0f64..3.0) {
        let cfg = OspaConfig { cutoff: c, order };
        let d = |a: &[Vec2], b: &[Vec2]| ospa(a, b, &cfg).unwrap().distance;
        prop_assert!(d(&x, &x).abs() < 1e-9);
        prop_assert!((d(&x, &y) - d(&y, &x)).abs() < 1e-9);
        prop_assert!(d(&x, &z) <= d(&x, &y) + d(&y, &z) + 1e-9);
        prop_assert!(d(&x, &y) <= c + 1e-9);
    }

    #[test]
    fn gospa_parts_sum_to_total(x in point_set(), y in point_set(), c in 1.0f64..30.0, order in 1.0f64..3.0) {
        let g = gospa(&x, &y, &OspaConfig { cutoff: c, order }).unwrap();
        let total = g.localisation + g.missed + g.false_targets;
        prop_assert!((total - g.distance.powf(order)).abs() <= 1e-9 * total.max(1.0));
        prop_assert_eq!(x.len() - g.n_missed, y.len() - g.n_false);
    }
}

#[test]
fn ospa_over_time_covers_every_frame() {
    let gt = points(&[(1, &[(1, 0.0), (3, 0.0)])]);
    let pred = points(&[(1, &[(1, 0.0), (2, 0.0)])]);
    let series = ospa_over_time(
        &gt,
        &pred,
        &OspaConfig {
            cutoff: 10.0,
            order: 1.0,
        },
    )
    .unwrap();
    let d: Vec<(u32, f64)> = series.iter().map(|(f, o)| (*f, o.distance)).collect();
    assert_eq!(d, vec![(1, 0.0), (2, 10.0), (3, 10.0)]);
}

// ---------------------------------------------------------------------------------------------
// The reproduced papers' metrics (paper_metrics.rs)

#[test]
fn mae_and_mmae_by_hand() {
    let m = mae(&[p(0.0, 0.0), p(1.0, 1.0)], &[p(3.0, 4.0), p(1.0, 2.0)]).unwrap();
    assert_relative_eq!(m.x, 1.5);
    assert_relative_eq!(m.y, 2.5);
    assert_relative_eq!(m.euclidean, 3.0);
    assert_relative_eq!(m.axis_mean, 2.0);
    let m2 = mae(&[p(0.0, 0.0)], &[p(1.0, 0.0)]).unwrap();
    // MMAE weighs segments equally: x = (1.5 + 1)/2, not the pooled (3 + 1)/3.
    let mm = mmae(&[m, m2]).unwrap();
    assert_relative_eq!(mm.x, 1.25);
    assert_relative_eq!(mm.euclidean, 2.0);
    assert_eq!(
        mae(&[p(0.0, 0.0)], &[]).unwrap_err(),
        Error::LengthMismatch {
            what: "MAE estimates (one per truth point)",
            expected: 1,
            got: 0
        }
    );
    assert!(mae(&[], &[]).is_err());
    assert!(mmae(&[]).is_err());
}

#[test]
fn success_rate_and_faf_by_hand() {
    // Frame 1: two truth boxes, one found, one false estimate. Frame 2: one truth box, no
    // estimate. SR = 1/3, FAF = 1 false / 2 frames.
    let gt = boxes(&[(1, &[(1, 0.0), (2, 0.0)]), (2, &[(1, 50.0)])]);
    let pred = boxes(&[(1, &[(1, 0.0)]), (2, &[(1, 100.0)])]);
    let s = success_rate(&gt, &pred, &MatchConfig::iou(0.5)).unwrap();
    assert_relative_eq!(s.success_rate, 1.0 / 3.0);
    assert_relative_eq!(s.false_alarms_per_frame, 0.5);
    // IoU 8/12 ≈ 0.67 counts at 0.5 but not at 0.7.
    let shifted = boxes(&[(1, &[(1, 2.0)])]);
    assert_eq!(
        success_rate(&gt, &shifted, &MatchConfig::iou(0.5))
            .unwrap()
            .n_matched,
        1
    );
    assert_eq!(
        success_rate(&gt, &shifted, &MatchConfig::iou(0.7))
            .unwrap()
            .n_matched,
        0
    );
    assert!(success_rate(&gt, &pred, &MatchConfig::iou(1.5)).is_err());
    // IoU on points is refused with a clear error.
    assert!(matches!(
        success_rate(
            &points(&[(1, &[(1, 0.0)])]),
            &points(&[]),
            &MatchConfig::iou(0.5)
        ),
        Err(Error::IouNeedsBoxes { side: Side::Truth })
    ));
}

#[test]
fn distance_errors_and_per_track_means() {
    let gt = points(&[
        (1, &[(1, 0.0), (2, 10.0), (3, 20.0)]),
        (2, &[(1, 100.0), (2, 100.0)]),
    ]);
    let pred = points(&[(7, &[(1, 3.0), (3, 21.0)]), (8, &[(2, 100.0)])]);
    let series = distance_error_series(&gt.tracks()[0], &pred.tracks()[0]);
    assert_eq!(series, vec![(1, 3.0), (3, 1.0)]);
    let per_track = mean_error_per_track(&gt, &pred, 5.0).unwrap();
    assert_eq!(per_track.len(), 2);
    assert_eq!(
        (per_track[0].gt_id, per_track[0].pred_id),
        (TrackId(1), TrackId(7))
    );
    assert_relative_eq!(per_track[0].mean_error, 2.0);
    assert_eq!(
        (
            per_track[1].gt_id,
            per_track[1].pred_id,
            per_track[1].mean_error
        ),
        (TrackId(2), TrackId(8), 0.0)
    );
}

#[test]
fn association_scores_by_hand() {
    let m = |origin| Measurement {
        value: p(0.0, 0.0),
        origin,
    };
    let t = |k| Origin::Target(TrackId(k));
    // Target 0 in scans 0, 1, 2 and target 1 in scans 0, 2: true links s0→s1, s1→s2 (target 0)
    // and s0→s2 (target 1).
    let scans = vec![
        Scan {
            frame: 0,
            measurements: vec![m(t(0)), m(t(1)), m(Origin::Clutter)],
        },
        Scan {
            frame: 1,
            measurements: vec![m(t(0))],
        },
        Scan {
            frame: 2,
            measurements: vec![m(t(1)), m(t(0))],
        },
    ];
    // Track 7: target 0 in scans 0 and 1, then target 1 in scan 2 (one right, one wrong link);
    // track 8 holds target 1's first detection alone; the clutter is a false alarm.
    let labels = vec![
        vec![Some(7), Some(8), None],
        vec![Some(7)],
        vec![Some(7), None],
    ];
    let s = association_scores(&scans, &labels).unwrap();
    assert_eq!(
        (s.n_true_links, s.n_estimated_links, s.n_correct_links),
        (3, 2, 1)
    );
    assert_relative_eq!(s.precision, 0.5);
    assert_relative_eq!(s.recall, 1.0 / 3.0);
    assert_relative_eq!(s.f1, 0.4);
    assert_eq!(
        association_scores(&scans, &labels[..2]).unwrap_err(),
        Error::LengthMismatch {
            what: "label lists (one per scan)",
            expected: 3,
            got: 2
        }
    );
    let short = vec![labels[0].clone(), labels[1].clone(), vec![Some(7)]];
    assert_eq!(
        association_scores(&scans, &short).unwrap_err(),
        Error::ScanLabelsMismatch {
            scan: 2,
            n_measurements: 2,
            n_labels: 1
        }
    );
}

#[test]
fn bad_configurations_are_errors() {
    let gt = boxes(&[(1, &[(1, 0.0)])]);
    let bad = EvalConfig {
        matching: MatchConfig {
            similarity: Similarity::Distance { zero_at: -1.0 },
            threshold: 0.5,
        },
    };
    assert!(evaluate(&gt, &gt, &bad).is_err());
    let bad = EvalConfig {
        matching: MatchConfig::iou(0.0),
    };
    assert!(evaluate(&gt, &gt, &bad).is_err());
    assert!(bad.check().is_err());
    assert!(EvalConfig::default().check().is_ok());
    // A bad OSPA configuration is refused even when there is nothing to score.
    let bad_ospa = OspaConfig {
        cutoff: 10.0,
        order: 0.5,
    };
    let empty = TrackSet::new();
    assert!(ospa_over_time(&empty, &empty, &bad_ospa).is_err());
    assert!(gospa_over_time(&empty, &empty, &bad_ospa).is_err());
    // IoU names the side that holds a point.
    let (b, pt) = (
        Location::Box(BoundingBox::new(0.0, 0.0, 1.0, 1.0).unwrap()),
        Location::Point(p(0.0, 0.0)),
    );
    assert_eq!(
        Similarity::Iou.between(&b, &pt).unwrap_err(),
        Error::IouNeedsBoxes {
            side: Side::Estimate
        }
    );
    assert_eq!(
        Similarity::Iou.matrix(&[pt], &[b]).unwrap_err(),
        Error::IouNeedsBoxes { side: Side::Truth }
    );
}

#[test]
fn configs_reject_unknown_fields() {
    let config: EvalConfig =
        serde_json::from_str(r#"{"matching": {"similarity": "iou", "threshold": 0.5}}"#).unwrap();
    assert_eq!(config, EvalConfig::default());
    assert_eq!(
        serde_json::from_str::<EvalConfig>("{}").unwrap(),
        EvalConfig::default()
    );
    for bad in [
        r#"{"matching": {"similarity": "iou", "threshold": 0.5}, "iou": 0.5}"#,
        r#"{"matching": {"similarity": "iou", "threshold": 0.5, "thresh": 0.5}}"#,
        r#"{"matching": {"similarity": {"distance": {"zero_at": 2.0, "zero": 1.0}}, "threshold": 0.5}}"#,
    ] {
        assert!(serde_json::from_str::<EvalConfig>(bad).is_err(), "{bad}");
    }
    assert!(serde_json::from_str::<OspaConfig>(r#"{"cutoff": 1.0, "order": 2.0}"#).is_ok());
    assert!(
        serde_json::from_str::<OspaConfig>(r#"{"cutoff": 1.0, "order": 2.0, "alpha": 2.0}"#)
            .is_err()
    );
}

// ---------------------------------------------------------------------------------------------
// Agreement with py-motmetrics on a synthetic sequence (testdata/gen_reference.py made the
// files and the reference numbers; py-motmetrics is an independent implementation).

#[test]
fn clear_and_identity_agree_with_py_motmetrics() {
    let load = |text: &str| {
        TrackSet::from_mot_rows(&tracker_model::parse_mot(text.as_bytes()).unwrap()).unwrap()
    };
    let gt = load(include_str!("../testdata/synthetic-gt.txt"));
    let pred = load(include_str!("../testdata/synthetic-pred.txt"));
    let reference: std::collections::BTreeMap<String, serde_json::Value> =
        serde_json::from_str(include_str!("../testdata/synthetic-motmetrics.json")).unwrap();
    let want = |k: &str| reference[k].as_f64().unwrap();
    let r = evaluate(&gt, &pred, &EvalConfig::default()).unwrap();
    let c = &r.clear;
    assert_eq!(c.true_positives as f64, want("num_detections"));
    assert_eq!(c.false_positives as f64, want("num_false_positives"));
    assert_eq!(c.false_negatives as f64, want("num_misses"));
    assert_eq!(c.id_switches as f64, want("num_switches"));
    assert_eq!(
        (c.true_positives + c.false_negatives) as f64,
        want("num_objects")
    );
    assert_relative_eq!(c.mota, want("mota"), epsilon = 1e-12);
    // py-motmetrics reports MOTP as the mean distance 1 − IoU.
    assert_relative_eq!(1.0 - c.motp, want("motp"), epsilon = 1e-9);
    assert_relative_eq!(c.precision, want("precision"), epsilon = 1e-12);
    assert_relative_eq!(c.recall, want("recall"), epsilon = 1e-12);
    let i = &r.identity;
    assert_eq!(
        (i.idtp as f64, i.idfp as f64, i.idfn as f64),
        (want("idtp"), want("idfp"), want("idfn"))
    );
    assert_relative_eq!(i.idf1, want("idf1"), epsilon = 1e-12);
    assert_relative_eq!(i.idp, want("idp"), epsilon = 1e-12);
    assert_relative_eq!(i.idr, want("idr"), epsilon = 1e-12);
}

#[test]
fn sparse_frame_numbers_group_like_dense_ones() {
    // Frames 1 and 2 use the bucket path; frames 1 and 10⁷ the sort path. The per-frame
    // similarity matrices must be the same.
    let dense = boxes(&[(1, &[(1, 0.0), (2, 3.0)]), (2, &[(2, 50.0)])]);
    let sparse = boxes(&[
        (1, &[(1, 0.0), (10_000_000, 3.0)]),
        (2, &[(10_000_000, 50.0)]),
    ]);
    let pred_dense = boxes(&[(5, &[(1, 1.0), (2, 4.0)]), (6, &[(2, 52.0)])]);
    let pred_sparse = boxes(&[
        (5, &[(1, 1.0), (10_000_000, 4.0)]),
        (6, &[(10_000_000, 52.0)]),
    ]);
    let a = Sequence::new(&dense, &pred_dense, Similarity::Iou).unwrap();
    let b = Sequence::new(&sparse, &pred_sparse, Similarity::Iou).unwrap();
    assert_eq!(a.frames.len(), b.frames.len());
    for (fa, fb) in a.frames.iter().zip(&b.frames) {
        assert_eq!(
            (&fa.gt, &fa.pred, &fa.sim, &fa.pair),
            (&fb.gt, &fb.pred, &fb.sim, &fb.pair)
        );
    }
}

// Agreement with TrackEval (Luiten et al.), the reference implementation of HOTA, on the same
// synthetic sequence (boxes with noise: IoU < 1, so LocA and MOTP are exercised) and on a small
// sequence with empty frames (testdata/gen_trackeval_reference.py made the reference numbers).
// TrackEval's MT/PT/ML thresholds (matched in > 80 %, ≥ 20 % of the frames a truth object is
// present) and its Frag (number of tracked runs of a truth object less one) are ours too.

fn trackeval_reference() -> serde_json::Value {
    serde_json::from_str(include_str!("../testdata/synthetic-trackeval.json")).unwrap()
}

fn check_against_trackeval(gt_text: &str, pred_text: &str, want: &serde_json::Value) {
    let load = |text: &str| {
        TrackSet::from_mot_rows(&tracker_model::parse_mot(text.as_bytes()).unwrap()).unwrap()
    };
    let r = evaluate(&load(gt_text), &load(pred_text), &EvalConfig::default()).unwrap();
    let f = |k: &str| want[k].as_f64().unwrap();
    let n = |k: &str| want[k].as_u64().unwrap() as usize;
    let c = &r.clear;
    assert_eq!(
        (c.true_positives, c.false_negatives, c.false_positives),
        (n("CLR_TP"), n("CLR_FN"), n("CLR_FP"))
    );
    assert_eq!(c.id_switches, n("IDSW"), "IDSW");
    assert_eq!(c.fragmentations, n("Frag"), "Frag");
    assert_eq!(
        (c.mostly_tracked, c.partially_tracked, c.mostly_lost),
        (n("MT"), n("PT"), n("ML")),
        "MT/PT/ML"
    );
    assert_eq!(c.n_gt_tracks, n("num_gt_ids"));
    for (ours, key) in [
        (c.mota, "MOTA"),
        (c.motp, "MOTP"),
        (c.moda, "MODA"),
        (c.recall, "CLR_Re"),
        (c.precision, "CLR_Pr"),
        (r.identity.idf1, "IDF1"),
        (r.identity.idp, "IDP"),
        (r.identity.idr, "IDR"),
        (r.hota.hota, "HOTA"),
        (r.hota.det_a, "DetA"),
        (r.hota.ass_a, "AssA"),
        (r.hota.loc_a, "LocA"),
        (r.hota.det_re, "DetRe"),
        (r.hota.det_pr, "DetPr"),
        (r.hota.ass_re, "AssRe"),
        (r.hota.ass_pr, "AssPr"),
    ] {
        assert!(
            (ours - f(key)).abs() <= 1e-9,
            "{key}: ours {ours}, TrackEval {}",
            f(key)
        );
    }
    assert_eq!(
        (r.identity.idtp, r.identity.idfp, r.identity.idfn),
        (n("IDTP"), n("IDFP"), n("IDFN"))
    );
    let per_alpha = want["HOTA_per_alpha"].as_array().unwrap();
    assert_eq!(r.hota.per_alpha.len(), per_alpha.len());
    for (ours, theirs) in r.hota.per_alpha.iter().zip(per_alpha) {
        assert!((ours - theirs.as_f64().unwrap()).abs() <= 1e-9);
    }
    // LocA is exercised: the matched boxes do not coincide.
    assert!(r.hota.loc_a < 0.9);
}

#[test]
fn hota_clear_and_identity_agree_with_trackeval() {
    check_against_trackeval(
        include_str!("../testdata/synthetic-gt.txt"),
        include_str!("../testdata/synthetic-pred.txt"),
        &trackeval_reference(),
    );
}

#[test]
fn empty_frames_follow_trackeval() {
    check_against_trackeval(
        include_str!("../testdata/gaps-gt.txt"),
        include_str!("../testdata/gaps-pred.txt"),
        &trackeval_reference()["gaps"],
    );
}
