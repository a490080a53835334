//! The interface of a per-object ("local") detector: a detector trained online for one object
//! that searches the current frame near where the object was. Trackers drive it; detectors
//! (an image-based one in sensors-video, a simulated one in phd-filter) implement it without
//! depending on any tracker.

use crate::geometry::BoundingBox;
use crate::track::Frame;

/// A detector that follows one object.
pub trait LocalDetector: Send {
    /// Searches frame `frame` near `around` (the object's last known box) and returns the
    /// object's box, or `None` if it is not found.
    fn detect(&mut self, frame: Frame, around: &BoundingBox) -> Option<BoundingBox>;

    /// Tells the detector where the tracker finally put its object in frame `frame`, so it
    /// can learn the object's appearance online. Does nothing by default.
    fn confirm(&mut self, _frame: Frame, _confirmed: &BoundingBox) {}
}

/// Creates a local detector for a newly confirmed object.
pub trait LocalDetectorFactory {
    /// A detector for the object first confirmed at `frame` in box `initial`.
    fn spawn(&mut self, frame: Frame, initial: &BoundingBox) -> Box<dyn LocalDetector>;
}
