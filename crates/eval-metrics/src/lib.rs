//! # eval-metrics
//!
//! Scores any tracker's [`TrackSet`] against the truth with the metrics the field and the seed
//! papers use, following the MOTChallenge conventions of py-motmetrics and TrackEval so the
//! numbers agree with those tools:
//!
//! * CLEAR MOT ([`clear_mot`]: MOTA, MOTP, MODA, IDSW, Frag, MT/PT/ML), identity metrics
//!   ([`identity`]: IDF1, IDP, IDR) and [`hota`] (HOTA, DetA, AssA, LocA, DetRe, DetPr, AssRe,
//!   AssPr), for boxes (IoU) or points (distance), all over one shared [`Sequence`];
//! * [`ospa`] and [`gospa`] between point sets, [`ospa_over_time`] and [`gospa_over_time`];
//! * the seed papers' metrics: [`mae`] / [`mmae`] (GDT), [`success_rate`] (SR and FAF of the
//!   SMC-PHD paper), [`distance_error_series`] (HMM), [`mean_error_per_track`] (audio-video
//!   fusion) and [`association_scores`] (MCMCDA's association F1).
//!
//! Optimal assignments come from `tracker_model::assignment` (the `lsap` crate, a port of
//! SciPy's `linear_sum_assignment`).
//!
//! ```
//! use eval_metrics::{EvalConfig, evaluate};
//! use tracker_model::{BoundingBox, Track, TrackId, TrackPoint, TrackSet};
//! let b = BoundingBox::new(0.0, 0.0, 10.0, 20.0).unwrap();
//! let track = Track::from_points(TrackId(1), vec![TrackPoint::boxed(1, b), TrackPoint::boxed(2, b)]).unwrap();
//! let truth = TrackSet::from_tracks(vec![track]).unwrap();
//! let report = evaluate(&truth, &truth, &EvalConfig::default()).unwrap();
//! assert_eq!(report.clear.mota, 1.0);
//! assert_eq!(report.identity.idf1, 1.0);
//! assert_eq!(report.hota.hota, 1.0);
//! ```

mod clear;
mod error;
mod hota;
mod identity;
mod ospa;
mod seed;
mod sequence;
mod similarity;

#[cfg(test)]
mod tests;

use serde::{Deserialize, Serialize};
use tracker_model::TrackSet;

pub use clear::{ClearMetrics, clear_mot};
pub use error::{Error, Result};
pub use hota::{ALPHAS, HotaMetrics, hota};
pub use identity::{IdentityMetrics, identity};
pub use ospa::{Gospa, Ospa, OspaConfig, gospa, gospa_over_time, ospa, ospa_over_time};
pub use seed::{
    AssociationScores, Mae, SuccessRate, TrackError, association_scores, distance_error_series,
    mae, mean_error_per_track, mmae, success_rate,
};
pub use sequence::{FrameData, NO_PAIR, Sequence};
pub use similarity::{MatchConfig, Similarity};

/// What [`evaluate`] computes with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EvalConfig {
    /// Similarity and match threshold for CLEAR, identity metrics and SR/FAF (HOTA sweeps its
    /// own thresholds α). Default: IoU ≥ 0.5.
    pub matching: MatchConfig,
}

impl Default for EvalConfig {
    fn default() -> Self {
        Self {
            matching: MatchConfig::iou(0.5),
        }
    }
}

/// Every sequence-level metric of one evaluation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    /// CLEAR MOT.
    pub clear: ClearMetrics,
    /// IDF1, IDP, IDR.
    pub identity: IdentityMetrics,
    /// HOTA and its parts.
    pub hota: HotaMetrics,
    /// SR and FAF at the match threshold.
    pub success: SuccessRate,
}

/// CLEAR MOT, identity, HOTA and SR/FAF of `pred` against `gt`, sharing one [`Sequence`].
pub fn evaluate(gt: &TrackSet, pred: &TrackSet, config: &EvalConfig) -> Result<EvalReport> {
    config.matching.check()?;
    let seq = Sequence::new(gt, pred, config.matching.similarity)?;
    Ok(EvalReport {
        clear: clear_mot(&seq, config.matching.threshold)?,
        identity: identity(&seq, config.matching.threshold)?,
        hota: hota(&seq)?,
        success: seed::success_rate_of(&seq, config.matching.threshold)?,
    })
}
