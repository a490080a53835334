//! Hand-worked cases: the filter against the textbook matrix formulas, the IoU, ByteTrack's
//! second stage, OC-SORT's direction term and its re-update after a gap, gaps and errors.
#![expect(
    clippy::float_cmp,
    reason = "IoUs rounded to f32 and boxes copied from the filter are compared exactly"
)]

use nalgebra::{DMatrix, DVector};
use tracker_model::{BoundingBox, Detection, Tracker, Vec2};

use crate::kalman::{BoxFilter, Noise, StateLayout};
use crate::ocsort::{OcSortTrack, direction_scores};
use crate::tracker::BoxDetection;
use crate::*;

fn det(id: u64, frame: u32, left: f64, top: f64, score: f64) -> Detection {
    let b = BoundingBox::new(left, top, 20.0, 40.0).expect("a valid box");
    Detection::boxed(id, frame, b).with_score(score)
}

fn corners(left: f64, top: f64) -> Corners {
    [left, top, left + 20.0, top + 40.0]
}

/// The textbook filter on full matrices: F with ones coupling each moving entry to its rate,
/// H = [I 0], P ← F P Fᵀ + Q, K = P Hᵀ (H P Hᵀ + R)⁻¹, Joseph form.
fn textbook(
    n: usize,
    n_moving: usize,
    noise: &Noise,
    b0: &Corners,
    zs: &[[f64; 4]],
) -> (DVector<f64>, DMatrix<f64>) {
    let mut f = DMatrix::<f64>::identity(n, n);
    for i in 0..n_moving {
        f[(i, i + 4)] = 1.0;
    }
    let h = DMatrix::<f64>::identity(4, n);
    let q = DMatrix::from_diagonal(&DVector::from_column_slice(&noise.q[..n]));
    let r = DMatrix::from_diagonal(&DVector::from_column_slice(&noise.r));
    let mut x = DVector::<f64>::zeros(n);
    let z0 = noise.layout.measure(b0);
    x.rows_mut(0, 4).copy_from_slice(&z0);
    let mut p = DMatrix::from_diagonal(&DVector::from_column_slice(&noise.p0[..n]));
    for z in zs {
        x = &f * &x;
        p = &f * &p * f.transpose() + &q;
        let s = &h * &p * h.transpose() + &r;
        let k = &p * h.transpose() * s.try_inverse().expect("S is invertible");
        let y = DVector::from_column_slice(&z[..]) - &h * &x;
        x += &k * y;
        let ikh = DMatrix::<f64>::identity(n, n) - &k * &h;
        p = &ikh * &p * ikh.transpose() + &k * &r * k.transpose();
    }
    (x, p)
}

#[test]
fn the_filter_equals_the_textbook_formulas_in_both_layouts() {
    let moves = [
        corners(12.0, 21.0),
        corners(15.5, 22.0),
        corners(19.0, 24.5),
    ];
    let cases = [
        (
            StateLayout::Corners,
            8,
            4,
            Noise::diagonal(StateLayout::Corners, [0.01; 8], [0.1; 4], [1.0; 8]),
        ),
        (
            StateLayout::CentreAreaAspect,
            7,
            3,
            Noise::diagonal(
                StateLayout::CentreAreaAspect,
                [1.0, 1.0, 1.0, 1.0, 0.01, 0.01, 1e-4, 0.0],
                [1.0, 1.0, 10.0, 10.0],
                [10.0, 10.0, 10.0, 10.0, 1e4, 1e4, 1e4, 0.0],
            ),
        ),
    ];
    for (layout, n, n_moving, noise) in cases {
        let b0 = corners(10.0, 20.0);
        let zs: Vec<[f64; 4]> = moves.iter().map(|b| layout.measure(b)).collect();
        let (expected, p) = textbook(n, n_moving, &noise, &b0, &zs);
        let mut filter = BoxFilter::new(&noise, &b0);
        for z in &zs {
            filter.predict(&noise);
            filter.update(&noise, z).expect("update");
        }
        for i in 0..n {
            let scale = expected[i].abs().max(1.0);
            assert!(
                (filter.x[i] - expected[i]).abs() < 1e-12 * scale,
                "{layout:?} state {i}: {} against {}",
                filter.x[i],
                expected[i]
            );
        }
        // And the covariance, entry by entry (the blocks and the zeros between them).
        for i in 0..n {
            for j in 0..n {
                let scale = p[(i, j)].abs().max(1.0);
                assert!(
                    (filter.covariance(i, j) - p[(i, j)]).abs() < 1e-12 * scale,
                    "{layout:?} P[{i}, {j}]: {} against {}",
                    filter.covariance(i, j),
                    p[(i, j)]
                );
            }
        }
        if layout == StateLayout::CentreAreaAspect {
            assert_eq!(filter.x[7], 0.0, "the unused eighth entry stays zero");
        }
    }
}

#[test]
fn iou_is_rounded_to_single_precision_and_zero_without_overlap() {
    // 5 × 5 overlap of two 10 × 10 boxes: 25 / 175.
    assert_eq!(
        iou(&[0.0, 0.0, 10.0, 10.0], &[5.0, 5.0, 15.0, 15.0]),
        (25.0f64 / 175.0) as f32
    );
    assert_eq!(iou(&[0.0, 0.0, 10.0, 10.0], &[10.0, 0.0, 20.0, 10.0]), 0.0);
    assert_eq!(
        iou(&[0.0, 0.0, f64::NAN, 10.0], &[0.0, 0.0, 10.0, 10.0]),
        0.0
    );
}

#[test]
fn assignment_gates_each_pair_on_the_gate_matrix() {
    let m = |values: Vec<f32>| Matrix {
        n_rows: 2,
        n_cols: 2,
        values,
    };
    // The best assignment is the diagonal (0.9 + 0.2 against 0.5 + 0.1); 0.2 is below 0.3.
    let score = m(vec![0.9, 0.5, 0.1, 0.2]);
    let matching = assign(&score, &score, 0.3).expect("assignment");
    assert_eq!(matching.matched, vec![(0, 0)]);
    assert_eq!(matching.unmatched_rows, vec![1]);
    assert_eq!(matching.unmatched_cols, vec![1]);
    // A threshold of 0.2 passes 0.2 in f32 as the reference compares.
    let matching = assign(&score, &score, 0.2).expect("assignment");
    assert_eq!(matching.matched, vec![(0, 0), (1, 1)]);
}

fn ids(states: &[tracker_model::TrackState]) -> Vec<u64> {
    states.iter().map(|s| s.id.0).collect()
}

#[test]
fn bytetrack_keeps_a_track_through_low_score_boxes_which_start_none() {
    let mut t = ByteTrackConfig::default().build().expect("defaults");
    assert!(ids(&t.step(1, &[det(1, 1, 100.0, 50.0, 0.9)]).expect("step")).is_empty());
    assert_eq!(
        ids(&t.step(2, &[det(2, 2, 102.0, 50.0, 0.9)]).expect("step")),
        vec![1]
    );
    // Frame 3: the person's box scores 0.3 (below the 0.6 of high-score boxes): the second
    // stage gives it to the track; a low-score box far away starts nothing.
    let low = [det(3, 3, 104.0, 50.0, 0.3), det(4, 3, 400.0, 300.0, 0.3)];
    let assigned = t.update(3, &low).expect("step");
    assert_eq!(assigned.len(), 1);
    assert_eq!((assigned[0].track.0, assigned[0].index), (1, 0));
    assert_eq!(t.association().config().minimum_consecutive_frames, 2);
    // Frame 4: the far box again, now high-scoring but below the 0.7 that starts a track.
    assert!(ids(&t.step(4, &[det(5, 4, 400.0, 300.0, 0.65)]).expect("step")).is_empty());
    let tracks = t.finish().expect("finish");
    assert_eq!(tracks.len(), 1);
    assert_eq!(tracks.tracks()[0].len(), 2);
}

#[test]
fn bytetrack_second_stage_can_have_its_own_gate() {
    let config = ByteTrackConfig {
        second_iou_threshold: Some(0.9),
        ..ByteTrackConfig::default()
    };
    let mut t = config.build().expect("valid");
    t.step(1, &[det(1, 1, 100.0, 50.0, 0.9)]).expect("step");
    t.step(2, &[det(2, 2, 100.0, 50.0, 0.9)]).expect("step");
    // IoU of a 20 × 40 box shifted 2 px: 36 · 40 / (2 · 800 − 720) ≈ 0.82 < 0.9.
    assert!(ids(&t.step(3, &[det(3, 3, 102.0, 50.0, 0.3)]).expect("step")).is_empty());
}

#[test]
fn sort_outputs_from_the_third_hit_and_deletes_after_its_buffer() {
    let config = SortConfig {
        lost_track_buffer: 1,
        ..SortConfig::default()
    };
    let mut t = config.build().expect("valid");
    let mut out = Vec::new();
    for f in 1..=4 {
        out.push(ids(&t
            .step(f, &[det(u64::from(f), f, 100.0 + f64::from(f), 50.0, 0.9)])
            .expect("step")));
    }
    assert_eq!(out, vec![vec![], vec![], vec![1], vec![1]]);
    // Two frames without it exceed a one-frame buffer: the same box later starts a new track.
    for f in 7..=9 {
        out.push(ids(&t
            .step(f, &[det(u64::from(f), f, 104.0, 50.0, 0.9)])
            .expect("step")));
    }
    assert_eq!(out[4..], [vec![], vec![], vec![2]]);
}

#[test]
fn without_history_steps_the_same_and_keeps_nothing() {
    let run = |keep: bool| {
        let config = SortConfig {
            coast_frames: 2,
            ..SortConfig::default()
        };
        let t = config.build().expect("valid");
        let mut t = if keep { t } else { t.without_history() };
        let mut steps = Vec::new();
        for f in 1..=6 {
            let dets: Vec<Detection> = if f == 5 {
                Vec::new()
            } else {
                vec![det(u64::from(f), f, 100.0 + f64::from(f), 50.0, 0.9)]
            };
            steps.push(t.step(f, &dets).expect("step"));
        }
        (steps, t.finish().expect("finish"))
    };
    let (kept_steps, kept) = run(true);
    let (steps, nothing) = run(false);
    assert_eq!(steps, kept_steps);
    // The coasted frame 5 is among the steps' output.
    assert!(steps[4].len() == 1 && steps[5].len() == 1);
    assert_eq!(kept.n_points(), 4);
    assert!(nothing.is_empty());
}

#[test]
fn a_gap_steps_like_its_empty_frames_and_a_huge_gap_is_cheap() {
    let frames = [1, 2, 3, 6, 7];
    let run = |with_empty: bool| {
        let mut t = OcSortConfig::default().build().expect("defaults");
        let mut rows = Vec::new();
        for f in 1..=7 {
            if frames.contains(&f) {
                let d = det(f.into(), f, 100.0 + 3.0 * f64::from(f), 50.0, 0.9);
                rows.push(ids(&t.step(f, &[d]).expect("step")));
            } else if with_empty {
                t.step(f, &[]).expect("step");
            }
        }
        (rows, t.finish().expect("finish"))
    };
    assert_eq!(run(true), run(false));
    let mut t = SortConfig::default().build().expect("defaults");
    t.step(1, &[det(1, 1, 0.0, 0.0, 0.9)]).expect("step");
    t.step(u32::MAX, &[]).expect("a gap of four billion frames");
    assert!(t.association().boxes().is_empty());
}

#[test]
fn ocm_scores_the_angle_between_the_track_and_the_detection() {
    let noise = OcSortConfig::default().checked().expect("defaults").noise;
    let mut track = OcSortTrack::new(&noise, &corners(0.0, 0.0));
    track.predict(&noise);
    track
        .update(&noise, &corners(10.0, 0.0), 3)
        .expect("update");
    track.predict(&noise);
    track
        .update(&noise, &corners(20.0, 0.0), 3)
        .expect("update");
    // The direction is now to the right, measured from the observation at age 1 (the first
    // box is not an observation in the reference, only the last one).
    let v = track.velocity.expect("a direction");
    assert!((v[1] - 1.0).abs() < 1e-6 && v[0].abs() < 1e-12);
    let boxes = [
        BoxDetection::of(&det(1, 3, 40.0, 0.0, 1.0)).expect("box"), // ahead: angle 0
        BoxDetection::of(&det(2, 3, 10.0, 30.0, 0.5)).expect("box"), // below, score 0.5
        BoxDetection::of(&det(3, 3, -20.0, 0.0, 1.0)).expect("box"), // behind: angle π
    ];
    let refs: Vec<&BoxDetection> = boxes.iter().collect();
    let m = direction_scores(std::slice::from_ref(&track), &refs, 3);
    // (π/2 − |Δθ|)/π: 0.5 ahead, 0 at a right angle, −0.5 behind, times the score (to
    // 1e-3: the 1e-6 the reference adds to each norm leaves cos Δθ just short of ±1).
    assert!((m.values[0] - 0.5).abs() < 1e-3);
    assert!(m.values[1].abs() < 1e-6);
    assert!((m.values[2] + 0.5).abs() < 1e-3);
    let fresh = OcSortTrack::new(&noise, &corners(0.0, 0.0));
    let m = direction_scores(std::slice::from_ref(&fresh), &refs, 3);
    assert!(m.values.iter().all(|&v| v == 0.0), "no direction, no term");
}

#[test]
fn oru_equals_a_filter_that_saw_the_line_through_the_gap() {
    // Observed at ages 0-2 on a straight line at 4 px a frame, missed for two frames, then
    // seen on the line again. ORU rolls back to the first missed frame's prediction and
    // re-updates along the line: the same as a filter that saw the true boxes at every frame
    // and the last one twice (the virtual one, then the real one).
    for layout in [StateLayout::Corners, StateLayout::CentreAreaAspect] {
        let config = OcSortConfig {
            state: layout,
            ..OcSortConfig::default()
        };
        let noise = config.checked().expect("valid").noise;
        let at = |k: u32| corners(4.0 * f64::from(k), 10.0);
        let mut track = OcSortTrack::new(&noise, &at(0));
        let mut seen = BoxFilter::new(&noise, &at(0));
        let mut coasted = BoxFilter::new(&noise, &at(0));
        for k in 1..=5 {
            track.predict(&noise);
            seen.predict(&noise);
            coasted.predict(&noise);
            let z = noise.layout.measure(&at(k));
            if k == 3 || k == 4 {
                seen.update(&noise, &z).expect("update");
                continue;
            }
            track.update(&noise, &at(k), 3).expect("update");
            seen.update(&noise, &z).expect("update");
            coasted.update(&noise, &z).expect("update");
            if k == 5 {
                seen.update(&noise, &z).expect("update");
            }
        }
        for i in 0..8 {
            let scale = seen.x[i].abs().max(1.0);
            assert!(
                (track.filter.x[i] - seen.x[i]).abs() < 1e-9 * scale,
                "{layout:?} state {i}: {} against {}",
                track.filter.x[i],
                seen.x[i]
            );
        }
        assert!(
            (track.filter.x[4] - coasted.x[4]).abs() > 1e-6,
            "{layout:?}: ORU changes the state"
        );
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let mut t = SortConfig::default().build().expect("defaults");
    t.step(5, &[]).expect("step");
    assert!(matches!(
        t.step(5, &[]),
        Err(Error::FramesOutOfOrder {
            frame: 5,
            previous: 5
        })
    ));
    let point = Detection::point(1, 6, Vec2::new(1.0, 2.0));
    assert!(t.step(6, &[point]).is_err());
    assert!(t.step(7, &[det(1, 7, 0.0, 0.0, f64::NAN)]).is_err());
    let bad = [
        SortConfig {
            lost_track_buffer: MAX_LOST_TRACK_BUFFER + 1,
            ..SortConfig::default()
        }
        .build()
        .err(),
        SortConfig {
            frame_rate: 0.0,
            ..SortConfig::default()
        }
        .build()
        .err(),
        SortConfig {
            minimum_iou_threshold: 1.5,
            ..SortConfig::default()
        }
        .build()
        .err(),
        SortConfig {
            minimum_consecutive_frames: MAX_CONSECUTIVE_FRAMES + 1,
            ..SortConfig::default()
        }
        .build()
        .err(),
    ];
    assert!(bad.iter().all(Option::is_some));
    let bad_oc = [
        OcSortConfig {
            delta_t: 0,
            ..OcSortConfig::default()
        }
        .build()
        .err(),
        OcSortConfig {
            direction_consistency_weight: f64::INFINITY,
            ..OcSortConfig::default()
        }
        .build()
        .err(),
    ];
    assert!(bad_oc.iter().all(Option::is_some));
    let bad_bt = ByteTrackConfig {
        low_conf_det_threshold: 0.8,
        ..ByteTrackConfig::default()
    };
    let message = bad_bt.build().expect_err("refused").to_string();
    assert!(message.contains("low_conf_det_threshold"), "{message}");
}

#[test]
fn frame_rate_scales_the_buffer_as_the_reference_does() {
    // ceil(fps / 30 · buffer), at least 1 for a positive buffer, 0 for none.
    let misses = |buffer, fps| {
        SortConfig {
            lost_track_buffer: buffer,
            frame_rate: fps,
            ..SortConfig::default()
        }
        .checked()
        .expect("valid")
        .max_misses
    };
    assert_eq!(misses(30, 30.0), 30);
    assert_eq!(misses(30, 60.0), 60);
    assert_eq!(misses(3, 15.0), 2);
    assert_eq!(misses(0, 30.0), 0);
    assert_eq!(misses(1, 1.0), 1);
}

#[test]
fn coasting_outputs_confirmed_tracks_at_their_prediction_through_a_gap() {
    let config = SortConfig {
        coast_frames: 2,
        minimum_consecutive_frames: 2,
        ..SortConfig::default()
    };
    let mut t = config.build().expect("valid");
    t.step(1, &[det(1, 1, 100.0, 50.0, 0.9)]).expect("step");
    assert_eq!(
        ids(&t.step(2, &[det(2, 2, 104.0, 50.0, 0.9)]).expect("step")),
        vec![1]
    );
    // Frame 3 without it: output at the prediction, which is the filter's box after the miss.
    let states = t.step(3, &[]).expect("step");
    assert_eq!(ids(&states), vec![1]);
    let predicted = t.association().boxes()[0];
    let tracker_model::Location::Box(b) = states[0].point.location else {
        panic!("a box");
    };
    assert_eq!([b.left, b.top, b.right(), b.bottom()], predicted);
    assert!(b.left > 104.0, "it moves on: {}", b.left);
    // Frames 4 and 5 are a gap (replayed): frame 4 is the second miss, output; frame 5 the
    // third, not output; at frame 6 it is found again.
    assert_eq!(
        ids(&t.step(6, &[det(6, 6, 120.0, 50.0, 0.9)]).expect("step")),
        vec![1]
    );
    let tracks = t.finish().expect("finish");
    let frames: Vec<u32> = tracks.tracks()[0]
        .points()
        .iter()
        .map(|p| p.frame)
        .collect();
    assert_eq!(frames, vec![2, 3, 4, 6]);
    // Without coasting (the reference's way) only the detections are output.
    let mut t = SortConfig::default().build().expect("defaults");
    for f in 1..=3 {
        t.step(
            f,
            &[det(f.into(), f, 100.0 + 4.0 * f64::from(f), 50.0, 0.9)],
        )
        .expect("step");
    }
    assert!(t.step(4, &[]).expect("step").is_empty());
    assert!(
        SortConfig {
            coast_frames: MAX_COAST_FRAMES + 1,
            ..SortConfig::default()
        }
        .build()
        .is_err()
    );
}

#[test]
fn the_overlap_groups_assign_as_the_dense_problem_on_random_scenes() {
    // 300 scenes of up to 40 tracks and 40 boxes, crowded enough that groups hold several of
    // each; a fixed linear congruential sequence, so the scenes are the same every run.
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let boxes = |n: usize, next: &mut dyn FnMut() -> f64| -> Vec<Corners> {
        (0..n)
            .map(|_| {
                let (x, y) = (300.0 * next(), 200.0 * next());
                let (w, h) = (10.0 + 30.0 * next(), 20.0 + 40.0 * next());
                [x, y, x + w, y + h]
            })
            .collect()
    };
    // An inverted row (corners crossed, as a diverged prediction can be) overlaps nothing.
    let inverted = [[50.0, 0.0, 10.0, 40.0], [0.0, 0.0, 20.0, 40.0]];
    // (The box at 15 starts within one width of the inverted row's left edge but after its
    // right one: the sweep's window is empty and must not be reversed.)
    let cols = [[15.0, 0.0, 35.0, 40.0], [0.0, 0.0, 20.0, 40.0]];
    let dense = Matrix::iou(&inverted, &cols);
    assert_eq!(
        assign_overlapping(&inverted, &cols, 0.3).expect("groups"),
        assign(&dense, &dense, 0.3).expect("dense")
    );
    let mut groups_seen = 0;
    for scene in 0..300 {
        let rows = boxes(scene % 40, &mut next);
        let cols = boxes((scene * 7) % 41, &mut next);
        for threshold in [0.1, 0.3] {
            let dense = Matrix::iou(&rows, &cols);
            let want = assign(&dense, &dense, threshold).expect("dense");
            let got = assign_overlapping(&rows, &cols, threshold).expect("groups");
            assert_eq!(got, want, "scene {scene}, threshold {threshold}");
            groups_seen += usize::from(want.matched.len() > 1);
        }
    }
    assert!(groups_seen > 100);
}
