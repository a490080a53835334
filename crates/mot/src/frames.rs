//! `cargo xtask track --tracker phd --frames DIR`: the fused tracker of Yoon, Hwang, Choi &
//! Yoon (2016) on a user's own video, as the `phd-images` pipeline runs it on rendered video:
//! SMC-PHD on the global detections of the detection file, fused (eqs. 1-2) with one
//! image-detector local detector per target, each searching the pixels of the frames around
//! its target, managed by eqs. 9-10 (phd-filter's `PhdTracker::with_local_detectors`).
//!
//! The frames are the PNG (or PGM/PPM) files of a folder, ordered by the frame number in their
//! file name (the last run of digits, so MOTChallenge's `img1/000001.png` is frame 1), decoded
//! with sensors-video's [`sensors_video::io::decode_image`]. Every image is one filter step
//! (a gap in the images' frame numbers is jumped in one prediction, as without images);
//! each frame's global detections are the detection file's rows with that frame number, and a
//! frame with an image but no detection is stepped with the local detectors alone. Only the
//! image headers are read up front (to check that the sizes agree); each picture is decoded when
//! its frame is stepped and dropped at the next one, so memory does not grow with the folder.
//!
//! JPEG: the workspace builds the `image` crate with PNG and PNM only, so a `.jpg` file is an
//! `sensors_video::Error::Image` that says to convert it.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use image_detector::image::RgbImage;
use image_detector::{DetectorConfig, FrameFeed, ImageDetectors};
use phd_filter::PhdConfig;
use phd_filter::{FusionConfig, PhdTracker, SmcPhd};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sensors_video::io::FrameFolder;
use sensors_video::{PixelFormat, VideoFrame};
use tracker_model::{
    BatchTracker, BoundingBox, Detection, Frame, FrameDetections, MotRow, TrackSet,
};

use crate::error::{Error, Result};
use crate::track::{EffectiveConfig, Labeller, PhdLabelConfig, TrackConfig, TrackerKind};

/// p_D of the fused filter: with local detectors feeding it, a followed target is observed in
/// nearly every frame, so the filter's p_D is that of the fused observations, not the global
/// detector's recall (the value of the `phd-images` scenes).
pub const FUSED_P_DETECT: f64 = 0.95;

/// Settings of the fused tracker beyond the `[phd]` table: phd-filter's fusion defaults
/// (Yoon et al.'s eqs. 1-2, 9-10), image-detector's defaults, and [`FUSED_P_DETECT`], as the
/// `phd-images` scenes run them (not tuned on the user's data).
#[derive(Debug, Clone, PartialEq)]
pub struct FusedSettings {
    /// Fusion and detector management.
    pub fusion: FusionConfig,
    /// The local detectors.
    pub detector: DetectorConfig,
    /// p_D of the fused filter.
    pub p_detect: f64,
    /// The fused filter's extraction threshold: the paper's 0.5 (`PhdConfig::default()`), which
    /// this path was built and tested with. The 0.3 of `--tracker phd` was tuned for the
    /// filter on global detections alone, whose p_D is lower.
    pub extraction_threshold: f64,
    /// `[phd_labels] duplicate_cover` of the fused tracker unless the table sets it: a
    /// tentative track whose box a confirmed track's covers this much is a second label on a
    /// followed target (a local detector's box beside the global detector's box of a group,
    /// say), not a new target. 0.2 had the fewest identity switches of 0.5, 0.3 and 0.2 on
    /// frames 300-794 of `vtest.avi` (docs/image-detector.md; chosen and reported on the same
    /// frames).
    pub duplicate_cover: f64,
    /// The frame number of the folder's first image ([`FrameFolder::renumbered`]); unset, the
    /// numbers in the file names, and images counted from 0 against detections counted from
    /// 1 are an [`Error::ImagesFromZero`].
    pub first_frame: Option<u32>,
}

impl Default for FusedSettings {
    fn default() -> Self {
        Self {
            fusion: FusionConfig::default(),
            detector: DetectorConfig::default(),
            p_detect: FUSED_P_DETECT,
            extraction_threshold: phd_filter::PhdConfig::default().extraction_threshold,
            duplicate_cover: 0.2,
            first_frame: None,
        }
    }
}

/// Tracks `rows` with SMC-PHD (the `[phd]` table of `settings`, scaled and fitted to the boxes
/// as `--tracker phd` does, then [`fused_config`]) fused with image local detectors on the
/// frames of `dir`. Tracks are made from the filter's labels by `--tracker phd`'s track
/// manager (`[phd_labels]`), ids from 1. The filter draws from `seed`, the local detectors
/// from a seed drawn from it.
pub fn track_frames(
    dir: &Path,
    rows: &[MotRow],
    settings: &TrackConfig,
    fused: &FusedSettings,
    seed: u64,
) -> Result<TrackSet> {
    let config = fused_config(settings, rows, fused)?;
    track_frames_resolved(dir, rows, &config, fused, seed)
}

/// The configuration the fused tracker runs with: `settings` resolved for the PHD, with p_D
/// replaced by the fused one, and the extraction threshold and the duplicate cover by the
/// fused defaults unless the `[phd]` and `[phd_labels]` tables set them.
pub fn fused_config(
    settings: &TrackConfig,
    rows: &[MotRow],
    fused: &FusedSettings,
) -> Result<EffectiveConfig> {
    let mut config = settings.resolve_for(rows, TrackerKind::Phd)?;
    config.phd.p_detect = fused.p_detect;
    if config.phd_labels.duplicate_cover.is_none() {
        config.phd_labels.duplicate_cover = Some(fused.duplicate_cover);
    }
    if !settings.sets_phd_key("extraction_threshold") {
        config.phd.extraction_threshold = fused.extraction_threshold;
    }
    Ok(config)
}

/// [`track_frames`] with the configuration of [`fused_config`].
pub(crate) fn track_frames_resolved(
    dir: &Path,
    rows: &[MotRow],
    config: &EffectiveConfig,
    fused: &FusedSettings,
    seed: u64,
) -> Result<TrackSet> {
    let mut tracker = FusedPhd::open(dir, config.phd, config.phd_labels, fused.clone(), seed)?;
    if rows.is_empty() {
        return Err(Error::NoDetections {
            what: "the input".into(),
        });
    }
    let detections = crate::driver::detections_of(rows);
    crate::driver::run(&mut tracker, &detections, None)
}

/// The fused tracker on a frame folder, behind tracker-model's [`BatchTracker`]: every image
/// of the folder is one filter step (a gap in the images' frame numbers is jumped in one
/// prediction), with the scan of its frame as the global detections (none where the scans
/// have no such frame: the local detectors alone).
#[derive(Debug)]
pub struct FusedPhd {
    folder: FrameFolder,
    filter: PhdConfig,
    labels: PhdLabelConfig,
    fused: FusedSettings,
    seed: u64,
}

impl FusedPhd {
    /// The folder's images listed and their sizes checked ([`FrameFolder::open`]); the filter
    /// draws from `seed`, the local detectors from a seed drawn from it. Tracks are made from
    /// the filter's labels by `--tracker phd`'s track manager, with `labels`.
    pub fn open(
        dir: &Path,
        filter: PhdConfig,
        labels: PhdLabelConfig,
        fused: FusedSettings,
        seed: u64,
    ) -> Result<Self> {
        labels.check()?;
        let folder = FrameFolder::open_numbered(dir, fused.first_frame)?;
        Ok(Self {
            folder,
            filter,
            labels,
            fused,
            seed,
        })
    }
}

impl BatchTracker for FusedPhd {
    type Error = Error;

    /// No scan, no track (the local detectors start from the global detections). A point
    /// detection is an error: the filter's state is a box.
    fn track(&mut self, scans: &[FrameDetections]) -> Result<TrackSet> {
        if scans.is_empty() {
            return Ok(TrackSet::new());
        }
        check_detections(&self.folder, scans, self.fused.first_frame.is_some())?;
        let by_frame: BTreeMap<Frame, Vec<BoundingBox>> = scans
            .iter()
            .map(|s| Ok((s.frame, boxes_of(&s.detections)?)))
            .collect::<Result<_>>()?;
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let detector_seed: u64 = rng.random();
        let feed = FrameFeed::new();
        let factory =
            ImageDetectors::new(self.fused.detector.clone(), feed.clone(), detector_seed)?;
        let mut tracker = PhdTracker::with_local_detectors(
            SmcPhd::new(self.filter, self.seed)?,
            factory,
            self.fused.fusion,
        )?;
        let mut labeller = Labeller::new(self.filter, self.labels);
        let mut previous: Option<Frame> = None;
        for frame in self.folder.frames() {
            feed.set(frame, Arc::new(rgb(self.folder.load(frame)?)?));
            let boxes = by_frame.get(&frame).map_or(&[][..], Vec::as_slice);
            // Missing frame numbers (a subsampled folder) are time passing: one prediction
            // over them, as `--tracker phd` without images does. The frames are in order.
            let frames = previous.map_or(1, |p| u64::from(frame - p));
            if let Some(prev) = previous {
                labeller.coast_gap(prev, frames - 1, tracker.filter());
            }
            let step = tracker.step_after(frames, frame, boxes)?;
            // The filter's labels are not tracks: on real video a label is born wherever the
            // local detectors or the background subtraction report something new (a body
            // part, a group splitting) and many live a frame or two. The track manager of
            // `--tracker phd` confirms M of N and carries ids across label changes.
            labeller.take_frame(frame, &step.estimates, tracker.filter());
            previous = Some(frame);
        }
        labeller.finish()
    }
}

/// The boxes of a frame's detections; a point detection is an error.
fn boxes_of(detections: &[Detection]) -> Result<Vec<BoundingBox>> {
    Ok(detections
        .iter()
        .map(|d| d.require_box("the PHD filter tracks boxes"))
        .collect::<tracker_model::Result<_>>()?)
}

/// Checks that every frame of `scans` has an image in `folder`, and, unless the numbering was
/// `given`, that the images do not count from 0 where the detections count from 1 (each image
/// would get the next frame's detections, with no other sign that anything is wrong).
fn check_detections(folder: &FrameFolder, scans: &[FrameDetections], given: bool) -> Result<()> {
    let first_scan = scans.first().map(|s| s.frame);
    if !given && folder.first() == Some(0) && first_scan == Some(1) {
        return Err(Error::ImagesFromZero {
            dir: folder.dir().to_path_buf(),
        });
    }
    let without: Vec<Frame> = scans
        .iter()
        .map(|s| s.frame)
        .filter(|&f| !folder.contains(f))
        .collect();
    match without.first() {
        Some(&frame) => Err(Error::FrameWithoutImage {
            frame,
            count: without.len(),
            dir: folder.dir().to_path_buf(),
        }),
        None => Ok(()),
    }
}

/// A frame as the image local detectors read it: RGB (a grey frame replicated to three
/// channels).
fn rgb(frame: VideoFrame) -> Result<RgbImage> {
    let (w, h) = (frame.width(), frame.height());
    let data = match frame.format() {
        PixelFormat::Rgb => frame.into_data(),
        PixelFormat::Grey => frame.data().iter().flat_map(|&v| [v, v, v]).collect(),
    };
    let size =
        |v: usize| u32::try_from(v).map_err(|e| crate::error::invalid("frame size", e.to_string()));
    RgbImage::from_raw(size(w)?, size(h)?, data)
        .ok_or_else(|| crate::error::invalid("frame", "pixel buffer of the wrong length".into()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    use rand::SeedableRng;
    use sensors_video::{SpriteConfig, SpriteRenderer};

    /// A fresh empty folder under the system's temp dir.
    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("track_frames_{}_{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn grey(w: usize, h: usize) -> VideoFrame {
        VideoFrame::new(w, h, PixelFormat::Grey, vec![100; w * h]).unwrap()
    }

    fn det(frame: Frame, b: BoundingBox) -> MotRow {
        MotRow {
            frame,
            id: -1,
            bbox: b,
            confidence: 1.0,
            world: [-1.0; 3],
        }
    }

    /// The error of the fused tracker on `rows` and the folder `dir`, default settings.
    fn error_of(dir: &Path, rows: &[MotRow]) -> Error {
        track_frames(
            dir,
            rows,
            &TrackConfig::default(),
            &FusedSettings::default(),
            0,
        )
        .unwrap_err()
    }

    fn a_box() -> BoundingBox {
        BoundingBox::new(10.0, 10.0, 10.0, 20.0).unwrap()
    }

    #[test]
    fn a_missing_folder_is_an_error() {
        let dir = std::env::temp_dir().join("track_frames_no_such_folder_7f3a");
        let err = error_of(&dir, &[det(1, a_box())]);
        assert!(
            matches!(err, Error::Frames(sensors_video::Error::Io { .. })),
            "{err}"
        );
    }

    #[test]
    #[expect(
        clippy::float_cmp,
        reason = "configuration values are copied, not computed"
    )]
    fn the_fused_config_keeps_a_set_extraction_threshold() {
        let rows = [det(1, a_box()), det(2, a_box())];
        let fused = FusedSettings::default();
        let default = fused_config(&TrackConfig::default(), &rows, &fused).unwrap();
        assert_eq!(default.phd.p_detect, fused.p_detect);
        assert_eq!(default.phd.extraction_threshold, 0.5);
        // `--tracker phd` alone uses the boxes' 0.3; the fused path its own 0.5 unless set.
        let alone = TrackConfig::default()
            .resolve_for(&rows, TrackerKind::Phd)
            .unwrap();
        assert_eq!(alone.phd.extraction_threshold, 0.3);
        let set: TrackConfig = toml::from_str("[phd]\nextraction_threshold = 0.9\n").unwrap();
        let user = fused_config(&set, &rows, &fused).unwrap();
        assert_eq!(user.phd.extraction_threshold, 0.9);
        assert_eq!(user.phd.p_detect, fused.p_detect);
    }

    #[test]
    fn a_folder_without_images_is_an_error() {
        let dir = temp_dir("empty");
        std::fs::write(dir.join("notes.txt"), "not an image").unwrap();
        let err = error_of(&dir, &[det(1, a_box())]);
        assert!(
            matches!(&err, Error::Frames(sensors_video::Error::EmptySequence { path }) if path == &dir),
            "{err}"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn images_from_zero_against_detections_from_one_are_named_unless_numbered() {
        let dir = temp_dir("from_zero");
        for f in 0..3 {
            let name = format!("vtest_{f:03}.png");
            sensors_video::io::write_image(&grey(32, 24), &dir.join(name)).unwrap();
        }
        let rows = [det(1, a_box()), det(2, a_box())];
        // Every detection frame has an image, so nothing else would have said so.
        let err = error_of(&dir, &rows);
        assert!(
            matches!(&err, Error::ImagesFromZero { dir: d } if d == &dir),
            "{err}"
        );
        assert!(err.to_string().contains("--first-frame 1"), "{err}");
        for first_frame in [0, 1] {
            let fused = FusedSettings {
                first_frame: Some(first_frame),
                ..FusedSettings::default()
            };
            track_frames(&dir, &rows, &TrackConfig::default(), &fused, 0).unwrap();
        }
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn detections_of_a_frame_without_an_image_are_an_error() {
        let dir = temp_dir("without");
        for f in 1..=3 {
            sensors_video::io::write_image(&grey(32, 24), &dir.join(format!("{f:06}.png")))
                .unwrap();
        }
        let rows = [
            det(1, a_box()),
            det(3, a_box()),
            det(5, a_box()),
            det(9, a_box()),
        ];
        let err = error_of(&dir, &rows);
        assert!(
            matches!(&err, Error::FrameWithoutImage { frame: 5, count: 2, dir: d } if d == &dir),
            "{err}"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn images_of_different_sizes_are_an_error() {
        let dir = temp_dir("sizes");
        sensors_video::io::write_image(&grey(32, 24), &dir.join("000001.png")).unwrap();
        sensors_video::io::write_image(&grey(32, 24), &dir.join("000002.png")).unwrap();
        sensors_video::io::write_image(&grey(40, 24), &dir.join("000003.png")).unwrap();
        let err = error_of(&dir, &[det(1, a_box())]);
        assert!(
            matches!(&err, Error::Frames(sensors_video::Error::SizeMismatch {
                path,
                size: (40, 24),
                expected: (32, 24)
            }) if path == &dir.join("000003.png")),
            "{err}"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn an_undecodable_image_is_an_error() {
        let dir = temp_dir("undecodable");
        sensors_video::io::write_image(&grey(32, 24), &dir.join("000001.png")).unwrap();
        // A PNG signature followed by garbage: the header cannot be read.
        let mut bytes = b"\x89PNG\r\n\x1a\n".to_vec();
        bytes.extend_from_slice(&[7u8; 40]);
        std::fs::write(dir.join("000002.png"), &bytes).unwrap();
        let err = error_of(&dir, &[det(1, a_box())]);
        assert!(
            matches!(&err, Error::Frames(sensors_video::Error::Image { path, .. }) if path == &dir.join("000002.png")),
            "{err}"
        );
        // A valid header over truncated pixel data passes `open` and fails in `load`.
        let good = std::fs::read(dir.join("000001.png")).unwrap();
        std::fs::write(dir.join("000002.png"), &good[..good.len() - 20]).unwrap();
        let folder = FrameFolder::open(&dir).unwrap();
        assert!(folder.load(1).is_ok());
        let err = folder.load(2).unwrap_err();
        assert!(err.to_string().contains("000002.png"), "{err}");
        // A JPEG file says that JPEG is not built in.
        std::fs::write(dir.join("000003.jpg"), [0xFFu8, 0xD8, 0xFF, 0xE0, 0, 16]).unwrap();
        let err = FrameFolder::open(&dir).unwrap_err();
        assert!(
            err.to_string().contains("convert the folder to PNG"),
            "{err}"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn duplicate_frame_numbers_are_an_error() {
        let dir = temp_dir("duplicate");
        sensors_video::io::write_image(&grey(32, 24), &dir.join("1.png")).unwrap();
        sensors_video::io::write_image(&grey(32, 24), &dir.join("000001.png")).unwrap();
        let err = FrameFolder::open(&dir).unwrap_err();
        assert!(
            matches!(err, sensors_video::Error::DuplicateFrame { frame: 1, .. }),
            "{err}"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }

    /// The sprite's box at frame `f` (1-based): walks right at 2 px per frame, swaying up
    /// and down.
    fn sprite_box(f: Frame) -> BoundingBox {
        let t = f64::from(f);
        BoundingBox::new(30.0 + 2.0 * t, 50.0 + 12.0 * (t / 12.0).sin(), 20.0, 48.0).unwrap()
    }

    #[test]
    fn the_fused_tracker_follows_a_rendered_sprite_through_frames_without_detections() {
        // 45 frames of one sprite on clutter rendered by sensors-video, written as PNG (file
        // names 000001.png..) as MOTChallenge's img1/. The global detections are the true box
        // jittered by ±1 px, except in frames 25-40, where only the pixels tell where it is.
        let dir = temp_dir("sequence");
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let config = SpriteConfig {
            width: 200,
            height: 150,
            ..SpriteConfig::default()
        };
        let renderer = SpriteRenderer::new(config, &mut rng).unwrap();
        let n: Frame = 45;
        let gap = 25..=40;
        let mut rows = Vec::new();
        for f in 1..=n {
            let truth = sprite_box(f);
            let frame = renderer.render(f, &[(1, truth)], &mut rng).unwrap();
            sensors_video::io::write_image(&frame, &dir.join(format!("{f:06}.png"))).unwrap();
            if !gap.contains(&f) {
                let j = |rng: &mut ChaCha8Rng| rng.random_range(-1.0..1.0);
                let b = BoundingBox::new(
                    truth.left + j(&mut rng),
                    truth.top + j(&mut rng),
                    truth.width,
                    truth.height,
                )
                .unwrap();
                rows.push(det(f, b));
            }
        }
        let tracks = track_frames(
            &dir,
            &rows,
            &TrackConfig::default(),
            &FusedSettings::default(),
            3,
        )
        .unwrap();
        // Per frame, the output box that best overlaps the sprite.
        let best = |f: Frame| -> f64 {
            tracks
                .tracks()
                .iter()
                .filter_map(|t| t.at(f))
                .filter_map(|p| match p.location {
                    tracker_model::Location::Box(b) => Some(b.iou(&sprite_box(f))),
                    _ => None,
                })
                .fold(0.0, f64::max)
        };
        let in_gap = gap.clone().filter(|&f| best(f) >= 0.5).count();
        let outside = (5..=n)
            .filter(|f| !gap.contains(f))
            .filter(|&f| best(f) >= 0.5)
            .count();
        // Measured (at writing): all 16, under one track id.
        assert!(
            in_gap >= 14,
            "followed in {in_gap} of 16 frames without detections"
        );
        assert!(
            outside >= 22,
            "followed in {outside} of 25 frames with detections"
        );
        // The frames without detections are where the pixels matter: SMC-PHD on the global
        // detections alone loses the sprite there (independent route: the same filter settings,
        // no local detectors).
        let filter = fused_config(&TrackConfig::default(), &rows, &FusedSettings::default())
            .unwrap()
            .phd;
        let mut alone = PhdTracker::global_only(SmcPhd::new(filter, 3).unwrap());
        let mut found_alone = 0;
        for f in 1..=n {
            let boxes: Vec<BoundingBox> = rows
                .iter()
                .filter(|r| r.frame == f)
                .map(|r| r.bbox)
                .collect();
            let out = alone.step(f, &boxes).unwrap();
            if gap.contains(&f)
                && out
                    .estimates
                    .iter()
                    .any(|e| e.bbox.iou(&sprite_box(f)) >= 0.5)
            {
                found_alone += 1;
            }
        }
        assert!(
            found_alone <= 4,
            "global-only followed in {found_alone} gap frames"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }
}
