//! Noise estimation from the known frames: the measurement variance r and the white-acceleration
//! spectral density q of the constant-velocity model, by maximum likelihood over the segments
//! either side of a gap (the Kalman filter's prediction-error decomposition of the likelihood,
//! Schweppe 1965; Harvey 1989, §3.4), so that GDT needs no value a practitioner could not know.

use serde::{Deserialize, Serialize};
use tracker_model::{Gaussian, ObservationModel, TransitionModel};

use crate::error::{Error, Result, invalid_parameter};
use crate::gap::{GdtConfig, GdtModel, Observation, check_frames};
use crate::search::golden_section;

/// A segment filtered with a [`GdtModel`].
pub(crate) struct SegmentRun {
    /// The filtered state at the segment's last frame.
    pub end: Gaussian<4>,
    /// log p(z_2, …, z_m | z_1): the sum of the innovation log-likelihoods after the first
    /// observation (the first only places the prior, so it carries no information on the noise).
    pub log_likelihood: f64,
}

/// Filters a segment of at least two observations in strictly increasing frames: the prior at
/// its first frame is [`GdtModel::prior`], updated with the first observation; each later
/// observation is predicted over the frames since the one before (in one step of the closed
/// form, so the work is proportional to the observations, not to the frame span) and updated.
pub(crate) fn filter_segment(segment: &[Observation], model: &GdtModel) -> Result<SegmentRun> {
    let first = match segment {
        [first, _, ..] => *first,
        _ => {
            return Err(Error::SegmentTooShort {
                len: segment.len(),
                min: 2,
            });
        }
    };
    check_frames(segment)?;
    let prior = model.prior(first.position)?;
    let mut state = model.sensor().update(&prior, &first.position)?.state;
    let mut log_likelihood = 0.0;
    for w in segment.windows(2) {
        let predicted = model
            .motion()
            .predict_steps(&state, w[1].frame - w[0].frame);
        let updated = model.sensor().update(&predicted, &w[1].position)?;
        log_likelihood += updated.innovation.log_likelihood;
        state = updated.state;
    }
    Ok(SegmentRun {
        end: state,
        log_likelihood,
    })
}

/// How [`estimate_noise`] searches: a log-spaced grid over both ranges, then rounds of
/// golden-section searches along one parameter at a time around the best point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NoiseSearch {
    /// Range of the measurement variance per axis (position units²).
    pub measurement_variance_range: [f64; 2],
    /// Range of the white-acceleration spectral density (position units² / frame³).
    pub accel_psd_range: [f64; 2],
    /// Prior velocity variance at a segment's first frame (as in [`GdtConfig`]); fixed, not
    /// estimated.
    pub initial_velocity_variance: f64,
    /// Grid points per parameter (at least 2).
    pub grid_points: usize,
    /// Rounds of coordinate-wise golden-section refinement.
    pub refine_rounds: usize,
}

impl Default for NoiseSearch {
    fn default() -> Self {
        Self {
            measurement_variance_range: [1e-3, 1e3],
            accel_psd_range: [1e-5, 1e2],
            initial_velocity_variance: 25.0,
            grid_points: 7,
            refine_rounds: 3,
        }
    }
}

impl NoiseSearch {
    /// Checks the ranges and counts.
    pub fn check(&self) -> Result<()> {
        for (name, [lo, hi]) in [
            (
                "measurement_variance_range",
                self.measurement_variance_range,
            ),
            ("accel_psd_range", self.accel_psd_range),
        ] {
            if !(lo > 0.0 && hi.is_finite() && lo < hi) {
                return Err(invalid_parameter(
                    name,
                    format!("[{lo}, {hi}] must be a finite range of positive values"),
                ));
            }
        }
        tracker_model::ensure_positive(
            self.initial_velocity_variance,
            "initial_velocity_variance",
        )?;
        if self.grid_points < 2 {
            return Err(invalid_parameter(
                "grid_points",
                format!("{}: at least 2 are needed", self.grid_points),
            ));
        }
        Ok(())
    }
}

/// The maximum-likelihood noise of a set of segments.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NoiseEstimate {
    /// The settings with the estimated `measurement_variance` and `accel_psd`.
    pub config: GdtConfig,
    /// The maximised log-likelihood Σ_segments log p(z_2, …, z_m | z_1).
    pub log_likelihood: f64,
}

/// The log-likelihood of `segments` (each at least two observations) under the model with
/// measurement variance r and spectral density q (see [`estimate_noise`]).
pub fn noise_log_likelihood(
    segments: &[&[Observation]],
    measurement_variance: f64,
    accel_psd: f64,
    initial_velocity_variance: f64,
) -> Result<f64> {
    let model = GdtConfig {
        accel_psd,
        measurement_variance,
        initial_velocity_variance,
    }
    .check()?;
    segments
        .iter()
        .map(|s| filter_segment(s, &model).map(|run| run.log_likelihood))
        .sum()
}

/// Estimates the measurement variance r and the process noise q of GDT's constant-velocity
/// model by maximising Σ_segments log p(z_2, …, z_m | z_1) (each segment filtered on its own
/// from the prior [`recover_gdt`](crate::recover_gdt) uses) over the ranges of `search`. Uses
/// only the observations, so it can run on the two segments of a gap before recovering it.
///
/// ```
/// use gdt_bridge::{NoiseSearch, Observation, estimate_noise, recover_gdt_goal_state};
/// use tracker_model::Vec2;
///
/// // A walker at 3 px per frame seen with ±0.5 px of (deterministic) jitter.
/// let seen = |frame: u32| Observation {
///     frame,
///     position: Vec2::new(3.0 * f64::from(frame) + 0.5 * (f64::from(frame) * 2.1).sin(), 40.0),
/// };
/// let (a, b): (Vec<_>, Vec<_>) = ((0..30).map(seen).collect(), (40..70).map(seen).collect());
/// let fit = estimate_noise(&[&a, &b], &NoiseSearch::default())?;
/// let gap = recover_gdt_goal_state(&a, &b, &fit.config.check()?)?;
/// assert!((gap.positions[4].x - 3.0 * 34.0).abs() < 2.0);
/// # Ok::<(), gdt_bridge::Error>(())
/// ```
pub fn estimate_noise(segments: &[&[Observation]], search: &NoiseSearch) -> Result<NoiseEstimate> {
    search.check()?;
    if segments.is_empty() {
        return Err(Error::SegmentTooShort { len: 0, min: 2 });
    }
    let v0 = search.initial_velocity_variance;
    let ln = |[lo, hi]: [f64; 2]| [lo.ln(), hi.ln()];
    let bounds = [
        ln(search.measurement_variance_range),
        ln(search.accel_psd_range),
    ];
    let eval = |u: [f64; 2]| noise_log_likelihood(segments, u[0].exp(), u[1].exp(), v0);
    let g = search.grid_points;
    let step = |k: usize| (bounds[k][1] - bounds[k][0]) / (g - 1) as f64;
    let mut best = ([bounds[0][0], bounds[1][0]], f64::NEG_INFINITY);
    for i in 0..g {
        for j in 0..g {
            let u = [
                bounds[0][0] + step(0) * i as f64,
                bounds[1][0] + step(1) * j as f64,
            ];
            let ll = eval(u)?;
            if ll > best.1 {
                best = (u, ll);
            }
        }
    }
    for round in 0..search.refine_rounds {
        for k in 0..2 {
            // Search ±(grid step / 2^round) around the best point along parameter k.
            let half = step(k) / f64::from(1u32 << round.min(30));
            let bracket = (
                (best.0[k] - half).max(bounds[k][0]),
                (best.0[k] + half).min(bounds[k][1]),
            );
            let centre = best.0;
            let at = |x: f64| -> Result<([f64; 2], f64)> {
                let mut u = centre;
                u[k] = x;
                Ok((u, eval(u)?))
            };
            let [f1, f2] = golden_section(bracket, 15, at, |a, b| a.1 > b.1)?;
            for (u, ll) in [f1, f2] {
                if ll > best.1 {
                    best = (u, ll);
                }
            }
        }
    }
    Ok(NoiseEstimate {
        config: GdtConfig {
            accel_psd: best.0[1].exp(),
            measurement_variance: best.0[0].exp(),
            initial_velocity_variance: v0,
        },
        log_likelihood: best.1,
    })
}
