//! The error type of mcmcda.

use tracker_model::Frame;

use crate::problem::MeasId;

/// What can go wrong setting up or running data association. Every variant names what is
/// wrong and carries the offending values.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model: a configuration parameter outside its range
    /// ([`tracker_model::Error::InvalidParameter`], for every configuration of this crate
    /// too), a non-finite measurement, a covariance that is not positive definite.
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// A scan arrives for a frame at or before the last scan already held.
    #[error(
        "scan for frame {frame} arrives after frame {last}; add late measurements with \
         add_measurement"
    )]
    FramesOutOfOrder {
        /// The frame of the scan pushed.
        frame: Frame,
        /// The last frame already held.
        last: Frame,
    },
    /// A scan arrives for a frame before the problem's first frame.
    #[error("scan for frame {frame} comes before the problem's first frame {first}")]
    FrameBeforeFirst {
        /// The frame of the scan pushed.
        frame: Frame,
        /// The problem's first frame.
        first: Frame,
    },
    /// A measurement is added to a frame whose scan the problem does not hold.
    #[error("frame {frame} is outside the scans held ({first}..{end}); push its scan first")]
    FrameNotHeld {
        /// The measurement's frame.
        frame: Frame,
        /// The first frame held.
        first: Frame,
        /// One past the last frame held (a u64: it can be 2^32).
        end: u64,
    },
    /// A late measurement arrives after its scan left the online tracker's window, when its
    /// associations are already final.
    #[error(
        "late measurement for frame {frame} arrives after its scan left the window (which \
         starts at frame {window_start})"
    )]
    LateMeasurement {
        /// The measurement's frame.
        frame: Frame,
        /// The first frame still open.
        window_start: Frame,
    },
    /// A measurement or a window reaches a scan that `Problem::forget_before`
    /// dropped.
    #[error("scan {scan} was forgotten: the problem keeps scans from {first_kept} on")]
    ScanForgotten {
        /// The scan index asked for.
        scan: usize,
        /// The first scan index kept.
        first_kept: usize,
    },
    /// More measurements than a [`MeasId`] can number.
    #[error("more than 2^32 measurements")]
    TooManyMeasurements,
    /// A scan's score ratios do not match its points one for one.
    #[error("{scores} log score ratios for {points} points; give one per point")]
    ScoreCount {
        /// Points in the scan.
        points: usize,
        /// Ratios given.
        scores: usize,
    },
    /// A partition (MCMCDA's chain) of a problem built without neighbourhoods.
    #[error(
        "the problem keeps no neighbourhoods (Problem::without_neighbourhoods); MCMCDA needs them: build it with Problem::empty"
    )]
    NoNeighbourhoods,
    /// A whole-problem window was asked of a problem without scans.
    #[error("the problem holds no scans")]
    EmptyProblem,
    /// A window of scan indices that is empty or reaches past the problem's scans.
    #[error("window {start}..={end} does not fit the problem's {n_scans} scans")]
    WindowOutOfRange {
        /// First scan index of the window.
        start: usize,
        /// Last scan index of the window.
        end: usize,
        /// Scans in the problem.
        n_scans: usize,
    },
    /// A track with fewer than two measurements.
    #[error("track {track} has {len} measurement(s): fewer than 2")]
    TrackTooShort {
        /// Index of the track in the list given.
        track: usize,
        /// Its number of measurements.
        len: usize,
    },
    /// A track holds a measurement id the problem does not have.
    #[error("track {track}: measurement {id} does not exist")]
    UnknownMeasurement {
        /// Index of the track.
        track: usize,
        /// The measurement id.
        id: MeasId,
    },
    /// A track holds a measurement of a scan outside the partition's window.
    #[error("track {track}: measurement {id} is outside the window")]
    MeasurementOutsideWindow {
        /// Index of the track.
        track: usize,
        /// The measurement id.
        id: MeasId,
    },
    /// Two tracks hold the same measurement.
    #[error("track {track}: measurement {id} is already in a track")]
    MeasurementTaken {
        /// Index of the track that repeats it.
        track: usize,
        /// The measurement id.
        id: MeasId,
    },
    /// Consecutive measurements of a track are not in increasing scans.
    #[error("track {track}: measurements {first} and {second} are not in increasing scans")]
    ScansNotIncreasing {
        /// Index of the track.
        track: usize,
        /// The earlier measurement in the track.
        first: MeasId,
        /// The measurement after it.
        second: MeasId,
    },
    /// Consecutive measurements of a track more than d̄ scans apart.
    #[error("track {track}: gap of {gap} scans between {first} and {second} exceeds d̄ = {max_gap}")]
    GapTooLong {
        /// Index of the track.
        track: usize,
        /// The earlier measurement.
        first: MeasId,
        /// The measurement after it.
        second: MeasId,
        /// Scans between them.
        gap: usize,
        /// d̄.
        max_gap: usize,
    },
    /// Consecutive measurements of a track farther apart than a target can move (outside
    /// the neighbourhood L(y, t, d)).
    #[error("track {track}: {first} and {second} are too far apart for {gap} scans")]
    TooFarApart {
        /// Index of the track.
        track: usize,
        /// The earlier measurement.
        first: MeasId,
        /// The measurement after it.
        second: MeasId,
        /// Scans between them.
        gap: usize,
    },
    /// A partition's cached posterior term disagrees with a fresh filter (a broken
    /// invariant, reported by [`crate::chain::Partition::check_invariants`]).
    #[error("track {track}: cached weight {cached} but fresh {fresh}")]
    StaleWeight {
        /// Index of the track.
        track: usize,
        /// The cached term.
        cached: f64,
        /// The term recomputed from scratch.
        fresh: f64,
    },
    /// A partition's owner or slot map is wrong for a measurement (a broken invariant,
    /// reported by [`crate::chain::Partition::check_invariants`]).
    #[error("owner/slot map wrong for measurement {id}")]
    OwnerMapWrong {
        /// The measurement id.
        id: MeasId,
    },
}

/// Result with mcmcda's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A configuration parameter outside its range, as tracker-model's parameter checks report
/// it.
pub(crate) fn invalid_parameter(name: &'static str, reason: String) -> Error {
    Error::Model(tracker_model::Error::InvalidParameter { name, reason })
}

/// The most MCMC steps one chain may be asked for (10⁹, several minutes of one core even at
/// the sampler's ~0.3 µs a step): a count past it is a typo, not a wish, and would run for
/// hours with nothing to show.
pub const MAX_SAMPLES: u64 = 1_000_000_000;

/// The most chains one run may start in parallel.
pub const MAX_CHAINS: usize = 64;

/// Checks a count of MCMC steps against [`MAX_SAMPLES`].
pub(crate) fn ensure_samples(samples: u64, name: &'static str) -> Result<()> {
    if samples > MAX_SAMPLES {
        return Err(invalid_parameter(
            name,
            format!("{samples}; at most {MAX_SAMPLES} samples per chain"),
        ));
    }
    Ok(())
}

/// Checks a chain count: 1 to [`MAX_CHAINS`].
pub(crate) fn ensure_chains(chains: usize) -> Result<()> {
    if !(1..=MAX_CHAINS).contains(&chains) {
        return Err(invalid_parameter(
            "chains",
            format!("{chains}; it must be in 1..={MAX_CHAINS}"),
        ));
    }
    Ok(())
}
