//! Video sensing for the audio-video tracker (Kushwaha, Oh, Amundson, Koutsoukos & Ledeczi, MFI 2008: background
//! subtraction and the detection function over angles).
//!
//! A camera node segments moving objects with the adaptive background mixture model of
//! KaewTraKulPong & Bowden (AVBS 2001) with shadow detection, cleans the mask, and reports
//! blobs and a detection function over angle (foreground pixels per bearing, 160 angles by
//! default) as a [`tracker_model::BearingProfile`], the type the audio crate produces.
//!
//! Main types:
//! * [`VideoFrame`] (8-bit grey or RGB) and [`io`]: PNG/PGM/PPM sequences, YUV4MPEG2 streams;
//! * [`MogConfig`] → [`BackgroundModel`] → [`ForegroundMask`] (labels background / shadow /
//!   foreground): the mixture, its two-phase update and shadows, parallel over rows with rayon
//!   and bit-identical for any thread count;
//! * [`post::clean`]: opening, closing, connected components, small-blob removal, [`Blob`]s
//!   (writable as [`tracker_model::MotRow`]); [`DetectionFilter`]: the paper's persistent
//!   background suppression and spike removal on the detection function;
//! * [`PinholeCamera`] and [`AngleProfiler`]: pixels to bearings, masks to profiles;
//! * [`overlay`]: tracks drawn on frames (outlines and ids), for looking at a tracker's output;
//! * [`render`]: a seeded scene renderer with truth masks, shadows and boxes, for tests;
//! * [`sprites`]: people-like textured sprites walking in given boxes over clutter, for
//!   image-based local detectors.
//!
//! Invariants: no global state, no ambient randomness (the renderer takes a generator); file
//! I/O only in [`io`]; every malformed input is an [`Error`], never a panic.
//!
//! Background subtraction on your frames (pixels row by row, as [`io`] reads them from files):
//!
//! ```
//! use sensors_video::{BackgroundModel, MogConfig, PixelFormat, VideoFrame, FOREGROUND};
//!
//! // A 4 × 3 grey scene at level 100; after learning, a bright square appears.
//! let mut model = BackgroundModel::new(&MogConfig::default(), 4, 3, PixelFormat::Grey)?;
//! let background = VideoFrame::filled(4, 3, PixelFormat::Grey, 100)?;
//! for _ in 0..20 {
//!     model.apply(&background)?;
//! }
//! let mut pixels = vec![100u8; 12];
//! pixels[5] = 220; // (x = 1, y = 1)
//! let mask = model.apply(&VideoFrame::new(4, 3, PixelFormat::Grey, pixels)?)?;
//! assert_eq!(mask.labels[5], FOREGROUND);
//! assert_eq!(mask.count_foreground(), 1);
//! # Ok::<(), sensors_video::Error>(())
//! ```

pub mod camera;
mod error;
mod frame;
pub mod io;
pub mod mog;
pub mod overlay;
pub mod post;
pub mod render;
pub mod sprites;

#[cfg(test)]
mod tests;

pub use camera::{AngleProfiler, DEFAULT_N_ANGLES, PinholeCamera};
pub use error::{Error, Result};
pub use frame::{PixelFormat, VideoFrame, check_sequence};
pub use mog::{
    BACKGROUND, BackgroundModel, ComponentState, FOREGROUND, ForegroundMask, MogConfig, SHADOW,
    ShadowConfig,
};
pub use post::{Blob, Cleaned, DetectionFilter, DetectionFilterConfig, PostConfig, clean};
pub use render::{ObjectKind, RenderedFrame, Scene, SceneConfig, SceneObject};
pub use sprites::{Appearance, SpriteConfig, SpriteRenderer};
