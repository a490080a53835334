//! The one error type of sensors-audio.

/// Everything that can go wrong in sensors-audio. Variants carry the offending values so that a
/// user can fix the input without reading the source.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A frame or recording with no channels at all.
    #[error("the input has no channels")]
    NoChannels,
    /// The input's channel count differs from the array's microphone count.
    #[error("the input has {got} channels but the array has {expected} microphones")]
    ChannelCountMismatch {
        /// Microphones in the array.
        expected: usize,
        /// Channels in the input.
        got: usize,
    },
    /// Channels of one input do not all have the same length.
    #[error("channel {channel} has {got} samples where {expected} were expected")]
    ChannelLengthMismatch {
        /// Index of the offending channel.
        channel: usize,
        /// Expected number of samples.
        expected: usize,
        /// Actual number of samples.
        got: usize,
    },
    /// A NaN or infinite sample.
    #[error("sample {index} of channel {channel} is {value}")]
    NonFiniteSample {
        /// Channel index.
        channel: usize,
        /// Sample index within the channel (or the frame).
        index: usize,
        /// The offending value.
        value: f32,
    },
    /// A frame too short for the array: the steering delays (and the time-domain filters) need
    /// more samples than the frame holds.
    #[error(
        "a frame of {frame_len} samples is too short; this array and configuration need at least {required}"
    )]
    FrameTooShort {
        /// Samples in the frame.
        frame_len: usize,
        /// The minimum length.
        required: usize,
    },
    /// A sample rate of zero.
    #[error("the sample rate is zero")]
    ZeroSampleRate,
    /// A WAV file this crate cannot use, or a failure of the WAV codec.
    #[error("WAV: {0}")]
    Wav(#[from] hound::Error),
    /// The requested combination of options does not exist (e.g. PHAT in the time domain).
    #[error("unsupported configuration: {0}")]
    Unsupported(String),
    /// A parameter or a shared-type check failed.
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
}

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
