//! The fusion node's side of the network: one circular buffer of time-stamped reports per
//! sensor, and the periodic scheduler that takes from every buffer the report nearest in time
//! to each fusion time stamp (Kushwaha et al. 2008, §4).

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};
use tracker_model::{ensure_non_negative, ensure_positive};

use crate::error::{Error, Result, invalid};
use crate::node::{Report, SensorNode};

/// A report in a buffer, its time converted to the fusion clock.
#[derive(Debug, Clone, PartialEq)]
pub struct Buffered {
    /// Fusion time, seconds.
    pub time_s: f64,
    /// The profile values.
    pub values: Vec<f64>,
}

/// What happened to an arriving report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arrival {
    /// Stored in time order (late arrivals go to their place).
    Stored,
    /// Stored; the oldest report was dropped to make room.
    StoredDroppingOldest,
    /// Replaced a report with the same time stamp (a re-sent report).
    Replaced,
    /// Dropped: the buffer is full of newer reports.
    DroppedTooOld,
}

/// A circular buffer of reports kept sorted by fusion time, holding at most `capacity`; when
/// full the oldest report makes room, and a report older than everything in a full buffer is
/// dropped.
#[derive(Debug, Clone)]
pub struct SensorBuffer {
    capacity: usize,
    entries: VecDeque<Buffered>,
}

impl SensorBuffer {
    /// An empty buffer; `capacity` ≥ 1.
    pub fn new(capacity: usize) -> Result<Self> {
        if capacity == 0 {
            return Err(invalid("buffer_capacity", "must be at least 1"));
        }
        Ok(Self {
            capacity,
            entries: VecDeque::with_capacity(capacity),
        })
    }

    /// Inserts a report at fusion time `time_s`, keeping time order.
    pub fn insert(&mut self, time_s: f64, values: Vec<f64>) -> Arrival {
        let at = self.entries.partition_point(|e| e.time_s < time_s);
        if let Some(e) = self.entries.get_mut(at)
            && e.time_s.to_bits() == time_s.to_bits()
        {
            e.values = values;
            return Arrival::Replaced;
        }
        let full = self.entries.len() == self.capacity;
        if full && at == 0 {
            return Arrival::DroppedTooOld;
        }
        self.entries.insert(at, Buffered { time_s, values });
        if full {
            self.entries.pop_front();
            Arrival::StoredDroppingOldest
        } else {
            Arrival::Stored
        }
    }

    /// The report nearest to `time_s` no more than `staleness_s` away; on a tie the later
    /// one (the fresher evidence).
    pub fn nearest(&self, time_s: f64, staleness_s: f64) -> Option<&Buffered> {
        let at = self.entries.partition_point(|e| e.time_s < time_s);
        let after = self.entries.get(at);
        let before = at.checked_sub(1).and_then(|i| self.entries.get(i));
        let best = match (before, after) {
            (Some(b), Some(a)) => {
                if time_s - b.time_s < a.time_s - time_s {
                    b
                } else {
                    a
                }
            }
            (Some(e), None) | (None, Some(e)) => e,
            (None, None) => return None,
        };
        ((best.time_s - time_s).abs() <= staleness_s).then_some(best)
    }

    /// Reports held, oldest first.
    pub fn entries(&self) -> impl Iterator<Item = &Buffered> {
        self.entries.iter()
    }

    /// Number of reports held.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the buffer is empty.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// The scheduler and buffers: fusion ticks at `start_s + k / rate_hz`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SchedulerConfig {
    /// Fusion rate, Hz (the tracker's scan rate).
    pub rate_hz: f64,
    /// Fusion time of tick 0, seconds.
    pub start_s: f64,
    /// A sensor whose nearest report is farther than this from the tick is left out of it.
    pub staleness_s: f64,
    /// Reports kept per sensor.
    pub buffer_capacity: usize,
}

impl Default for SchedulerConfig {
    fn default() -> Self {
        Self {
            rate_hz: 10.0,
            start_s: 0.0,
            staleness_s: 0.1,
            buffer_capacity: 32,
        }
    }
}

impl SchedulerConfig {
    /// Checks rate > 0, staleness ≥ 0, finite start and capacity ≥ 1.
    pub fn check(&self) -> Result<()> {
        ensure_positive(self.rate_hz, "rate_hz")?;
        ensure_non_negative(self.staleness_s, "staleness_s")?;
        if !self.start_s.is_finite() {
            return Err(tracker_model::Error::NonFinite { what: "start_s" }.into());
        }
        if self.buffer_capacity == 0 {
            return Err(invalid("buffer_capacity", "must be at least 1"));
        }
        Ok(())
    }

    /// Seconds between ticks.
    pub fn period_s(&self) -> f64 {
        1.0 / self.rate_hz
    }

    /// Fusion time of tick `k`.
    pub fn tick_time_s(&self, k: u64) -> f64 {
        self.start_s + k as f64 / self.rate_hz
    }
}

/// One sensor's contribution to a tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Selected<'a> {
    /// The sensor index.
    pub sensor: usize,
    /// Fusion time of the chosen report.
    pub time_s: f64,
    /// Its values.
    pub values: &'a [f64],
}

/// What the scheduler hands the fusion step for one tick.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot<'a> {
    /// Tick index.
    pub tick: u64,
    /// Fusion time of the tick.
    pub time_s: f64,
    /// The sensors with a report recent enough, in sensor order; the others are absent.
    pub selected: Vec<Selected<'a>>,
}

/// The fusion node's receiving side: registered sensors and their buffers.
#[derive(Debug, Clone)]
pub struct FusionNode {
    sensors: Vec<SensorNode>,
    buffers: Vec<SensorBuffer>,
    config: SchedulerConfig,
}

impl FusionNode {
    /// A node for `sensors` (each checked) with empty buffers.
    pub fn new(sensors: Vec<SensorNode>, config: SchedulerConfig) -> Result<Self> {
        config.check()?;
        if sensors.is_empty() {
            return Err(tracker_model::Error::Empty { what: "sensors" }.into());
        }
        for s in &sensors {
            s.check()?;
        }
        let buffers = sensors
            .iter()
            .map(|_| SensorBuffer::new(config.buffer_capacity))
            .collect::<Result<_>>()?;
        Ok(Self {
            sensors,
            buffers,
            config,
        })
    }

    /// The registered sensors.
    pub fn sensors(&self) -> &[SensorNode] {
        &self.sensors
    }

    /// The scheduler settings.
    pub fn config(&self) -> &SchedulerConfig {
        &self.config
    }

    /// Sensor `i`'s buffer.
    pub fn buffer(&self, i: usize) -> Option<&SensorBuffer> {
        self.buffers.get(i)
    }

    /// Receives a report: checks it, converts its time stamp to the fusion clock (subtracting
    /// the sensor's clock offset) and stores it in time order, whatever order reports come in.
    pub fn receive(&mut self, report: Report) -> Result<Arrival> {
        let n_sensors = self.sensors.len();
        let sensor = self
            .sensors
            .get(report.sensor)
            .ok_or(Error::UnknownSensor {
                sensor: report.sensor,
                n_sensors,
            })?;
        report.check()?;
        let expected = sensor.shape.n_bins();
        if report.values.len() != expected {
            return Err(Error::ProfileLength {
                sensor: report.sensor,
                expected,
                got: report.values.len(),
            });
        }
        let time_s = sensor.fusion_time_s(report.local_time_s);
        Ok(self.buffers[report.sensor].insert(time_s, report.values))
    }

    /// The snapshot of tick `k`: each sensor's report nearest to the tick's time within the
    /// staleness limit; sensors with none are left out (not zero-filled).
    pub fn snapshot(&self, k: u64) -> Snapshot<'_> {
        let time_s = self.config.tick_time_s(k);
        let selected = self
            .buffers
            .iter()
            .enumerate()
            .filter_map(|(sensor, b)| {
                b.nearest(time_s, self.config.staleness_s)
                    .map(|e| Selected {
                        sensor,
                        time_s: e.time_s,
                        values: &e.values,
                    })
            })
            .collect();
        Snapshot {
            tick: k,
            time_s,
            selected,
        }
    }
}
