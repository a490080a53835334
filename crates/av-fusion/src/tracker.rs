//! The whole chain: reports into the fusion node, one fused scan per scheduler tick, the
//! scans' peak lists into online MCMCDA (Oh, Russell & Sastry 2009 Algorithm 4), tracks out as
//! a [`TrackSet`] whose frames are the scheduler's ticks.

use mcmcda::{McmcdaConfig, OnlineConfig, OnlineStep, OnlineTracker};
use serde::{Deserialize, Serialize};
use tracker_model::{Frame, FrameClock, TrackSet};

use crate::buffer::{Arrival, FusionNode, SchedulerConfig};
use crate::error::{Error, Result, invalid};
use crate::fusion::{FusedScan, FusionConfig, fuse_snapshot};
use crate::node::{Report, SensorNode};

/// The tracker: the MCMCDA model (its motion period must be the scheduler's period), the
/// online window and the seed of the sampler's generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackerConfig {
    /// The posterior and proposal; measurement noise R should match the peaks' typical
    /// covariance (see [`crate::PeakMeasurement::covariance`]).
    pub mcmcda: McmcdaConfig,
    /// Window and samples per scan.
    pub online: OnlineConfig,
    /// Seed of the sampler's ChaCha8 generator.
    pub seed: u64,
}

/// Everything the pipeline needs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AvConfig {
    /// Scheduler and buffers.
    pub scheduler: SchedulerConfig,
    /// Grids, rule and peaks.
    pub fusion: FusionConfig,
    /// Online MCMCDA.
    pub tracker: TrackerConfig,
}

impl AvConfig {
    /// Checks every part and that the tracker's motion period equals the tick period.
    pub fn check(&self) -> Result<()> {
        self.scheduler.check()?;
        self.fusion.check()?;
        self.tracker.online.check()?;
        let motion_dt_s = self.tracker.mcmcda.motion.dt_s();
        let tick_s = self.scheduler.period_s();
        if (motion_dt_s - tick_s).abs() > 1e-9 * tick_s {
            return Err(Error::PeriodMismatch {
                motion_dt_s,
                tick_s,
            });
        }
        Ok(())
    }
}

/// The fusion node with its tracker, processing ticks in order.
pub struct AvPipeline {
    node: FusionNode,
    fusion: FusionConfig,
    tracker: OnlineTracker,
    clock: FrameClock,
    next_tick: u64,
}

impl AvPipeline {
    /// A pipeline for `sensors` whose first tick is 0.
    pub fn new(sensors: Vec<SensorNode>, config: &AvConfig) -> Result<Self> {
        config.check()?;
        let model = config.tracker.mcmcda.check()?;
        let node = FusionNode::new(sensors, config.scheduler)?;
        let clock = FrameClock::new(config.scheduler.start_s, config.scheduler.period_s())?;
        Ok(Self {
            node,
            fusion: config.fusion.clone(),
            tracker: OnlineTracker::new(model, 0, config.tracker.online, config.tracker.seed)?,
            clock,
            next_tick: 0,
        })
    }

    /// The fusion node (sensors and buffers).
    pub fn node(&self) -> &FusionNode {
        &self.node
    }

    /// Ticks to frames and back: tick k is frame k at `start_s + k / rate_hz`.
    pub fn clock(&self) -> FrameClock {
        self.clock
    }

    /// The next tick to process.
    pub fn next_tick(&self) -> u64 {
        self.next_tick
    }

    /// Receives a report (any order; see [`FusionNode::receive`]).
    pub fn receive(&mut self, report: Report) -> Result<Arrival> {
        self.node.receive(report)
    }

    /// Fuses tick `k` (≥ the next tick; skipped ticks are empty scans for the tracker) and
    /// feeds its peaks to the tracker.
    pub fn process(&mut self, k: u64) -> Result<(FusedScan, OnlineStep)> {
        if k < self.next_tick {
            return Err(Error::TickOutOfOrder {
                tick: k,
                last: self.next_tick - 1,
            });
        }
        let frame = Frame::try_from(k).map_err(|_| invalid("tick", format!("{k} exceeds u32")))?;
        let scan = fuse_snapshot(self.node.sensors(), &self.node.snapshot(k), &self.fusion)?;
        let points: Vec<_> = scan.peaks.iter().map(|p| p.position).collect();
        let step = self.tracker.push_scan(frame, &points)?;
        self.next_tick = k + 1;
        Ok((scan, step))
    }

    /// Commits the window and returns the smoothed tracks (frames = ticks).
    pub fn finish(self) -> Result<TrackSet> {
        Ok(self.tracker.finish()?.tracks)
    }
}

/// What [`track_reports`] produced.
#[derive(Debug, Clone)]
pub struct AvRun {
    /// The tracks, frames = ticks.
    pub tracks: TrackSet,
    /// Every tick's fused scan.
    pub scans: Vec<FusedScan>,
    /// Ticks to seconds.
    pub clock: FrameClock,
}

/// Runs the pipeline over recorded reports for ticks 0..n_ticks as the live system would:
/// reports are delivered in fusion-time order, and tick k is processed once every report up
/// to its time plus the staleness limit has arrived (the scheduler's latency is the
/// staleness limit). Out-of-order reports in `reports` are fine.
pub fn track_reports(
    sensors: Vec<SensorNode>,
    mut reports: Vec<Report>,
    n_ticks: u64,
    config: &AvConfig,
) -> Result<AvRun> {
    let mut pipeline = AvPipeline::new(sensors, config)?;
    let fusion_time = |r: &Report| {
        pipeline
            .node
            .sensors()
            .get(r.sensor)
            .map_or(r.local_time_s, |s| s.fusion_time_s(r.local_time_s))
    };
    let mut keyed: Vec<(f64, Report)> = reports.drain(..).map(|r| (fusion_time(&r), r)).collect();
    keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut pending = keyed.into_iter().peekable();
    // Grown as ticks succeed: a huge `n_ticks` gets `process`'s typed error, not an abort.
    let mut scans = Vec::with_capacity(usize::try_from(n_ticks).unwrap_or(0).min(1 << 16));
    let staleness = config.scheduler.staleness_s;
    for k in 0..n_ticks {
        let due = config.scheduler.tick_time_s(k) + staleness;
        while let Some((_, r)) = pending.next_if(|(t, _)| *t <= due) {
            pipeline.receive(r)?;
        }
        scans.push(pipeline.process(k)?.0);
    }
    let clock = pipeline.clock();
    Ok(AvRun {
        tracks: pipeline.finish()?,
        scans,
        clock,
    })
}
