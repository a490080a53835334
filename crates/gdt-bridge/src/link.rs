//! Segment linking: which track segments continue which. Oh & Jung (2015) associate segments
//! before recovering the gaps between them.
//!
//! The cost of continuing segment A with segment B is the negative log-likelihood of B's first
//! observation under A's filtered end state propagated over the gap: the normalising constant
//! of the goal-directed conditioning, N(y_B; H Φ x_A, H (Φ P_A Φᵀ + Σ Q) Hᵀ + R). Pairs are gated
//! by the largest gap and the largest speed, and the optimal one-to-one assignment (the `lsap`
//! crate) keeps the pairs whose cost beats starting a new track.

use serde::{Deserialize, Serialize};
use tracker_model::{Gaussian, ObservationModel, TransitionModel, ensure_positive};

use crate::error::{Result, invalid_parameter};
use crate::gap::{GdtConfig, GdtModel, Observation};
use crate::noise::filter_segment;

/// Linking settings; [`LinkConfig::check`] turns them into the [`LinkModel`] that
/// [`link_costs`] and [`link_segments`] take.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkConfig {
    /// Motion and noise model of the segments.
    pub model: GdtConfig,
    /// Largest number of frames between A's last and B's first observation.
    pub max_gap_frames: u32,
    /// Largest speed (distance per frame) between A's last and B's first observation.
    pub max_speed: f64,
    /// A link must cost less than this (a negative log-likelihood); otherwise B starts a new
    /// track.
    pub new_track_cost: f64,
}

impl LinkConfig {
    /// Checks every field and builds the segments' model.
    pub fn check(&self) -> Result<LinkModel> {
        let model = self.model.check()?;
        if self.max_gap_frames == 0 {
            return Err(invalid_parameter(
                "max_gap_frames",
                "0: no segment could continue another".into(),
            ));
        }
        ensure_positive(self.max_speed, "max_speed")?;
        if !self.new_track_cost.is_finite() {
            return Err(invalid_parameter(
                "new_track_cost",
                format!("{} must be finite", self.new_track_cost),
            ));
        }
        Ok(LinkModel {
            config: *self,
            model,
        })
    }
}

/// A checked [`LinkConfig`] with the segments' model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkModel {
    config: LinkConfig,
    model: GdtModel,
}

impl LinkModel {
    /// The settings it was built from.
    pub fn config(&self) -> &LinkConfig {
        &self.config
    }

    /// The segments' motion and noise model.
    pub fn model(&self) -> &GdtModel {
        &self.model
    }
}

/// A chosen link: segment `from` continues as segment `to`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Link {
    /// Index of the earlier segment.
    pub from: usize,
    /// Index of the later segment.
    pub to: usize,
    /// Negative log-likelihood of the continuation.
    pub cost: f64,
}

/// Filters a segment and returns its state at its last frame (work and memory proportional to
/// its observations, whatever frames they span).
pub(crate) fn end_state(segment: &[Observation], model: &GdtModel) -> Result<Gaussian<4>> {
    filter_segment(segment, model).map(|run| run.end)
}

/// The cost of every gated (A, B) pair, as (from, to, cost).
pub fn link_costs(
    segments: &[Vec<Observation>],
    linking: &LinkModel,
) -> Result<Vec<(usize, usize, f64)>> {
    let (cfg, motion, sensor) = (
        &linking.config,
        linking.model.motion(),
        linking.model.sensor(),
    );
    let ends = segments
        .iter()
        .map(|s| end_state(s, &linking.model))
        .collect::<Result<Vec<_>>>()?;
    let mut out = Vec::new();
    for (i, a) in segments.iter().enumerate() {
        let last = a[a.len() - 1];
        for (j, b) in segments.iter().enumerate() {
            let Some(first) = b.first() else { continue };
            if i == j || first.frame <= last.frame || first.frame - last.frame > cfg.max_gap_frames
            {
                continue;
            }
            let gap = first.frame - last.frame;
            if (first.position - last.position).norm() > cfg.max_speed * f64::from(gap) {
                continue;
            }
            let predicted = motion.predict_steps(&ends[i], gap);
            let cost = -sensor
                .innovation(&predicted, &first.position)?
                .log_likelihood;
            out.push((i, j, cost));
        }
    }
    Ok(out)
}

/// The optimal set of links: each segment continues at most one earlier segment and is
/// continued by at most one later one, minimising the total cost of the chosen links minus
/// `new_track_cost` for each (so a link is worth taking only when it costs less than that).
pub fn link_segments(segments: &[Vec<Observation>], linking: &LinkModel) -> Result<Vec<Link>> {
    let n = segments.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    let costs = link_costs(segments, linking)?;
    let cfg = &linking.config;
    // Maximum-weight matching with weight max(0, new_track_cost − cost): pairs that do not beat
    // a new track weigh 0 and are dropped after the assignment.
    let mut weights = vec![0.0; n * n];
    for &(i, j, c) in &costs {
        weights[i * n + j] = (cfg.new_track_cost - c).max(0.0);
    }
    let mut links: Vec<Link> = tracker_model::assignment::maximise(n, n, &weights)?
        .into_iter()
        .filter(|&(i, j)| weights[i * n + j] > 0.0)
        .filter_map(|(i, j)| {
            costs
                .iter()
                .find(|c| c.0 == i && c.1 == j)
                .map(|&(from, to, cost)| Link { from, to, cost })
        })
        .collect();
    links.sort_by_key(|l| l.from);
    Ok(links)
}
