//! Radar and point plots tracked by GNN with a KF, EKF, UKF or IMM, as `cargo xtask track
//! --plots` does (air-traffic's plot files).

use std::path::PathBuf;

use air_traffic::{PlotFilter, PlotRow, PlotTrackConfig, PlotValue, parse_plots, track_plots};
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{table, to_numpy};
use crate::errors::{IntoPy, invalid};
use crate::trackers::settings;

const PLOTS: &str = "(K, 6): time_s, sensor, sensor_x, sensor_y, x, y";

/// Position plots from an array (K, 6), sorted by time as the file reader sorts them.
fn rows_of(obj: &Bound<'_, PyAny>) -> PyResult<Vec<PlotRow>> {
    let t = table(obj, "plots", (6, 6), PLOTS)?;
    let mut rows = t
        .iter()
        .enumerate()
        .map(|(i, r)| {
            if !r.iter().all(|v| v.is_finite()) {
                return Err(invalid(format!(
                    "plots row {i} has a value that is not finite"
                )));
            }
            if !(r[1] >= 0.0 && r[1].fract() == 0.0 && r[1] <= f64::from(u32::MAX)) {
                return Err(invalid(format!(
                    "plots row {i}: sensor {} is not an id",
                    r[1]
                )));
            }
            Ok(PlotRow {
                time_s: r[0],
                sensor: r[1] as u32,
                sensor_position: [r[2], r[3]],
                value: PlotValue::Position([r[4], r[5]]),
                sigma: None,
                beam: None,
            })
        })
        .collect::<PyResult<Vec<_>>>()?;
    rows.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    Ok(rows)
}

/// Tracks plots (a plot file's path, or position plots (K, 6)) with GNN and `filter`: rows
/// (R, 7) time_s, id, x, y, vx, vy, hit.
#[pyfunction]
#[pyo3(signature = (plots, filter="imm", params=None))]
pub fn track_plot_rows<'py>(
    py: Python<'py>,
    plots: &Bound<'py, PyAny>,
    filter: &str,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let rows = match plots.extract::<PathBuf>() {
        Ok(path) => {
            let text = std::fs::read_to_string(&path)
                .map_err(|e| invalid(format!("cannot read {}: {e}", path.display())))?;
            parse_plots(&text).map_err(|e| invalid(format!("{}: {e}", path.display())))?
        }
        Err(_) => rows_of(plots)?,
    };
    let filter: PlotFilter = filter.parse().or_raise()?;
    let config: PlotTrackConfig = settings(params)?;
    let tracks = py
        .detach(|| track_plots(&rows, filter, &config))
        .or_raise()?;
    let mut out = Vec::with_capacity(tracks.len() * 7);
    for t in tracks {
        out.extend_from_slice(&[
            t.time_s,
            t.id as f64,
            t.position[0],
            t.position[1],
            t.velocity[0],
            t.velocity[1],
            f64::from(u8::from(t.hit)),
        ]);
    }
    to_numpy(py, out, 7)
}
