//! The one error type of the crate: each variant carries what a user needs to fix the input.

use std::path::PathBuf;

use tracker_model::Frame;

/// Everything that can go wrong reading detection files, resolving a configuration or tracking.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A parameter or shared type from tracker-model was rejected (a parameter's name and the
    /// reason are in `InvalidParameter`).
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// MCMCDA or GNN rejected its model or input.
    #[error(transparent)]
    Mcmcda(#[from] mcmcda::Error),
    /// The PHD filter rejected its configuration or input.
    #[error(transparent)]
    Phd(#[from] phd_filter::Error),
    /// SORT, ByteTrack or OC-SORT rejected its configuration or input.
    #[error(transparent)]
    BoxTracker(#[from] box_trackers::Error),
    /// The image local detectors rejected their configuration.
    #[error(transparent)]
    Detector(#[from] image_detector::Error),
    /// A frame folder could not be read.
    #[error(transparent)]
    Frames(#[from] sensors_video::Error),
    /// A MOTChallenge file that does not parse; `source` names the line.
    #[error("{file} is not a valid MOTChallenge file: {error}")]
    File {
        /// The file's name as the user gave it.
        file: String,
        /// What is wrong, with the line (in the message, so not also a source).
        error: tracker_model::Error,
    },
    /// Rows of a file that parse but do not make tracks (e.g. one id twice in a frame).
    #[error("in {file}: {error}")]
    Rows {
        /// The file.
        file: String,
        /// What is wrong (in the message, so not also a source).
        error: tracker_model::Error,
    },
    /// Detections were needed and there are none.
    #[error("{what} holds no detections")]
    NoDetections {
        /// The file, or "the input".
        what: String,
    },
    /// Ground truth without a row to score against.
    #[error(
        "{file} holds {what}: there is no ground truth to score against (every metric divides \
         by the number of truth objects)"
    )]
    NoGroundTruth {
        /// The file.
        file: String,
        /// "no rows", or how many ignore rows it had.
        what: String,
    },
    /// A table of the configuration file with a wrong value; `source` names the key.
    #[error("in the [{table}] table of the configuration: {error}")]
    Table {
        /// The table, e.g. "offline".
        table: &'static str,
        /// What is wrong in it (in the message, so not also a source: a chain printer such
        /// as anyhow's `{:#}` would repeat it).
        error: Box<Error>,
    },
    /// A configuration whose keys or types do not fit the table.
    #[error("in the [{table}] table of the configuration: {error}")]
    TableSyntax {
        /// The table.
        table: &'static str,
        /// What serde said (in the message, so not also a source).
        error: toml::de::Error,
    },
    /// The configuration could not be written as TOML.
    #[error("the configuration cannot be written as TOML: {0}")]
    Render(#[from] toml::ser::Error),
    /// `[scores] gnn_min_log_ratio` above every detection's fitted ratio.
    #[error(
        "in the [scores] table of the configuration: gnn_min_log_ratio = {min} drops every \
         detection (the file's fitted ln f₁/f₀ reaches at most {best:.3})"
    )]
    DropsEveryDetection {
        /// The threshold.
        min: f64,
        /// The largest fitted log ratio of the file.
        best: f64,
    },
    /// A tracker name that is not one of [`crate::track::TrackerKind::ALL`].
    #[error("unknown tracker {name:?}; known: mcmcda, mcmcda-online, gnn, gnn-online, phd")]
    UnknownTracker {
        /// The name given.
        name: String,
    },
    /// Image frames were given to a tracker that does not read pictures.
    #[error(
        "a frame folder (--frames) runs the fused PHD tracker: use it with --tracker phd, not {tracker}"
    )]
    FramesNeedPhd {
        /// The tracker asked for.
        tracker: &'static str,
    },
    /// Detection frames with no picture in the frame folder.
    #[error("frame {frame} of the detections has no image in {} ({count} frames have none)", dir.display())]
    FrameWithoutImage {
        /// The first such frame.
        frame: Frame,
        /// How many frames of the detections have no image.
        count: usize,
        /// The folder.
        dir: PathBuf,
    },
    /// A frame folder whose images count from 0 against detections that count from 1.
    #[error(
        "the images of {} are numbered from 0 (their file names) but the detections from 1, so \
         each image would get the next frame's detections; MOTChallenge frames start at 1: pass \
         --first-frame 1 (FusedSettings::first_frame) to number the first image 1, or \
         --first-frame 0 if the names are right",
        dir.display()
    )]
    ImagesFromZero {
        /// The folder.
        dir: PathBuf,
    },
    /// An output frame past the last representable frame number.
    #[error(
        "an output frame {frame} is beyond the largest frame number {}",
        Frame::MAX
    )]
    FrameOverflow {
        /// The frame asked for.
        frame: i128,
    },
}

/// Result with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// An [`Error`] naming a parameter (tracker-model's `InvalidParameter`, the one route every
/// crate reports a bad parameter by).
pub(crate) fn invalid(name: &'static str, reason: String) -> Error {
    Error::Model(tracker_model::Error::InvalidParameter { name, reason })
}

/// Adds "in the [table] table of the configuration" to an error.
pub(crate) trait InTable<T> {
    /// The error, inside `table`.
    fn in_table(self, table: &'static str) -> Result<T>;
}

impl<T, E: Into<Error>> InTable<T> for std::result::Result<T, E> {
    fn in_table(self, table: &'static str) -> Result<T> {
        self.map_err(|e| Error::Table {
            table,
            error: Box::new(e.into()),
        })
    }
}

/// A frame number from a computed i64, or [`Error::FrameOverflow`].
pub(crate) fn frame_of(frame: impl Into<i128>) -> Result<Frame> {
    let frame = frame.into();
    Frame::try_from(frame).map_err(|_| Error::FrameOverflow { frame })
}
