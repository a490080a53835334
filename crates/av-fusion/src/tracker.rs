//! The whole chain: reports into the fusion node, one fused scan per scheduler tick, the
//! scans' peak lists into online MCMCDA (Oh, Russell & Sastry 2009 Algorithm 4), tracks out as
//! a [`TrackSet`] whose frames are the scheduler's ticks.

use mcmcda::{McmcdaConfig, OnlineConfig, OnlineStep, OnlineTracker};
use serde::{Deserialize, Serialize};
use tracker_model::{Frame, FrameClock, TrackSet};

use crate::buffer::{Arrival, FusionNode, SchedulerConfig};
use crate::error::{Error, Result, invalid};
use crate::fusion::{FusedScan, FusionConfig, RangeFades, fuse_snapshot_with};
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
    /// The peaks' values as detection scores (`None`: every peak counts the same, as the
    /// plain MCMCDA posterior has it).
    #[serde(default)]
    pub peak_scores: Option<PeakScores>,
}

/// The score likelihood ratio ln f₁(c)/f₀(c) of a peak as a function of its contrast c, the
/// fused grid's value at the peak over the grid's mean value (the grid sums to 1, so
/// c = value × cells): piecewise constant, `log_ratios[i]` for c in
/// \[`contrast_edges[i − 1]`, `contrast_edges[i]`) with the outer bins open-ended. MCMCDA adds
/// it to a track's term for every peak the track holds (Lerro & Bar-Shalom's amplitude
/// likelihood ratio, through [`mcmcda::OnlineTracker::push_scan_scored`]), so a strong peak
/// is readily a vehicle and a weak one readily clutter. The table is learnt offline, e.g. from
/// histograms of the contrasts of peaks near and far from known vehicles on calibration runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeakScores {
    /// Strictly increasing, finite.
    pub contrast_edges: Vec<f64>,
    /// One more than the edges, finite.
    pub log_ratios: Vec<f64>,
}

impl PeakScores {
    /// Checks the table's shape and values.
    pub fn check(&self) -> Result<()> {
        if self.log_ratios.len() != self.contrast_edges.len() + 1 {
            return Err(invalid(
                "log_ratios",
                format!(
                    "{} values for {} edges; it needs one more than the edges",
                    self.log_ratios.len(),
                    self.contrast_edges.len()
                ),
            ));
        }
        if let Some(x) = self
            .contrast_edges
            .iter()
            .chain(&self.log_ratios)
            .find(|x| !x.is_finite())
        {
            return Err(invalid("peak_scores", format!("{x} is not finite")));
        }
        if self.contrast_edges.windows(2).any(|w| w[0] >= w[1]) {
            return Err(invalid("contrast_edges", "must be strictly increasing"));
        }
        Ok(())
    }

    /// ln f₁(c)/f₀(c) of a peak of contrast `contrast` (the table is checked first; a
    /// non-finite contrast is an error).
    pub fn log_ratio(&self, contrast: f64) -> Result<f64> {
        self.check()?;
        self.checked_log_ratio(contrast)
    }

    /// [`Self::log_ratio`] for a table already checked (the pipeline checks it once, at
    /// construction, not for every peak).
    fn checked_log_ratio(&self, contrast: f64) -> Result<f64> {
        if !contrast.is_finite() {
            return Err(invalid("contrast", format!("{contrast} is not finite")));
        }
        let bin = self.contrast_edges.partition_point(|&e| e <= contrast);
        self.log_ratios
            .get(bin)
            .copied()
            .ok_or_else(|| invalid("log_ratios", "shorter than the edges"))
    }
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
        if let Some(scores) = &self.tracker.peak_scores {
            scores.check()?;
        }
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
    /// Each sensor's range fade over the grid, computed once.
    fades: RangeFades,
    peak_scores: Option<PeakScores>,
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
        let fades = RangeFades::new(node.sensors(), &config.fusion)?;
        let clock = FrameClock::new(config.scheduler.start_s, config.scheduler.period_s())?;
        Ok(Self {
            node,
            fusion: config.fusion.clone(),
            fades,
            peak_scores: config.tracker.peak_scores.clone(),
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
        let scan = fuse_snapshot_with(
            self.node.sensors(),
            &self.node.snapshot(k),
            &self.fusion,
            &self.fades,
        )?;
        let points: Vec<_> = scan.peaks.iter().map(|p| p.position).collect();
        let step = match &self.peak_scores {
            None => self.tracker.push_scan(frame, &points)?,
            Some(scores) => {
                let cells = scan.grid.values().len() as f64;
                let ratios: Vec<f64> = scan
                    .peaks
                    .iter()
                    .map(|p| scores.checked_log_ratio(p.value * cells))
                    .collect::<Result<_>>()?;
                self.tracker.push_scan_scored(frame, &points, &ratios)?
            }
        };
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
