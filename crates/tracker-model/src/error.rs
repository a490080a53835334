//! The one error type of tracker-model; every other library crate wraps it with `#[from]`.

/// Everything that can go wrong in tracker-model. Messages name the offending field, value or
/// line so that a user can fix the input without reading the source.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A covariance (or an innovation covariance) could not be Cholesky-factorised.
    #[error("{what} is not symmetric positive definite")]
    NotPositiveDefinite {
        /// Which matrix failed, e.g. "innovation covariance".
        what: &'static str,
    },
    /// A matrix that must be symmetric is not (beyond a relative tolerance of 1e-9).
    #[error("{what} is not symmetric")]
    NotSymmetric {
        /// Which matrix.
        what: &'static str,
    },
    /// A NaN or an infinity where a finite number is required.
    #[error("{what} contains a non-finite value")]
    NonFinite {
        /// Which value or array.
        what: &'static str,
    },
    /// A parameter outside its valid range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// The parameter's name as it appears in the API or configuration.
        name: &'static str,
        /// What is wrong with it, including the value.
        reason: String,
    },
    /// An input that must not be empty is.
    #[error("{what} is empty")]
    Empty {
        /// What was empty.
        what: &'static str,
    },
    /// Two things that must have the same shape do not.
    #[error("shape mismatch: {0}")]
    ShapeMismatch(String),
    /// A malformed row in a text input; `line` is 1-based.
    #[error("line {line}: {reason}")]
    Parse {
        /// 1-based line number in the input.
        line: usize,
        /// What is wrong with the line.
        reason: String,
    },
    /// A MOTChallenge row whose box has zero width or height. Such a box has no area, so its
    /// IoU with anything, itself included, is undefined (0/0); it is rejected where it is read
    /// instead of silently matching nothing.
    #[error(
        "line {line}: the box has zero area (width {width}, height {height}); MOTChallenge \
         boxes need a positive width and height"
    )]
    ZeroAreaBox {
        /// 1-based line number in the input.
        line: usize,
        /// The box width.
        width: f64,
        /// The box height.
        height: f64,
    },
    /// A MOTChallenge row whose coordinates are so large that its size is lost to rounding
    /// (`left + width − left` is not `width` to 1e-6): its IoU, even with itself, would be
    /// rounding noise.
    #[error(
        "line {line}: the box at ({left}, {top}) of size {width} × {height} is beyond f64 \
         precision: at that distance from the origin its size is lost to rounding"
    )]
    BoxBeyondPrecision {
        /// 1-based line number in the input.
        line: usize,
        /// The box's left edge.
        left: f64,
        /// The box's top edge.
        top: f64,
        /// The box width.
        width: f64,
        /// The box height.
        height: f64,
    },
    /// Reading from the caller's reader failed.
    #[error("read failed: {0}")]
    Io(String),
}

/// Result with tracker-model's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Checks that `value` is finite and in the closed interval [lo, hi].
pub fn ensure_in_range(value: f64, lo: f64, hi: f64, name: &'static str) -> Result<f64> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            reason: format!("{value} is outside [{lo}, {hi}]"),
        })
    }
}

/// Checks that `value` is finite and not negative (zero allowed).
pub fn ensure_non_negative(value: f64, name: &'static str) -> Result<f64> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            reason: format!("{value} must be finite and ≥ 0"),
        })
    }
}

/// Checks that `value` is finite and strictly positive.
pub fn ensure_positive(value: f64, name: &'static str) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            reason: format!("{value} must be finite and > 0"),
        })
    }
}

/// Checks that `value` is a probability strictly inside (0, 1).
pub fn ensure_open_probability(value: f64, name: &'static str) -> Result<f64> {
    if value.is_finite() && value > 0.0 && value < 1.0 {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            reason: format!("{value} must lie strictly between 0 and 1"),
        })
    }
}
