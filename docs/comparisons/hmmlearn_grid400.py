# Times hmmlearn on the 20×20 grid model of crates/hmm-grid/benches/hmm.rs (pip install hmmlearn).
import time, numpy as np
from hmmlearn import hmm
rng = np.random.default_rng(1)
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
m = hmm.CategoricalHMM(n_components=n, init_params="", params="ste", n_iter=1, tol=0)
m.startprob_ = np.full(n, 1/n); m.transmat_ = A; m.emissionprob_ = B; m.n_features = n
X, _ = m.sample(1000, random_state=1)
def best(f, k=3):
    ts = []
    for _ in range(k):
        t = time.perf_counter(); f(); ts.append(time.perf_counter()-t)
    return min(ts)
print("hmmlearn %s" % __import__("hmmlearn").__version__)
print("forward-backward (predict_proba): %.3f s" % best(lambda: m.predict_proba(X)))
print("viterbi (decode): %.3f s" % best(lambda: m.decode(X, algorithm="viterbi")))
def bw():
    mm = hmm.CategoricalHMM(n_components=n, init_params="", params="te", n_iter=1, tol=0)
    mm.startprob_ = m.startprob_; mm.transmat_ = A.copy(); mm.emissionprob_ = B.copy(); mm.n_features = n
    mm.fit(X)
print("one Baum-Welch iteration (fit n_iter=1): %.3f s" % best(bw))
