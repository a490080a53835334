# Times the Python package (python/, `pip install ./python`) against the Python peers it
# replaces, in one run on the same arrays (pip install motmetrics hmmlearn numpy pandas):
#   1. evaluate() against py-motmetrics on the sequence of motmetrics_1000x20.py (1000 frames,
#      20 objects, 10 % misses, an identity swap every 200 frames, one false box a frame):
#      both compute CLEAR MOT and IDF1 from the same rows; ours also HOTA, SR/FAF;
#   2. CategoricalHMM against hmmlearn's on the 20 x 20 grid model of hmmlearn_grid400.py
#      (N = M = 400, T = 1000): decode (Viterbi), predict_proba (forward-backward) and one
#      Baum-Welch iteration, ours with the transition matrix as scipy.sparse (its 5 nonzeros a
#      row) and dense, hmmlearn's dense (it has no sparse storage).
# Each figure is the best of k runs; the numbers go in docs/benchmarks.md.
import sys
import time

import numpy as np

if not hasattr(np, "asfarray"):  # py-motmetrics 1.4.0 on NumPy 2
    np.asfarray = lambda a, dtype=np.float64: np.asarray(a, dtype=dtype)
import motmetrics as mm
import pandas as pd
import scipy.sparse as sp
from hmmlearn import hmm as hl

import tracking_toolkit as tt


def best(f, k=5):
    ts = []
    for _ in range(k):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return min(ts)


def mot_sequence():
    rng = np.random.default_rng(7)
    gt, pr = [], []
    for o in range(20):
        x0, y0, vx, vy = rng.uniform(0, 1500), rng.uniform(0, 900), rng.uniform(-2, 2), rng.uniform(-1, 1)
        for f in range(1, 1001):
            x, y = x0 + vx * f, y0 + vy * f
            gt.append((f, o, x, y, 40.0, 90.0))
            if rng.random() < 0.9:
                pr.append((f, o * 2 + (f // 200) % 2, x + rng.uniform(-3, 3), y + rng.uniform(-3, 3), 40.0, 90.0))
    for f in range(1, 1001):
        pr.append((f, 100000 + f, rng.uniform(0, 1500), rng.uniform(0, 900), 40.0, 90.0))
    return np.array(gt), np.array(pr)


def metrics():
    gt, pr = mot_sequence()
    cols = ["FrameId", "Id", "X", "Y", "Width", "Height"]
    g = pd.DataFrame(gt, columns=cols).astype({"FrameId": int, "Id": int}).set_index(["FrameId", "Id"])
    p = pd.DataFrame(pr, columns=cols).astype({"FrameId": int, "Id": int}).set_index(["FrameId", "Id"])
    g["Confidence"] = p["Confidence"] = 1.0

    def peer():
        acc = mm.utils.compare_to_groundtruth(g, p, "iou", distth=0.5)
        return mm.metrics.create().compute(acc, metrics=["mota", "motp", "idf1", "num_switches"], name="x")

    ours = tt.evaluate(gt, pr)
    theirs = peer()
    for k in ("mota", "idf1", "num_switches"):
        assert abs(ours[k] - float(theirs[k].iloc[0])) < 1e-9, k
    t_ours, t_peer = best(lambda: tt.evaluate(gt, pr)), best(peer, k=3)
    print(f"evaluate 1000 x 20: ours {1e3 * t_ours:.1f} ms, py-motmetrics {1e3 * t_peer:.0f} ms, "
          f"{t_peer / t_ours:.0f}x (MOTA {ours['mota']:.4f} both)")


def grid_model():
    n = 400
    A = np.zeros((n, n))
    for r in range(20):
        for c in range(20):
            i = r * 20 + c
            nb = [(r + dr) * 20 + (c + dc) for dr, dc in ((0, -1), (0, 1), (-1, 0), (1, 0))
                  if 0 <= r + dr < 20 and 0 <= c + dc < 20]
            A[i, i] = 0.3
            for j in nb:
                A[i, j] = 0.7 / len(nb)
    pos = np.array([[c + 0.5, r + 0.5] for r in range(20) for c in range(20)])
    d2 = ((pos[:, None, :] - pos[None, :, :]) ** 2).sum(-1)
    B = np.exp(-d2 / (2 * 1.2**2))
    B /= B.sum(1, keepdims=True)
    return np.full(n, 1 / n), A, B


def hmm():
    pi, A, B = grid_model()
    n = len(pi)

    def model(cls, a, **kw):
        m = cls(n_components=n, init_params="", params="ste", n_iter=1, tol=0, **kw)
        m.startprob_, m.transmat_, m.emissionprob_ = pi, a, B
        m.n_features = n
        return m

    peer = model(hl.CategoricalHMM, A)
    X, _ = peer.sample(1000, random_state=1)
    dense, sparse = model(tt.CategoricalHMM, A), model(tt.CategoricalHMM, sp.csr_array(A))
    assert abs(dense.score(X) - peer.score(X)) < 1e-6 * abs(peer.score(X))
    for name, call in (
        ("decode (Viterbi)", lambda m: m.decode(X, algorithm="viterbi")),
        ("predict_proba", lambda m: m.predict_proba(X)),
        ("one Baum-Welch iteration", lambda m: model(type(m), m.transmat_.copy()).fit(X)),
    ):
        t_peer = best(lambda: call(peer), k=3)
        t_dense, t_sparse = best(lambda: call(dense)), best(lambda: call(sparse))
        print(f"grid400 {name}: hmmlearn {1e3 * t_peer:.0f} ms, ours dense {1e3 * t_dense:.1f} ms "
              f"({t_peer / t_dense:.1f}x), ours sparse {1e3 * t_sparse:.1f} ms ({t_peer / t_sparse:.0f}x)")


if __name__ == "__main__":
    print("numpy", np.__version__, "motmetrics", mm.__version__, "hmmlearn", __import__("hmmlearn").__version__,
          "python", sys.version.split()[0])
    metrics()
    hmm()
