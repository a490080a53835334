//! The PHD filters stepped once per frame: SMC-PHD (Yoon et al. 2016's filter, seeded) and
//! GM-PHD (Vo & Ma 2006) on boxes, each estimate with its persistent label.

use numpy::PyArray2;
use phd_filter::{GmConfig, GmPhd, PhdConfig, PhdStep, SmcPhd};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::to_numpy;
use crate::errors::IntoPy;
use crate::trackers::{OUT_COLS, read_dets, settings};

enum Filter {
    Smc(Box<SmcPhd>),
    Gm(Box<GmPhd>),
}

/// A PHD filter on boxes: `update(dets)` with a frame's detections gives its estimates.
#[pyclass(module = "tracking_toolkit._native")]
pub struct PhdTracker {
    filter: Filter,
    frames: u64,
}

#[pymethods]
impl PhdTracker {
    /// `kind` "smc" (with `seed`) or "gm" (with `gm`, GM-PHD's mixture settings); `params`
    /// the filter's settings (phd_filter::PhdConfig's fields).
    #[new]
    #[pyo3(signature = (kind, params=None, gm=None, seed=0))]
    fn new(
        kind: &str,
        params: Option<&Bound<'_, PyDict>>,
        gm: Option<&Bound<'_, PyDict>>,
        seed: u64,
    ) -> PyResult<Self> {
        let config: PhdConfig = settings(params)?;
        let filter = match kind {
            "smc" => Filter::Smc(Box::new(SmcPhd::new(config, seed).or_raise()?)),
            "gm" => {
                let gm: GmConfig = settings(gm)?;
                Filter::Gm(Box::new(GmPhd::new(config, gm).or_raise()?))
            }
            other => {
                return Err(PyValueError::new_err(format!(
                    "unknown PHD filter {other:?}; expected smc or gm"
                )));
            }
        };
        Ok(Self { filter, frames: 0 })
    }

    /// One frame's detections (N, 6) → the estimates (M, 8): x1, y1, x2, y2, label, weight,
    /// class and index of the detection it was extracted from (−1 and −1 for GM-PHD, whose
    /// estimates are mixture components).
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        dets: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (dets, boxes) = read_dets(dets)?;
        let step: PhdStep = py
            .detach(|| match &mut self.filter {
                Filter::Smc(f) => f.step(&boxes),
                Filter::Gm(f) => f.step(&boxes),
            })
            .or_raise()?;
        self.frames += 1;
        let mut out = Vec::with_capacity(step.estimates.len() * OUT_COLS);
        for e in &step.estimates {
            let b = e.bbox;
            let (class, index) = match e.measurement {
                Some(i) => (dets.row(i)[5], i as f64),
                None => (-1.0, -1.0),
            };
            out.extend_from_slice(&[
                b.left,
                b.top,
                b.right(),
                b.bottom(),
                e.label as f64,
                e.weight,
                class,
                index,
            ]);
        }
        to_numpy(py, out, OUT_COLS)
    }

    /// Frames stepped so far.
    #[getter]
    fn frame_count(&self) -> u64 {
        self.frames
    }
}
