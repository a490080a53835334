//! The fuzz entry points.
//!
//! Each `fuzz_*` function takes arbitrary bytes, runs one parser the way the command line
//! does and checks what must hold of its result; it panics only when such a property fails
//! (the fuzz targets call these, and a stable test replays the committed corpora through them).

use crate::scenario_file::parse_scenario;

/// Fuzz entry: the MOTChallenge reader. A file that parses formats back to text that parses
/// to the same rows, and its rows with ids ≥ 0 group into tracks or give an error.
pub fn fuzz_mot(data: &[u8]) {
    let Ok(file) = tracker_model::read_mot(data) else {
        return;
    };
    let text = tracker_model::format_mot(&file.rows);
    let again = tracker_model::parse_mot(text.as_bytes());
    assert_eq!(
        again.as_ref(),
        Ok(&file.rows),
        "format_mot did not round-trip"
    );
    let _ = tracker_model::TrackSet::from_mot_rows(&file.rows);
    // The command-line conventions on top (headers, empty files).
    let text = String::from_utf8_lossy(data);
    let _ = mot::text::load_evaluation_pair((&text, "gt"), (&text, "pred"));
}

/// Fuzz entry: a scenario file (parsing and checks only; no pipeline runs).
pub fn fuzz_scenario_toml(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = parse_scenario(text);
    }
}

/// Fuzz entry: a `cargo xtask track` configuration. One that resolves prints as TOML that
/// loads back to the same configuration.
pub fn fuzz_track_config(data: &[u8]) {
    use mot::track::{TrackConfig, render_config};
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(config) = toml::from_str::<TrackConfig>(text) else {
        return;
    };
    let Ok(effective) = config.resolve(&[]) else {
        return;
    };
    let printed = render_config(&effective, None).expect("a resolved configuration prints");
    let back: TrackConfig = toml::from_str(&printed).expect("the printed configuration parses");
    let again = back
        .resolve(&[])
        .expect("the printed configuration resolves");
    assert_eq!(
        render_config(&again, None).expect("prints"),
        printed,
        "the configuration changed on the round trip"
    );
}

/// Fuzz entry: an HMM model as JSON (hmm-grid's `Hmm`, checked by its `try_from`). A model
/// that loads serialises and loads again.
pub fn fuzz_hmm_json(data: &[u8]) {
    let Ok(hmm) = serde_json::from_slice::<hmm_grid::Hmm>(data) else {
        return;
    };
    let json = serde_json::to_string(&hmm).expect("a checked model serialises");
    serde_json::from_str::<hmm_grid::Hmm>(&json).expect("a serialised model loads again");
}

/// Fuzz entry: a WAV file (sensors-audio through `hound`). A recording that loads is written
/// as 32-bit float WAV (or refused with a typed error when WAV cannot hold it) and reads back
/// with the same channels and length.
pub fn fuzz_wav(data: &[u8]) {
    let Ok(rec) = sensors_audio::Recording::read_wav(std::io::Cursor::new(data), 0.0) else {
        return;
    };
    let mut out = std::io::Cursor::new(Vec::new());
    match rec.write_wav(&mut out) {
        // A file can declare what WAV cannot store again (a byte rate over 32 bits).
        Err(sensors_audio::Error::Unsupported(_)) => return,
        written => written.expect("a loaded recording writes"),
    }
    let back = sensors_audio::Recording::read_wav(std::io::Cursor::new(out.into_inner()), 0.0)
        .expect("a written recording reads back");
    assert_eq!(back.n_channels(), rec.n_channels(), "channel count changed");
    assert_eq!(back.n_samples(), rec.n_samples(), "sample count changed");
}

/// Fuzz entry: one PNG/PGM/PPM image (sensors-video through `image`). A frame that decodes has
/// a pixel buffer of exactly the size it claims.
pub fn fuzz_image(data: &[u8]) {
    let name = std::path::Path::new("fuzz-input");
    let Ok(frame) = sensors_video::io::decode_image(data, name) else {
        return;
    };
    let channels = match frame.format() {
        sensors_video::PixelFormat::Grey => 1,
        sensors_video::PixelFormat::Rgb => 3,
    };
    assert_eq!(
        frame.data().len(),
        frame.width() * frame.height() * channels,
        "pixel buffer does not match the size"
    );
}

/// Fuzz entry: a YUV4MPEG2 stream (sensors-video through `y4m`). Every frame of a stream that
/// reads has the stream's size and format.
pub fn fuzz_y4m(data: &[u8]) {
    let Ok(frames) = sensors_video::io::read_y4m(data, "fuzz-input") else {
        return;
    };
    if let Some(first) = frames.first() {
        assert!(
            frames.iter().all(|f| (f.width(), f.height(), f.format())
                == (first.width(), first.height(), first.format())),
            "frames of one stream differ in size or format"
        );
    }
}

/// Fuzz entry: `cargo xtask eval` end to end. The bytes before the first NUL are the ground
/// truth, those after it the predictions (without a NUL, both are the same text); every metric
/// of a pair that loads is finite, and tracks scored against themselves have no FP and no FN.
pub fn fuzz_eval(data: &[u8]) {
    use eval_metrics::{EvalConfig, MatchConfig, evaluate};
    let (gt, pred) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, data),
    };
    let (gt, pred) = (String::from_utf8_lossy(gt), String::from_utf8_lossy(pred));
    let Ok(pair) = mot::text::load_evaluation_pair((&gt, "gt"), (&pred, "pred")) else {
        return;
    };
    let config = EvalConfig {
        matching: MatchConfig::iou(0.5),
    };
    let Ok(report) = evaluate(&pair.gt, &pair.pred, &config) else {
        return;
    };
    let json = serde_json::to_value(&report).expect("a report serialises");
    assert!(all_numbers_finite(&json), "a metric is not finite: {json}");
    if pair.gt == pair.pred {
        // Every prediction is a truth box (IoU 1), so a maximum-similarity matching matches all.
        let clear = &report.clear;
        assert_eq!(
            (clear.false_positives, clear.false_negatives),
            (0, 0),
            "a file against itself: {json}"
        );
    }
}

/// The most detection rows `fuzz_track` runs (the rest of a longer file is dropped), so that
/// one input runs in milliseconds.
pub const FUZZ_TRACK_ROWS: usize = 40;

/// The work knobs of a tracker configuration and the most `fuzz_track` lets an input ask for
/// (a missing key gets this value too): the chains' lengths, windows, particle counts,
/// coasting and extrapolation. The tables' parsing and checks with any value are fuzzed by
/// `track_config`.
const FUZZ_TRACK_CAPS: [(&str, &str, i64); 11] = [
    ("offline", "samples_per_detection", 2),
    ("offline", "min_samples", 300),
    ("online", "samples_per_scan", 5),
    ("online", "window", 4),
    ("online", "coast_scans", 8),
    ("fit", "iterations", 1),
    ("phd", "particles_per_target", 30),
    ("phd", "birth_particles", 15),
    ("phd", "max_particles", 3000),
    ("boxes", "extrapolate_frames", 5),
    ("phd_labels", "max_misses", 16),
];

/// Fuzz entry: `cargo xtask track` end to end, every tracker. The bytes before the first NUL
/// are the detection file (at most [`FUZZ_TRACK_ROWS`] rows are run), those after it a
/// configuration TOML (none without a NUL), its work knobs capped (`FUZZ_TRACK_CAPS`). Frame
/// numbers are arbitrary, so far-apart frames are fuzzed too. Every tracker either returns a
/// typed error or tracks whose points are finite boxes of positive size, at frames within the
/// input's first and last frame widened by `[boxes] extrapolate_frames`.
pub fn fuzz_track(data: &[u8]) {
    use mot::track::{TrackConfig, TrackerKind, empty_output_warning, track_detections};
    let (dets, config) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], Some(&data[i + 1..])),
        None => (data, None),
    };
    let Ok((mut rows, _notes)) = mot::text::read_detections(&String::from_utf8_lossy(dets), "dets")
    else {
        return;
    };
    rows.truncate(FUZZ_TRACK_ROWS);
    let mut table = match config.map(std::str::from_utf8) {
        None => toml::Table::new(),
        Some(Ok(text)) => match text.parse::<toml::Table>() {
            Ok(table) => table,
            Err(_) => return,
        },
        Some(Err(_)) => return,
    };
    for (name, key, cap) in FUZZ_TRACK_CAPS {
        let entry = table
            .entry(name)
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        if let toml::Value::Table(t) = entry {
            match t.get(key) {
                Some(toml::Value::Integer(v)) if *v <= cap => {}
                Some(toml::Value::Integer(_)) | None => {
                    t.insert(key.into(), toml::Value::Integer(cap));
                }
                Some(_) => {}
            }
        }
    }
    let Ok(settings) = table.try_into::<TrackConfig>() else {
        return;
    };
    let Ok(effective) = settings.resolve(&rows) else {
        return;
    };
    let extra = effective.boxes.extrapolate_frames;
    let first = rows.iter().map(|r| r.frame).min().unwrap_or(0);
    let last = rows.iter().map(|r| r.frame).max().unwrap_or(0);
    let span = first.saturating_sub(extra)..=last.saturating_add(extra);
    for tracker in TrackerKind::ALL {
        let Ok(set) = track_detections(tracker, &rows, &settings, 1) else {
            continue;
        };
        let _ = empty_output_warning(tracker, &rows, &effective, &set);
        for track in set.tracks() {
            for p in track.points() {
                assert!(
                    span.contains(&p.frame),
                    "{tracker}: a point at frame {} outside {span:?}",
                    p.frame
                );
                if let tracker_model::Location::Box(b) = p.location {
                    assert!(
                        [b.left, b.top, b.width, b.height]
                            .iter()
                            .all(|v| v.is_finite())
                            && b.width > 0.0
                            && b.height > 0.0,
                        "{tracker}: frame {}: box {b:?}",
                        p.frame
                    );
                }
            }
        }
    }
}

fn all_numbers_finite(v: &serde_json::Value) -> bool {
    match v {
        serde_json::Value::Number(n) => n.as_f64().is_none_or(f64::is_finite),
        serde_json::Value::Array(a) => a.iter().all(all_numbers_finite),
        serde_json::Value::Object(o) => o.values().all(all_numbers_finite),
        _ => true,
    }
}

/// A fuzz entry function.
pub type FuzzEntry = fn(&[u8]);

/// The fuzz targets: name (also the corpus directory under `fuzz/corpus/`) and entry.
pub const FUZZ_TARGETS: [(&str, FuzzEntry); 9] = [
    ("mot_reader", fuzz_mot),
    ("scenario_toml", fuzz_scenario_toml),
    ("track_config", fuzz_track_config),
    ("hmm_json", fuzz_hmm_json),
    ("wav_reader", fuzz_wav),
    ("image_reader", fuzz_image),
    ("y4m_reader", fuzz_y4m),
    ("eval_end_to_end", fuzz_eval),
    ("track_end_to_end", fuzz_track),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fuzz_corpora_replay_without_a_failure() {
        // Every input the fuzzers kept (and every crash they found, once fixed) runs through
        // the same entry functions on stable Rust.
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus");
        for (name, entry) in FUZZ_TARGETS {
            let dir = root.join(name);
            let mut n = 0;
            for file in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{dir:?}: {e}")) {
                let path = file.unwrap().path();
                entry(&std::fs::read(&path).unwrap());
                n += 1;
            }
            assert!(n > 0, "no corpus for {name}");
        }
    }
}
