"""CategoricalHMM against brute force on a tiny model and against hmmlearn itself."""

import itertools

import numpy as np
import pytest
import scipy.sparse as sp
from hmmlearn import hmm as hl

import tracking_toolkit as tt

PI = np.array([0.6, 0.3, 0.1])
A = np.array([[0.7, 0.3, 0.0], [0.1, 0.6, 0.3], [0.0, 0.4, 0.6]])
B = np.array([[0.8, 0.1, 0.1], [0.2, 0.6, 0.2], [0.1, 0.2, 0.7]])
X = np.array([0, 0, 1, 2, 2, 1, 0])


def model(**kw):
    m = tt.CategoricalHMM(n_components=3, **kw)
    m.startprob_, m.transmat_, m.emissionprob_ = PI, A, B
    return m


def brute_force(obs):
    """P(obs, path) for every path."""
    joint = {}
    for path in itertools.product(range(3), repeat=len(obs)):
        p = PI[path[0]] * B[path[0], obs[0]]
        for t in range(1, len(obs)):
            p *= A[path[t - 1], path[t]] * B[path[t], obs[t]]
        joint[path] = p
    return joint


def test_score_decode_and_posteriors_equal_brute_force():
    joint = brute_force(X)
    total = sum(joint.values())
    m = model()
    assert m.score(X) == pytest.approx(np.log(total), rel=1e-12)
    best = max(joint, key=joint.get)
    log_p, path = m.decode(X.reshape(-1, 1))
    assert tuple(path) == best and log_p == pytest.approx(np.log(joint[best]), rel=1e-12)
    gamma = np.zeros((len(X), 3))
    for path, p in joint.items():
        gamma[np.arange(len(X)), path] += p / total
    np.testing.assert_allclose(m.predict_proba(X), gamma, rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(m.decode(X, algorithm="map")[1], gamma.argmax(1))


def test_sequences_are_scored_apart():
    m = model()
    both = m.score(np.concatenate([X, X[:3]]), lengths=[len(X), 3])
    assert both == pytest.approx(m.score(X) + m.score(X[:3]), rel=1e-12)


def path_log_prob(m, x, path):
    """log P(x, path) under m's parameters."""
    s = np.log(m.startprob_[path[0]] * m.emissionprob_[path[0], x[0]])
    for t in range(1, len(x)):
        s += np.log(m.transmat_[path[t - 1], path[t]] * m.emissionprob_[path[t], x[t]])
    return s


def hmmlearn_model(**kw):
    return hl.CategoricalHMM(n_components=3, **kw)


@pytest.mark.parametrize("init_params,seed", [("", 0), ("ste", 3), ("e", 11)])
def test_fit_equals_hmmlearn(init_params, seed):
    rng = np.random.default_rng(5)
    truth = hmmlearn_model(init_params="")
    truth.startprob_, truth.transmat_, truth.emissionprob_ = PI, A, B
    truth.n_features = 3
    Xs, _ = truth.sample(300, random_state=7)
    lengths = [120, 100, 80]
    # Enough iterations to stop on tol: hmmlearn re-estimates once more in the iteration
    # that finds the gain below it, and so must we.
    theirs = hmmlearn_model(init_params=init_params, random_state=seed, n_iter=500, tol=1e-4)
    ours = tt.CategoricalHMM(
        n_components=3, init_params=init_params, random_state=seed, n_iter=500, tol=1e-4
    )
    if init_params != "ste":
        start = rng.dirichlet(np.ones(3))
        trans = rng.dirichlet(np.ones(3), size=3)
        emit = rng.dirichlet(np.ones(3), size=3)
        for m in (theirs, ours):
            m.startprob_, m.transmat_, m.emissionprob_ = start, trans.copy(), emit.copy()
    theirs.fit(Xs, lengths)
    ours.fit(Xs, lengths)
    for name in ("startprob_", "transmat_", "emissionprob_"):
        np.testing.assert_allclose(getattr(ours, name), getattr(theirs, name), atol=1e-9)
    assert ours.monitor_.iter == theirs.monitor_.iter < 500
    assert ours.monitor_.converged and theirs.monitor_.converged
    # hmmlearn's history holds the model before each re-estimation; ours also the last.
    np.testing.assert_allclose(ours.monitor_.history[:-1], theirs.monitor_.history, rtol=1e-10)
    assert ours.score(Xs, lengths) == pytest.approx(theirs.score(Xs, lengths), rel=1e-10)
    # Viterbi paths: trained models can tie two paths exactly, so compare what each path is
    # worth under the model, sequence by sequence.
    ends = np.cumsum(lengths)
    for x, mine, peer in zip(
        np.split(Xs[:, 0], ends[:-1]),
        np.split(ours.predict(Xs, lengths), ends[:-1]),
        np.split(theirs.predict(Xs, lengths), ends[:-1]),
    ):
        assert path_log_prob(ours, x, mine) == pytest.approx(path_log_prob(ours, x, peer), rel=1e-12)
        assert path_log_prob(ours, x, mine) == pytest.approx(ours.decode(x)[0], rel=1e-12)
    np.testing.assert_allclose(
        ours.predict_proba(Xs, lengths), theirs.predict_proba(Xs, lengths), atol=1e-9
    )


def test_sparse_transitions_stay_sparse_and_equal_dense():
    rng = np.random.default_rng(2)
    n = 30
    a = np.zeros((n, n))
    for i in range(n):
        for j in (i - 1, i, i + 1):
            if 0 <= j < n:
                a[i, j] = rng.uniform(0.1, 1)
    a /= a.sum(1, keepdims=True)
    b = rng.dirichlet(np.ones(5), size=n)
    pi = np.full(n, 1 / n)
    obs = rng.integers(0, 5, 400)
    dense = tt.CategoricalHMM(n_components=n, init_params="", n_iter=5, tol=0.0, transmat_storage="dense")
    sparse = tt.CategoricalHMM(n_components=n, init_params="", n_iter=5, tol=0.0)
    dense.startprob_, dense.transmat_, dense.emissionprob_ = pi, a, b
    sparse.startprob_, sparse.transmat_, sparse.emissionprob_ = pi, sp.csr_array(a), b
    assert sparse.score(obs) == pytest.approx(dense.score(obs), rel=1e-12)
    dense.fit(obs)
    sparse.fit(obs)
    assert sp.issparse(sparse.transmat_) and sparse.transmat_.nnz == np.count_nonzero(a)
    np.testing.assert_allclose(sparse.transmat_.toarray(), dense.transmat_, atol=1e-12)
    np.testing.assert_allclose(sparse.emissionprob_, dense.emissionprob_, atol=1e-12)
    # hmmlearn on the same dense model: the same re-estimation.
    theirs = hl.CategoricalHMM(n_components=n, init_params="", n_iter=5, tol=-np.inf)
    minus_inf = tt.CategoricalHMM(n_components=n, init_params="", n_iter=5, tol=-np.inf)
    minus_inf.startprob_, minus_inf.transmat_, minus_inf.emissionprob_ = pi, a, b
    minus_inf.fit(obs)
    assert minus_inf.monitor_.iter == 5
    theirs.startprob_, theirs.transmat_, theirs.emissionprob_ = pi, a, b
    theirs.n_features = 5
    theirs.fit(obs.reshape(-1, 1))
    np.testing.assert_allclose(dense.transmat_, theirs.transmat_, atol=1e-9)
    np.testing.assert_allclose(minus_inf.transmat_, theirs.transmat_, atol=1e-9)


def test_bad_input_raises():
    m = model()
    with pytest.raises(ValueError, match="integers"):
        m.score(np.array([0.5, 1.0]))
    with pytest.raises(ValueError, match="nonnegative"):
        m.score(np.array([0, -1]))
    with pytest.raises(tt.TrackingError):
        m.score(np.array([0, 7]))
    with pytest.raises(tt.TrackingError, match="lengths"):
        m.score(X, lengths=[3, 3])
    bad = model()
    bad.transmat_ = A * 2
    with pytest.raises(tt.TrackingError, match="row"):
        bad.score(X)
    bad.transmat_ = np.where(A > 0, np.nan, 0)
    with pytest.raises(tt.TrackingError):
        bad.score(X)
    with pytest.raises(tt.TrackingError, match="not set"):
        tt.CategoricalHMM(n_components=3).score(X)
    with pytest.raises(tt.TrackingError, match="prior"):
        model(transmat_prior=0.5, init_params="").fit(X)
    with pytest.raises(tt.TrackingError, match="overflow"):
        m.score(X, lengths=[2**64 - 2048, 2048 + len(X)])
    with pytest.raises(ValueError, match="lengths"):
        m.score(X, lengths=[-1, len(X) + 1])
    # A CSR matrix whose indptr falls (scipy's own checks may not run first): refused, no
    # panic.
    csr = sp.csr_array(A)
    for indptr in ([0, 5, 2, 7], [1, 2, 4, 7]):
        with pytest.raises(tt.TrackingError, match="CSR"):
            tt._native.Hmm.sparse(PI, indptr, csr.indices, csr.data, B)
