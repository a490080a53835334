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
//! A detector learns a red square on a grey background and finds it again after it moved:
//!
//! ```
//! use std::sync::Arc;
//! use image::{Rgb, RgbImage};
//! use image_detector::{DetectorConfig, FrameFeed, ImageDetectors};
//! use tracker_model::{BoundingBox, LocalDetector};
//!
//! let picture = |x0: u32| {
//!     let mut im = RgbImage::from_pixel(160, 120, Rgb([90, 90, 90]));
//!     for y in 40..80 {
//!         for x in x0..x0 + 20 {
//!             im.put_pixel(x, y, Rgb([200, 30, 30]));
//!         }
//!     }
//!     Arc::new(im)
//! };
//! let feed = FrameFeed::new();
//! let mut factory = ImageDetectors::new(DetectorConfig::default(), feed.clone(), 7)?;
//! feed.set(0, picture(60));
//! let mut detector = factory.detector(0, &BoundingBox::new(60.0, 40.0, 20.0, 40.0)?)?;
//! feed.set(1, picture(64));
//! let found = detector.detect(1, &BoundingBox::new(60.0, 40.0, 20.0, 40.0)?).expect("found");
//! assert!(found.iou(&BoundingBox::new(64.0, 40.0, 20.0, 40.0)?) > 0.7);
//! # Ok::<(), Box<dyn std::error::Error>>(())
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
