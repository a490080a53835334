//! The crate's trackers behind tracker-model's one interface: [`OnlineTracker`] steps frame by
//! frame ([`tracker_model::Tracker`]); [`BatchMcmcda`] and [`Gnn`] take a whole window
//! ([`tracker_model::BatchTracker`]); [`JpdaTracker`] follows a known set of targets with
//! single-scan association (Oh, Russell & Sastry 2009, Algorithms 1-2, or exact JPDA).
//!
//! Detection scores are not read here (their likelihood ratio needs densities fitted to the
//! data, which `Problem::push_scan_scored` takes); only positions (a box's centre) are.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tracker_model::{
    BatchTracker, Detection, Frame, FrameDetections, Gaussian, PositionMeasurement2, Track,
    TrackId, TrackPoint, TrackSet, TrackState, Tracker, TransitionModel, Vec2,
};

use crate::error::{Error, Result};
use crate::{
    BatchConfig, Model, NearestNeighbourConfig, OnlineTracker, Problem, SingleScanConfig,
    batch_mcmcda, jpda_exact, nearest_neighbour_tracks, single_scan_mcmcda, smoothed_tracks,
};

fn positions(detections: &[Detection]) -> Vec<Vec2> {
    detections.iter().map(Detection::position).collect()
}

impl Tracker for OnlineTracker {
    type Error = Error;

    /// [`OnlineTracker::push_scan`] on the detections' positions; the states are the tracks the
    /// window's MAP reports at `frame`, labels as ids.
    fn step(&mut self, frame: Frame, detections: &[Detection]) -> Result<Vec<TrackState>> {
        let step = self.push_scan(frame, &positions(detections))?;
        Ok(step
            .estimates
            .iter()
            .map(|&(label, p)| TrackState {
                id: TrackId(label),
                point: TrackPoint::at(frame, p),
            })
            .collect())
    }

    /// [`OnlineTracker::finish`]'s smoothed tracks. The tracker is spent: it holds no
    /// measurement afterwards.
    fn finish(&mut self) -> Result<TrackSet> {
        Ok(self.finish_in_place()?.tracks)
    }
}

/// The scans as a [`Problem`] (built by `empty`, with or without neighbourhood lists),
/// associated by `associate` and smoothed ([`smoothed_tracks`], ids from 1); no scan, no track.
fn associate_and_smooth(
    model: &Model,
    scans: &[FrameDetections],
    empty: fn(&Model, Frame) -> Problem,
    associate: impl FnOnce(&Problem) -> Result<Vec<Vec<crate::MeasId>>>,
) -> Result<TrackSet> {
    let Some(first) = scans.first() else {
        return Ok(TrackSet::new());
    };
    let mut problem = empty(model, first.frame);
    for scan in scans {
        problem.push_scan(scan.frame, &positions(&scan.detections))?;
    }
    let tracks = associate(&problem)?;
    smoothed_tracks(model, &problem, &tracks, 1)
}

/// Offline multi-scan MCMCDA ([`batch_mcmcda`]) over the whole window, tracks smoothed
/// ([`smoothed_tracks`]).
#[derive(Debug, Clone)]
pub struct BatchMcmcda {
    /// The checked model.
    pub model: Model,
    /// Chains, samples and seed.
    pub config: BatchConfig,
}

impl BatchTracker for BatchMcmcda {
    type Error = Error;

    fn track(&mut self, scans: &[FrameDetections]) -> Result<TrackSet> {
        associate_and_smooth(&self.model, scans, Problem::empty, |problem| {
            Ok(batch_mcmcda(&self.model, problem, &self.config)?.tracks)
        })
    }
}

/// Global nearest neighbour ([`nearest_neighbour_tracks`]) over the whole window, tracks
/// smoothed ([`smoothed_tracks`]).
#[derive(Debug, Clone)]
pub struct Gnn {
    /// The checked model.
    pub model: Model,
    /// Assignment, cost, gate and confirmation.
    pub config: NearestNeighbourConfig,
}

impl BatchTracker for Gnn {
    type Error = Error;

    fn track(&mut self, scans: &[FrameDetections]) -> Result<TrackSet> {
        associate_and_smooth(
            &self.model,
            scans,
            Problem::without_neighbourhoods,
            |problem| {
                nearest_neighbour_tracks(&self.model, problem, problem.all_scans()?, &self.config)
            },
        )
    }
}

/// How [`JpdaTracker`] computes the association probabilities β.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JpdaAssociation {
    /// By enumerating every joint event ([`jpda_exact`]; exponential in the targets).
    Exact,
    /// By Algorithms 1-2's chain over matchings ([`single_scan_mcmcda`]).
    Mcmc,
}

/// A known set of targets followed by JPDA: each frame predicts every target (over the whole
/// gap since the last frame, in one step), computes β and takes the JPDA posterior. Target i
/// is track i + 1 in every frame (the number of targets is known, as in the paper's
/// single-scan setting).
#[derive(Debug, Clone)]
pub struct JpdaTracker<M> {
    motion: M,
    sensor: PositionMeasurement2,
    config: SingleScanConfig,
    association: JpdaAssociation,
    targets: Vec<Gaussian<4>>,
    /// The frame of the priors, then of the last step.
    last: Frame,
    stepped: bool,
    rng: ChaCha8Rng,
    tracks: Vec<Vec<TrackPoint>>,
}

impl<M: TransitionModel<4>> JpdaTracker<M> {
    /// Targets with the given states at frame `start`; the MCMC association draws from ChaCha8
    /// seeded with `seed`. Fails if `config` does not pass [`SingleScanConfig::check`].
    pub fn new(
        motion: M,
        sensor: PositionMeasurement2,
        priors: Vec<Gaussian<4>>,
        start: Frame,
        config: SingleScanConfig,
        association: JpdaAssociation,
        seed: u64,
    ) -> Result<Self> {
        config.check()?;
        Ok(Self {
            motion,
            sensor,
            config,
            association,
            tracks: vec![Vec::new(); priors.len()],
            targets: priors,
            last: start,
            stepped: false,
            rng: ChaCha8Rng::seed_from_u64(seed),
        })
    }
}

impl<M: TransitionModel<4>> Tracker for JpdaTracker<M> {
    type Error = Error;

    fn step(&mut self, frame: Frame, detections: &[Detection]) -> Result<Vec<TrackState>> {
        // The first step may be at the priors' frame; every later one is later.
        if frame < self.last || (self.stepped && frame == self.last) {
            return Err(Error::Model(tracker_model::Error::InvalidParameter {
                name: "frame",
                reason: format!("{frame} is not after the last frame, {}", self.last),
            }));
        }
        let steps = frame - self.last;
        let predicted: Vec<Gaussian<4>> = self
            .targets
            .iter()
            .map(|t| self.motion.predict_steps(t, steps))
            .collect();
        let ys = positions(detections);
        let result = match self.association {
            JpdaAssociation::Exact => jpda_exact(&predicted, &self.sensor, &ys, &self.config)?,
            JpdaAssociation::Mcmc => {
                single_scan_mcmcda(&predicted, &self.sensor, &ys, &self.config, &mut self.rng)?
            }
        };
        self.targets = result.states;
        self.last = frame;
        self.stepped = true;
        let mut states = Vec::with_capacity(self.targets.len());
        for (i, (target, track)) in self.targets.iter().zip(&mut self.tracks).enumerate() {
            let m = target.mean();
            let point = TrackPoint::at(frame, Vec2::new(m[0], m[1]));
            track.push(point);
            states.push(TrackState {
                id: TrackId(i as u64 + 1),
                point,
            });
        }
        Ok(states)
    }

    fn finish(&mut self) -> Result<TrackSet> {
        let tracks = self
            .tracks
            .iter()
            .enumerate()
            .filter(|(_, points)| !points.is_empty())
            .map(|(i, points)| Track::from_points(TrackId(i as u64 + 1), points.clone()))
            .collect::<tracker_model::Result<Vec<_>>>()?;
        Ok(TrackSet::from_tracks(tracks)?)
    }
}
