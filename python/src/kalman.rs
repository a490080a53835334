//! The linear Kalman filter and RTS smoother of tracker-model for any model x_{k+1} = F x_k +
//! w, z_k = H x_k + v with up to [`MAX_STATE`] states and [`MAX_MEASURED`] measured values
//! (the sizes are compile-time in tracker-model; every pair is built here once).

use nalgebra::{SMatrix, SVector};
use numpy::PyArray2;
use pyo3::prelude::*;
use tracker_model::{FilterRun, FilterStep, Gaussian, LinearObservation, LinearTransition};
use tracker_model::{TransitionModel, filter, smooth};

use crate::arrays::{Table, table, to_numpy};
use crate::errors::{IntoPy, invalid};

/// The most states.
const MAX_STATE: usize = 6;
/// The most measured values.
const MAX_MEASURED: usize = 4;

/// Means (T, N) and covariances (T, N·N) row-major, and the log-likelihood.
type Run = (Vec<f64>, Vec<f64>, f64);

fn matrix<const R: usize, const C: usize>(t: &Table, name: &str) -> PyResult<SMatrix<f64, R, C>> {
    if (t.rows, t.cols) != (R, C) {
        return Err(invalid(format!(
            "{name} must be {R} x {C}; it is {} x {}",
            t.rows, t.cols
        )));
    }
    Ok(SMatrix::from_row_slice(&t.values))
}

fn flatten<const N: usize>(states: &[Gaussian<N>], log_likelihood: f64) -> Run {
    let mut means = Vec::with_capacity(states.len() * N);
    let mut covs = Vec::with_capacity(states.len() * N * N);
    for g in states {
        means.extend(g.mean().iter());
        // Row-major for numpy (nalgebra stores columns; the covariance is symmetric anyway).
        covs.extend(g.covariance().transpose().iter());
    }
    (means, covs, log_likelihood)
}

/// The model's matrices read for sizes N and M.
struct Inputs<'a> {
    f: &'a Table,
    q: &'a Table,
    h: &'a Table,
    r: &'a Table,
    x0: &'a Table,
    p0: &'a Table,
    zs: &'a Table,
}

fn run<const N: usize, const M: usize>(i: &Inputs<'_>, rts: bool) -> PyResult<Run> {
    let transition =
        LinearTransition::new(matrix::<N, N>(i.f, "F")?, matrix::<N, N>(i.q, "Q")?).or_raise()?;
    let observation =
        LinearObservation::new(matrix::<M, N>(i.h, "H")?, matrix::<M, M>(i.r, "R")?).or_raise()?;
    let prior = Gaussian::new(
        SVector::from(matrix::<N, 1>(i.x0, "x")?),
        matrix::<N, N>(i.p0, "P")?,
    )
    .or_raise()?;
    let zs: Vec<Option<SVector<f64, M>>> =
        i.zs.iter()
            .map(|z| {
                z.iter()
                    .all(|v| v.is_finite())
                    .then(|| SVector::from_row_slice(z))
            })
            .collect();
    let run = filter(&transition, &observation, &prior, &zs).or_raise()?;
    let states: Vec<Gaussian<N>> = if rts && !run.steps.is_empty() {
        smooth(&transition, &run).or_raise()?
    } else {
        run.filtered().cloned().collect()
    };
    Ok(flatten(&states, run.log_likelihood()))
}

/// RTS over given filtered states: each prediction recomputed as F x, F P Fᵀ + Q (as
/// filterpy's `rts_smoother` does).
fn rts_of<const N: usize>(f: &Table, q: &Table, means: &Table, covs: &Table) -> PyResult<Run> {
    let transition =
        LinearTransition::new(matrix::<N, N>(f, "F")?, matrix::<N, N>(q, "Q")?).or_raise()?;
    let mut steps: Vec<FilterStep<N>> = Vec::with_capacity(means.rows);
    for (x, p) in means.iter().zip(covs.iter()) {
        let filtered =
            Gaussian::new(SVector::from_row_slice(x), SMatrix::from_row_slice(p)).or_raise()?;
        let predicted = match steps.last() {
            Some(previous) => transition.predict(&previous.filtered),
            None => filtered.clone(),
        };
        steps.push(FilterStep {
            predicted,
            filtered,
            log_likelihood: None,
            innovation_mahalanobis_sq: None,
        });
    }
    if steps.is_empty() {
        return Ok((Vec::new(), Vec::new(), 0.0));
    }
    let smoothed = smooth(&transition, &FilterRun { steps }).or_raise()?;
    Ok(flatten(&smoothed, 0.0))
}

/// Calls `$call::<N, M>(args)` for the runtime sizes `$n` and `$m`, or `$call::<N>(args)`
/// for `state $n` (checked by [`sizes`]).
macro_rules! by_size {
    (state $n:expr, $call:ident, $args:tt) => {
        match $n {
            1 => $call::<1> $args,
            2 => $call::<2> $args,
            3 => $call::<3> $args,
            4 => $call::<4> $args,
            5 => $call::<5> $args,
            6 => $call::<6> $args,
            _ => unreachable!("sizes are checked first"),
        }
    };
    ($n:expr, $m:expr, $call:ident, $args:tt) => {
        by_size!(@n $n, $m, $call, $args, 1 2 3 4 5 6)
    };
    (@n $n:expr, $m:expr, $call:ident, $args:tt, $($size:literal)*) => {
        match $n {
            $($size => by_size!(@m $size, $m, $call, $args, 1 2 3 4),)*
            _ => unreachable!("sizes are checked first"),
        }
    };
    (@m $size:literal, $m:expr, $call:ident, $args:tt, $($msize:literal)*) => {
        match $m {
            $($msize => $call::<$size, $msize> $args,)*
            _ => unreachable!("sizes are checked first"),
        }
    };
}

fn sizes(n: usize, m: usize) -> PyResult<()> {
    if !(1..=MAX_STATE).contains(&n) || !(1..=MAX_MEASURED).contains(&m) {
        return Err(invalid(format!(
            "a {n}-state model with {m} measured values: 1 to {MAX_STATE} states and 1 to \
             {MAX_MEASURED} measured values are built"
        )));
    }
    Ok(())
}

fn out<'py>(py: Python<'py>, n: usize, run: Run) -> PyResult<KalmanOut<'py>> {
    Ok((to_numpy(py, run.0, n)?, to_numpy(py, run.1, n * n)?, run.2))
}

/// Means (T, N), covariances (T, N·N) and the log-likelihood, for Python.
type KalmanOut<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>, f64);

/// Filters (and with `rts`, smooths) the measurements `zs` (T, M; a row with a NaN is a
/// missing measurement) from the prior (x, P) at the first step.
#[pyfunction]
#[pyo3(signature = (f, q, h, r, x, p, zs, rts=false))]
#[allow(clippy::too_many_arguments)]
pub fn kalman<'py>(
    py: Python<'py>,
    f: &Bound<'py, PyAny>,
    q: &Bound<'py, PyAny>,
    h: &Bound<'py, PyAny>,
    r: &Bound<'py, PyAny>,
    x: &Bound<'py, PyAny>,
    p: &Bound<'py, PyAny>,
    zs: &Bound<'py, PyAny>,
    rts: bool,
) -> PyResult<KalmanOut<'py>> {
    let big = (1, usize::MAX);
    let (f, q, h, r) = (
        table(f, "F", big, "(N, N)")?,
        table(q, "Q", big, "(N, N)")?,
        table(h, "H", big, "(M, N)")?,
        table(r, "R", big, "(M, M)")?,
    );
    let (x, p, zs) = (
        table(x, "x", (1, 1), "(N, 1)")?,
        table(p, "P", big, "(N, N)")?,
        table(zs, "zs", big, "(T, M)")?,
    );
    let (n, m) = (f.rows, h.rows);
    sizes(n, m)?;
    if zs.rows > 0 && zs.cols != m {
        return Err(invalid(format!(
            "zs must have {m} columns; it has {}",
            zs.cols
        )));
    }
    let inputs = Inputs {
        f: &f,
        q: &q,
        h: &h,
        r: &r,
        x0: &x,
        p0: &p,
        zs: &zs,
    };
    let run = py.detach(|| by_size!(n, m, run, (&inputs, rts)))?;
    out(py, n, run)
}

/// RTS-smooths filtered means (T, N) and covariances (T, N·N) with F and Q.
#[pyfunction]
pub fn rts_smooth<'py>(
    py: Python<'py>,
    f: &Bound<'py, PyAny>,
    q: &Bound<'py, PyAny>,
    means: &Bound<'py, PyAny>,
    covs: &Bound<'py, PyAny>,
) -> PyResult<KalmanOut<'py>> {
    let big = (1, usize::MAX);
    let (f, q) = (table(f, "F", big, "(N, N)")?, table(q, "Q", big, "(N, N)")?);
    let n = f.rows;
    sizes(n, 1)?;
    let means = table(means, "Xs", (n, n), "(T, N)")?;
    let covs = table(covs, "Ps", (n * n, n * n), "(T, N * N)")?;
    if means.rows != covs.rows {
        return Err(invalid(format!(
            "{} means but {} covariances",
            means.rows, covs.rows
        )));
    }
    let run = py.detach(|| by_size!(state n, rts_of, (&f, &q, &means, &covs)))?;
    out(py, n, run)
}
