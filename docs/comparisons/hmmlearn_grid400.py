# Times hmmlearn on the HMM models of crates/hmm-grid/benches/hmm.rs (pip install hmmlearn numpy).
#   1. the 20×20 grid model (400 states, stay + 4-neighbour moves, M = 400, T = 1000). hmmlearn
#      stores A dense, so the like-for-like Rust numbers are the `grid400_dense_*` benchmarks
#      (the same grid model forced to dense storage); `grid400_*` is our sparse storage.
#   2. a dense random model of the same size (N = M = 400, every transition possible), the shape
#      of the `dense400_*` benchmarks (same distribution of entries, not the same bytes).
# Each time is the best of `k` runs, as criterion's median is over warm runs.
import time, numpy as np
from hmmlearn import hmm
n = 400
# 20x20 grid, stay 0.3, move 0.7 split over 4-neighbours (as the Rust benchmark)
A = np.zeros((n, n))
for r in range(20):
    for c in range(20):
        i = r*20+c
        nb = [(r+dr)*20+(c+dc) for dr,dc in ((0,-1),(0,1),(-1,0),(1,0)) if 0<=r+dr<20 and 0<=c+dc<20]
        A[i,i] = 0.3
        for j in nb: A[i,j] = 0.7/len(nb)
pos = np.array([[c+0.5, r+0.5] for r in range(20) for c in range(20)])
d2 = ((pos[:,None,:]-pos[None,:,:])**2).sum(-1)
B = np.exp(-d2/(2*1.2**2)); B /= B.sum(1, keepdims=True)

def model(A, B):
    m = hmm.CategoricalHMM(n_components=n, init_params="", params="ste", n_iter=1, tol=0)
    m.startprob_ = np.full(n, 1/n); m.transmat_ = A; m.emissionprob_ = B; m.n_features = n
    return m

def best(f, k=3):
    ts = []
    for _ in range(k):
        t = time.perf_counter(); f(); ts.append(time.perf_counter()-t)
    return min(ts)

def bw(m, X):
    mm = hmm.CategoricalHMM(n_components=n, init_params="", params="te", n_iter=1, tol=0)
    mm.startprob_ = m.startprob_; mm.transmat_ = m.transmat_.copy()
    mm.emissionprob_ = m.emissionprob_.copy(); mm.n_features = n
    mm.fit(X)

print("hmmlearn %s, numpy %s" % (__import__("hmmlearn").__version__, np.__version__))
rng = np.random.default_rng(1)
dense_rows = lambda: (lambda r: r / r.sum(1, keepdims=True))(rng.uniform(0.01, 1.0, (n, n)))
for name, m in (("grid400", model(A, B)), ("dense400", model(dense_rows(), dense_rows()))):
    X, _ = m.sample(1000, random_state=1)
    print("%s forward-backward (predict_proba): %.3f s" % (name, best(lambda: m.predict_proba(X))))
    print("%s viterbi (decode): %.3f s" % (name, best(lambda: m.decode(X, algorithm="viterbi"))))
    print("%s one Baum-Welch iteration (fit n_iter=1): %.3f s" % (name, best(lambda: bw(m, X))))
