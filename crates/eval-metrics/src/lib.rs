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
//! Scoring a tracker's MOTChallenge output against the ground truth. Two people walk for four
//! frames; the tracker follows the first closely, loses the second in the last frame and
//! reports one false box:
//!
//! ```
//! use eval_metrics::{EvalConfig, evaluate};
//! use tracker_model::{TrackSet, parse_mot};
//!
//! // gt.txt and res.txt as read from disk: frame,id,left,top,width,height.
//! let gt = "1,1,10,50,20,40\n2,1,14,50,20,40\n3,1,18,50,20,40\n4,1,22,50,20,40\n\
//!           1,2,200,60,20,40\n2,2,196,60,20,40\n3,2,192,60,20,40\n4,2,188,60,20,40\n";
//! let res = "1,7,11,51,20,40\n2,7,15,51,20,40\n3,7,19,51,20,40\n4,7,23,51,20,40\n\
//!            1,8,200,60,20,40\n2,8,196,60,20,40\n3,8,192,60,20,40\n2,9,400,300,20,40\n";
//! let truth = TrackSet::from_mot_rows(&parse_mot(gt.as_bytes())?)?;
//! let tracks = TrackSet::from_mot_rows(&parse_mot(res.as_bytes())?)?;
//! let m = evaluate(&truth, &tracks, &EvalConfig::default())?;
//! println!("MOTA {:.3} IDF1 {:.3} HOTA {:.3}", m.clear.mota, m.identity.idf1, m.hota.hota);
//! // At IoU ≥ 0.5: 7 of 8 true boxes found, 1 miss, 1 false box, no identity switch.
//! assert_eq!(m.clear.mota, 1.0 - (1.0 + 1.0) / 8.0);
//! assert!(m.hota.hota > 0.5 && m.hota.hota < m.identity.idf1);
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
