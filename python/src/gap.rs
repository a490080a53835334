//! Gap recovery: goal-directed tracking (Oh & Jung 2015) and the spline baselines between
//! two segments of one track.

use gdt_bridge::{Baseline, GdtConfig, Observation, RecoveredGap, recover_baseline, recover_gdt};
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use tracker_model::Vec2;

use crate::arrays::{table, to_numpy};
use crate::errors::{IntoPy, invalid};
use crate::trackers::settings;

/// A segment (N, 3): frame, x, y.
fn segment(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<Observation>> {
    let t = table(obj, name, (3, 3), "(N, 3): frame, x, y")?;
    t.iter()
        .enumerate()
        .map(|(i, r)| {
            if !(r[0] >= 0.0 && r[0].fract() == 0.0 && r[0] <= f64::from(u32::MAX)) {
                return Err(invalid(format!(
                    "{name} row {i}: frame {} is not a frame number",
                    r[0]
                )));
            }
            Ok(Observation {
                frame: r[0] as u32,
                position: Vec2::new(r[1], r[2]),
            })
        })
        .collect()
}

/// The baseline `method` with `params` (its configuration's fields, if it has one).
fn baseline(
    py: Python<'_>,
    method: &str,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Baseline> {
    if matches!(method, "linear" | "natural_cubic_spline") {
        if params.is_some_and(|p| !p.is_empty()) {
            return Err(invalid(format!("{method} takes no settings")));
        }
        return pythonize::depythonize(PyString::new(py, method).as_any()).or_raise();
    }
    let tagged = PyDict::new(py);
    match params {
        Some(p) => tagged.set_item(method, p)?,
        None => tagged.set_item(method, PyDict::new(py))?,
    }
    pythonize::depythonize(tagged.as_any()).or_raise()
}

/// Recovered positions (G, 3): frame, x, y; and, for GDT, their covariances (G, 4) row-major
/// (none, (0, 4), for a baseline).
type Recovered<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);

/// Recovers the frames between segment `a` (before) and `b` (after), each (N, 3): frame, x,
/// y, by GDT (`params`: GdtConfig's fields) or a baseline.
#[pyfunction]
#[pyo3(signature = (a, b, method="gdt", params=None))]
pub fn recover_gap<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    method: &str,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Recovered<'py>> {
    let (a, b) = (segment(a, "a")?, segment(b, "b")?);
    let gap: RecoveredGap = if method == "gdt" {
        let model = settings::<GdtConfig>(params)?.check().or_raise()?;
        py.detach(|| recover_gdt(&a, &b, &model)).or_raise()?
    } else {
        let method = baseline(py, method, params)?;
        py.detach(|| recover_baseline(&a, &b, &method)).or_raise()?
    };
    let mut points = Vec::with_capacity(gap.frames.len() * 3);
    for (f, p) in gap.frames.iter().zip(&gap.positions) {
        points.extend_from_slice(&[f64::from(*f), p.x, p.y]);
    }
    let covs = gap
        .covariances
        .iter()
        .flat_map(|c| [c[(0, 0)], c[(0, 1)], c[(1, 0)], c[(1, 1)]])
        .collect();
    Ok((to_numpy(py, points, 3)?, to_numpy(py, covs, 4)?))
}
