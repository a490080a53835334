//! The error type of gdt-bridge.

use tracker_model::Frame;

/// What can go wrong recovering a gap or linking segments.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model (covariances, Kalman filtering), and a configuration
    /// value or argument outside its range ([`tracker_model::Error::InvalidParameter`]).
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// A track segment with too few observations for what is asked of it.
    #[error("a segment of {len} observations is too short: at least {min} are needed")]
    SegmentTooShort {
        /// Its number of observations.
        len: usize,
        /// The fewest that work: 1 for a goal or a baseline, 2 to estimate a velocity.
        min: usize,
    },
    /// A segment's frames do not strictly increase.
    #[error("frame {frame} follows frame {last}: segment frames must strictly increase")]
    FramesOutOfOrder {
        /// The offending frame.
        frame: Frame,
        /// The frame before it.
        last: Frame,
    },
    /// An observed position is NaN or infinite.
    #[error("the position observed at frame {frame} is not finite")]
    NonFiniteObservation {
        /// Its frame.
        frame: Frame,
    },
    /// Segment B starts right after (or before) segment A ends: there is no gap to recover.
    #[error("segment B starts at frame {first_b}, so nothing is missing after frame {last_a}")]
    NoGap {
        /// A's last frame.
        last_a: Frame,
        /// B's first frame.
        first_b: Frame,
    },
    /// Interpolation samples (times and values, or weights) of different lengths.
    #[error("{n_times} sample times but {len} {what}")]
    LengthMismatch {
        /// What does not match the times ("values", "weights").
        what: &'static str,
        /// How many sample times.
        n_times: usize,
        /// How many of `what`.
        len: usize,
    },
    /// Too few samples for an interpolation or fit.
    #[error("{len} samples cannot determine {what}: at least {min} are needed")]
    TooFewSamples {
        /// What they should determine ("a cubic B-spline", "its coefficients", ...).
        what: &'static str,
        /// How many samples.
        len: usize,
        /// The fewest that work.
        min: usize,
    },
    /// A sample time or value that is NaN or infinite.
    #[error("sample {index} (time {time}, value {value}) is not finite")]
    NonFiniteSample {
        /// Its index.
        index: usize,
        /// Its time.
        time: f64,
        /// Its value.
        value: f64,
    },
    /// Sample times that do not strictly increase.
    #[error("sample time {time} follows {last}: sample times must strictly increase")]
    TimesOutOfOrder {
        /// The offending time.
        time: f64,
        /// The time before it.
        last: f64,
    },
    /// A sample time outside the spline's base interval [t_3, t_n].
    #[error("sample time {time} lies outside the knots' base interval [{lower}, {upper}]")]
    SampleOutsideKnots {
        /// The sample time.
        time: f64,
        /// t_3.
        lower: f64,
        /// t_n.
        upper: f64,
    },
    /// A gap longer than [`MAX_GAP_FRAMES`](crate::MAX_GAP_FRAMES): recovering it would
    /// allocate a position per missing frame.
    #[error("{frames} missing frames between segments: at most {max} can be recovered")]
    GapTooLong {
        /// Missing frames.
        frames: u64,
        /// The limit.
        max: u32,
    },
    /// A least-squares or smoothing spline fit whose system is singular: for a B-spline, knot
    /// spans without data (the Schoenberg-Whitney condition fails).
    #[error("the spline fit is rank deficient (knots without data)")]
    RankDeficientFit,
    /// Model and noise sequences of different lengths, or no step at all.
    #[error(
        "need T ≥ 1 transitions and as many process-noise matrices, \
         got {transitions} and {process_noise}"
    )]
    HorizonMismatch {
        /// Number of transition matrices A_1..A_T.
        transitions: usize,
        /// Number of process-noise matrices Q_1..Q_T.
        process_noise: usize,
    },
    /// A process-noise matrix Q_t that is not a covariance.
    #[error("process noise of step {step}: {source}")]
    ProcessNoise {
        /// The step t (1-based).
        step: usize,
        /// What is wrong with Q_t.
        source: tracker_model::Error,
    },
    /// [`GoalDirected::pseudo_inverse_form`](crate::GoalDirected::pseudo_inverse_form) needs HᵀH
    /// invertible: the goal must determine the whole state.
    #[error("HᵀH is singular: the goal does not determine the state")]
    GoalUnderdetermined,
    /// [`GoalDirected::pseudo_inverse_form`](crate::GoalDirected::pseudo_inverse_form) needs every
    /// Φ(T, t) invertible.
    #[error("Φ(T, {step}) is singular: Oh & Jung's form needs invertible transitions")]
    SingularTransition {
        /// The step t.
        step: usize,
    },
}

/// Result with gdt-bridge's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A configuration value or argument outside its range, as tracker-model's parameter checks
/// report it.
pub(crate) fn invalid_parameter(name: &'static str, reason: String) -> Error {
    Error::Model(tracker_model::Error::InvalidParameter { name, reason })
}
