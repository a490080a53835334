"""A categorical (discrete-emission) HMM in hmmlearn's shape, on hmm-grid's Rust model.

Fitted with the same settings and ``random_state`` as ``hmmlearn.hmm.CategoricalHMM``
(0.3.3), it starts from the same parameters, runs the same Baum-Welch iterations and stops
at the same one, so ``startprob_``, ``transmat_`` and ``emissionprob_`` agree with
hmmlearn's to rounding. Two cases part from hmmlearn: a fit whose log-likelihood falls by
more than ``tol`` (EM never does without priors above 1) stops there in hmmlearn and goes
on here, and with ``startprob_prior`` above 1 a zero start probability gets the prior's
count here but stays zero in hmmlearn. Unlike hmmlearn, ``transmat_`` may be a ``scipy.sparse`` matrix:
it stays sparse, and every algorithm then costs O(T · nnz(A)) instead of O(T · N²).
"""

from __future__ import annotations

import numbers

import numpy as np

from . import _native

__all__ = ["CategoricalHMM", "ConvergenceMonitor"]

_MAX_ITER = 1_000_000


def _check_random_state(seed):
    """sklearn's rule: None the global RandomState, an int a new one, a RandomState itself."""
    if seed is None or seed is np.random:
        return np.random.mtrand._rand
    if isinstance(seed, numbers.Integral):
        return np.random.RandomState(seed)
    if isinstance(seed, np.random.RandomState):
        return seed
    raise ValueError(f"random_state {seed!r} is not None, an int or a numpy RandomState")


def _issparse(a) -> bool:
    try:
        import scipy.sparse as sp
    except ImportError:  # pragma: no cover - scipy is optional
        return False
    return sp.issparse(a)


class ConvergenceMonitor:
    """What the last ``fit`` did: ``history`` holds the log-likelihood of the training data
    under each model Baum-Welch visited, the starting one first; ``iter`` the re-estimations
    run; ``converged`` whether the gain fell below ``tol`` before ``n_iter`` ran out
    (hmmlearn's monitor also says converged when ``n_iter`` ran out; this one does not)."""

    def __init__(self, tol: float, n_iter: int):
        self.tol, self.n_iter = tol, n_iter
        self.history: list[float] = []
        self.iter = 0
        self.converged = False

    def __repr__(self) -> str:
        return (
            f"ConvergenceMonitor(iter={self.iter}, converged={self.converged}, "
            f"history=[...{len(self.history)} values])"
        )


class CategoricalHMM:
    """Hidden Markov model with categorical emissions, hmmlearn's ``CategoricalHMM`` API.

    Parameters are hmmlearn's: ``n_components`` states; Dirichlet priors
    ``startprob_prior``, ``transmat_prior`` and ``emissionprob_prior`` (scalars >= 1; 1 adds
    nothing); ``n_features`` symbols (from the data when None); ``algorithm`` "viterbi" or
    "map"; ``random_state`` (int, RandomState or None, used as hmmlearn uses it to start
    the parameters named in ``init_params``); ``n_iter`` and ``tol`` for Baum-Welch;
    ``params`` the parameters it re-estimates ('s' startprob, 't' transmat, 'e'
    emissionprob).

    Attributes ``startprob_`` (N,), ``transmat_`` (N, N) and ``emissionprob_`` (N, M) may be
    set before ``fit`` (drop their letters from ``init_params``) or used without it.
    ``transmat_`` may be a scipy.sparse matrix. ``transmat_storage`` (not hmmlearn's) says
    how a dense ``transmat_`` is stored: "auto" (sparse when at most a quarter of it is
    non-zero), "dense" or "sparse"; every algorithm then costs O(T * nnz(A)).
    """

    def __init__(
        self,
        n_components: int = 1,
        startprob_prior: float = 1.0,
        transmat_prior: float = 1.0,
        emissionprob_prior: float = 1.0,
        n_features: int | None = None,
        algorithm: str = "viterbi",
        random_state=None,
        n_iter: int = 10,
        tol: float = 1e-2,
        verbose: bool = False,
        params: str = "ste",
        init_params: str = "ste",
        transmat_storage: str = "auto",
    ):
        self.n_components = n_components
        self.startprob_prior = startprob_prior
        self.transmat_prior = transmat_prior
        self.emissionprob_prior = emissionprob_prior
        self.n_features = n_features
        self.algorithm = algorithm
        self.random_state = random_state
        self.n_iter = n_iter
        self.tol = tol
        self.verbose = verbose
        self.params = params
        self.init_params = init_params
        self.transmat_storage = transmat_storage

    # -- the model ------------------------------------------------------------------------

    def _model(self) -> _native.Hmm:
        for name in ("startprob_", "transmat_", "emissionprob_"):
            if not hasattr(self, name):
                raise _native.TrackingError(
                    f"{name} is not set: call fit, or set it before scoring"
                )
        if _issparse(self.transmat_):
            a = self.transmat_.tocsr()
            a.sort_indices()
            if a.shape != (self.n_components, self.n_components):
                raise ValueError(
                    f"transmat_ must have shape ({self.n_components}, {self.n_components}); "
                    f"it has {a.shape}"
                )
            return _native.Hmm.sparse(
                self.startprob_, a.indptr, a.indices, a.data, self.emissionprob_
            )
        return _native.Hmm.dense(
            self.startprob_, self.transmat_, self.emissionprob_, self.transmat_storage
        )

    def _take(self, model: _native.Hmm, sparse: bool) -> None:
        self.startprob_ = np.asarray(model.startprob)
        self.emissionprob_ = np.asarray(model.emissionprob)
        if sparse:
            import scipy.sparse as sp

            indptr, indices, data = model.transmat_csr()
            n = self.n_components
            self.transmat_ = sp.csr_array((data, indices, indptr), shape=(n, n))
        else:
            self.transmat_ = np.asarray(model.transmat_dense())

    @staticmethod
    def _symbols(X) -> np.ndarray:
        X = np.asarray(X)
        if X.ndim == 2 and X.shape[1] == 1:
            X = X[:, 0]
        if X.ndim != 1:
            raise ValueError(f"X must have shape (n_samples, 1); it has shape {X.shape}")
        if X.size and not np.issubdtype(X.dtype, np.integer):
            raise ValueError("Symbols should be integers")
        if X.size and X.min() < 0:
            raise ValueError("Symbols should be nonnegative")
        return np.ascontiguousarray(X, dtype=np.int64)

    # -- hmmlearn's initialisation (0.3.3: base._init, then CategoricalHMM._init) ---------

    def _needs_init(self, code: str, name: str) -> bool:
        return code in self.init_params or not hasattr(self, name)

    def _init(self, X: np.ndarray) -> None:
        if self.n_features is None:
            self.n_features = int(X.max()) + 1
        elif self.n_features - 1 < X.max():
            raise ValueError(
                f"Largest symbol is {X.max()} but the model only emits symbols up to "
                f"{self.n_features - 1}"
            )
        n = self.n_components
        rs = _check_random_state(self.random_state)
        if self._needs_init("s", "startprob_"):
            self.startprob_ = rs.dirichlet(np.full(n, 1.0 / n))
        if self._needs_init("t", "transmat_"):
            self.transmat_ = rs.dirichlet(np.full(n, 1.0 / n), size=n)
        self.random_state = _check_random_state(self.random_state)
        if self._needs_init("e", "emissionprob_"):
            e = self.random_state.rand(n, self.n_features)
            self.emissionprob_ = e / e.sum(axis=1, keepdims=True)

    # -- the API ---------------------------------------------------------------------------

    def fit(self, X, lengths=None) -> "CategoricalHMM":
        """Baum-Welch from the parameters ``init_params`` starts (or those already set)."""
        if not 0 <= self.n_iter <= _MAX_ITER:
            raise ValueError(f"n_iter = {self.n_iter}; it must be from 0 to {_MAX_ITER}")
        X = self._symbols(X)
        self._init(X)
        sparse = _issparse(self.transmat_)
        priors = (self.startprob_prior, self.transmat_prior, self.emissionprob_prior)
        # hmmlearn stops when the gain falls below tol; with tol <= 0 (-inf included) that
        # is never under EM, which our tolerance 0 gives too.
        tol = max(float(self.tol), 0.0)
        model, history, converged = self._model().fit(
            X, lengths, self.n_iter, tol, self.params, priors
        )
        steps = len(history) - 1
        if converged and steps < self.n_iter:
            # hmmlearn re-estimates once more in the iteration that finds the gain below tol.
            model, more, _ = model.fit(X, lengths, 1, 0.0, self.params, priors)
            history.append(more[-1])
            steps += 1
        self._take(model, sparse)
        self.monitor_ = ConvergenceMonitor(self.tol, self.n_iter)
        self.monitor_.history, self.monitor_.iter = history, steps
        self.monitor_.converged = converged
        return self

    def score(self, X, lengths=None) -> float:
        """log P(X | model), summed over the sequences."""
        return self._model().score(self._symbols(X), lengths)

    def score_samples(self, X, lengths=None):
        """(log P(X | model), posteriors (n_samples, n_components))."""
        model, X = self._model(), self._symbols(X)
        return model.score(X, lengths), np.asarray(model.posteriors(X, lengths))

    def predict_proba(self, X, lengths=None) -> np.ndarray:
        """Posterior state probabilities, (n_samples, n_components)."""
        return np.asarray(self._model().posteriors(self._symbols(X), lengths))

    def decode(self, X, lengths=None, algorithm=None):
        """(log probability, state sequence) by Viterbi, or by the posterior mode ("map",
        whose log probability is hmmlearn's: the sum of the largest posteriors)."""
        algorithm = algorithm or self.algorithm
        if algorithm == "viterbi":
            log_p, path = self._model().decode(self._symbols(X), lengths)
            return log_p, np.asarray(path)
        if algorithm == "map":
            gamma = self.predict_proba(X, lengths)
            return float(gamma.max(axis=1).sum()), gamma.argmax(axis=1)
        raise ValueError(f"algorithm {algorithm!r}: expected 'viterbi' or 'map'")

    def predict(self, X, lengths=None) -> np.ndarray:
        """The most likely states (by ``algorithm``)."""
        return self.decode(X, lengths)[1]
