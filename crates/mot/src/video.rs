//! `cargo xtask track --video DIR`: the camera half of the review's pipeline (Oh 2012 §V;
//! Kushwaha et al., MFI 2008) on a folder of frames. Each frame goes through the adaptive
//! background mixture with shadow detection (KaewTraKulPong & Bowden, AVBS 2001), the mask is
//! cleaned (opening, closing, small components removed) and every remaining blob's bounding
//! box is a detection. Any tracker then runs on those detections; [`write_overlay`] draws its
//! tracks on the frames for looking at.
//!
//! Frames are decoded one at a time ([`FrameFolder::load`]) and dropped after use, so memory
//! does not grow with the video.

use std::collections::BTreeMap;
use std::path::Path;

use sensors_video::io::{FrameFolder, write_image};
use sensors_video::{BackgroundModel, ForegroundMask, MogConfig, PostConfig, clean};
use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, MotRow, TrackSet};

use crate::error::Result;

/// The detector's settings: the mixture and the mask cleaning.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VideoDetectorConfig {
    /// The background mixture and its shadow test.
    pub mog: MogConfig,
    /// Opening, closing and the smallest blob kept.
    pub post: PostConfig,
    /// Frames at the start that only teach the background (no detection is reported from
    /// them: the mixture calls everything foreground until it has seen the scene).
    pub warmup_frames: u32,
}

impl Default for VideoDetectorConfig {
    /// sensors-video's mixture; a cleaning for people at a few tens of pixels wide: an
    /// opening of radius 1 (speckle and swaying leaves), a closing of radius 3 (a body split
    /// by a background of its own colour) and blobs of 300 px or more. On frames 300-794 of
    /// `vtest.avi` (768 × 576) sensors-video's defaults, made for the rendered scenes, left
    /// a quarter of the blobs at 7 px tall or less, and GNN made 179 tracks of them; these
    /// settings 33 (docs/image-detector.md).
    fn default() -> Self {
        Self {
            mog: MogConfig::default(),
            post: PostConfig {
                open_radius: 1,
                close_radius: 3,
                min_blob_area: 300,
            },
            warmup_frames: 10,
        }
    }
}

/// The most warm-up frames: the mixture's history is at most this long too.
pub const MAX_WARMUP_FRAMES: u32 = 10_000;

/// The detections of every frame of `folder` after the warm-up, as MOTChallenge rows (id −1,
/// confidence 1), in frame order; `progress` is called after each frame with its number.
pub fn detect_folder(
    folder: &FrameFolder,
    config: &VideoDetectorConfig,
    progress: &mut dyn FnMut(u32),
) -> Result<Vec<MotRow>> {
    if config.warmup_frames > MAX_WARMUP_FRAMES {
        return Err(crate::error::invalid(
            "warmup_frames",
            format!("{}; at most {MAX_WARMUP_FRAMES}", config.warmup_frames),
        ));
    }
    let mut model: Option<(BackgroundModel, ForegroundMask)> = None;
    let mut rows = Vec::new();
    for (k, frame) in folder.frames().enumerate() {
        let image = folder.load(frame)?;
        let (model, mask) = match &mut model {
            Some(m) => m,
            None => {
                let (w, h) = (image.width(), image.height());
                let m = BackgroundModel::new(&config.mog, w, h, image.format())?;
                let mask = ForegroundMask {
                    width: w,
                    height: h,
                    labels: vec![0; w * h],
                };
                model.insert((m, mask))
            }
        };
        model.apply_into(&image, mask)?;
        if k as u64 >= u64::from(config.warmup_frames) {
            let cleaned = clean(mask, &config.post)?;
            rows.extend(cleaned.blobs.iter().map(|b| b.to_mot_row(frame)));
        }
        progress(frame);
    }
    Ok(rows)
}

/// Draws `tracks` on every frame of `folder` and writes the frames as PNG to `out_dir`
/// ([`write_overlay_frames`]); frames without a track are written too, undrawn, so the
/// overlay plays as the video does.
pub fn write_overlay(
    folder: &FrameFolder,
    tracks: &TrackSet,
    out_dir: &Path,
    progress: &mut dyn FnMut(u32),
) -> Result<usize> {
    let all: Vec<u32> = folder.frames().collect();
    write_overlay_frames(folder, tracks, out_dir, &all, progress)
}

/// Draws `tracks` on the given `frames` of `folder` and writes them as PNG to `out_dir`
/// (created if missing), named by frame number; returns how many were written.
pub fn write_overlay_frames(
    folder: &FrameFolder,
    tracks: &TrackSet,
    out_dir: &Path,
    frames: &[u32],
    progress: &mut dyn FnMut(u32),
) -> Result<usize> {
    std::fs::create_dir_all(out_dir).map_err(|error| sensors_video::Error::Io {
        path: out_dir.to_path_buf(),
        error,
    })?;
    let mut by_frame: BTreeMap<u32, Vec<(u64, BoundingBox)>> = BTreeMap::new();
    for row in tracks.to_mot_rows(0.0) {
        by_frame
            .entry(row.frame)
            .or_default()
            .push((row.id as u64, row.bbox));
    }
    for &frame in frames {
        let image = folder.load(frame)?;
        let boxes = by_frame.get(&frame).map_or(&[][..], Vec::as_slice);
        let drawn = sensors_video::overlay::draw_tracks(&image, boxes)?;
        write_image(&drawn, &out_dir.join(format!("{frame:06}.png")))?;
        progress(frame);
    }
    Ok(frames.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use sensors_video::{PixelFormat, VideoFrame};

    fn temp_dir(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("mot_video_{}_{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A grey scene at level 90 with a 12 × 30 bright block at `left` on frames ≥ 20.
    fn scene(dir: &Path, n: u32, left: impl Fn(u32) -> usize) {
        for f in 0..n {
            let (w, h) = (96, 64);
            let mut pixels = vec![90u8; w * h];
            if f >= 20 {
                let x0 = left(f);
                for y in 20..50 {
                    for x in x0..x0 + 12 {
                        pixels[y * w + x] = 230;
                    }
                }
            }
            let frame = VideoFrame::new(w, h, PixelFormat::Grey, pixels).unwrap();
            write_image(&frame, &dir.join(format!("f{f:03}.png"))).unwrap();
        }
    }

    #[test]
    fn a_moving_block_is_one_box_per_frame_where_it_is() {
        let dir = temp_dir("block");
        scene(&dir, 40, |f| 10 + 2 * (f as usize - 20));
        let folder = FrameFolder::open(&dir).unwrap();
        let config = VideoDetectorConfig {
            warmup_frames: 10,
            ..VideoDetectorConfig::default()
        };
        let mut seen = Vec::new();
        let rows = detect_folder(&folder, &config, &mut |f| seen.push(f)).unwrap();
        assert_eq!(seen, (0..40).collect::<Vec<_>>());
        // Nothing before the block appears; one box on it in every frame after.
        assert!(rows.iter().all(|r| r.frame >= 20), "{rows:?}");
        for f in 20..40 {
            let here: Vec<_> = rows.iter().filter(|r| r.frame == f).collect();
            assert_eq!(here.len(), 1, "frame {f}: {here:?}");
            let b = here[0].bbox;
            let x0 = 10.0 + 2.0 * f64::from(f - 20);
            assert!(
                (b.left - x0).abs() <= 1.0 && (b.width - 12.0).abs() <= 2.0,
                "{b:?}"
            );
            assert!(
                (b.top - 20.0).abs() <= 1.0 && (b.height - 30.0).abs() <= 2.0,
                "{b:?}"
            );
        }
        // The overlay has one PNG per frame, and the drawn frame differs from the input
        // exactly where a track is.
        let tracks = TrackSet::from_mot_rows(
            &rows
                .iter()
                .map(|r| MotRow { id: 3, ..*r })
                .collect::<Vec<_>>(),
        )
        .unwrap();
        let out = dir.join("overlay");
        assert_eq!(
            write_overlay(&folder, &tracks, &out, &mut |_| {}).unwrap(),
            40
        );
        let plain = sensors_video::io::read_image(&out.join("000005.png")).unwrap();
        assert!(plain.data().chunks(3).all(|p| p == [90, 90, 90]));
        let drawn = sensors_video::io::read_image(&out.join("000030.png")).unwrap();
        let colour = sensors_video::overlay::colour_of(3);
        let b = rows.iter().find(|r| r.frame == 30).unwrap().bbox;
        assert_eq!(drawn.pixel(b.left as usize, b.top as usize), &colour[..]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn too_long_a_warmup_is_an_error() {
        let dir = temp_dir("warmup");
        scene(&dir, 2, |_| 0);
        let folder = FrameFolder::open(&dir).unwrap();
        let config = VideoDetectorConfig {
            warmup_frames: u32::MAX,
            ..VideoDetectorConfig::default()
        };
        let err = detect_folder(&folder, &config, &mut |_| {}).unwrap_err();
        assert!(err.to_string().contains("warmup_frames"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
