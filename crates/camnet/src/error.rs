//! The one error type of camnet.

/// Everything that can go wrong in camnet. Degenerate geometry is an error with the numbers
/// that show it, never a panic or a meaningless pose.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A parameter or shared type from tracker-model was rejected.
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// The image tracker failed.
    #[error(transparent)]
    Mcmcda(#[from] mcmcda::Error),
    /// Fewer correspondences than the estimator needs.
    #[error("{found} correspondences; the 8-point essential matrix needs at least {needed}")]
    TooFewCorrespondences {
        /// Correspondences given (or inliers left).
        found: usize,
        /// The least the step needs.
        needed: usize,
    },
    /// The two views were given different numbers of points.
    #[error("view 1 has {first} points but view 2 has {second}")]
    LengthMismatch {
        /// Points in view 1.
        first: usize,
        /// Points in view 2.
        second: usize,
    },
    /// A point with a NaN or infinite coordinate.
    #[error("point {index} of view {view} is not finite")]
    NonFinitePoint {
        /// 1 or 2.
        view: usize,
        /// Its index.
        index: usize,
    },
    /// All the points of one view lie on a line: the epipolar geometry is not determined.
    #[error(
        "the points of view {view} are collinear (spread ratio {spread_ratio:.3e} below {threshold:.1e})"
    )]
    Collinear {
        /// 1 or 2.
        view: usize,
        /// Smallest over largest singular value of the centred points.
        spread_ratio: f64,
        /// The ratio below which the points count as collinear.
        threshold: f64,
    },
    /// The two camera centres coincide (or nearly): a rotation explains the points, and the
    /// translation direction is not observable.
    #[error(
        "zero baseline: a pure rotation explains the inliers with median residual {parallax_rad:.3e} rad (threshold {threshold_rad:.1e})"
    )]
    ZeroBaseline {
        /// Median angle between each second-view ray and the rotated first-view ray.
        parallax_rad: f64,
        /// The parallax below which the baseline counts as zero.
        threshold_rad: f64,
    },
    /// A decomposition or factorisation that did not succeed.
    #[error("numerical failure: {what}")]
    Numerical {
        /// What failed.
        what: &'static str,
    },
    /// Camera index out of range, or a camera without valid intrinsics.
    #[error("camera {index}: {reason}")]
    BadCamera {
        /// The camera.
        index: usize,
        /// What is wrong.
        reason: String,
    },
}

/// Result with this crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

pub(crate) fn invalid(name: &'static str, reason: String) -> Error {
    Error::Model(tracker_model::Error::InvalidParameter { name, reason })
}
