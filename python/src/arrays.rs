//! numpy arrays in and out. Input arrays of any numeric dtype and any strides are read (an
//! array that is not C-contiguous is read through its strides, not refused); a wrong shape is
//! a `ValueError`, a non-numeric dtype a `TypeError`, both naming the argument.

use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, IntoPyArray, PyArray2, PyArrayLike1, PyArrayLike2, PyUntypedArray};
use numpy::{PyArrayDescrMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

/// The largest number of rows any array argument may have (2³¹: 16 GiB of a six-column f64
/// array), so a size read from a user's array always fits the trackers' counters.
pub const MAX_ROWS: usize = 1 << 31;

/// A 2-D array read into row-major `f64`s.
pub struct Table {
    /// The values, row by row.
    pub values: Vec<f64>,
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
}

impl Table {
    /// Row `i`.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.values[i * self.cols..(i + 1) * self.cols]
    }

    /// The rows in order.
    pub fn iter(&self) -> impl Iterator<Item = &[f64]> {
        self.values.chunks_exact(self.cols.max(1)).take(self.rows)
    }
}

/// `obj` as a numpy array (a list or any array-like through `numpy.asarray`).
fn as_ndarray<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    if obj.cast::<PyUntypedArray>().is_ok() {
        return Ok(obj.clone());
    }
    obj.py().import("numpy")?.call_method1("asarray", (obj,))
}

/// Checks that `obj`, if it is a numpy array, is numeric with `ndim` dimensions.
fn check_array(obj: &Bound<'_, PyAny>, name: &str, ndim: usize, shape: &str) -> PyResult<()> {
    if let Ok(array) = obj.cast::<PyUntypedArray>() {
        let kind = array.dtype().kind();
        if !matches!(kind, b'f' | b'i' | b'u' | b'b') {
            return Err(PyTypeError::new_err(format!(
                "{name} must be a numeric array {shape}; its dtype is {}",
                array.dtype()
            )));
        }
        if array.ndim() != ndim {
            return Err(PyValueError::new_err(format!(
                "{name} must be a {ndim}-D array {shape}; it has shape {:?}",
                array.shape()
            )));
        }
    }
    Ok(())
}

/// `obj` as a 2-D table with between `min_cols` and `max_cols` columns (`shape` describes
/// them in messages, e.g. "(N, 6): x1, y1, x2, y2, score, class").
pub fn table(
    obj: &Bound<'_, PyAny>,
    name: &str,
    (min_cols, max_cols): (usize, usize),
    shape: &str,
) -> PyResult<Table> {
    let obj = &as_ndarray(obj)?;
    check_array(obj, name, 2, shape)?;
    let array = obj
        .extract::<PyArrayLike2<'_, f64, AllowTypeChange>>()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be a 2-D numeric array {shape}")))?;
    let view = array.as_array();
    let (rows, cols) = view.dim();
    if rows > 0 && !(min_cols..=max_cols).contains(&cols) || rows == 0 && cols > max_cols {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape {shape}; it has shape ({rows}, {cols})"
        )));
    }
    if rows > MAX_ROWS {
        return Err(PyValueError::new_err(format!(
            "{name} has {rows} rows; at most {MAX_ROWS} are read"
        )));
    }
    Ok(Table {
        values: view.iter().copied().collect(),
        rows,
        cols,
    })
}

/// `obj` as a 1-D vector of `f64`.
pub fn vector(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    let obj = &as_ndarray(obj)?;
    check_array(obj, name, 1, "(N,)")?;
    let array = obj
        .extract::<PyArrayLike1<'_, f64, AllowTypeChange>>()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be a 1-D numeric array")))?;
    Ok(array.as_array().iter().copied().collect())
}

/// `obj` as a 1-D vector of non-negative integers (symbols, lengths, indices).
pub fn indices(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<usize>> {
    let values = vector(obj, name)?;
    values
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            if v >= 0.0 && v.fract() == 0.0 && v < usize::MAX as f64 {
                Ok(v as usize)
            } else {
                Err(PyValueError::new_err(format!(
                    "{name}[{i}] = {v} is not a non-negative integer"
                )))
            }
        })
        .collect()
}

/// A row-major `rows × cols` array for Python.
pub fn to_numpy<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    cols: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let rows = values.len().checked_div(cols).unwrap_or(0);
    let array = Array2::from_shape_vec((rows, cols), values)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(array.into_pyarray(py))
}
