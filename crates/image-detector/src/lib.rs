//! # image-detector
//!
//! The image-based local detector of Yoon, Hwang, Choi & Yoon (2016): one detector per
//! object, trained online on the pixels where the tracker confirms it, searching a small window
//! around where the object was, in the way of Grabner and Bischof's online-boosting tracker
//! (CVPR 2006). Depends on tracker-model only.
//!
//! * [`hog`]: the Dalal-Triggs (CVPR 2005) descriptor — [-1, 0, 1] gradients, 9 unsigned bins,
//!   8 × 8 cells, 16 × 16 blocks at stride 8, L2-Hys — computed once per patch as a
//!   [`CellGrid`] and a [`BlockGrid`]; any cell-aligned window is read without recomputation.
//! * [`boost`]: [`OnlineBooster`], online boosting for feature selection with a pool of
//!   online Gaussian weak learners shared by the selectors, λ propagated as in the paper and
//!   the worst learner replaced.
//! * [`colour`]: an 8 × 8 × 8 RGB [`ColourHistogram`] and the Bhattacharyya coefficient.
//! * [`ImageDetector`] (a [`tracker_model::LocalDetector`]) and its factory [`ImageDetectors`]
//!   (a [`tracker_model::LocalDetectorFactory`]), which read the current picture from a
//!   [`FrameFeed`] the caller fills frame by frame.
//!
//! Invariants: no file I/O, no clock, no ambient randomness (each detector has its own
//! `ChaCha8Rng` stream from the factory's seed); scales are searched in parallel and reduced
//! in order, so results do not depend on the thread count.
//!
//! A detector learns an object from the tracker's box in one frame and finds it again in the
//! next, after it moved:
//!
//! ```
//! use image::{Rgb, RgbImage};
//! use image_detector::{DetectorConfig, FrameFeed, ImageDetectors};
//! use tracker_model::{BoundingBox, LocalDetector};
//!
//! // Your frames (`image::open(path)?.to_rgb8()`); here a red square on grey, 4 px further right.
//! let frame = |x0: u32| RgbImage::from_fn(160, 120, |x, y| {
//!     Rgb(if (x0..x0 + 20).contains(&x) && (40..80).contains(&y) { [200, 30, 30] } else { [90; 3] })
//! });
//! let feed = FrameFeed::new();
//! let mut detectors = ImageDetectors::new(DetectorConfig::default(), feed.clone(), 7)?;
//! feed.set(0, frame(60).into()); // learn the object inside the tracker's box in frame 0
//! let mut detector = detectors.detector(0, &BoundingBox::new(60.0, 40.0, 20.0, 40.0)?)?;
//! feed.set(1, frame(64).into()); // search around where it was, in frame 1
//! let found = detector.detect(1, &BoundingBox::new(60.0, 40.0, 20.0, 40.0)?).expect("found");
//! assert!(found.iou(&BoundingBox::new(64.0, 40.0, 20.0, 40.0)?) > 0.7);
//! # Ok::<(), image_detector::Error>(())
//! ```

pub mod boost;
pub mod colour;
mod detector;
mod error;
pub mod hog;
pub mod scene;

#[cfg(test)]
mod tests;

pub use boost::{BoostConfig, OnlineBooster};
pub use colour::ColourHistogram;
pub use detector::{
    Detection, DetectorConfig, FrameFeed, ImageDetector, ImageDetectors, confirm_all, detect_all,
};
pub use error::{Error, Result};
pub use hog::{BlockGrid, CellGrid, Plane};
/// The `image` crate, whose `RgbImage` the detectors read.
pub use image;
