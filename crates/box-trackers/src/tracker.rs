//! [`BoxTracker`]: any of the three associations behind tracker-model's [`Tracker`].
//!
//! The reference steps every frame, with or without detections. A step after a gap of k
//! frames replays the k − 1 empty frames first (each one prediction and one more miss, as
//! there), which stops as soon as no track is left: every track dies after at most
//! `max_misses + 1` empty frames, so a gap costs at most that many frames of work, however
//! long it is.

use tracker_model::{
    BoundingBox, Detection, DetectionId, Frame, Track, TrackId, TrackPoint, TrackSet, TrackState,
    Tracker,
};

use crate::error::{Error, Result};
use crate::kalman::{BoxFilter, Corners, StateLayout};

/// A box detection as the associations read it.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxDetection {
    /// The box.
    pub bbox: BoundingBox,
    /// Its corners `[x₁, y₁, x₂, y₂]`.
    pub corners: Corners,
    /// The detector's score (1 when the detection has none, as in the reference).
    pub score: f64,
}

impl BoxDetection {
    /// Reads a detection: it must be a box, finite, with a finite score if it has one.
    pub fn of(d: &Detection) -> Result<Self> {
        let bbox = d.require_box("SORT, ByteTrack and OC-SORT track boxes")?;
        let corners = [bbox.left, bbox.top, bbox.right(), bbox.bottom()];
        if !corners.iter().all(|v| v.is_finite()) {
            return Err(tracker_model::Error::NonFinite {
                what: "detection box",
            }
            .into());
        }
        let score = d.score.unwrap_or(1.0);
        if !score.is_finite() {
            return Err(tracker_model::Error::NonFinite {
                what: "detection score",
            }
            .into());
        }
        Ok(Self {
            bbox,
            corners,
            score,
        })
    }
}

/// Hands out track numbers 0, 1, 2, … in the order tracks are confirmed (the reference's
/// order); a track's id is its number + 1.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct IdSource {
    next: u64,
}

impl IdSource {
    /// The next number.
    pub fn allocate(&mut self) -> u64 {
        self.next += 1;
        self.next - 1
    }
}

/// One frame of a box tracker's association.
pub trait Association {
    /// Whether any track (confirmed or not) is alive.
    fn has_tracks(&self) -> bool;

    /// One frame: predict every track, associate, update, start and end tracks. Returns the
    /// detections that belong to a confirmed track, as (detection index, track number).
    fn associate(
        &mut self,
        detections: &[BoxDetection],
        ids: &mut IdSource,
    ) -> Result<Vec<(usize, u64)>>;

    /// The confirmed tracks missed for 1 to `max` frames now, as (track number, predicted
    /// box).
    fn coasting(&self, max: u32) -> Vec<(u64, Corners)>;
}

/// [`Association::coasting`] over any association's tracks, given as (number, misses,
/// filter).
pub(crate) fn coasting_of<'a>(
    tracks: impl Iterator<Item = (Option<u64>, u32, &'a BoxFilter)>,
    layout: StateLayout,
    max: u32,
) -> Vec<(u64, Corners)> {
    tracks
        .filter(|(_, misses, _)| (1..=max).contains(misses))
        .filter_map(|(number, _, filter)| Some((number?, filter.corners(layout))))
        .collect()
}

/// A detection given to a confirmed track at a step.
#[derive(Debug, Clone, PartialEq)]
pub struct Assigned {
    /// The track.
    pub track: TrackId,
    /// The detection's id.
    pub detection: DetectionId,
    /// The detection's position in the step's slice.
    pub index: usize,
    /// The detection's box (the reference outputs detection boxes, not filtered ones).
    pub bbox: BoundingBox,
}

/// A box tracker: an [`Association`] stepped frame by frame, with the confirmed tracks'
/// boxes kept for [`Tracker::finish`].
#[derive(Debug, Clone)]
pub struct BoxTracker<A> {
    association: A,
    /// Frames a confirmed track is output at its prediction after a miss (0: only the
    /// detections given to tracks, as the reference).
    coast_frames: u32,
    ids: IdSource,
    previous: Option<Frame>,
    /// Whether the output is kept for [`Tracker::finish`] (off for a stream read step by
    /// step, whose memory then grows with the live tracks only).
    keep_history: bool,
    /// The confirmed tracks' output, by track number (numbers are handed out in order).
    tracks: Vec<Track>,
}

impl<A: Association> BoxTracker<A> {
    /// A tracker around `association`, before its first frame.
    pub fn new(association: A) -> Self {
        Self {
            association,
            coast_frames: 0,
            ids: IdSource::default(),
            previous: None,
            keep_history: true,
            tracks: Vec::new(),
        }
    }

    /// The same tracker keeping no output for [`Tracker::finish`] (which then returns no
    /// track): for a stream whose steps are all the caller reads, so memory stays bounded by
    /// the live tracks however long it runs.
    #[must_use]
    pub fn without_history(mut self) -> Self {
        self.keep_history = false;
        self
    }

    /// The same tracker, outputting each confirmed track at its predicted box for up to
    /// `frames` frames after a miss (see the configs' `coast_frames`).
    #[must_use]
    pub fn coasting(mut self, frames: u32) -> Self {
        self.coast_frames = frames;
        self
    }

    /// The association (its settings and live tracks).
    pub fn association(&self) -> &A {
        &self.association
    }

    /// Steps to `frame` with its detections and returns those given to confirmed tracks, in
    /// the association's order (the coasted tracks are [`BoxTracker::coasted`]).
    pub fn update(&mut self, frame: Frame, detections: &[Detection]) -> Result<Vec<Assigned>> {
        let boxes = detections
            .iter()
            .map(BoxDetection::of)
            .collect::<Result<Vec<_>>>()?;
        if let Some(previous) = self.previous {
            if frame <= previous {
                return Err(Error::FramesOutOfOrder { frame, previous });
            }
            for empty in previous + 1..frame {
                if !self.association.has_tracks() {
                    break;
                }
                self.association.associate(&[], &mut self.ids)?;
                self.record_coasted(empty)?;
            }
        }
        self.previous = Some(frame);
        let pairs = self.association.associate(&boxes, &mut self.ids)?;
        let mut out = Vec::with_capacity(pairs.len());
        for (index, number) in pairs {
            let track = TrackId(number + 1);
            let bbox = boxes[index].bbox;
            self.record(number, frame, bbox)?;
            out.push(Assigned {
                track,
                detection: detections[index].id,
                index,
                bbox,
            });
        }
        self.record_coasted(frame)?;
        Ok(out)
    }

    /// The confirmed tracks output at their predictions now (none unless coasting is on):
    /// (track, box), boxes that are no longer a valid box (a diverged prediction) left out.
    pub fn coasted(&self) -> Vec<(TrackId, BoundingBox)> {
        if self.coast_frames == 0 {
            return Vec::new();
        }
        let mut out: Vec<(TrackId, BoundingBox)> = self
            .association
            .coasting(self.coast_frames)
            .into_iter()
            .filter_map(|(number, c)| {
                let b = BoundingBox::new(c[0], c[1], c[2] - c[0], c[3] - c[1]).ok()?;
                Some((TrackId(number + 1), b))
            })
            .collect();
        out.sort_by_key(|(id, _)| *id);
        out
    }

    fn record_coasted(&mut self, frame: Frame) -> Result<()> {
        for (track, bbox) in self.coasted() {
            self.record(track.0 - 1, frame, bbox)?;
        }
        Ok(())
    }

    fn record(&mut self, number: u64, frame: Frame, bbox: BoundingBox) -> Result<()> {
        if !self.keep_history {
            return Ok(());
        }
        while self.tracks.len() as u64 <= number {
            let id = TrackId(self.tracks.len() as u64 + 1);
            self.tracks.push(Track::new(id));
        }
        Ok(self.tracks[number as usize].push(TrackPoint::boxed(frame, bbox))?)
    }
}

impl<A: Association> Tracker for BoxTracker<A> {
    type Error = Error;

    /// [`BoxTracker::update`]: each confirmed track given a detection, at the detection's box,
    /// then the coasted ones at their predictions.
    fn step(&mut self, frame: Frame, detections: &[Detection]) -> Result<Vec<TrackState>> {
        let assigned = self.update(frame, detections)?;
        let states = assigned.into_iter().map(|a| (a.track, a.bbox));
        Ok(states
            .chain(self.coasted())
            .map(|(id, bbox)| TrackState {
                id,
                point: TrackPoint::boxed(frame, bbox),
            })
            .collect())
    }

    /// Every confirmed track's boxes: at the frames a detection was given to it, and with
    /// coasting at the frames it was output at its prediction.
    fn finish(&mut self) -> Result<TrackSet> {
        Ok(TrackSet::from_tracks(std::mem::take(&mut self.tracks))?)
    }
}
