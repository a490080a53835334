//! The evaluation protocol of Oh & Jung (2015, §4): a mask hides part of the scene; every true
//! trajectory that crosses the mask becomes a gap whose hidden positions are to be recovered
//! from the observations before and after it.

use serde::{Deserialize, Serialize};
use tracker_model::{Frame, Region2, TrackId, TrackSet};

use crate::gap::Observation;

/// One masked crossing of one trajectory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GapCase {
    /// The true trajectory it comes from.
    pub truth_id: TrackId,
    /// Which crossing of that trajectory (0 for the first).
    pub crossing: usize,
    /// Observations outside the mask before the crossing (since the previous crossing).
    pub before: Vec<Observation>,
    /// The hidden true positions inside the mask.
    pub hidden: Vec<Observation>,
    /// Observations outside the mask after the crossing (until the next crossing).
    pub after: Vec<Observation>,
}

/// Whether frame `next` comes right after `frame` (`frame + 1` would overflow at u32::MAX).
fn follows(frame: Frame, next: Frame) -> bool {
    frame.checked_add(1) == Some(next)
}

/// Cuts every truth trajectory at the mask. A run of consecutive frames inside the mask is a
/// gap when the trajectory is seen outside the mask both before and after it; a second crossing
/// is a separate gap; trajectories that start or end inside the mask contribute no gap for that
/// run. Points must be at consecutive frames within a track for a run to count as one crossing;
/// a frame missing from the truth also ends a run.
pub fn gaps_from_mask(truth: &TrackSet, mask: &Region2) -> Vec<GapCase> {
    let mut out = Vec::new();
    for track in truth.tracks() {
        let pts: Vec<Observation> = track
            .points()
            .iter()
            .map(|p| Observation {
                frame: p.frame,
                position: p.location.position(),
            })
            .collect();
        let inside: Vec<bool> = pts.iter().map(|o| mask.contains(&o.position)).collect();
        // Runs as (start, end) index ranges, alternating outside / inside.
        let mut runs: Vec<(usize, usize, bool)> = Vec::new();
        for (k, &flag) in inside.iter().enumerate() {
            let contiguous = k > 0 && follows(pts[k - 1].frame, pts[k].frame);
            match runs.last_mut() {
                Some(run) if run.2 == flag && contiguous => run.1 = k + 1,
                _ => runs.push((k, k + 1, flag)),
            }
        }
        let mut crossing = 0;
        for r in 1..runs.len().saturating_sub(1) {
            let (prev, cur, next) = (runs[r - 1], runs[r], runs[r + 1]);
            let frames_join = follows(pts[prev.1 - 1].frame, pts[cur.0].frame)
                && follows(pts[cur.1 - 1].frame, pts[next.0].frame);
            if cur.2 && !prev.2 && !next.2 && frames_join {
                out.push(GapCase {
                    truth_id: track.id(),
                    crossing,
                    before: pts[prev.0..prev.1].to_vec(),
                    hidden: pts[cur.0..cur.1].to_vec(),
                    after: pts[next.0..next.1].to_vec(),
                });
                crossing += 1;
            }
        }
    }
    out
}
