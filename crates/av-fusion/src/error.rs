//! The one error type of av-fusion.

/// Everything that can go wrong in av-fusion. Variants carry the offending values.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A report names a sensor the fusion node does not know.
    #[error("report for sensor {sensor}, but the fusion node has {n_sensors} sensors")]
    UnknownSensor {
        /// The sensor index in the report.
        sensor: usize,
        /// Sensors registered.
        n_sensors: usize,
    },
    /// A report's profile has a different number of bins than its sensor's shape.
    #[error("sensor {sensor} reports {got} values but its profile has {expected} bins")]
    ProfileLength {
        /// The sensor index.
        sensor: usize,
        /// Bins of the sensor's profile shape.
        expected: usize,
        /// Values in the report.
        got: usize,
    },
    /// A report with a NaN or infinite time stamp or a value that is negative or not finite.
    #[error("sensor {sensor}: report value {index} (or its time stamp) is {value}")]
    BadReport {
        /// The sensor index.
        sensor: usize,
        /// Index of the bad value (`usize::MAX` for the time stamp).
        index: usize,
        /// The value.
        value: f64,
    },
    /// The tracker's motion model period differs from the scheduler's.
    #[error("the tracker's motion period {motion_dt_s} s differs from the scheduler's {tick_s} s")]
    PeriodMismatch {
        /// `McmcdaConfig::motion.dt_s()`.
        motion_dt_s: f64,
        /// 1 / rate of the scheduler.
        tick_s: f64,
    },
    /// A tick was asked for out of order (ticks are processed once, increasing).
    #[error("tick {tick} requested after tick {last} was processed")]
    TickOutOfOrder {
        /// The requested tick.
        tick: u64,
        /// The last processed tick.
        last: u64,
    },
    /// A tracking error.
    #[error(transparent)]
    Mcmcda(#[from] mcmcda::Error),
    /// A parameter or a shared-type check failed.
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// An error from the audio crate (building reports from beamforms).
    #[error(transparent)]
    Audio(#[from] sensors_audio::Error),
    /// An error from the video crate (building nodes from cameras, rendering the road scene).
    #[error(transparent)]
    Video(#[from] sensors_video::Error),
    /// An error scoring tracks against the truth (the road scene's runs).
    #[error(transparent)]
    Eval(#[from] eval_metrics::Error),
    /// Two seed lists that must be disjoint (tuning, fitting, reported, fresh) share a seed.
    #[error(
        "{first} and {second} share seed {seed}: seeds that choose settings are never reported"
    )]
    SharedSeed {
        /// The first list's name.
        first: &'static str,
        /// The second list's name.
        second: &'static str,
        /// The shared seed.
        seed: u64,
    },
    /// A peak-score table is keyed by a name that is not one of the road scene's approaches.
    #[error("[params.multi_peak_scores]: unknown approach {name} (one of {known})")]
    UnknownApproach {
        /// The key.
        name: String,
        /// The approaches' keys, comma-separated.
        known: String,
    },
    /// A list of approaches names something other than `all`, an approach's index or an
    /// approach's settings key.
    #[error("{given:?} is not `all`, an approach index 0..{n_approaches} or one of {known}")]
    ApproachListItem {
        /// The list's item.
        given: String,
        /// The number of approaches.
        n_approaches: usize,
        /// The approaches' settings keys, comma-separated.
        known: String,
    },
    /// An approach is scored but has no peak-score table.
    #[error("approach {approach} is scored but [params.multi_peak_scores] has no {approach}")]
    MissingPeakScores {
        /// The approach's key.
        approach: String,
    },
    /// An approach's peak-score table fails its check.
    #[error("[params.multi_peak_scores.{approach}]: {source}")]
    PeakScoreTable {
        /// The approach's key.
        approach: String,
        /// What is wrong with the table.
        source: Box<Error>,
    },
}

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

pub(crate) fn invalid(name: &'static str, reason: impl Into<String>) -> Error {
    Error::Model(tracker_model::Error::InvalidParameter {
        name,
        reason: reason.into(),
    })
}
