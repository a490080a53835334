//! Online (sliding-window) MCMCDA (Oh, Russell & Sastry 2009, Algorithm 4) stepped once per
//! scan on point detections.

use mcmcda::{McmcdaConfig, OnlineConfig, OnlineTracker};
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tracker_model::Vec2;

use crate::arrays::{table, to_numpy};
use crate::errors::{IntoPy, invalid};
use crate::trackers::settings;

/// Online MCMCDA: `update(points)` with a scan's detections gives the tracks the window's MAP
/// reports at that scan.
#[pyclass(module = "tracking_toolkit._native")]
pub struct McmcdaOnline {
    tracker: OnlineTracker,
    frame: u32,
}

#[pymethods]
impl McmcdaOnline {
    /// `model`: mcmcda::McmcdaConfig's fields; `params`: mcmcda::OnlineConfig's.
    #[new]
    #[pyo3(signature = (model=None, params=None, seed=0))]
    fn new(
        model: Option<&Bound<'_, PyDict>>,
        params: Option<&Bound<'_, PyDict>>,
        seed: u64,
    ) -> PyResult<Self> {
        let model = settings::<McmcdaConfig>(model)?.check().or_raise()?;
        let config: OnlineConfig = settings(params)?;
        if config.samples_per_scan == 0 {
            return Err(invalid(
                "samples_per_scan = 0; MCMCDA needs at least 1 sample per scan to find any track",
            ));
        }
        Ok(Self {
            tracker: OnlineTracker::new(model, 1, config, seed).or_raise()?,
            frame: 0,
        })
    }

    /// One scan's points (N, 2) → the reported tracks (M, 3): x, y, label. Associations that
    /// leave the window are dropped, so memory is bounded by the window, not the stream.
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let t = table(points, "points", (2, 2), "(N, 2): x, y")?;
        if let Some(i) = t.iter().position(|r| !r.iter().all(|v| v.is_finite())) {
            return Err(invalid(format!(
                "points row {i} has a value that is not finite"
            )));
        }
        let points: Vec<Vec2> = t.iter().map(|r| Vec2::new(r[0], r[1])).collect();
        let frame = self
            .frame
            .checked_add(1)
            .ok_or_else(|| invalid("the tracker has stepped u32::MAX scans; start a new one"))?;
        let step = py
            .detach(|| {
                let step = self.tracker.push_scan(frame, &points)?;
                self.tracker.drain_committed();
                Ok::<_, mcmcda::Error>(step)
            })
            .or_raise()?;
        self.frame = frame;
        let out = step
            .estimates
            .iter()
            .flat_map(|&(label, p)| [p.x, p.y, label as f64])
            .collect();
        to_numpy(py, out, 3)
    }

    /// Scans stepped so far.
    #[getter]
    fn frame_count(&self) -> u32 {
        self.frame
    }
}
