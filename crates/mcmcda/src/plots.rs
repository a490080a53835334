//! Global nearest neighbour on radar plots with any state estimator: the Kalman filter, the
//! EKF, the UKF or an IMM ([`tracker_model::StateEstimator`]) and any measurement model
//! (range-bearing, range-bearing-elevation, positions).
//!
//! Plots come in dwells: the plots a sensor reports at one time over the part of its coverage
//! it looked at (a rotating radar's beam sector). A track is predicted and may miss only when
//! it is in view, so a sensor that sees a sector at a time never counts misses elsewhere; a
//! track at a sector's edge may take a plot there but is not missed there ([`View::Edge`]),
//! because its plot may fall in the neighbouring dwell.
//! Each dwell is one optimal assignment of the tracks in view to the plots, weighted by the
//! log-likelihood ratio of target against clutter, ln p(z | track) − ln λ (Blackman &
//! Popoli 1999, §6.3, the GNN score); pairs outside the χ² gate or below zero are not made.
//! Tracks start tentative on an unassigned plot, are confirmed after `confirm_hits` hits in
//! their first `confirm_window` dwells in view, and are deleted after `max_misses` misses
//! in a row.

use std::collections::BTreeMap;

use nalgebra::{Matrix2, SMatrix, SVector};
use serde::{Deserialize, Serialize};
use tracker_model::{
    Detection, Error as ModelError, Frame, Gaussian, LinearObservation, MeasurementModel,
    MeasurementPrediction, RangeBearing, StateEstimator, TrackId, TrackPoint, TrackSet, TrackState,
    Tracker, Vec2, assignment, ensure_positive,
};

use crate::error::Result;

/// The most tracks, tentative and confirmed, a [`PlotGnn`] keeps.
pub const MAX_PLOT_TRACKS: usize = 100_000;

/// The most plots in one dwell.
pub const MAX_DWELL_PLOTS: usize = 100_000;

/// Gate, clutter density, confirmation and deletion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlotGnnConfig {
    /// χ² gate on the innovation (M degrees of freedom).
    pub gate_chi2: f64,
    /// ln λ, λ the false alarms per unit measurement volume (e.g. per metre·radian).
    pub clutter_log_density: f64,
    /// Hits needed to confirm a tentative track …
    pub confirm_hits: u32,
    /// … within its first this many dwells in view.
    pub confirm_window: u32,
    /// Consecutive misses in view that delete a confirmed track.
    pub max_misses: u32,
    /// The most tracks kept; births beyond it are refused and counted.
    pub max_tracks: usize,
}

impl PlotGnnConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        ensure_positive(self.gate_chi2, "gate_chi2")?;
        if !self.clutter_log_density.is_finite() {
            return Err(invalid("clutter_log_density", "must be finite".into()));
        }
        if self.confirm_hits == 0 || self.confirm_hits > self.confirm_window {
            return Err(invalid(
                "confirm_hits",
                format!(
                    "{} must be between 1 and confirm_window ({})",
                    self.confirm_hits, self.confirm_window
                ),
            ));
        }
        if self.confirm_window > 1000 || self.max_misses == 0 || self.max_misses > 1000 {
            return Err(invalid(
                "confirm_window / max_misses",
                format!(
                    "{} / {}: each must be 1 to 1000",
                    self.confirm_window, self.max_misses
                ),
            ));
        }
        if self.max_tracks == 0 || self.max_tracks > MAX_PLOT_TRACKS {
            return Err(invalid(
                "max_tracks",
                format!("{} must be 1 to {MAX_PLOT_TRACKS}", self.max_tracks),
            ));
        }
        Ok(())
    }
}

fn invalid(name: &'static str, reason: String) -> crate::Error {
    crate::Error::Model(ModelError::InvalidParameter { name, reason })
}

/// Where a track's predicted measurement falls against what a dwell looked at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// Outside: the track is left alone.
    Out,
    /// At the edge (within the prediction's error of the border): the track may take a plot,
    /// but a dwell without one is no miss, since the neighbouring dwell may hold its plot.
    Edge,
    /// Inside: the track takes a plot or misses.
    In,
}

/// One dwell of one sensor.
pub struct Dwell<'a, O: ?Sized, const N: usize, const M: usize> {
    /// When, in seconds; dwells come in order of time.
    pub time_s: f64,
    /// The sensor's measurement model (its position, its noise).
    pub sensor: &'a O,
    /// The plots.
    pub plots: &'a [SVector<f64, M>],
    /// Where a predicted measurement falls against the part of the coverage looked at.
    pub in_view: &'a dyn Fn(&SVector<f64, M>) -> View,
    /// The state of a new target from its first plot.
    pub birth: &'a dyn Fn(&SVector<f64, M>) -> tracker_model::Result<Gaussian<N>>,
}

/// A confirmed track's estimate after a dwell that saw it.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotTrackState<const N: usize> {
    /// The track.
    pub id: TrackId,
    /// The dwell's time.
    pub time_s: f64,
    /// The estimate (an IMM's combined Gaussian).
    pub estimate: Gaussian<N>,
    /// Whether a plot updated it (else it coasted).
    pub hit: bool,
}

#[derive(Debug, Clone)]
struct PlotTrack<B> {
    id: Option<TrackId>,
    belief: B,
    time_s: f64,
    hits: u32,
    chances: u32,
    misses: u32,
}

/// GNN over dwells of plots with the estimator `E`.
#[derive(Debug, Clone)]
pub struct PlotGnn<E: StateEstimator<N>, const N: usize> {
    estimator: E,
    config: PlotGnnConfig,
    tracks: Vec<PlotTrack<E::Belief>>,
    next_id: u64,
    last_time_s: f64,
    births_refused: u64,
}

/// A track in view: where it is in `tracks`, its prediction to the dwell.
struct InView<B, const M: usize> {
    index: usize,
    predicted: B,
    zhat: MeasurementPrediction<M>,
    view: View,
}

impl<E: StateEstimator<N>, const N: usize> PlotGnn<E, N> {
    /// A tracker with no tracks; fails if `config` does not pass [`PlotGnnConfig::check`].
    pub fn new(estimator: E, config: PlotGnnConfig) -> Result<Self> {
        config.check()?;
        Ok(Self {
            estimator,
            config,
            tracks: Vec::new(),
            next_id: 1,
            last_time_s: f64::NEG_INFINITY,
            births_refused: 0,
        })
    }

    /// Tracks held, tentative and confirmed.
    pub fn track_count(&self) -> usize {
        self.tracks.len()
    }

    /// Births refused because `max_tracks` were held.
    pub fn births_refused(&self) -> u64 {
        self.births_refused
    }

    /// Associates one dwell, updates, confirms, deletes and starts tracks; returns the
    /// confirmed tracks the dwell saw.
    pub fn step<O, const M: usize>(
        &mut self,
        dwell: &Dwell<'_, O, N, M>,
    ) -> Result<Vec<PlotTrackState<N>>>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        self.check_dwell(dwell)?;
        let in_view = self.tracks_in_view(dwell)?;
        let (pairs, updates) = self.associate(dwell, &in_view)?;
        let mut taken = vec![false; dwell.plots.len()];
        let mut out = Vec::new();
        for (k, view) in in_view.into_iter().enumerate() {
            if pairs[k].is_none() && view.view == View::Edge {
                continue;
            }
            let track = &mut self.tracks[view.index];
            track.chances += 1;
            track.time_s = dwell.time_s;
            let hit = match pairs[k] {
                Some(j) => {
                    taken[j] = true;
                    track.belief = updates[k]
                        .clone()
                        .ok_or_else(|| invalid("assignment", "a pair without its update".into()))?;
                    track.hits += 1;
                    track.misses = 0;
                    true
                }
                None => {
                    track.belief = view.predicted;
                    track.misses += 1;
                    false
                }
            };
            if track.id.is_none() && track.hits >= self.config.confirm_hits {
                track.id = Some(TrackId(self.next_id));
                self.next_id += 1;
            }
            if let Some(id) = track.id {
                out.push(PlotTrackState {
                    id,
                    time_s: dwell.time_s,
                    estimate: self.estimator.estimate(&track.belief),
                    hit,
                });
            }
        }
        self.delete_lost();
        self.start_tracks(dwell, &taken)?;
        self.last_time_s = dwell.time_s;
        Ok(out)
    }

    fn check_dwell<O, const M: usize>(&self, dwell: &Dwell<'_, O, N, M>) -> Result<()>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        if !dwell.time_s.is_finite() || dwell.time_s < self.last_time_s {
            return Err(invalid(
                "time_s",
                format!(
                    "dwell at {} s after one at {} s; dwells come in order of time",
                    dwell.time_s, self.last_time_s
                ),
            ));
        }
        if dwell.plots.len() > MAX_DWELL_PLOTS {
            return Err(invalid(
                "plots",
                format!(
                    "{} plots in one dwell; at most {MAX_DWELL_PLOTS}",
                    dwell.plots.len()
                ),
            ));
        }
        Ok(())
    }

    /// Every track whose predicted measurement is in view, predicted to the dwell.
    fn tracks_in_view<O, const M: usize>(
        &self,
        dwell: &Dwell<'_, O, N, M>,
    ) -> Result<Vec<InView<E::Belief, M>>>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        let mut in_view = Vec::new();
        for (index, track) in self.tracks.iter().enumerate() {
            let predicted = self
                .estimator
                .predict(&track.belief, dwell.time_s - track.time_s)?;
            let zhat = self
                .estimator
                .predict_measurement(dwell.sensor, &predicted)?;
            let view = (dwell.in_view)(zhat.mean());
            if view != View::Out {
                in_view.push(InView {
                    index,
                    predicted,
                    zhat,
                    view,
                });
            }
        }
        Ok(in_view)
    }

    /// The optimal assignment of tracks in view to plots: for each track its plot, and its
    /// update with that plot.
    #[expect(clippy::type_complexity, reason = "two parallel per-track lists")]
    fn associate<O, const M: usize>(
        &self,
        dwell: &Dwell<'_, O, N, M>,
        in_view: &[InView<E::Belief, M>],
    ) -> Result<(Vec<Option<usize>>, Vec<Option<E::Belief>>)>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        let (rows, cols) = (in_view.len(), dwell.plots.len());
        let mut weights = vec![0.0; rows * cols];
        let mut candidates: Vec<Vec<(usize, E::Belief)>> = vec![Vec::new(); rows];
        for (i, view) in in_view.iter().enumerate() {
            for (j, z) in dwell.plots.iter().enumerate() {
                if view.zhat.mahalanobis_sq(dwell.sensor, z) > self.config.gate_chi2 {
                    continue;
                }
                let scored = self.estimator.update(dwell.sensor, &view.predicted, z)?;
                let w = scored.log_likelihood - self.config.clutter_log_density;
                if w > 0.0 {
                    weights[i * cols + j] = w;
                    candidates[i].push((j, scored.belief));
                }
            }
        }
        let mut pairs = vec![None; rows];
        let mut updates = vec![None; rows];
        for (i, j) in assignment::maximise(rows, cols, &weights)? {
            if weights[i * cols + j] > 0.0 {
                pairs[i] = Some(j);
                updates[i] = candidates[i]
                    .iter()
                    .find(|(c, _)| *c == j)
                    .map(|(_, b)| b.clone());
            }
        }
        Ok((pairs, updates))
    }

    fn delete_lost(&mut self) {
        let config = self.config;
        self.tracks.retain(|t| match t.id {
            Some(_) => t.misses < config.max_misses,
            // Tentative: still able to reach confirm_hits within the window.
            None => {
                let left = config.confirm_window.saturating_sub(t.chances);
                t.hits + left >= config.confirm_hits
            }
        });
    }

    fn start_tracks<O, const M: usize>(
        &mut self,
        dwell: &Dwell<'_, O, N, M>,
        taken: &[bool],
    ) -> Result<()>
    where
        O: MeasurementModel<N, M> + ?Sized,
    {
        for (z, _) in dwell.plots.iter().zip(taken).filter(|(_, t)| !**t) {
            if self.tracks.len() >= self.config.max_tracks {
                self.births_refused += 1;
                continue;
            }
            let belief = self.estimator.start((dwell.birth)(z)?)?;
            let id = (self.config.confirm_hits == 1).then(|| {
                self.next_id += 1;
                TrackId(self.next_id - 1)
            });
            self.tracks.push(PlotTrack {
                id,
                belief,
                time_s: dwell.time_s,
                hits: 1,
                chances: 1,
                misses: 0,
            });
        }
        Ok(())
    }
}

/// How a track starts from one plot: its position converted from the plot, its velocity zero
/// with σ `sigma_speed_m_s` per axis and, in a five-component state, its turn rate zero with σ
/// `sigma_turn_rad_s`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BirthPrior {
    /// σ of each velocity component, m/s.
    pub sigma_speed_m_s: f64,
    /// σ of the turn rate, rad/s.
    pub sigma_turn_rad_s: f64,
}

impl BirthPrior {
    /// The prior of a track started on plot `z` of `sensor`, state [e, n, ė, ṅ(, ω)].
    pub fn at<const N: usize>(
        &self,
        sensor: &RangeBearing<N>,
        z: &SVector<f64, 2>,
    ) -> tracker_model::Result<Gaussian<N>> {
        let (p, pc) = sensor.position_of(z);
        self.around(&p, &pc)
    }

    /// The prior of a track started at a position with this covariance.
    pub fn around<const N: usize>(
        &self,
        position: &SVector<f64, 2>,
        covariance: &SMatrix<f64, 2, 2>,
    ) -> tracker_model::Result<Gaussian<N>> {
        let mut mean = SVector::<f64, N>::zeros();
        let mut cov = SMatrix::<f64, N, N>::zeros();
        mean.fixed_rows_mut::<2>(0).copy_from(position);
        cov.fixed_view_mut::<2, 2>(0, 0).copy_from(covariance);
        for i in 2..N {
            let sigma = if i < 4 {
                self.sigma_speed_m_s
            } else {
                self.sigma_turn_rad_s
            };
            cov[(i, i)] = sigma * sigma;
        }
        Gaussian::new(mean, cov)
    }
}

/// Detections that share a covariance: it, and their positions.
type Group = (Matrix2<f64>, Vec<SVector<f64, 2>>);

/// [`PlotGnn`] behind the one tracker interface, on point [`Detection`]s in the plane: each
/// frame is a dwell that sees everything, `frame_s` seconds after the last; a detection's
/// covariance (else `position_covariance`) is its noise, and detections with the same
/// covariance share a dwell. With any estimator: KF, EKF, UKF or an IMM.
pub struct PointGnn<E: StateEstimator<N>, const N: usize> {
    gnn: PlotGnn<E, N>,
    frame_s: f64,
    position_covariance: Matrix2<f64>,
    birth: BirthPrior,
    tracks: BTreeMap<TrackId, Vec<TrackPoint>>,
}

impl<E: StateEstimator<N>, const N: usize> PointGnn<E, N> {
    /// A tracker on frames `frame_s` seconds apart.
    pub fn new(
        gnn: PlotGnn<E, N>,
        frame_s: f64,
        position_covariance: Matrix2<f64>,
        birth: BirthPrior,
    ) -> Result<Self> {
        ensure_positive(frame_s, "frame_s")?;
        tracker_model::CholeskyFactor::new(&position_covariance, "position_covariance")?;
        Ok(Self {
            gnn,
            frame_s,
            position_covariance,
            birth,
            tracks: BTreeMap::new(),
        })
    }
}

impl<E: StateEstimator<N>, const N: usize> Tracker for PointGnn<E, N> {
    type Error = crate::Error;

    fn step(&mut self, frame: Frame, detections: &[Detection]) -> Result<Vec<TrackState>> {
        let time_s = f64::from(frame) * self.frame_s;
        // Detections by their covariance's bits: one dwell each.
        let mut groups: BTreeMap<[u64; 4], Group> = BTreeMap::new();
        for d in detections {
            let r = d.covariance.unwrap_or(self.position_covariance);
            let p = d.position();
            let key = [r[(0, 0)], r[(0, 1)], r[(1, 0)], r[(1, 1)]].map(f64::to_bits);
            groups
                .entry(key)
                .or_insert_with(|| (r, Vec::new()))
                .1
                .push(SVector::<f64, 2>::new(p.x, p.y));
        }
        if groups.is_empty() {
            groups.insert([0; 4], (self.position_covariance, Vec::new()));
        }
        let mut out = Vec::new();
        for (r, plots) in groups.values() {
            let sensor = LinearObservation::<N, 2>::leading_components(*r)?;
            let birth = self.birth;
            let dwell = Dwell {
                time_s,
                sensor: &sensor,
                plots,
                in_view: &|_| View::In,
                birth: &|z| birth.around::<N>(z, r),
            };
            for s in self.gnn.step(&dwell)? {
                let m = s.estimate.mean();
                let point = TrackPoint::at(frame, Vec2::new(m[0], m[1]));
                let track = self.tracks.entry(s.id).or_default();
                if track.last().is_none_or(|p| p.frame < frame) {
                    track.push(point);
                    out.push(TrackState { id: s.id, point });
                }
            }
        }
        Ok(out)
    }

    fn finish(&mut self) -> Result<TrackSet> {
        Ok(TrackSet::from_point_lists(std::mem::take(
            &mut self.tracks,
        ))?)
    }
}
