#!/usr/bin/env bash
# Per-frame time of box-trackers' SORT, ByteTrack and OC-SORT against trackforge 0.5.1 (MIT,
# crates.io) in one run, both in release, on the scene of crates/box-trackers/benches/
# association.rs (30 frames of 10, 100 and 1,000 walkers) and on any MOTChallenge files given.
#
#     bash docs/comparisons/trackforge_speed.sh [DETS.txt ...]
#
# It writes a throw-away Cargo project to /tmp/trackforge-speed that depends on trackforge from
# crates.io and on this repository's box-trackers by path; nothing of it is committed.
#
# Like for like: both sides get the same boxes and scores per frame, prepared before the clock
# starts, and do their whole step (prediction, IoU, assignment, updates, track births and
# deaths). trackforge runs with the settings closest to ours: SORT max_age 30, min_hits 3, IoU
# 0.3; ByteTrack track_thresh 0.6, buffer 30, match_thresh 0.9 (IoU ≥ 0.1), det_thresh 0.7,
# second_match_thresh 0.9; OC-SORT max_age 30, min_hits 3, IoU 0.3, delta_t 3, inertia 0.2.
# trackforge works in f32 and returns its tracks' boxes; ours works in f64 and returns the
# detections given to confirmed tracks.
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
dir=/tmp/trackforge-speed
mkdir -p "$dir/src"
cat > "$dir/Cargo.toml" <<EOF
[package]
name = "trackforge-speed"
version = "0.0.0"
edition = "2024"
publish = false

[dependencies]
trackforge = "=0.5.1"
box-trackers = { path = "$repo/crates/box-trackers" }
tracker-model = { path = "$repo/crates/tracker-model" }

[profile.release]
debug = "line-tables-only"

[workspace]
EOF
cat > "$dir/src/main.rs" <<'EOF'
use std::time::Instant;

use box_trackers::{ByteTrackConfig, OcSortConfig, SortConfig};
use tracker_model::{BoundingBox, Detection, Tracker, parse_mot};

type Frames = Vec<Vec<Detection>>;

fn scene(n: usize) -> Frames {
    let side = (n as f64).sqrt().ceil() as usize;
    (1..=30u32)
        .map(|f| {
            (0..n)
                .map(|i| {
                    let (row, col) = ((i / side) as f64, (i % side) as f64);
                    let speed = 1.0 + (i % 3) as f64;
                    let jitter = (0.7 * f64::from(f) + i as f64).sin();
                    let left = 40.0 * col + speed * f64::from(f) + jitter;
                    let b = BoundingBox::new(left, 80.0 * row + jitter, 20.0, 50.0).unwrap();
                    let score = if (i + f as usize).is_multiple_of(10) { 0.4 } else { 0.9 };
                    Detection::boxed((i + n * f as usize) as u64, f, b).with_score(score)
                })
                .collect()
        })
        .collect()
}

fn file(path: &str) -> Frames {
    let rows = parse_mot(std::fs::read(path).unwrap().as_slice()).unwrap();
    let last = rows.iter().map(|r| r.frame).max().unwrap_or(0) as usize;
    let mut frames: Frames = vec![Vec::new(); last];
    for (i, r) in rows.iter().enumerate() {
        let d = Detection::boxed(i as u64, r.frame, r.bbox).with_score(r.confidence);
        frames[r.frame as usize - 1].push(d);
    }
    frames
}

fn tf_input(frames: &Frames) -> Vec<Vec<([f32; 4], f32, i64)>> {
    frames
        .iter()
        .map(|ds| {
            ds.iter()
                .map(|d| {
                    let b = d.bbox().unwrap();
                    let tlwh = [b.left as f32, b.top as f32, b.width as f32, b.height as f32];
                    (tlwh, d.score.unwrap() as f32, 0)
                })
                .collect()
        })
        .collect()
}

/// Median over 11 runs of the time per frame, in µs.
fn median(mut run: impl FnMut() -> f64) -> f64 {
    let mut t: Vec<f64> = (0..11).map(|_| run()).collect();
    t.sort_by(f64::total_cmp);
    t[5]
}

fn ours<T: Tracker>(make: impl Fn() -> T, frames: &Frames) -> f64 {
    median(|| {
        let mut tracker = make();
        let start = Instant::now();
        for (f, ds) in frames.iter().enumerate() {
            std::hint::black_box(tracker.step(f as u32 + 1, ds).unwrap());
        }
        start.elapsed().as_secs_f64() * 1e6 / frames.len() as f64
    })
}

macro_rules! theirs {
    ($make:expr, $input:expr) => {
        median(|| {
            let mut tracker = $make;
            let input = $input.clone();
            let n = input.len();
            let start = Instant::now();
            for ds in input {
                std::hint::black_box(tracker.update(ds));
            }
            start.elapsed().as_secs_f64() * 1e6 / n as f64
        })
    };
}

fn compare(name: &str, frames: &Frames) {
    let input = tf_input(frames);
    let boxes: usize = frames.iter().map(Vec::len).sum();
    let rows = [
        (
            "sort",
            ours(|| SortConfig::default().build().unwrap(), frames),
            theirs!(trackforge::trackers::sort::Sort::new(30, 3, 0.3), input),
        ),
        (
            "bytetrack",
            ours(|| ByteTrackConfig::default().build().unwrap(), frames),
            theirs!(
                trackforge::trackers::byte_track::ByteTrack::from_params(
                    trackforge::trackers::byte_track::ByteTrackParams {
                        common: trackforge::trackers::common::CommonParams::new(30, 3),
                        track_thresh: 0.6,
                        match_thresh: 0.9,
                        det_thresh: 0.7,
                        second_match_thresh: 0.9,
                    }
                ),
                input
            ),
        ),
        (
            "ocsort",
            ours(|| OcSortConfig::default().build().unwrap(), frames),
            theirs!(trackforge::trackers::ocsort::OcSort::new(30, 3, 0.3, 3, 0.2), input),
        ),
    ];
    for (tracker, us, tf) in rows {
        println!(
            "{name} ({boxes} boxes, {} frames) {tracker}: box-trackers {us:.1} µs/frame, \
             trackforge {tf:.1} µs/frame, ratio {:.2}",
            frames.len(),
            tf / us
        );
    }
}

fn main() {
    for n in [10, 100, 1000] {
        compare(&format!("scene {n}"), &scene(n));
    }
    for path in std::env::args().skip(1) {
        compare(&path, &file(&path));
    }
}
EOF
files=()
for f in "$@"; do files+=("$(realpath "$f")"); done
cd "$dir" && cargo run --release --quiet -- "${files[@]}"
