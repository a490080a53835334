//! Resources on big inputs (issue 20): `eval` on 10⁶-row files generated here. Peak heap is
//! measured by a counting global allocator (`peak_alloc`), which is why this is a test binary of
//! its own. Memory must follow the number of rows, not the span of frame numbers: the same rows
//! spread over a frame span a thousand times larger may not cost more.

use std::time::Instant;

use eval_metrics::{EvalConfig, evaluate};
use peak_alloc::PeakAlloc;
use scenarios::mot::load_evaluation_pair;

#[global_allocator]
static HEAP: PeakAlloc = PeakAlloc;

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
