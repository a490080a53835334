//! Post-processing of a foreground mask: morphological opening then closing, 8-connected
//! components with small-blob removal (all through `imageproc`), blobs as detections; and the
//! paper's two filters on the detection function over angle.

use std::collections::VecDeque;

use imageproc::distance_transform::Norm;
use imageproc::region_labelling::{Connectivity, connected_components};
use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, Frame, MotRow};

use crate::error::Result;
use crate::mog::{FOREGROUND, ForegroundMask};

/// Morphology and blob parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PostConfig {
    /// Radius of the square (L∞) structuring element of the opening; 0 skips it (1 = 3 × 3).
    pub open_radius: u8,
    /// Radius of the closing after the opening; 0 skips it.
    pub close_radius: u8,
    /// Components with fewer pixels are removed.
    pub min_blob_area: usize,
}

impl Default for PostConfig {
    fn default() -> Self {
        Self {
            open_radius: 0,
            close_radius: 1,
            min_blob_area: 20,
        }
    }
}

/// A connected foreground region.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Blob {
    /// Bounding box in pixels (left, top inclusive; width and height count pixels).
    pub bbox: BoundingBox,
    /// Mean pixel position (x, y).
    pub centroid: [f64; 2],
    /// Pixels.
    pub area: usize,
}

impl Blob {
    /// The blob as a MOTChallenge detection row (id −1, confidence 1, no world position).
    pub fn to_mot_row(&self, frame: Frame) -> MotRow {
        MotRow {
            frame,
            id: -1,
            bbox: self.bbox,
            confidence: 1.0,
            world: [-1.0; 3],
        }
    }
}

/// A cleaned binary mask and its blobs.
#[derive(Debug, Clone, PartialEq)]
pub struct Cleaned {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major, true = foreground (shadows excluded).
    pub foreground: Vec<bool>,
    /// Blobs in label order (raster order of their first pixel).
    pub blobs: Vec<Blob>,
}

/// Opening, closing and small-blob removal of the foreground (shadow pixels count as
/// background), then blob statistics.
pub fn clean(mask: &ForegroundMask, config: &PostConfig) -> Result<Cleaned> {
    let (w, h) = (mask.width, mask.height);
    let bin: Vec<u8> = mask
        .labels
        .iter()
        .map(|&l| if l == FOREGROUND { 255 } else { 0 })
        .collect();
    let Some(mut img) = image::GrayImage::from_raw(w as u32, h as u32, bin) else {
        return Err(crate::Error::BufferSize {
            len: mask.labels.len(),
            expected: w * h,
            width: w,
            height: h,
            channels: 1,
        });
    };
    if config.open_radius > 0 {
        imageproc::morphology::open_mut(&mut img, Norm::LInf, config.open_radius);
    }
    if config.close_radius > 0 {
        imageproc::morphology::close_mut(&mut img, Norm::LInf, config.close_radius);
    }
    let labels = connected_components(&img, Connectivity::Eight, image::Luma([0u8]));
    // Per label: area, Σx, Σy, min/max x and y.
    let n_labels = labels.pixels().map(|p| p.0[0]).max().unwrap_or(0) as usize;
    let mut stats =
        vec![(0usize, 0f64, 0f64, usize::MAX, usize::MAX, 0usize, 0usize); n_labels + 1];
    for (x, y, p) in labels.enumerate_pixels() {
        let l = p.0[0] as usize;
        if l == 0 {
            continue;
        }
        let (x, y) = (x as usize, y as usize);
        let s = &mut stats[l];
        s.0 += 1;
        s.1 += x as f64;
        s.2 += y as f64;
        s.3 = s.3.min(x);
        s.4 = s.4.min(y);
        s.5 = s.5.max(x);
        s.6 = s.6.max(y);
    }
    let keep: Vec<bool> = stats
        .iter()
        .map(|s| s.0 >= config.min_blob_area.max(1))
        .collect();
    let foreground = labels
        .pixels()
        .map(|p| p.0[0] != 0 && keep[p.0[0] as usize])
        .collect();
    let blobs = stats
        .iter()
        .skip(1)
        .filter(|s| s.0 >= config.min_blob_area.max(1))
        .map(|s| Blob {
            bbox: BoundingBox {
                left: s.3 as f64,
                top: s.4 as f64,
                width: (s.5 - s.3 + 1) as f64,
                height: (s.6 - s.4 + 1) as f64,
            },
            centroid: [s.1 / s.0 as f64, s.2 / s.0 as f64],
            area: s.0,
        })
        .collect();
    Ok(Cleaned {
        width: w,
        height: h,
        foreground,
        blobs,
    })
}

/// The paper's two filters on the detection function D(θ) [I: the paper names them only]:
/// persistent background is the per-angle minimum over the previous `persistence_frames`
/// profiles and is subtracted (clutter that never leaves an angle, like a swaying tree, is
/// removed while a passing object is not); spikes are removed by a 3-bin median over angle
/// (a one-bin peak is glint or noise; an object spans at least two bins at 160 angles).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DetectionFilterConfig {
    /// Profiles in the persistent-background minimum; 0 disables the suppression.
    pub persistence_frames: usize,
    /// Apply the 3-bin median.
    pub remove_spikes: bool,
}

impl Default for DetectionFilterConfig {
    fn default() -> Self {
        Self {
            persistence_frames: 50,
            remove_spikes: true,
        }
    }
}

/// State of the two detection-function filters over a sequence of profiles.
#[derive(Debug, Clone)]
pub struct DetectionFilter {
    config: DetectionFilterConfig,
    history: VecDeque<Vec<f64>>,
}

impl DetectionFilter {
    /// A filter with no history.
    pub fn new(config: DetectionFilterConfig) -> Self {
        Self {
            config,
            history: VecDeque::new(),
        }
    }

    /// Filters one profile's values (a sequence's profiles must share their length; a change
    /// of length restarts the history).
    pub fn apply(&mut self, values: &[f64]) -> Vec<f64> {
        if self
            .history
            .front()
            .is_some_and(|h| h.len() != values.len())
        {
            self.history.clear();
        }
        let mut out = values.to_vec();
        if self.config.persistence_frames > 0
            && self.history.len() == self.config.persistence_frames
        {
            for (i, v) in out.iter_mut().enumerate() {
                let base = self
                    .history
                    .iter()
                    .map(|h| h[i])
                    .fold(f64::INFINITY, f64::min);
                *v = (*v - base).max(0.0);
            }
        }
        if self.config.persistence_frames > 0 {
            if self.history.len() == self.config.persistence_frames {
                self.history.pop_front();
            }
            self.history.push_back(values.to_vec());
        }
        if self.config.remove_spikes && out.len() >= 3 {
            out = median3(&out);
        }
        out
    }
}

/// 3-point median over angle, ends replicated.
pub fn median3(v: &[f64]) -> Vec<f64> {
    let n = v.len();
    (0..n)
        .map(|i| {
            let (a, b, c) = (v[i.saturating_sub(1)], v[i], v[(i + 1).min(n - 1)]);
            a.max(b).min(a.min(b).max(c))
        })
        .collect()
}
