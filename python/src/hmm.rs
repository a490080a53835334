//! The categorical HMM under `tracking_toolkit.CategoricalHMM`: hmm-grid's model, dense or
//! sparse (CSR) transitions, and its inference and Baum-Welch over several sequences.

use hmm_grid::{BaumWelchConfig, Freeze, PseudoCounts, StorageChoice, Transitions};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;

use crate::arrays::{indices, table, to_numpy, vector};
use crate::errors::{IntoPy, invalid};

/// The most states or symbols a model may have (a dense 2¹⁶ × 2¹⁶ matrix is 32 GiB).
const MAX_SIZE: usize = 1 << 16;

/// A checked model λ = (π, A, B).
#[pyclass(module = "tracking_toolkit._native", frozen)]
pub struct Hmm {
    model: hmm_grid::Hmm,
}

fn emissions(emissionprob: &Bound<'_, PyAny>) -> PyResult<(Vec<f64>, usize)> {
    let b = table(emissionprob, "emissionprob", (1, MAX_SIZE), "(N, M)")?;
    Ok((b.values, b.cols))
}

fn build(startprob: Vec<f64>, a: Transitions, b: (Vec<f64>, usize)) -> PyResult<Hmm> {
    if startprob.len() > MAX_SIZE {
        return Err(invalid(format!("at most {MAX_SIZE} states")));
    }
    Ok(Hmm {
        model: hmm_grid::Hmm::new(startprob, a, b.0, b.1).or_raise()?,
    })
}

/// The observation sequences: `x` cut at `lengths` (one sequence without).
fn sequences(
    x: &Bound<'_, PyAny>,
    lengths: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<Vec<usize>>> {
    let symbols = indices(x, "X")?;
    let Some(lengths) = lengths.filter(|l| !l.is_none()) else {
        return Ok(vec![symbols]);
    };
    let lengths = indices(lengths, "lengths")?;
    let total = lengths
        .iter()
        .try_fold(0usize, |a, &n| a.checked_add(n))
        .ok_or_else(|| invalid("lengths overflow when summed"))?;
    if total != symbols.len() {
        return Err(invalid(format!(
            "lengths sum to {total} but X has {} samples",
            symbols.len()
        )));
    }
    let mut out = Vec::with_capacity(lengths.len());
    let mut start = 0;
    for n in lengths {
        out.push(symbols[start..start + n].to_vec());
        start += n;
    }
    Ok(out)
}

#[pymethods]
impl Hmm {
    /// A model from a dense transition matrix, stored as `storage` says: "auto" (sparse when
    /// mostly zero), "dense" or "sparse".
    #[staticmethod]
    #[pyo3(signature = (startprob, transmat, emissionprob, storage="auto"))]
    fn dense(
        startprob: &Bound<'_, PyAny>,
        transmat: &Bound<'_, PyAny>,
        emissionprob: &Bound<'_, PyAny>,
        storage: &str,
    ) -> PyResult<Self> {
        let storage = match storage {
            "auto" => StorageChoice::Auto,
            "dense" => StorageChoice::Dense,
            "sparse" => StorageChoice::Sparse,
            other => {
                return Err(invalid(format!(
                    "transmat_storage {other:?}: expected auto, dense or sparse"
                )));
            }
        };
        let a = table(transmat, "transmat", (1, MAX_SIZE), "(N, N)")?;
        if a.rows != a.cols {
            return Err(invalid(format!(
                "transmat must be square; it is {} × {}",
                a.rows, a.cols
            )));
        }
        let a = Transitions::from_row_major(a.rows, a.values, storage).or_raise()?;
        build(vector(startprob, "startprob")?, a, emissions(emissionprob)?)
    }

    /// A model whose transition matrix is CSR (indptr, indices, data), stored sparse.
    #[staticmethod]
    fn sparse(
        startprob: &Bound<'_, PyAny>,
        indptr: &Bound<'_, PyAny>,
        col: &Bound<'_, PyAny>,
        data: &Bound<'_, PyAny>,
        emissionprob: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let (indptr, col, data) = (
            indices(indptr, "transmat.indptr")?,
            indices(col, "transmat.indices")?,
            vector(data, "transmat.data")?,
        );
        if col.len() != data.len()
            || indptr.first().copied() != Some(0)
            || indptr.last().copied() != Some(data.len())
            || indptr.windows(2).any(|w| w[0] > w[1])
        {
            return Err(invalid(
                "transmat is not a valid CSR matrix: indptr must rise from 0 to the number of \
                 entries, and indices and data must have that many",
            ));
        }
        let rows = indptr
            .windows(2)
            .map(|w| {
                Ok(col[w[0]..w[1]]
                    .iter()
                    .copied()
                    .zip(data[w[0]..w[1]].iter().copied())
                    .collect())
            })
            .collect::<PyResult<Vec<Vec<(usize, f64)>>>>()?;
        let a = Transitions::sparse(rows).or_raise()?;
        build(vector(startprob, "startprob")?, a, emissions(emissionprob)?)
    }

    /// π.
    #[getter]
    fn startprob<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.model.initial().to_vec().into_pyarray(py)
    }

    /// B, N × M.
    #[getter]
    fn emissionprob<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        to_numpy(py, self.model.emissions().to_vec(), self.model.n_symbols())
    }

    /// Whether A is stored sparse.
    #[getter]
    fn is_sparse(&self) -> bool {
        self.model.transitions().is_sparse()
    }

    /// A as a dense N × N array.
    fn transmat_dense<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let a = self.model.transitions();
        to_numpy(py, a.dense_values(), a.n_states())
    }

    /// A as CSR: (indptr, indices, data).
    fn transmat_csr(&self) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let (mut indptr, mut col, mut data) = (vec![0], Vec::new(), Vec::new());
        for row in self.model.transitions().rows() {
            for (j, v) in row {
                col.push(j);
                data.push(v);
            }
            indptr.push(col.len());
        }
        (indptr, col, data)
    }

    /// Σ log P(O_k | λ) over the sequences.
    #[pyo3(signature = (x, lengths=None))]
    fn score(
        &self,
        py: Python<'_>,
        x: &Bound<'_, PyAny>,
        lengths: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<f64> {
        let seqs = sequences(x, lengths)?;
        py.detach(|| {
            seqs.iter()
                .map(|o| hmm_grid::forward(&self.model, o).map(|f| f.log_likelihood))
                .sum::<hmm_grid::Result<f64>>()
        })
        .or_raise()
    }

    /// Viterbi: (Σ log P of the best paths, the paths concatenated).
    #[pyo3(signature = (x, lengths=None))]
    fn decode<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        lengths: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(f64, Bound<'py, PyArray1<i64>>)> {
        let seqs = sequences(x, lengths)?;
        let (log_p, path) = py
            .detach(|| -> hmm_grid::Result<(f64, Vec<i64>)> {
                let (mut log_p, mut path) = (0.0, Vec::new());
                for o in &seqs {
                    let (p, l) = hmm_grid::viterbi(&self.model, o)?;
                    log_p += l;
                    path.extend(p.into_iter().map(|s| s as i64));
                }
                Ok((log_p, path))
            })
            .or_raise()?;
        Ok((log_p, path.into_pyarray(py)))
    }

    /// Posterior marginals γ, (T, N) with the sequences' steps concatenated.
    #[pyo3(signature = (x, lengths=None))]
    fn posteriors<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        lengths: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let seqs = sequences(x, lengths)?;
        let gamma = py
            .detach(|| -> hmm_grid::Result<Vec<f64>> {
                let mut out = Vec::new();
                for o in &seqs {
                    out.extend(hmm_grid::posterior(&self.model, o)?.gamma);
                }
                Ok(out)
            })
            .or_raise()?;
        to_numpy(py, gamma, self.model.n_states())
    }

    /// Baum-Welch: at most `n_iter` re-estimations, stopping when the log-likelihood gains
    /// less than `tol`; `params` names what is re-estimated ('s' π, 't' A, 'e' B); the
    /// priors are Dirichlet concentrations ≥ 1 (their excess over 1 is added to the counts).
    /// Returns the model, the log-likelihood history and whether it converged.
    #[pyo3(signature = (x, lengths, n_iter, tol, params, priors))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        &self,
        py: Python<'_>,
        x: &Bound<'_, PyAny>,
        lengths: Option<&Bound<'_, PyAny>>,
        n_iter: usize,
        tol: f64,
        params: &str,
        priors: (f64, f64, f64),
    ) -> PyResult<(Hmm, Vec<f64>, bool)> {
        const MAX_ITER: usize = 1_000_000;
        if n_iter > MAX_ITER {
            return Err(invalid(format!("n_iter = {n_iter}; at most {MAX_ITER}")));
        }
        let seqs = sequences(x, lengths)?;
        let pseudo = |p: f64, name: &str| {
            if p.is_finite() && p >= 1.0 {
                Ok(p - 1.0)
            } else {
                Err(invalid(format!(
                    "{name} = {p}; a Dirichlet prior here must be finite and >= 1"
                )))
            }
        };
        let config = BaumWelchConfig {
            max_iterations: n_iter,
            tolerance: tol,
            relative_tolerance: 0.0,
            freeze: Freeze {
                initial: !params.contains('s'),
                transitions: !params.contains('t'),
                emissions: !params.contains('e'),
            },
            pseudo_counts: PseudoCounts {
                initial: pseudo(priors.0, "startprob_prior")?,
                transitions: pseudo(priors.1, "transmat_prior")?,
                emissions: pseudo(priors.2, "emissionprob_prior")?,
            },
        };
        let (model, report) = py
            .detach(|| hmm_grid::baum_welch(&self.model, &seqs, &config))
            .or_raise()?;
        Ok((Hmm { model }, report.log_likelihoods, report.converged))
    }
}
