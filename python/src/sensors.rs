//! Sensors on numpy arrays: the background subtractor (OpenCV's `apply(frame) -> mask`
//! shape) and the microphone-array beamformers (delay-and-sum, SRP-PHAT, MVDR).

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sensors_audio::{Beamform, BeamformConfig, MicArray, PeakSearch, Recording};
use sensors_video::{BackgroundModel, MogConfig, PixelFormat, VideoFrame};

use crate::arrays::{table, to_numpy};
use crate::errors::IntoPy;
use crate::trackers::settings;

/// The largest frame side read (OpenCV's own limit is 2³¹ pixels; 2¹⁶ a side is 12 GiB RGB).
const MAX_SIDE: usize = 1 << 16;

/// A mixture-of-Gaussians background subtractor (Stauffer & Grimson 1999 as OpenCV's bgsegm
/// MOG): the model is sized by the first frame.
#[pyclass(module = "tracking_toolkit._native")]
pub struct BackgroundSubtractor {
    config: MogConfig,
    model: Option<BackgroundModel>,
}

/// A uint8 image (H, W) or (H, W, 3) as a frame.
fn frame_of(image: &PyReadonlyArrayDyn<'_, u8>) -> PyResult<VideoFrame> {
    let shape = image.shape().to_vec();
    let format = match shape.as_slice() {
        [_, _] => PixelFormat::Grey,
        [_, _, 3] => PixelFormat::Rgb,
        _ => {
            return Err(PyValueError::new_err(format!(
                "frame must have shape (H, W) or (H, W, 3); it has shape {shape:?}"
            )));
        }
    };
    let (h, w) = (shape[0], shape[1]);
    if h > MAX_SIDE || w > MAX_SIDE {
        return Err(PyValueError::new_err(format!(
            "frame is {w} x {h}; at most {MAX_SIDE} pixels a side"
        )));
    }
    let data = image.as_array().iter().copied().collect();
    VideoFrame::new(w, h, format, data).or_raise()
}

#[pymethods]
impl BackgroundSubtractor {
    /// `params`: sensors_video::MogConfig's fields.
    #[new]
    #[pyo3(signature = (params=None))]
    fn new(params: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let config: MogConfig = settings(params)?;
        // Checks the settings now, not at the first frame.
        BackgroundModel::new(&config, 1, 1, PixelFormat::Grey).or_raise()?;
        Ok(Self {
            config,
            model: None,
        })
    }

    /// Classifies `frame` (uint8, (H, W) grey or (H, W, 3) colour, any channel order) and
    /// learns from it; returns the mask (H, W) uint8: 0 background, 127 shadow, 255
    /// foreground.
    fn apply<'py>(
        &mut self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<u8>>> {
        let image = frame
            .extract::<PyReadonlyArrayDyn<'py, u8>>()
            .map_err(|_| {
                PyTypeError::new_err("frame must be a uint8 numpy array (H, W) or (H, W, 3)")
            })?;
        let frame = frame_of(&image)?;
        let model = match &mut self.model {
            Some(model) => model,
            empty => empty.insert(
                BackgroundModel::new(&self.config, frame.width(), frame.height(), frame.format())
                    .or_raise()?,
            ),
        };
        // A fresh mask each frame: numpy takes its labels without a copy.
        let mask = py.detach(|| model.apply(&frame)).or_raise()?;
        let array = Array2::from_shape_vec((mask.height, mask.width), mask.labels)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(array.into_pyarray(py))
    }

    /// Frames learnt so far.
    #[getter]
    fn frame_count(&self) -> u64 {
        self.model.as_ref().map_or(0, BackgroundModel::n_frames)
    }
}

/// A vector and a second array for Python.
type Pair<'py, T> = (Bound<'py, PyArray1<f64>>, Bound<'py, T>);

/// The channels (M, T) and the microphones (M, 2) as a recording and an array.
fn recording(
    signals: &Bound<'_, PyAny>,
    mics: &Bound<'_, PyAny>,
    sample_rate_hz: u32,
) -> PyResult<(Recording, MicArray)> {
    let s = table(
        signals,
        "signals",
        (1, usize::MAX),
        "(M, T): one row per microphone",
    )?;
    let m = table(mics, "mics", (2, 2), "(M, 2): microphone positions, metres")?;
    if m.rows != s.rows {
        return Err(PyValueError::new_err(format!(
            "signals has {} channels but mics gives {} microphones",
            s.rows, m.rows
        )));
    }
    let positions: Vec<[f64; 2]> = m.iter().map(|r| [r[0], r[1]]).collect();
    let array = MicArray::new(&positions).or_raise()?;
    let channels = s
        .iter()
        .map(|row| row.iter().map(|&v| v as f32).collect())
        .collect();
    Ok((
        Recording::new(sample_rate_hz, 0.0, channels).or_raise()?,
        array,
    ))
}

/// Every frame's beamform of the recording (`signals`, `mics`) under `config`, the GIL
/// released.
fn beamform_frames(
    py: Python<'_>,
    signals: &Bound<'_, PyAny>,
    mics: &Bound<'_, PyAny>,
    config: &BeamformConfig,
) -> PyResult<Vec<Beamform>> {
    let (rec, array) = recording(signals, mics, config.sample_rate_hz)?;
    py.detach(|| config.check(&array)?.beamform(&rec))
        .or_raise()
}

/// Beamforms a recording frame by frame: (frame centre times, s (F,), energies (F, B)); beam
/// b is steered to b · 2π / B in the array frame.
#[pyfunction]
#[pyo3(signature = (signals, mics, params=None))]
pub fn beamform<'py>(
    py: Python<'py>,
    signals: &Bound<'py, PyAny>,
    mics: &Bound<'py, PyAny>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Pair<'py, PyArray2<f64>>> {
    let config: BeamformConfig = settings(params)?;
    let frames = beamform_frames(py, signals, mics, &config)?;
    let times: Vec<f64> = frames.iter().map(|f| f.time_s).collect();
    let energies = frames.into_iter().flat_map(|f| f.energies).collect();
    Ok((
        times.into_pyarray(py),
        to_numpy(py, energies, config.n_beams)?,
    ))
}

/// Directions of arrival over a whole recording: the frames' beam energies summed, then up
/// to `max_peaks` peaks at least `min_relative` of the range above the minimum, strongest
/// first, each refined between beams: (bearings in radians in [0, 2π), their energies).
#[pyfunction]
#[pyo3(signature = (signals, mics, max_peaks=1, min_relative=0.1, params=None))]
pub fn doa<'py>(
    py: Python<'py>,
    signals: &Bound<'py, PyAny>,
    mics: &Bound<'py, PyAny>,
    max_peaks: usize,
    min_relative: f64,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Pair<'py, PyArray1<f64>>> {
    let config: BeamformConfig = settings(params)?;
    if !(0.0..=1.0).contains(&min_relative) {
        return Err(PyValueError::new_err(format!(
            "min_relative = {min_relative}; it must be within [0, 1]"
        )));
    }
    let frames = beamform_frames(py, signals, mics, &config)?;
    let mut total = Beamform {
        time_s: 0.0,
        energies: vec![0.0; config.n_beams],
    };
    for f in &frames {
        total
            .energies
            .iter_mut()
            .zip(&f.energies)
            .for_each(|(t, e)| *t += e);
    }
    let search = PeakSearch {
        max_peaks,
        min_relative,
    };
    let peaks = total.peaks(&search);
    let bearings: Vec<f64> = peaks.iter().map(|p| p.bearing_rad).collect();
    let energies: Vec<f64> = peaks.iter().map(|p| p.energy).collect();
    Ok((bearings.into_pyarray(py), energies.into_pyarray(py)))
}
