//! One approach tracked on one simulated run and scored against the truth: the mean error of
//! each vehicle's paired track, CLEAR MOT (Bernardin & Stiefelhagen 2008) and OSPA (Schuhmacher,
//! Vo & Vo 2008, order 1).

use eval_metrics::{
    ClearMetrics, EvalConfig, MatchConfig, OspaConfig, evaluate, mean_error_per_track,
    ospa_over_time,
};

use super::{
    Approach, ApproachSettings, Calibration, Params, Simulated, av_config, count_aware_of,
    peak_scores_of, sensor_nodes,
};
use crate::{AvRun, PeakScores, Result, track_reports};

/// One approach's scores on one run.
pub struct Score {
    /// Mean error of each vehicle's paired track, in the truth's track order (None: no track).
    pub errors: Vec<Option<f64>>,
    /// MOTA.
    pub mota: f64,
    /// Mean OSPA over the ticks, m.
    pub ospa: f64,
    /// The CLEAR MOT counts behind the MOTA.
    pub clear: ClearMetrics,
    /// The fusion node's scans and the tracks.
    pub result: AvRun,
}

/// Approach `a` with settings `s` and peak scores `scores` on one simulated run, the nodes
/// with heading errors `calib`.
pub fn score_with(
    p: &Params,
    sim: &Simulated,
    calib: Calibration,
    a: Approach,
    s: &ApproachSettings,
    scores: Option<&PeakScores>,
) -> Result<Score> {
    let nodes = sensor_nodes(p, calib, s)?;
    let result = track_reports(
        nodes,
        sim.reports.clone(),
        sim.n_ticks,
        &av_config(p, a, s, scores)?,
    )?;
    let gt = &sim.gt;
    let pairs = mean_error_per_track(gt, &result.tracks, p.match_distance_m)?;
    let errors = gt
        .tracks()
        .iter()
        .map(|g| {
            pairs
                .iter()
                .find(|e| e.gt_id == g.id())
                .map(|e| e.mean_error)
        })
        .collect();
    let eval = evaluate(
        gt,
        &result.tracks,
        &EvalConfig {
            matching: MatchConfig::within_distance(p.match_distance_m),
        },
    )?;
    let ospa = ospa_over_time(
        gt,
        &result.tracks,
        &OspaConfig {
            cutoff: p.ospa_cutoff_m,
            order: 1.0,
        },
    )?;
    let mean_ospa = ospa.iter().map(|(_, o)| o.distance).sum::<f64>() / ospa.len().max(1) as f64;
    Ok(Score {
        errors,
        mota: eval.clear.mota,
        ospa: mean_ospa,
        clear: eval.clear,
        result,
    })
}

/// Approach `a` on one simulated run with its count-aware reference settings for the run's
/// true vehicle count (and their peak scores): the comparison the one configuration is
/// measured against ([`CountAware`](super::CountAware)).
pub fn score_count_aware(
    p: &Params,
    sim: &Simulated,
    calib: Calibration,
    a: Approach,
) -> Result<Score> {
    let s = count_aware_of(p, a, sim.multi);
    score_with(p, sim, calib, a, s, peak_scores_of(p, a, s)?)
}
