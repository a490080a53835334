//! SORT, ByteTrack and OC-SORT (the `box-trackers` crate) on a detection file: every row a
//! box detection with the file's confidence as its score, stepped frame by frame.

use box_trackers::{Association, BoxTracker};
use tracker_model::{BatchTracker, Detection, MotRow, Online, TrackSet, scans_of};

use super::{EffectiveConfig, TrackerKind};
use crate::error::Result;

/// Tracks `rows` with the box tracker `kind`, its `[sort]`, `[bytetrack]` or `[ocsort]`
/// settings from `config`; ids from 1 in the order tracks are confirmed.
pub(crate) fn track_sort_family(
    kind: TrackerKind,
    rows: &[MotRow],
    config: &EffectiveConfig,
) -> Result<TrackSet> {
    let detections: Vec<Detection> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| Detection::boxed(i as u64, r.frame, r.bbox).with_score(r.confidence))
        .collect();
    let scans = scans_of(&detections, None)?;
    match kind {
        TrackerKind::Sort => run(config.sort.build()?, &scans),
        TrackerKind::ByteTrack => run(config.bytetrack.build()?, &scans),
        _ => run(config.ocsort.build()?, &scans),
    }
}

fn run<A: Association>(
    tracker: BoxTracker<A>,
    scans: &[tracker_model::FrameDetections],
) -> Result<TrackSet> {
    Ok(Online(tracker).track(scans)?)
}

/// Why a box tracker may have found no track, with the settings that decide it.
pub(crate) fn why_empty(kind: TrackerKind, config: &EffectiveConfig) -> String {
    let (start, hits, iou) = match kind {
        TrackerKind::Sort => (
            config.sort.track_activation_threshold,
            config.sort.minimum_consecutive_frames,
            config.sort.minimum_iou_threshold,
        ),
        TrackerKind::ByteTrack => (
            config.bytetrack.track_activation_threshold,
            config.bytetrack.minimum_consecutive_frames,
            config.bytetrack.minimum_iou_threshold,
        ),
        _ => (
            config.ocsort.high_conf_det_threshold,
            config.ocsort.minimum_consecutive_frames,
            config.ocsort.minimum_iou_threshold,
        ),
    };
    format!(
        "a track starts from a box scoring at least {start} (the file's confidence column) and \
         is output after {hits} matches at IoU ≥ {iou} in consecutive frames"
    )
}
