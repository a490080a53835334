//! The three trackers with their defaults equal roboflow `trackers` 2.6.1 on three files:
//! the same (frame, detection) rows output, with ids equal up to renaming. The reference's
//! output was recorded by `docs/comparisons/roboflow_trackers.py record` into
//! `testdata/reference/` (see `testdata/README.md` for the files).
//! - `walkers-det.txt`: scores 0.5 and 0.9, so ByteTrack's second stage takes the 0.5 boxes;
//! - `realistic-301-det.txt`: a realistic pedestrian file (scores spread over 0.1-1);
//! - `gaps-302-det.txt`: another, with every detection of frames 40-44, 100-101 and 170-179
//!   removed (gaps of 5, 2 and 10 frames, which OC-SORT re-updates across).

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

use box_trackers::{Assigned, Association, BoxTracker, ByteTrackConfig, OcSortConfig, SortConfig};
use tracker_model::{Detection, Frame, parse_mot};

const FILES: [&str; 4] = [
    "walkers-det",
    "realistic-301-det",
    "gaps-302-det",
    "realistic-10fps-303-det",
];

fn testdata(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("testdata")
        .join(name)
}

/// The file's detections by frame, each with its 0-based row as id and the file's score.
fn scans(name: &str) -> BTreeMap<Frame, Vec<Detection>> {
    let text = std::fs::read(testdata(&format!("{name}.txt"))).expect("test file");
    let rows = parse_mot(text.as_slice()).expect("a MOTChallenge file");
    let mut scans: BTreeMap<Frame, Vec<Detection>> = BTreeMap::new();
    for (i, r) in rows.iter().enumerate() {
        let d = Detection::boxed(i as u64, r.frame, r.bbox).with_score(r.confidence);
        scans.entry(r.frame).or_default().push(d);
    }
    scans
}

/// (frame, row) → id of the reference's output.
fn reference(name: &str, tracker: &str) -> BTreeMap<(Frame, u64), u64> {
    let path = testdata(&format!("reference/{name}.{tracker}.txt"));
    let text = std::fs::read_to_string(path).expect("recorded reference output");
    text.lines()
        .map(|line| {
            let v: Vec<u64> = line
                .split(',')
                .map(|s| s.parse().expect("a number"))
                .collect();
            ((v[0] as Frame, v[1]), v[2])
        })
        .collect()
}

fn ours(
    scans: &BTreeMap<Frame, Vec<Detection>>,
    mut step: impl FnMut(Frame, &[Detection]) -> Vec<Assigned>,
) -> BTreeMap<(Frame, u64), u64> {
    let mut out = BTreeMap::new();
    for (&frame, detections) in scans {
        for a in step(frame, detections) {
            assert_eq!(
                Some(a.bbox),
                detections[a.index].bbox(),
                "the detection's own box"
            );
            out.insert((frame, a.detection.0), a.track.0);
        }
    }
    out
}

/// The same rows, and one id of ours for each id of the reference and back.
fn check(name: &str, tracker: &str, got: &BTreeMap<(Frame, u64), u64>) {
    let want = reference(name, tracker);
    let (got_rows, want_rows): (BTreeSet<_>, BTreeSet<_>) =
        (got.keys().collect(), want.keys().collect());
    let missing: Vec<_> = want_rows.difference(&got_rows).take(5).collect();
    let extra: Vec<_> = got_rows.difference(&want_rows).take(5).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "{name} {tracker}: {} rows against the reference's {}; missing {missing:?}, extra {extra:?}",
        got.len(),
        want.len()
    );
    let (mut forward, mut backward) = (HashMap::new(), HashMap::new());
    for (key, &theirs) in &want {
        let mine = got[key];
        assert_eq!(
            *forward.entry(theirs).or_insert(mine),
            mine,
            "{name} {tracker}: id {theirs} at {key:?}"
        );
        assert_eq!(
            *backward.entry(mine).or_insert(theirs),
            theirs,
            "{name} {tracker}: our id {mine} at {key:?}"
        );
    }
    assert!(!want.is_empty());
}

/// Every file through a tracker built by `make`, against the reference's output for `name`.
fn check_all<A: Association>(name: &str, make: impl Fn() -> BoxTracker<A>) {
    for file in FILES {
        let mut t = make();
        let got = ours(&scans(file), |f, d| t.update(f, d).expect("step"));
        check(file, name, &got);
    }
}

#[test]
fn sort_equals_the_reference() {
    check_all("sort", || SortConfig::default().build().expect("defaults"));
}

#[test]
fn bytetrack_equals_the_reference() {
    check_all("bytetrack", || {
        ByteTrackConfig::default().build().expect("defaults")
    });
}

#[test]
fn ocsort_equals_the_reference() {
    check_all("ocsort", || {
        OcSortConfig::default().build().expect("defaults")
    });
}
