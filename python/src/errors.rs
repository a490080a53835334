//! One error route: every Rust error becomes a `TrackingError` (a `ValueError`) with the
//! Rust message and its causes, as the command line prints them.

use pyo3::PyErr;
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;

create_exception!(
    _native,
    TrackingError,
    PyValueError,
    "Bad input or settings for a tracker, a metric or a model; the message is the Rust error's."
);

/// The error and its sources, joined by ": ".
pub fn tracking_error(error: &(dyn std::error::Error + 'static)) -> PyErr {
    let mut message = error.to_string();
    let mut source = error.source();
    while let Some(cause) = source {
        let text = cause.to_string();
        if !message.contains(&text) {
            message.push_str(": ");
            message.push_str(&text);
        }
        source = cause.source();
    }
    TrackingError::new_err(message)
}

/// A `TrackingError` with `message`.
pub fn invalid(message: impl Into<String>) -> PyErr {
    TrackingError::new_err(message.into())
}

/// `Result::map_err` into a [`TrackingError`].
pub trait IntoPy<T> {
    /// The value, or the error as a `TrackingError`.
    fn or_raise(self) -> pyo3::PyResult<T>;
}

impl<T, E: std::error::Error + 'static> IntoPy<T> for Result<T, E> {
    fn or_raise(self) -> pyo3::PyResult<T> {
        self.map_err(|e| tracking_error(&e))
    }
}
