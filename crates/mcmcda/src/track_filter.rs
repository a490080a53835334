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
    /// Σ of the score ratios ln f₁/f₀ of the track's measurements up to this one (set by
    /// [`Model::filter_track`]; summed in scan order, as the posterior term sums them), so
    /// that a track's weight costs O(1), not a pass over the track.
    cum_log_score: f64,
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
                    cum_log_score: 0.0,
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
                    cum_log_score: 0.0,
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
    #[inline]
    pub(crate) fn step(&self, node: &Node, y: Vector2<f64>, gap: usize) -> (Node, f64) {
        if self.axes_decoupled {
            self.step_by_axis(node, y, gap)
        } else {
            self.step_general(node, y, gap)
        }
    }

    /// [`Self::step`] when nothing couples the x and y axes (R, every Q(d) and the start
    /// covariance without x–y terms, so every filtered covariance is without them too): each
    /// axis's (position, velocity) block on its own. Every remaining entry is the same
    /// expression of the same operands as in [`Self::step_general`], whose products with the
    /// coupling entries are exact zeros that do not change a floating-point sum, so the
    /// result is the general route's bit for bit (test
    /// `kalman_step_by_axis_equals_the_general_step`) at about a third of the operations.
    pub(crate) fn step_by_axis(&self, node: &Node, y: Vector2<f64>, gap: usize) -> (Node, f64) {
        let tau = gap as f64 * self.config.motion.dt_s();
        let (p, x) = (&node.cov, &node.mean);
        let q = &self.process_noise[gap - 1];
        let r = &self.config.measurement_noise;
        // Predicted blocks per axis a (position a, velocity a + 2), as transport_covariance
        // and the added Q(d) form them.
        let block = |a: usize| {
            let (i, j) = (a, a + 2);
            let (c, b, bt) = (p[(j, j)], p[(i, j)], p[(j, i)]);
            [
                p[(i, i)] + tau * (b + bt) + tau * tau * c + q[(i, i)],
                b + tau * c + q[(i, j)],
                bt + tau * c + q[(j, i)],
                c + q[(j, j)],
            ]
        };
        let (bx, by) = (block(0), block(1));
        let (s00, s11) = (bx[0] + r[(0, 0)], by[0] + r[(1, 1)]);
        let det = s00 * s11;
        let (inv_x, inv_y) = (s11 / det, s00 / det);
        let mean_pred = [x[0] + tau * x[2], x[1] + tau * x[3]];
        let residual = [y.x - mean_pred[0], y.y - mean_pred[1]];
        let maha = residual[0] * (inv_x * residual[0]) + residual[1] * (inv_y * residual[1]);
        let log_likelihood = -LN_2PI - 0.5 * det.ln() - 0.5 * maha;
        let mut mean = Vector4::zeros();
        let mut cov = Matrix4::zeros();
        for (a, bl, inv) in [(0, bx, inv_x), (1, by, inv_y)] {
            let (i, j) = (a, a + 2);
            let [pp, pv, vp, vv] = bl;
            let (g_pos, g_vel) = (pp * inv, vp * inv);
            mean[i] = mean_pred[a] + g_pos * residual[a];
            mean[j] = x[j] + g_vel * residual[a];
            let (c_pp, c_pv, c_vp, c_vv) = (
                pp - g_pos * pp,
                pv - g_pos * vp,
                vp - g_vel * pp,
                vv - g_vel * vp,
            );
            cov[(i, i)] = (c_pp + c_pp) * 0.5;
            cov[(i, j)] = (c_pv + c_vp) * 0.5;
            cov[(j, i)] = (c_vp + c_pv) * 0.5;
            cov[(j, j)] = (c_vv + c_vv) * 0.5;
        }
        let next = Node {
            mean,
            cov,
            cum_log_likelihood: node.cum_log_likelihood + log_likelihood,
            cum_log_score: node.cum_log_score,
        };
        (next, maha)
    }

    /// [`Self::step`] by the general 4 × 4 route.
    pub(crate) fn step_general(&self, node: &Node, y: Vector2<f64>, gap: usize) -> (Node, f64) {
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
            cum_log_score: node.cum_log_score,
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
            let mut first = self.first_node(problem, meas);
            // The first term of the sum in scan order (-0.0 + r = r: f64's `sum` starts at
            // -0.0).
            first.cum_log_score = problem.log_score_ratio(meas[0]);
            nodes.push(first);
        }
        for i in nodes.len()..meas.len() {
            let gap = problem.scan_of(meas[i]) - problem.scan_of(meas[i - 1]);
            let (mut next, _) = self.step(&nodes[i - 1], problem.position(meas[i]), gap);
            next.cum_log_score += problem.log_score_ratio(meas[i]);
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
        last_node: &Node,
        last_scan: usize,
    ) -> f64 {
        let log_likelihood = last_node.cum_log_likelihood;
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
            + last_node.cum_log_score
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

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix2, Vector2};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use tracker_model::ConstantVelocity2;

    use crate::config::McmcdaConfig;

    /// The per-axis Kalman step is the general 4 × 4 step bit for bit (== on every entry)
    /// along random tracks with random gaps, for several decoupled models; a coupled R
    /// takes the general route.
    #[test]
    fn kalman_step_by_axis_equals_the_general_step() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut steps = 0;
        for (q, rx, ry) in [(0.86, 7.1, 27.0), (4.4, 10.3, 35.0), (1e-3, 100.0, 1.0)] {
            let model = McmcdaConfig {
                motion: ConstantVelocity2::mcmcda(1.0, q).unwrap(),
                measurement_noise: Matrix2::new(rx, 0.0, 0.0, ry),
                max_gap: 6,
                max_speed: 50.0,
                ..McmcdaConfig::default()
            }
            .check()
            .unwrap();
            assert!(model.axes_decoupled);
            let (mean, cov) = model.start_at(Vector2::new(100.0, 50.0), 30.0);
            let mut node = super::Node {
                mean,
                cov,
                cum_log_likelihood: 0.0,
                cum_log_score: 0.0,
            };
            let mut at = Vector2::new(100.0, 50.0);
            for _ in 0..200 {
                let gap = rng.random_range(1..=6);
                at += Vector2::new(rng.random_range(-9.0..9.0), rng.random_range(-4.0..4.0))
                    * gap as f64;
                let (fast, maha_fast) = model.step_by_axis(&node, at, gap);
                let (slow, maha_slow) = model.step_general(&node, at, gap);
                assert_eq!(maha_fast.to_bits(), maha_slow.to_bits());
                assert_eq!(
                    fast.cum_log_likelihood.to_bits(),
                    slow.cum_log_likelihood.to_bits()
                );
                assert!(fast.mean == slow.mean, "{} vs {}", fast.mean, slow.mean);
                assert!(fast.cov == slow.cov, "{} vs {}", fast.cov, slow.cov);
                node = slow;
                steps += 1;
            }
        }
        assert_eq!(steps, 600);
        let coupled = McmcdaConfig {
            measurement_noise: Matrix2::new(100.0, 10.0, 10.0, 100.0),
            ..McmcdaConfig::default()
        }
        .check()
        .unwrap();
        assert!(!coupled.axes_decoupled);
    }
}
