//! The detector fusion and local-detector management of Yoon, Hwang, Choi & Yoon (2016).
//!
//! * Eqs. 1-2: a local and a global detection overlapping with IoU above the threshold are
//!   averaged into one fused observation; the filter sees Z = Z_F ∪ unmatched Z_G ∪ unmatched
//!   Z_L.
//! * Eqs. 9-10: each local detector keeps a confidence P(LD), updated by Bayes' rule with p_D
//!   and p_FA: when some global detection overlaps its box with IoU ≥ the threshold,
//!   P ← p_D P / (p_D P + p_FA (1 − P)); otherwise P ← (1 − p_D) P / ((1 − p_D) P +
//!   (1 − p_FA)(1 − P)). A detector whose confidence falls to the removal level is dropped.

use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, Frame, LocalDetector, ensure_in_range, ensure_open_probability};

use crate::config::measurement_from_box;
use crate::error::Result;

/// Parameters of fusion and local-detector management; defaults are Yoon et al. 2016's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FusionConfig {
    /// Two detections fuse if their IoU is strictly above this (eq. 1: 0.5).
    pub fuse_iou: f64,
    /// Weight of the local detection in the fused box; the global one gets 1 − this (0.5).
    pub local_weight: f64,
    /// A local detector counts as confirmed by the global detector when some global box
    /// overlaps its box with IoU at least this (0.5).
    pub confirm_iou: f64,
    /// p_D of eqs. 9-10: how often the global detector finds a person a local detector
    /// really follows. Yoon et al. give no values for eqs. 9-10; with their filter's p_D = 0.95
    /// and p_FA = 0.3, one missed global detection would take a new detector from 0.5 to
    /// 0.07 and remove it, so the default is the global detector's own rate.
    pub p_detect: f64,
    /// p_FA of eqs. 9-10: how often a global box overlaps a local detector that follows
    /// nothing real.
    pub p_false_alarm: f64,
    /// Confidence a new local detector starts with. Yoon et al. write P₀ = 0, which Bayes' rule
    /// can never move; we start undecided.
    pub initial_confidence: f64,
    /// A detector is removed when its confidence is at or below this (0.1).
    pub removal_confidence: f64,
}

impl Default for FusionConfig {
    fn default() -> Self {
        Self {
            fuse_iou: 0.5,
            local_weight: 0.5,
            confirm_iou: 0.5,
            p_detect: 0.7,
            p_false_alarm: 0.1,
            initial_confidence: 0.5,
            removal_confidence: 0.1,
        }
    }
}

impl FusionConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        for (name, v) in [
            ("fuse_iou", self.fuse_iou),
            ("local_weight", self.local_weight),
            ("confirm_iou", self.confirm_iou),
            ("removal_confidence", self.removal_confidence),
        ] {
            ensure_in_range(v, 0.0, 1.0, name)?;
        }
        for (name, v) in [
            ("p_detect", self.p_detect),
            ("p_false_alarm", self.p_false_alarm),
            ("initial_confidence", self.initial_confidence),
        ] {
            ensure_open_probability(v, name)?;
        }
        Ok(())
    }
}

/// Where an observation of the fused set came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// Global detection i and local detection j, averaged.
    Fused {
        /// Index into the global detections.
        global: usize,
        /// Index into the local detections.
        local: usize,
    },
    /// Global detection i alone.
    Global(usize),
    /// Local detection j alone.
    Local(usize),
}

/// Eqs. 1-2: the fused observation set. Pairs are matched greedily by decreasing IoU, each
/// detection used once; degenerate boxes (see [`measurement_from_box`]) never fuse.
pub fn fuse(
    global: &[BoundingBox],
    local: &[BoundingBox],
    config: &FusionConfig,
) -> Vec<(BoundingBox, Source)> {
    let ok = |b: &BoundingBox| measurement_from_box(b).is_some();
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (i, g) in global.iter().enumerate().filter(|(_, b)| ok(b)) {
        for (j, l) in local.iter().enumerate().filter(|(_, b)| ok(b)) {
            let iou = g.iou(l);
            if iou > config.fuse_iou {
                pairs.push((iou, i, j));
            }
        }
    }
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut global_used = vec![false; global.len()];
    let mut local_used = vec![false; local.len()];
    let mut out = Vec::with_capacity(global.len() + local.len());
    let a = config.local_weight;
    for (_, i, j) in pairs {
        if global_used[i] || local_used[j] {
            continue;
        }
        global_used[i] = true;
        local_used[j] = true;
        let (g, l) = (&global[i], &local[j]);
        let fused = BoundingBox {
            left: a * l.left + (1.0 - a) * g.left,
            top: a * l.top + (1.0 - a) * g.top,
            width: a * l.width + (1.0 - a) * g.width,
            height: a * l.height + (1.0 - a) * g.height,
        };
        out.push((
            fused,
            Source::Fused {
                global: i,
                local: j,
            },
        ));
    }
    out.extend(
        global
            .iter()
            .enumerate()
            .filter(|(i, _)| !global_used[*i])
            .map(|(i, b)| (*b, Source::Global(i))),
    );
    out.extend(
        local
            .iter()
            .enumerate()
            .filter(|(j, _)| !local_used[*j])
            .map(|(j, b)| (*b, Source::Local(j))),
    );
    out
}

/// The highest confidence a local detector keeps: 1 − 2⁻⁵². In exact arithmetic eqs. 9-10
/// never reach 1, but in f64 about twenty confirmations in a row round the posterior to
/// exactly 1, where eq. 10 can no longer lower it and the detector would never be removed.
/// Capping one ulp-pair below 1 changes nothing before that point, and after it a run of
/// misses (15 at the paper's p_D = 0.95, p_FA = 0.3) removes the detector again.
pub const MAX_CONFIDENCE: f64 = 1.0 - f64::EPSILON;

/// Eq. 9 (`confirmed`) or eq. 10: the next confidence of a local detector, capped at
/// [`MAX_CONFIDENCE`].
pub fn updated_confidence(previous: f64, confirmed: bool, config: &FusionConfig) -> f64 {
    let (p_d, p_fa) = (config.p_detect, config.p_false_alarm);
    let (hit, miss) = if confirmed {
        (p_d, p_fa)
    } else {
        (1.0 - p_d, 1.0 - p_fa)
    };
    (hit * previous / (hit * previous + miss * (1.0 - previous))).min(MAX_CONFIDENCE)
}

/// A local detector attached to one track.
pub struct ManagedDetector {
    /// The track's label.
    pub label: u64,
    /// The detector.
    pub detector: Box<dyn LocalDetector>,
    /// P(LD).
    pub confidence: f64,
    /// The box it last reported or was confirmed at (where it searches next).
    pub last_box: BoundingBox,
}

/// The set of local detectors of a tracker.
#[derive(Default)]
pub struct DetectorBank {
    detectors: Vec<ManagedDetector>,
}

impl DetectorBank {
    /// The live detectors.
    pub fn detectors(&self) -> &[ManagedDetector] {
        &self.detectors
    }

    /// Whether a detector follows `label`.
    pub fn has(&self, label: u64) -> bool {
        self.detectors.iter().any(|d| d.label == label)
    }

    /// Adds a detector for `label`.
    pub fn add(
        &mut self,
        label: u64,
        detector: Box<dyn LocalDetector>,
        at: BoundingBox,
        config: &FusionConfig,
    ) {
        self.detectors.push(ManagedDetector {
            label,
            detector,
            confidence: config.initial_confidence,
            last_box: at,
        });
    }

    /// Runs every detector on `frame`; returns (detector index, box) for those that found
    /// their object.
    pub fn detect(&mut self, frame: Frame) -> Vec<(usize, BoundingBox)> {
        let mut out = Vec::new();
        for (i, d) in self.detectors.iter_mut().enumerate() {
            if let Some(b) = d.detector.detect(frame, &d.last_box)
                && measurement_from_box(&b).is_some()
            {
                d.last_box = b;
                out.push((i, b));
            }
        }
        out
    }

    /// Drops detectors that found the same object as a more confident one (boxes with IoU
    /// above `iou`; ties go to the older detector), and returns the remaining findings with
    /// indices into the updated list.
    pub fn suppress_duplicates(
        &mut self,
        found: Vec<(usize, BoundingBox)>,
        iou: f64,
    ) -> Vec<(usize, BoundingBox)> {
        let mut order: Vec<usize> = (0..found.len()).collect();
        order.sort_by(|&a, &b| {
            let (ca, cb) = (
                self.detectors[found[a].0].confidence,
                self.detectors[found[b].0].confidence,
            );
            cb.total_cmp(&ca).then(found[a].0.cmp(&found[b].0))
        });
        let mut kept: Vec<usize> = Vec::new();
        let mut dropped = vec![false; self.detectors.len()];
        for k in order {
            if kept.iter().any(|&j| found[j].1.iou(&found[k].1) > iou) {
                dropped[found[k].0] = true;
            } else {
                kept.push(k);
            }
        }
        // Re-index the survivors after removing the dropped detectors.
        let mut new_index = vec![usize::MAX; self.detectors.len()];
        let mut next = 0;
        for (i, d) in dropped.iter().enumerate() {
            if !d {
                new_index[i] = next;
                next += 1;
            }
        }
        let mut i = 0;
        self.detectors.retain(|_| {
            i += 1;
            !dropped[i - 1]
        });
        let mut out: Vec<(usize, BoundingBox)> = found
            .into_iter()
            .filter(|(j, _)| !dropped[*j])
            .map(|(j, b)| (new_index[j], b))
            .collect();
        out.sort_by_key(|(j, _)| *j);
        out
    }

    /// Gives the detector whose box overlaps `at` most (IoU above `iou`) to `label`, unless its
    /// own label is in `taken`; returns whether one was found. A "newborn" estimate on top of
    /// an existing detector is the same object under a new identity, not a new object.
    pub fn adopt(&mut self, label: u64, at: &BoundingBox, iou: f64, taken: &[u64]) -> bool {
        let best = self
            .detectors
            .iter_mut()
            .filter(|d| !taken.contains(&d.label))
            .map(|d| (d.last_box.iou(at), d))
            .filter(|(o, _)| *o > iou)
            .max_by(|a, b| a.0.total_cmp(&b.0));
        match best {
            Some((_, d)) => {
                d.label = label;
                true
            }
            None => false,
        }
    }

    /// Eqs. 9-10 for every detector against the global detections (a detector that found
    /// nothing this frame counts as unconfirmed), then removal of the unconfident ones.
    /// Returns the labels of removed detectors.
    pub fn update_confidence(
        &mut self,
        found: &[(usize, BoundingBox)],
        global: &[BoundingBox],
        config: &FusionConfig,
    ) -> Vec<u64> {
        for (i, d) in self.detectors.iter_mut().enumerate() {
            let confirmed = found
                .iter()
                .any(|(j, b)| *j == i && global.iter().any(|g| g.iou(b) >= config.confirm_iou));
            d.confidence = updated_confidence(d.confidence, confirmed, config);
        }
        let mut removed = Vec::new();
        self.detectors.retain(|d| {
            let keep = d.confidence > config.removal_confidence;
            if !keep {
                removed.push(d.label);
            }
            keep
        });
        removed
    }

    /// Tells the detector of `label` where its track was confirmed.
    pub fn confirm(&mut self, label: u64, frame: Frame, at: &BoundingBox) {
        if let Some(d) = self.detectors.iter_mut().find(|d| d.label == label) {
            d.detector.confirm(frame, at);
            d.last_box = *at;
        }
    }
}
