//! The Kalman filter along one MCMCDA track and the track's term of the log posterior.
//!
//! Specialised to the constant-velocity model with position measurements: the innovation
//! covariance is 2×2, so it is inverted in closed form. Every measurement of a track keeps its
//! filtered state and the cumulative log-likelihood, so a move that keeps a track's prefix
//! (extension, reduction, update, split, merge, switch) filters only the new part.

use nalgebra::{Matrix2, Matrix4, Matrix4x2, Vector2, Vector4};
use tracker_model::LN_2PI;

use crate::config::{Model, TrackInit};
use crate::problem::{MeasId, Problem};

/// Filtered state after one measurement of a track.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    mean: Vector4<f64>,
    cov: Matrix4<f64>,
    /// Σ of the log predictive densities of the track's measurements up to this one.
    cum_log_likelihood: f64,
}

impl Model {
    /// A track starting at position `y`: mean [y, 0], covariance diag(R, v I) with per-axis
    /// velocity variance `v`.
    pub(crate) fn start_at(&self, y: Vector2<f64>, v: f64) -> (Vector4<f64>, Matrix4<f64>) {
        let mut cov = Matrix4::zeros();
        cov.fixed_view_mut::<2, 2>(0, 0)
            .copy_from(&self.config.measurement_noise);
        cov[(2, 2)] = v;
        cov[(3, 3)] = v;
        (Vector4::new(y.x, y.y, 0.0, 0.0), cov)
    }

    pub(crate) fn first_node(&self, problem: &Problem, meas: &[MeasId]) -> Node {
        let y1 = problem.position(meas[0]);
        match self.config.track_init {
            TrackInit::FirstMeasurement { .. } => {
                let (mean, cov) = self.start_at(y1, self.initial_velocity_variance);
                Node {
                    mean,
                    cov,
                    cum_log_likelihood: 0.0,
                }
            }
            TrackInit::TwoPoint { initial_covariance } => {
                // Tracks always have two measurements; `meas[1]` exists.
                let y2 = problem.position(meas[1]);
                let gap = (problem.scan_of(meas[1]) - problem.scan_of(meas[0])) as f64;
                let v = (y2 - y1) / (gap * self.config.motion.dt_s());
                Node {
                    mean: Vector4::new(y1.x, y1.y, v.x, v.y),
                    cov: initial_covariance,
                    cum_log_likelihood: 0.0,
                }
            }
        }
    }

    /// How many of `len` leading nodes shared with another track can be reused: all of them,
    /// except that the two-point start depends on the second measurement.
    pub(crate) fn reusable_prefix(&self, len: usize) -> usize {
        match self.config.track_init {
            TrackInit::TwoPoint { .. } if len < 2 => 0,
            _ => len,
        }
    }

    /// Predict over `gap` scans and update with `y`; also returns the innovation's squared
    /// Mahalanobis distance (for gating).
    pub(crate) fn step(&self, node: &Node, y: Vector2<f64>, gap: usize) -> (Node, f64) {
        let tau = gap as f64 * self.config.motion.dt_s();
        let p = &node.cov;
        let x = &node.mean;
        let mean_pred = Vector4::new(x[0] + tau * x[2], x[1] + tau * x[3], x[2], x[3]);
        let mut cov_pred = self.config.motion.transport_covariance(p, gap as u32);
        cov_pred += self.process_noise[gap - 1];
        let s: Matrix2<f64> =
            cov_pred.fixed_view::<2, 2>(0, 0).into_owned() + self.config.measurement_noise;
        let det = s[(0, 0)] * s[(1, 1)] - s[(0, 1)] * s[(1, 0)];
        let s_inv = Matrix2::new(s[(1, 1)], -s[(0, 1)], -s[(1, 0)], s[(0, 0)]) / det;
        let residual = y - mean_pred.fixed_rows::<2>(0);
        let maha = residual.dot(&(s_inv * residual));
        let log_likelihood = -LN_2PI - 0.5 * det.ln() - 0.5 * maha;
        let ph: Matrix4x2<f64> = cov_pred.fixed_columns::<2>(0).into_owned();
        let gain = ph * s_inv;
        let mean = mean_pred + gain * residual;
        let cov = cov_pred - gain * ph.transpose();
        let next = Node {
            mean,
            cov: (cov + cov.transpose()) * 0.5,
            cum_log_likelihood: node.cum_log_likelihood + log_likelihood,
        };
        (next, maha)
    }

    /// Filters `meas` (scan-ordered, ≥ 2 measurements) into `nodes`, reusing the first
    /// `keep` entries already there.
    pub(crate) fn filter_track(
        &self,
        problem: &Problem,
        meas: &[MeasId],
        nodes: &mut Vec<Node>,
        keep: usize,
    ) {
        let keep = self.reusable_prefix(keep.min(nodes.len()));
        nodes.truncate(keep);
        if nodes.is_empty() {
            nodes.push(self.first_node(problem, meas));
        }
        for i in nodes.len()..meas.len() {
            let gap = problem.scan_of(meas[i]) - problem.scan_of(meas[i - 1]);
            let (next, _) = self.step(&nodes[i - 1], problem.position(meas[i]), gap);
            nodes.push(next);
        }
    }

    /// The track's term of the log posterior (all terms of Oh, Russell & Sastry 2009 eq. 9 that
    /// the track changes, with the false-alarm baseline taken out):
    /// log λ_b + [ends before the last scan] log p_z (or see [`crate::TrackEnd`])
    /// + (t_last − t_first) log(1 − p_z)
    /// + |τ| (log p_d − log λ_f) + (t_last − t_first + 1 − |τ|) log(1 − p_d) + Σ log N(...)
    /// + Σ ln f₁(s)/f₀(s) over the track's measurements
    ///
    /// (the last sum: their score likelihood ratios, [`Problem::push_scan_scored`]; 0 without
    /// scores).
    pub(crate) fn track_weight(
        &self,
        problem: &Problem,
        meas: &[MeasId],
        log_likelihood: f64,
        last_scan: usize,
    ) -> f64 {
        let (Some(&first), Some(&last)) = (meas.first(), meas.last()) else {
            return 0.0;
        };
        let t_first = problem.scan_of(first);
        let t_last = problem.scan_of(last);
        let span = (t_last - t_first) as f64;
        let n = meas.len() as f64;
        let ends = if t_last < last_scan {
            self.log_track_end(last_scan - t_last)
        } else {
            0.0
        };
        self.log_birth
            + ends
            + span * self.log_survive
            + n * self.log_detect_vs_clutter
            + (span + 1.0 - n) * self.log_miss
            + log_likelihood
            + meas
                .iter()
                .map(|&m| problem.log_score_ratio(m))
                .sum::<f64>()
    }
}

impl Node {
    pub(crate) fn cum_log_likelihood(&self) -> f64 {
        self.cum_log_likelihood
    }

    /// The filtered position moved on by `dt` at the filtered velocity.
    pub(crate) fn position_after(&self, dt: f64) -> Vector2<f64> {
        Vector2::new(
            self.mean[0] + dt * self.mean[2],
            self.mean[1] + dt * self.mean[3],
        )
    }
}
