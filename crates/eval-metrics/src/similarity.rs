//! How a ground-truth object and an estimate are compared: IoU of boxes, or a distance-based
//! similarity of points, both in [0, 1] so that every metric uses one threshold convention.

use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, Location, Vec2, ensure_positive};

use crate::error::{Error, Result, Side, invalid_parameter};

/// The similarity of a truth/estimate pair.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
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

/// Similarity plus the threshold at which a pair counts as a match; checked by
/// [`MatchConfig::check`] in every function that takes one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
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

    /// Checks the threshold (in (0, 1]) and the distance scale (finite, > 0).
    pub fn check(&self) -> Result<()> {
        if !(self.threshold > 0.0 && self.threshold <= 1.0) {
            return Err(invalid_parameter(
                "match threshold",
                format!("{} is outside (0, 1]", self.threshold),
            ));
        }
        if let Similarity::Distance { zero_at } = self.similarity {
            ensure_positive(zero_at, "distance scale")?;
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
                let boxes = |locations: &[Location], side| {
                    locations
                        .iter()
                        .map(|l| match l {
                            Location::Box(b) => Ok(*b),
                            Location::Point(_) => Err(Error::IouNeedsBoxes { side }),
                        })
                        .collect::<Result<Vec<BoundingBox>>>()
                };
                let g = boxes(gt, Side::Truth)?;
                let h = boxes(pred, Side::Estimate)?;
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
            (Similarity::Iou, Location::Point(_), _) => {
                Err(Error::IouNeedsBoxes { side: Side::Truth })
            }
            (Similarity::Iou, _, Location::Point(_)) => Err(Error::IouNeedsBoxes {
                side: Side::Estimate,
            }),
            (Similarity::Distance { zero_at }, a, b) => {
                let d = (a.position() - b.position()).norm();
                Ok((1.0 - d / zero_at).max(0.0))
            }
        }
    }
}
