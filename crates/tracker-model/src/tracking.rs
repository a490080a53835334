//! The one tracker interface: one [`Detection`] type in, confirmed tracks out.
//!
//! A tracker that decides frame by frame implements [`Tracker`] (MATLAB's
//! `tracks = tracker(detections, time)`, Stone Soup's iteration protocol); one that needs the
//! whole window implements [`BatchTracker`]. [`Online`] runs any [`Tracker`] as a
//! [`BatchTracker`], so a caller that holds a whole file drives every tracker the same way, and
//! [`scans_of`] groups a list of detections into the frames both traits read.
//!
//! Time: a step names its [`Frame`], and a tracker jumps a gap of k frames in one prediction
//! (its cost does not grow with k). Detections stamped in seconds are put on frames by a
//! [`FrameClock`].

use std::collections::BTreeMap;

use nalgebra::Matrix2;

use crate::error::{Error, Result};
use crate::geometry::{BoundingBox, Vec2};
use crate::track::{Frame, FrameClock, Location, TrackId, TrackPoint, TrackSet};

/// When a detection was made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stamp {
    /// A frame of the trackers' clock.
    Frame(Frame),
    /// Seconds, put on a frame by a [`FrameClock`].
    Seconds(f64),
}

/// Identifies a detection across the whole input (a row number, a sensor's report id): it is
/// what a tracker's associations name, never a position in some vector.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct DetectionId(pub u64);

/// What a detector reports, the one input type of every tracker.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    /// The caller's id of the detection.
    pub id: DetectionId,
    /// When.
    pub stamp: Stamp,
    /// A point in the plane or an image box.
    pub location: Location,
    /// The detector's confidence, when it gives one.
    pub score: Option<f64>,
    /// The position's covariance, when the sensor knows it (else the tracker's R).
    pub covariance: Option<Matrix2<f64>>,
    /// Which sensor made it, for multi-sensor trackers.
    pub sensor: Option<u32>,
    /// An appearance vector (re-identification features, a colour histogram).
    pub appearance: Option<Vec<f32>>,
}

impl Detection {
    /// A point detection at `frame` with nothing else.
    pub fn point(id: u64, frame: Frame, position: Vec2) -> Self {
        Self::at(id, frame, Location::Point(position))
    }

    /// A box detection at `frame` with nothing else.
    pub fn boxed(id: u64, frame: Frame, bbox: BoundingBox) -> Self {
        Self::at(id, frame, Location::Box(bbox))
    }

    fn at(id: u64, frame: Frame, location: Location) -> Self {
        Self {
            id: DetectionId(id),
            stamp: Stamp::Frame(frame),
            location,
            score: None,
            covariance: None,
            sensor: None,
            appearance: None,
        }
    }

    /// The same detection with a score.
    #[must_use]
    pub fn with_score(mut self, score: f64) -> Self {
        self.score = Some(score);
        self
    }

    /// The point, or the box's centre.
    pub fn position(&self) -> Vec2 {
        self.location.position()
    }

    /// The box, if it is one.
    pub fn bbox(&self) -> Option<BoundingBox> {
        match self.location {
            Location::Box(b) => Some(b),
            Location::Point(_) => None,
        }
    }

    /// The box, or for a point an `InvalidParameter` error saying `why` a box is needed
    /// (e.g. "the PHD filter tracks boxes"): the one check every box tracker makes.
    pub fn require_box(&self, why: &str) -> Result<BoundingBox> {
        self.bbox().ok_or_else(|| Error::InvalidParameter {
            name: "detection",
            reason: format!("detection {} is a point; {why}", self.id.0),
        })
    }

    /// The frame, the seconds mapped by `clock`; a time in seconds without a clock is an
    /// error.
    pub fn frame(&self, clock: Option<&FrameClock>) -> Result<Frame> {
        match (self.stamp, clock) {
            (Stamp::Frame(f), _) => Ok(f),
            (Stamp::Seconds(s), Some(clock)) => clock.frame_at(s),
            (Stamp::Seconds(s), None) => Err(Error::InvalidParameter {
                name: "stamp",
                reason: format!(
                    "detection {} is stamped {s} s and no frame clock maps seconds to frames",
                    self.id.0
                ),
            }),
        }
    }
}

/// The detections of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameDetections {
    /// The frame.
    pub frame: Frame,
    /// Its detections, in input order.
    pub detections: Vec<Detection>,
}

/// Groups `detections` by frame (seconds mapped by `clock`), frames in increasing order and
/// each frame's detections in input order. Ids must be unique.
pub fn scans_of(
    detections: &[Detection],
    clock: Option<&FrameClock>,
) -> Result<Vec<FrameDetections>> {
    let mut by_frame: BTreeMap<Frame, Vec<Detection>> = BTreeMap::new();
    let mut ids = std::collections::HashSet::with_capacity(detections.len());
    for d in detections {
        if !ids.insert(d.id) {
            return Err(Error::InvalidParameter {
                name: "id",
                reason: format!("detection id {} appears twice", d.id.0),
            });
        }
        by_frame.entry(d.frame(clock)?).or_default().push(d.clone());
    }
    Ok(by_frame
        .into_iter()
        .map(|(frame, detections)| FrameDetections { frame, detections })
        .collect())
}

/// A confirmed track's current state, as a step reports it.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackState {
    /// The track's id, stable over the run.
    pub id: TrackId,
    /// Where it is now (filtered, or predicted through a miss).
    pub point: TrackPoint,
}

/// A tracker that decides frame by frame.
pub trait Tracker {
    /// What can go wrong.
    type Error: std::error::Error + Send + Sync + 'static;

    /// Advances to `frame` (later than the previous step's; the frames between had no
    /// detection) with that frame's detections, and returns the confirmed tracks' current
    /// states with stable ids.
    fn step(
        &mut self,
        frame: Frame,
        detections: &[Detection],
    ) -> std::result::Result<Vec<TrackState>, Self::Error>;

    /// Ends the run: every track, as the tracker's final estimate of the whole run (smoothed
    /// where the tracker smooths). The tracker is spent afterwards: a new run needs a new
    /// tracker (stepping it again is not a supported way to start one).
    fn finish(&mut self) -> std::result::Result<TrackSet, Self::Error>;
}

/// A tracker that needs the whole window at once.
pub trait BatchTracker {
    /// What can go wrong.
    type Error: std::error::Error + Send + Sync + 'static;

    /// Tracks the scans (frames in increasing order, as [`scans_of`] gives them); no scan
    /// gives no track. A tracker whose state carries over (an [`Online`] one) is spent
    /// afterwards.
    fn track(&mut self, scans: &[FrameDetections]) -> std::result::Result<TrackSet, Self::Error>;
}

/// Any [`Tracker`] run over a whole window: every scan stepped in order, then finished.
#[derive(Debug, Clone)]
pub struct Online<T>(pub T);

impl<T: Tracker> BatchTracker for Online<T> {
    type Error = T::Error;

    fn track(&mut self, scans: &[FrameDetections]) -> std::result::Result<TrackSet, T::Error> {
        for scan in scans {
            self.0.step(scan.frame, &scan.detections)?;
        }
        self.0.finish()
    }
}
