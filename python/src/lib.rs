//! `tracking_toolkit._native`: the Rust side of the Python package. The public API, its
//! docstrings and its types are in `tracking_toolkit/` (`__init__.py` and the `.pyi` stubs);
//! this module only converts arrays and errors and calls the workspace crates, with the GIL
//! released around their work. No workspace crate depends on pyo3.

use pyo3::prelude::*;

mod arrays;
mod errors;
mod gap;
mod hmm;
mod kalman;
mod metrics;
mod online;
mod phd;
mod plots;
mod sensors;
mod trackers;

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("TrackingError", m.py().get_type::<errors::TrackingError>())?;
    m.add_class::<trackers::BoxTracker>()?;
    m.add_class::<phd::PhdTracker>()?;
    m.add_class::<online::McmcdaOnline>()?;
    m.add_function(wrap_pyfunction!(plots::track_plot_rows, m)?)?;
    m.add_function(wrap_pyfunction!(trackers::track, m)?)?;
    m.add_function(wrap_pyfunction!(trackers::track_file, m)?)?;
    m.add_function(wrap_pyfunction!(trackers::tracker_names, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::evaluate, m)?)?;
    m.add_class::<hmm::Hmm>()?;
    m.add_function(wrap_pyfunction!(gap::recover_gap, m)?)?;
    m.add_function(wrap_pyfunction!(kalman::kalman, m)?)?;
    m.add_function(wrap_pyfunction!(kalman::rts_smooth, m)?)?;
    m.add_class::<sensors::BackgroundSubtractor>()?;
    m.add_function(wrap_pyfunction!(sensors::beamform, m)?)?;
    m.add_function(wrap_pyfunction!(sensors::doa, m)?)?;
    Ok(())
}
