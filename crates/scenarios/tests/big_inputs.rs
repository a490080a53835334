//! Resources on big inputs: `eval` and `track` on 10⁶-row files generated here (the
//! MCMCDA and PHD trackers on fewer rows: see their tests). Peak heap is
//! measured by a counting global allocator (`peak_alloc`), which is why this is a test binary of
//! its own. Memory must follow the number of rows, not the span of frame numbers: the same rows
//! spread over a frame span a thousand times larger may not cost more.

use std::time::Instant;

use eval_metrics::{EvalConfig, evaluate};
use mot::text::{load_evaluation_pair, read_detections};
use mot::track::{TrackConfig, TrackerKind, track_detections};
use peak_alloc::PeakAlloc;

#[global_allocator]
static HEAP: PeakAlloc = PeakAlloc;

/// The peak counter is global: the tests of this binary run one at a time.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// `n_objects` boxes on every used frame, `n_frames` used frames `stride` apart; predictions
/// shifted by a pixel, with one identity swap per object every 1000 frames.
fn files(n_objects: u64, n_frames: u64, stride: u64) -> (String, String) {
    let mut gt = String::with_capacity((n_objects * n_frames * 40) as usize);
    let mut pred = String::with_capacity(gt.capacity());
    for f in 0..n_frames {
        let frame = 1 + f * stride;
        for id in 0..n_objects {
            let x = (id * 60 + f % 50) as f64;
            gt.push_str(&format!("{frame},{id},{x},100,40,80,1,-1,-1,-1\n"));
            let pid = if (f / 1000) % 2 == 1 {
                (id + 1) % n_objects
            } else {
                id
            };
            pred.push_str(&format!("{frame},{pid},{},101,40,80,1,-1,-1,-1\n", x + 1.0));
        }
    }
    (gt, pred)
}

/// Peak heap (bytes) above the input texts, and seconds, of parsing and scoring one pair.
fn measure(gt: &str, pred: &str) -> (usize, f64) {
    HEAP.reset_peak_usage();
    let base = HEAP.current_usage();
    let start = Instant::now();
    let pair = load_evaluation_pair((gt, "gt"), (pred, "pred")).expect("the files load");
    let report = evaluate(&pair.gt, &pair.pred, &EvalConfig::default()).expect("scored");
    let seconds = start.elapsed().as_secs_f64();
    assert!(
        report.clear.mota > 0.9 && report.clear.mota < 1.0,
        "{}",
        report.clear.mota
    );
    (HEAP.peak_usage() - base, seconds)
}

#[test]
fn eval_on_a_million_rows_costs_memory_by_rows_not_by_frame_span() {
    let _serial = one_at_a_time();
    let (n_objects, n_frames) = (10, 100_000);
    let rows = (n_objects * n_frames) as f64;
    let (gt, pred) = files(n_objects, n_frames, 1);
    let (dense_peak, dense_s) = measure(&gt, &pred);
    drop((gt, pred));
    let (gt, pred) = files(n_objects, n_frames, 1000);
    let (sparse_peak, sparse_s) = measure(&gt, &pred);
    eprintln!(
        "eval, 1e6 rows: frames 1..1e5: peak heap {:.1} MB ({:.0} B/row), {:.2} µs/row; \
         frames 1..1e8 (stride 1000): peak heap {:.1} MB, {:.2} µs/row",
        dense_peak as f64 / 1e6,
        dense_peak as f64 / rows,
        1e6 * dense_s / rows,
        sparse_peak as f64 / 1e6,
        1e6 * sparse_s / rows,
    );
    // Proportional to the data: a fixed budget per row (two parsed rows, the tracks, the
    // per-frame similarity matrices of HOTA's 19 thresholds stay per frame).
    assert!(dense_peak as f64 / rows < 2000.0, "{dense_peak} bytes");
    // Not to the span: 1000× the frame span may cost at most 10 % more.
    assert!(
        (sparse_peak as f64) < 1.1 * dense_peak as f64,
        "{sparse_peak} bytes over frames 1..1e8 against {dense_peak} over 1..1e5"
    );
}

/// A detection file: `n_objects` walkers, each seen on every used frame, `n_frames` used frames:
/// consecutive, or (`spread`) in bursts of 100 consecutive frames 100 000 frames apart, a
/// frame span 1000 times larger with the same rows and tracks as long as a burst. Walker i moves right at 1 + i/10 px per used frame from x = 200 i, with a
/// deterministic ±1 px jitter and box sizes varying by a few pixels (as detections do).
fn detections(n_objects: u64, n_frames: u64, spread: bool) -> String {
    let mut text = String::with_capacity((n_objects * n_frames * 44) as usize);
    for f in 0..n_frames {
        let frame = if spread {
            1 + f + (f / 100) * 99_900
        } else {
            1 + f
        };
        for id in 0..n_objects {
            let j = ((f * 7 + id * 3) % 3) as f64 - 1.0;
            let x = (id * 200) as f64 + (f % 1000) as f64 * (1.0 + id as f64 / 10.0) + j;
            let y = 100.0 + (id % 3) as f64 * 150.0 - j;
            let (w, h) = (40.0 + (f % 3) as f64, 90.0 + (f % 5) as f64);
            text.push_str(&format!("{frame},-1,{x},{y},{w},{h},1,-1,-1,-1\n"));
        }
    }
    text
}

/// Peak heap (bytes) above the detection text, seconds, and output points of reading the file
/// and tracking it.
fn measure_track(tracker: TrackerKind, text: &str) -> (usize, f64, usize) {
    HEAP.reset_peak_usage();
    let base = HEAP.current_usage();
    let start = Instant::now();
    let (rows, _) = read_detections(text, "dets").expect("the file loads");
    let tracks =
        track_detections(tracker, &rows, &TrackConfig::default(), 1).expect("the file tracks");
    let seconds = start.elapsed().as_secs_f64();
    (HEAP.peak_usage() - base, seconds, tracks.n_points())
}

/// Tracks `n_objects × n_frames` rows on consecutive frames and the same rows in bursts over a
/// span 1000 times larger; checks the memory budget per row and that the spread-out file costs
/// no more.
#[expect(
    clippy::print_stderr,
    reason = "the measurements are the test's record"
)]
fn track_by_rows_not_by_frame_span(tracker: TrackerKind, n_objects: u64, n_frames: u64) {
    let rows = (n_objects * n_frames) as f64;
    let text = detections(n_objects, n_frames, false);
    let (dense_peak, dense_s, dense_points) = measure_track(tracker, &text);
    drop(text);
    let text = detections(n_objects, n_frames, true);
    let (sparse_peak, sparse_s, sparse_points) = measure_track(tracker, &text);
    eprintln!(
        "track {tracker}, {rows:.0} rows: frames 1..{n_frames}: peak heap {:.1} MB \
         ({:.0} B/row), {:.2} µs/row, {dense_points} points out; in bursts over a span 1000× larger: peak heap \
         {:.1} MB ({:.0} B/row), {:.2} µs/row, {sparse_points} points out",
        dense_peak as f64 / 1e6,
        dense_peak as f64 / rows,
        1e6 * dense_s / rows,
        sparse_peak as f64 / 1e6,
        sparse_peak as f64 / rows,
        1e6 * sparse_s / rows,
    );
    // The walkers are tracked (nearly every row in a track), in the bursts too.
    assert!(
        dense_points as f64 > 0.9 * rows,
        "{tracker}: {dense_points} points"
    );
    assert!(
        sparse_points as f64 > 0.8 * rows,
        "{tracker}: {sparse_points} points"
    );
    assert!(
        dense_peak as f64 / rows < 6000.0,
        "{tracker}: {dense_peak} bytes"
    );
    assert!(
        (sparse_peak as f64) < 1.1 * dense_peak as f64 + 1e6,
        "{tracker}: {sparse_peak} bytes over a frame span 1000× larger against {dense_peak}"
    );
}

#[test]
fn track_on_a_million_rows_costs_memory_by_rows_not_by_frame_span() {
    let _serial = one_at_a_time();
    track_by_rows_not_by_frame_span(TrackerKind::Gnn, 10, 100_000);
}

#[test]
fn track_phd_and_mcmcda_cost_memory_by_rows_not_by_frame_span() {
    let _serial = one_at_a_time();
    track_by_rows_not_by_frame_span(TrackerKind::Phd, 10, 10_000);
    track_by_rows_not_by_frame_span(TrackerKind::Mcmcda, 10, 200);
}
