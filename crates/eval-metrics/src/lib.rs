//! # eval-metrics
//!
//! Scores any tracker's [`TrackSet`] against the truth with the metrics the field and the
//! reproduced papers use, following the MOTChallenge conventions of py-motmetrics and TrackEval
//! so the numbers agree with those tools:
//!
//! * CLEAR MOT ([`clear_mot`]: MOTA, MOTP, MODA, IDSW, Frag, MT/PT/ML), identity metrics
//!   ([`identity`]: IDF1, IDP, IDR) and [`hota`] (HOTA, DetA, AssA, LocA, DetRe, DetPr, AssRe,
//!   AssPr), for boxes (IoU) or points (distance), all over one shared [`Sequence`];
//! * [`ospa`] and [`gospa`] between point sets, [`ospa_over_time`] and [`gospa_over_time`];
//! * the reproduced papers' metrics: [`mae`] / [`mmae`] (goal-directed tracking, Oh & Jung
//!   2015), [`success_rate`] (SR and FAF of Yoon, Hwang, Choi & Yoon 2016),
//!   [`distance_error_series`] (Huynh & Vu 2006), [`mean_error_per_track`] (audio-video
//!   fusion, Kushwaha et al. 2008) and [`association_scores`] (MCMCDA's association F1, Oh,
//!   Russell & Sastry 2009).
//!
//! Configurations ([`EvalConfig`], [`MatchConfig`], [`OspaConfig`]) are checked once by the
//! function that takes them. Optimal assignments come from `tracker_model::assignment` (the
//! `lsap` crate, a port of SciPy's `linear_sum_assignment`).
//!
//! Two people walk for four frames; a tracker follows the first closely, loses the second in
//! the last frame and reports one false box:
//!
//! ```
//! use std::collections::BTreeMap;
//!
//! use eval_metrics::{EvalConfig, evaluate};
//! use tracker_model::{BoundingBox, Track, TrackId, TrackPoint, TrackSet};
//!
//! /// Rows of (frame, id, left, top, width, height) into tracks.
//! fn tracks(rows: &[(u32, u64, f64, f64, f64, f64)]) -> Result<TrackSet, tracker_model::Error> {
//!     let mut by_id: BTreeMap<u64, Vec<TrackPoint>> = BTreeMap::new();
//!     for &(frame, id, left, top, width, height) in rows {
//!         let bbox = BoundingBox::new(left, top, width, height)?;
//!         by_id.entry(id).or_default().push(TrackPoint::boxed(frame, bbox));
//!     }
//!     let tracks = by_id
//!         .into_iter()
//!         .map(|(id, points)| Track::from_points(TrackId(id), points))
//!         .collect::<Result<_, _>>()?;
//!     TrackSet::from_tracks(tracks)
//! }
//!
//! let truth = tracks(&[
//!     (1, 1, 10.0, 50.0, 20.0, 40.0),
//!     (2, 1, 14.0, 50.0, 20.0, 40.0),
//!     (3, 1, 18.0, 50.0, 20.0, 40.0),
//!     (4, 1, 22.0, 50.0, 20.0, 40.0),
//!     (1, 2, 200.0, 60.0, 20.0, 40.0),
//!     (2, 2, 196.0, 60.0, 20.0, 40.0),
//!     (3, 2, 192.0, 60.0, 20.0, 40.0),
//!     (4, 2, 188.0, 60.0, 20.0, 40.0),
//! ])?;
//! let estimates = tracks(&[
//!     (1, 7, 11.0, 51.0, 20.0, 40.0),
//!     (2, 7, 15.0, 51.0, 20.0, 40.0),
//!     (3, 7, 19.0, 51.0, 20.0, 40.0),
//!     (4, 7, 23.0, 51.0, 20.0, 40.0),
//!     (1, 8, 200.0, 60.0, 20.0, 40.0),
//!     (2, 8, 196.0, 60.0, 20.0, 40.0),
//!     (3, 8, 192.0, 60.0, 20.0, 40.0),
//!     (2, 9, 400.0, 300.0, 20.0, 40.0),
//! ])?;
//!
//! // Matches at IoU ≥ 0.5: 7 of 8 true boxes found, 1 miss, 1 false box, no identity switch.
//! let report = evaluate(&truth, &estimates, &EvalConfig::default())?;
//! assert_eq!(report.clear.mota, 1.0 - (1.0 + 1.0) / 8.0);
//! assert_eq!(report.identity.idf1, 2.0 * 7.0 / (2.0 * 7.0 + 1.0 + 1.0));
//! // HOTA also weighs how well the boxes overlap and how long each identity is kept.
//! assert!(report.hota.hota > 0.5 && report.hota.hota < report.identity.idf1);
//! # Ok::<(), eval_metrics::Error>(())
//! ```

mod clear;
mod error;
mod hota;
mod identity;
mod ospa;
mod paper_metrics;
mod sequence;
mod similarity;

#[cfg(test)]
mod tests;

use serde::{Deserialize, Serialize};
use tracker_model::TrackSet;

pub use clear::{ClearMetrics, clear_mot};
pub use error::{Error, Result, Side};
pub use hota::{ALPHAS, HotaMetrics, hota};
pub use identity::{IdentityMetrics, identity};
pub use ospa::{Gospa, Ospa, OspaConfig, gospa, gospa_over_time, ospa, ospa_over_time};
pub use paper_metrics::{
    AssociationScores, Mae, SuccessRate, TrackError, association_scores, distance_error_series,
    mae, mean_error_per_track, mmae, success_rate,
};
pub use sequence::{FrameData, NO_PAIR, Sequence};
pub use similarity::{MatchConfig, Similarity};

/// What [`evaluate`] computes with; checked by [`EvalConfig::check`] when evaluating.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
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

impl EvalConfig {
    /// Checks the match threshold and similarity ([`MatchConfig::check`]).
    pub fn check(&self) -> Result<()> {
        self.matching.check()
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
    config.check()?;
    let seq = Sequence::new(gt, pred, config.matching.similarity)?;
    Ok(EvalReport {
        clear: clear_mot(&seq, config.matching.threshold)?,
        identity: identity(&seq, config.matching.threshold)?,
        hota: hota(&seq)?,
        success: paper_metrics::success_rate_of(&seq, config.matching.threshold)?,
    })
}
