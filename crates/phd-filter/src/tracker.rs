//! The tracking loop of Yoon, Hwang, Choi & Yoon (2016, Fig. 2): local detections, fusion with
//! the global ones, the PHD filter, local detectors for new targets, confidence updates; and
//! the output tracks.

use std::collections::BTreeMap;

use tracker_model::{
    BoundingBox, Detection, Frame, LocalDetectorFactory, Track, TrackId, TrackPoint, TrackSet,
    TrackState,
};

use crate::error::{Error, Result, invalid_parameter};
use crate::fusion::{DetectorBank, FusionConfig, fuse};
use crate::smc::{Estimate, PhdStep};

/// A PHD filter over boxes: one frame of detections in, estimates out.
pub trait PhdFilter {
    /// Runs the frame `frames` frames after the last one (the frames between hold no
    /// detection; one prediction by the exact multi-frame transition).
    fn step_after(&mut self, frames: u64, boxes: &[BoundingBox]) -> Result<PhdStep>;

    /// Runs the next frame.
    fn step(&mut self, boxes: &[BoundingBox]) -> Result<PhdStep> {
        self.step_after(1, boxes)
    }
}

impl PhdFilter for crate::smc::SmcPhd {
    fn step_after(&mut self, frames: u64, boxes: &[BoundingBox]) -> Result<PhdStep> {
        crate::smc::SmcPhd::step_after(self, frames, boxes)
    }
}

impl PhdFilter for crate::gm::GmPhd {
    fn step_after(&mut self, frames: u64, boxes: &[BoundingBox]) -> Result<PhdStep> {
        crate::gm::GmPhd::step_after(self, frames, boxes)
    }
}

/// What happened in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameOutput {
    /// The frame.
    pub frame: Frame,
    /// Reported targets.
    pub estimates: Vec<Estimate>,
    /// N̂.
    pub expected_targets: f64,
    /// Observations the filter received (after fusion).
    pub observations: usize,
    /// Local detectors alive after the frame.
    pub local_detectors: usize,
    /// Degenerate boxes skipped.
    pub skipped: usize,
}

/// A PHD filter, optionally fed by local detectors, with the tracks it has reported.
///
/// [`PhdTracker::global_only`] runs the filter on the detections it is given;
/// [`PhdTracker::with_local_detectors`] also spawns a local detector for every new track and
/// fuses what they find with the global detections.
pub struct PhdTracker<F, D = NoLocalDetectors> {
    filter: F,
    factory: Option<D>,
    fusion: FusionConfig,
    bank: DetectorBank,
    tracks: BTreeMap<u64, Vec<TrackPoint>>,
    /// The last frame stepped, for [`tracker_model::Tracker::step`]'s gaps.
    last_frame: Option<Frame>,
}

impl<F: PhdFilter> PhdTracker<F> {
    /// A tracker on the global detections only (no local detectors, nothing to fuse).
    pub fn global_only(filter: F) -> Self {
        Self {
            filter,
            factory: None,
            fusion: FusionConfig::default(),
            bank: DetectorBank::default(),
            tracks: BTreeMap::new(),
            last_frame: None,
        }
    }
}

impl<F: PhdFilter, D: LocalDetectorFactory> PhdTracker<F, D> {
    /// A tracker that spawns a local detector from `factory` for every new track and fuses
    /// their detections with the global ones (Yoon et al. 2016, eqs. 1-2 and 9-10).
    pub fn with_local_detectors(filter: F, factory: D, fusion: FusionConfig) -> Result<Self> {
        fusion.check()?;
        Ok(Self {
            filter,
            factory: Some(factory),
            fusion,
            bank: DetectorBank::default(),
            tracks: BTreeMap::new(),
            last_frame: None,
        })
    }

    /// The filter, for what it knows beyond the estimates (its particles' labels and
    /// weights, say).
    pub fn filter(&self) -> &F {
        &self.filter
    }

    /// The local detectors.
    pub fn bank(&self) -> &DetectorBank {
        &self.bank
    }

    /// Processes one frame of global detections: the frame after the last one processed.
    pub fn step(&mut self, frame: Frame, global: &[BoundingBox]) -> Result<FrameOutput> {
        self.step_after(1, frame, global)
    }

    /// Processes the global detections of `frame`, `frames` frames after the last one
    /// processed (a sequence with missing frame numbers, such as a subsampled image folder:
    /// the filter jumps the frames between in one prediction, [`PhdFilter::step_after`]).
    pub fn step_after(
        &mut self,
        frames: u64,
        frame: Frame,
        global: &[BoundingBox],
    ) -> Result<FrameOutput> {
        let found = if self.factory.is_some() {
            let found = self.bank.detect(frame);
            self.bank.suppress_duplicates(found, self.fusion.fuse_iou)
        } else {
            Vec::new()
        };
        let local: Vec<BoundingBox> = found.iter().map(|(_, b)| *b).collect();
        let observations: Vec<BoundingBox> = fuse(global, &local, &self.fusion)
            .into_iter()
            .map(|(b, _)| b)
            .collect();
        let step = self.filter.step_after(frames, &observations)?;
        if let Some(factory) = self.factory.as_mut() {
            let labels: Vec<u64> = step.estimates.iter().map(|e| e.label).collect();
            for e in &step.estimates {
                if !self.bank.has(e.label)
                    && !self
                        .bank
                        .adopt(e.label, &e.bbox, self.fusion.fuse_iou, &labels)
                {
                    let detector = factory.spawn(frame, &e.bbox);
                    self.bank.add(e.label, detector, e.bbox, &self.fusion);
                }
                self.bank.confirm(e.label, frame, &e.bbox);
            }
            self.bank.update_confidence(&found, global, &self.fusion);
        }
        self.last_frame = Some(frame);
        for e in &step.estimates {
            self.tracks
                .entry(e.label)
                .or_default()
                .push(TrackPoint::boxed(frame, e.bbox));
        }
        Ok(FrameOutput {
            frame,
            estimates: step.estimates,
            expected_targets: step.expected_targets,
            observations: observations.len(),
            local_detectors: self.bank.detectors().len(),
            skipped: step.skipped,
        })
    }

    /// Every track reported so far (label as id).
    pub fn tracks(&self) -> Result<TrackSet> {
        let tracks = self
            .tracks
            .iter()
            .map(|(l, points)| Track::from_points(TrackId(*l), points.clone()))
            .collect::<tracker_model::Result<Vec<_>>>()?;
        Ok(TrackSet::from_tracks(tracks)?)
    }
}

impl<F: PhdFilter, D: LocalDetectorFactory> tracker_model::Tracker for PhdTracker<F, D> {
    type Error = Error;

    /// [`PhdTracker::step_after`] over the frames since the last step (one for the first), on
    /// the detections' boxes; the states are the frame's estimates, labels as ids. A point
    /// detection is an error: the filter's state is a box.
    fn step(&mut self, frame: Frame, detections: &[Detection]) -> Result<Vec<TrackState>> {
        let frames = match self.last_frame {
            None => 1,
            Some(last) if frame > last => u64::from(frame - last),
            Some(last) => {
                return Err(invalid_parameter(
                    "frame",
                    format!("{frame} is not after the last frame stepped, {last}"),
                ));
            }
        };
        let boxes = detections
            .iter()
            .map(|d| d.require_box("the PHD filter tracks boxes"))
            .collect::<tracker_model::Result<Vec<BoundingBox>>>()?;
        let output = self.step_after(frames, frame, &boxes)?;
        Ok(output
            .estimates
            .iter()
            .map(|e| TrackState {
                id: TrackId(e.label),
                point: TrackPoint::boxed(frame, e.bbox),
            })
            .collect())
    }

    /// Every track reported ([`PhdTracker::tracks`]).
    fn finish(&mut self) -> Result<TrackSet> {
        self.tracks()
    }
}

/// The local-detector factory of a [`PhdTracker::global_only`] tracker: it is never asked for
/// a detector.
pub struct NoLocalDetectors;

impl LocalDetectorFactory for NoLocalDetectors {
    fn spawn(
        &mut self,
        _frame: Frame,
        _initial: &BoundingBox,
    ) -> Box<dyn tracker_model::LocalDetector> {
        Box::new(Never)
    }
}

/// A detector that never finds anything.
struct Never;

impl tracker_model::LocalDetector for Never {
    fn detect(&mut self, _frame: Frame, _around: &BoundingBox) -> Option<BoundingBox> {
        None
    }
}
