//! Image tracks per camera: MCMCDA (online, sliding window) on blob centroids. A blob carries
//! its centroid, which the tracker sees, and its top and bottom points (head and feet of a
//! standing person), which the geometry may use as two more features of the same track.

use mcmcda::{McmcdaConfig, OnlineConfig, OnlineTracker};
use nalgebra::Vector2;
use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, Frame, MotRow, Vec2};

use crate::error::{Result, invalid};
use crate::geometry::Intrinsics;

/// One foreground blob in one frame, in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blob {
    /// Centroid: what MCMCDA tracks.
    pub centre: Vec2,
    /// Top point (top-centre of the blob's box).
    pub top: Vec2,
    /// Bottom point (bottom-centre of the blob's box).
    pub bottom: Vec2,
}

impl Blob {
    /// A blob known only by its centroid (top and bottom equal to it).
    pub fn point(centre: Vec2) -> Self {
        Self {
            centre,
            top: centre,
            bottom: centre,
        }
    }

    /// A blob from its bounding box: centre, top-centre and bottom-centre. For a standing
    /// person seen by a camera without roll these are the projections of the body's middle,
    /// head and feet, up to the lean of the person's image.
    pub fn from_box(b: &BoundingBox) -> Self {
        let c = b.centre();
        Self {
            centre: c,
            top: Vec2::new(c.x, b.top),
            bottom: Vec2::new(c.x, b.bottom()),
        }
    }
}

/// Which points of a blob become correspondences.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Features {
    /// The centroid only. People walking on flat ground put every centroid near one plane,
    /// where the 8-point algorithm is degenerate; use this when objects move in 3-D.
    Centre,
    /// Top and bottom: two heights per blob, so ground traffic is not planar (default).
    TopBottom,
    /// Centre, top and bottom.
    All,
}

impl Features {
    /// The selected points of `blob`, in a fixed order.
    pub fn points(self, blob: &Blob) -> Vec<Vec2> {
        match self {
            Features::Centre => vec![blob.centre],
            Features::TopBottom => vec![blob.top, blob.bottom],
            Features::All => vec![blob.centre, blob.top, blob.bottom],
        }
    }
}

/// One camera's image track: blobs in increasing frame order.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageTrack {
    /// The tracker's label.
    pub id: u64,
    /// Frames, increasing.
    pub frames: Vec<Frame>,
    /// The blob at each frame.
    pub blobs: Vec<Blob>,
    /// Each blob's place in the input: (index of its frame's scan, index within the scan).
    pub sources: Vec<(usize, usize)>,
}

impl ImageTrack {
    /// Normalised feature points per frame ([`Intrinsics::normalise`]).
    pub fn normalised(
        &self,
        intrinsics: &Intrinsics,
        features: Features,
    ) -> Vec<Vec<Vector2<f64>>> {
        self.blobs
            .iter()
            .map(|b| {
                features
                    .points(b)
                    .iter()
                    .map(|p| intrinsics.normalise(p))
                    .collect()
            })
            .collect()
    }
}

/// Settings of [`image_tracks`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImageTrackConfig {
    /// The MCMCDA model in pixels (default: the paper's defaults, meant to be scaled to the
    /// image; see `McmcdaConfig::for_boxes`).
    pub model: McmcdaConfig,
    /// The sliding window (default: 10 frames, 300 samples per frame).
    pub online: OnlineConfig,
    /// Tracks shorter than this many blobs are dropped (default 5).
    pub min_length: usize,
}

impl Default for ImageTrackConfig {
    fn default() -> Self {
        Self {
            model: McmcdaConfig::default(),
            online: OnlineConfig {
                window: 10,
                samples_per_scan: 300,
                ..OnlineConfig::default()
            },
            min_length: 5,
        }
    }
}

/// Image tracks of one camera from its blobs, frame by frame (`scans`: frames increasing,
/// each with its blobs). Online MCMCDA on the centroids, seeded with `seed`; each track keeps
/// its raw blobs (not smoothed: the geometry wants measurements, and smoothing with a
/// constant-velocity model in the image would bend perspective motion).
pub fn image_tracks(
    scans: &[(Frame, Vec<Blob>)],
    config: &ImageTrackConfig,
    seed: u64,
) -> Result<Vec<ImageTrack>> {
    let model = config.model.check()?;
    let Some(first) = scans.first().map(|s| s.0) else {
        return Ok(Vec::new());
    };
    if scans.windows(2).any(|w| w[1].0 <= w[0].0) {
        return Err(invalid("scans", "frames must increase strictly".into()));
    }
    let mut online = OnlineTracker::new(model, first, config.online, seed)?;
    // MeasIds are given in push order: the flattened (scan, index) of every blob.
    let mut sources = Vec::new();
    for (s, (frame, blobs)) in scans.iter().enumerate() {
        let centres: Vec<Vec2> = blobs.iter().map(|b| b.centre).collect();
        online.push_scan(*frame, &centres)?;
        sources.extend((0..blobs.len()).map(|k| (s, k)));
    }
    let result = online.finish()?;
    let mut tracks = Vec::new();
    for (label, meas) in result.associations {
        if meas.len() < config.min_length {
            continue;
        }
        let mut track = ImageTrack {
            id: label,
            frames: Vec::with_capacity(meas.len()),
            blobs: Vec::with_capacity(meas.len()),
            sources: Vec::with_capacity(meas.len()),
        };
        let mut sorted = meas;
        sorted.sort_unstable();
        for m in sorted {
            let Some(&(s, k)) = sources.get(m as usize) else {
                continue;
            };
            track.frames.push(scans[s].0);
            track.blobs.push(scans[s].1[k]);
            track.sources.push((s, k));
        }
        tracks.push(track);
    }
    Ok(tracks)
}

/// [`image_tracks`] on MOTChallenge detection rows (blobs from their boxes, rows grouped by
/// frame in file order). `sources` then index the frames with detections, in order.
pub fn image_tracks_from_mot(
    rows: &[MotRow],
    config: &ImageTrackConfig,
    seed: u64,
) -> Result<Vec<ImageTrack>> {
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<Blob>> = Default::default();
    for r in rows {
        by_frame
            .entry(r.frame)
            .or_default()
            .push(Blob::from_box(&r.bbox));
    }
    let scans: Vec<(Frame, Vec<Blob>)> = by_frame.into_iter().collect();
    image_tracks(&scans, config, seed)
}
