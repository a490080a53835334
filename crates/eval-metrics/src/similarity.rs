//! How a ground-truth object and an estimate are compared: IoU of boxes, or a distance-based
//! similarity of points, both in [0, 1] so that every metric uses one threshold convention.

use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, Location, Vec2};

use crate::error::{Error, Result};

/// The similarity of a truth/estimate pair.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Similarity {
    /// Intersection over union of boxes (MOTChallenge). Both locations must be boxes.
    Iou,
    /// s = max(0, 1 − d / zero_at) for the Euclidean distance d between points (box centres
    /// for boxes). With the usual threshold 0.5, a match means d ≤ zero_at / 2.
    Distance {
        /// Distance at which the similarity reaches 0.
        zero_at: f64,
    },
}

/// Similarity plus the threshold at which a pair counts as a match.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MatchConfig {
    /// How pairs are compared.
    pub similarity: Similarity,
    /// A pair matches when its similarity is ≥ this (MOTChallenge: IoU ≥ 0.5).
    pub threshold: f64,
}

impl MatchConfig {
    /// Boxes matched at IoU ≥ `threshold`.
    pub fn iou(threshold: f64) -> Self {
        Self {
            similarity: Similarity::Iou,
            threshold,
        }
    }

    /// Points matched within `max_distance` (similarity 1 − d / (2 · max_distance), threshold ½).
    pub fn within_distance(max_distance: f64) -> Self {
        Self {
            similarity: Similarity::Distance {
                zero_at: 2.0 * max_distance,
            },
            threshold: 0.5,
        }
    }

    /// Checks the parameters once.
    pub fn check(&self) -> Result<()> {
        if !(self.threshold > 0.0 && self.threshold <= 1.0) {
            return Err(Error::InvalidParameter {
                name: "match threshold",
                reason: format!("{} is outside (0, 1]", self.threshold),
            });
        }
        if let Similarity::Distance { zero_at } = self.similarity
            && !(zero_at.is_finite() && zero_at > 0.0)
        {
            return Err(Error::InvalidParameter {
                name: "distance scale",
                reason: format!("{zero_at} must be finite and > 0"),
            });
        }
        Ok(())
    }
}

impl Similarity {
    /// Row-major similarities of every (truth, estimate) pair. The kind is matched once, so the
    /// inner loop is a plain IoU or distance computation.
    pub fn matrix(&self, gt: &[Location], pred: &[Location]) -> Result<Vec<f64>> {
        let mut out = Vec::with_capacity(gt.len() * pred.len());
        match self {
            Similarity::Iou => {
                let as_box = |l: &Location| {
                    match l {
                    Location::Box(b) => Ok(*b),
                    Location::Point(_) => Err(Error::Incompatible(
                        "IoU similarity needs boxes on both sides; use a distance similarity for points".into(),
                    )),
                }
                };
                let g: Vec<BoundingBox> = gt.iter().map(as_box).collect::<Result<_>>()?;
                let h: Vec<BoundingBox> = pred.iter().map(as_box).collect::<Result<_>>()?;
                for a in &g {
                    out.extend(h.iter().map(|b| a.iou(b)));
                }
            }
            Similarity::Distance { zero_at } => {
                let h: Vec<Vec2> = pred.iter().map(Location::position).collect();
                for a in gt {
                    let pa = a.position();
                    out.extend(
                        h.iter()
                            .map(|pb| (1.0 - (pa - pb).norm() / zero_at).max(0.0)),
                    );
                }
            }
        }
        Ok(out)
    }

    /// The similarity of `gt` and `pred`, in [0, 1].
    pub fn between(&self, gt: &Location, pred: &Location) -> Result<f64> {
        match (self, gt, pred) {
            (Similarity::Iou, Location::Box(a), Location::Box(b)) => Ok(a.iou(b)),
            (Similarity::Iou, _, _) => Err(Error::Incompatible(
                "IoU similarity needs boxes on both sides; use a distance similarity for points"
                    .into(),
            )),
            (Similarity::Distance { zero_at }, a, b) => {
                let d = (a.position() - b.position()).norm();
                Ok((1.0 - d / zero_at).max(0.0))
            }
        }
    }
}
