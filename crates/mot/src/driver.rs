//! The one generic driver: any tracker of tracker-model's interface on detections from a
//! file or a stream. Online trackers run as batch ones through [`tracker_model::Online`].

use tracker_model::{
    BatchTracker, Detection, Frame, FrameClock, FrameDetections, MotRow, TrackSet, TrackState,
    Tracker, scans_of,
};

use crate::error::{Error, Result};

/// The rows of a MOTChallenge file as detections: row i (0-based, in file order) is detection
/// i + 1, with its frame, its box and its confidence as the score.
pub fn detections_of(rows: &[MotRow]) -> Vec<Detection> {
    rows.iter()
        .enumerate()
        .map(|(i, r)| Detection::boxed(i as u64 + 1, r.frame, r.bbox).with_score(r.confidence))
        .collect()
}

/// Box detections back as MOTChallenge rows, frame by frame (id −1; a detection without a
/// score gets confidence 1); a point detection is an error.
pub fn rows_of(scans: &[FrameDetections]) -> Result<Vec<MotRow>> {
    let mut rows = Vec::with_capacity(scans.iter().map(|s| s.detections.len()).sum());
    for scan in scans {
        for d in &scan.detections {
            let bbox = d.require_box("a detection file holds boxes")?;
            rows.push(MotRow {
                frame: scan.frame,
                id: -1,
                bbox,
                confidence: d.score.unwrap_or(1.0),
                world: [-1.0; 3],
            });
        }
    }
    Ok(rows)
}

/// Runs any tracker on `detections` (stamped in frames, or in seconds with a `clock`): they
/// are grouped by frame ([`scans_of`]) and given to the tracker as one window. Frames without
/// a detection are not stepped; each tracker jumps such a gap in one prediction.
pub fn run<T>(
    tracker: &mut T,
    detections: &[Detection],
    clock: Option<&FrameClock>,
) -> Result<TrackSet>
where
    T: BatchTracker + ?Sized,
    Error: From<T::Error>,
{
    let scans = scans_of(detections, clock)?;
    Ok(tracker.track(&scans)?)
}

/// Runs a frame-by-frame tracker on a stream of scans (frames in increasing order, e.g. read
/// from a socket or a camera as they come): each scan is stepped as it arrives and its
/// confirmed tracks' states handed to `on_step`; at the end of the stream the tracker
/// finishes. Memory is the tracker's own, not the stream's.
pub fn stream<T, I>(
    tracker: &mut T,
    scans: I,
    mut on_step: impl FnMut(Frame, &[TrackState]),
) -> Result<TrackSet>
where
    T: Tracker + ?Sized,
    I: IntoIterator<Item = FrameDetections>,
    Error: From<T::Error>,
{
    for scan in scans {
        let states = tracker.step(scan.frame, &scan.detections)?;
        on_step(scan.frame, &states);
    }
    Ok(tracker.finish()?)
}
