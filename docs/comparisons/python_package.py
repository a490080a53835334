# Times the Python package (python/, `pip install ./python`) against the Python peer each part
# replaces, in one run on the same arrays, like for like:
#   pip install motmetrics hmmlearn filterpy pyroomacoustics opencv-contrib-python-headless
#   python docs/comparisons/python_package.py            # every comparison, one after another
#   python docs/comparisons/python_package.py NAME       # one: mot, mot-long, hmm, kalman, mog, doa
# Each figure is the best of k runs. Peak memory (mot-long) is the resident-set high-water mark
# of a fresh process that loads the arrays and does only that side's work, less the mark after
# loading; the numbers go in docs/benchmarks.md.
#   mot       evaluate() and py-motmetrics' compare_to_groundtruth + compute on the sequence of
#             motmetrics_1000x20.py (1000 frames x 20 objects, 10 % missed, an identity swap
#             every 200 frames, one false box a frame). Both compute CLEAR MOT and IDF1 from
#             the same rows; ours also HOTA and SR/FAF in the same call.
#   mot-long  the same kind of sequence over 15 000 frames (300 000 true boxes; the motion
#             restarts every 1000 frames), time and memory.
#   hmm       CategoricalHMM and hmmlearn's on the 20 x 20 grid model of hmmlearn_grid400.py
#             (N = M = 400, T = 1000): decode, predict_proba and one Baum-Welch iteration;
#             ours with transmat_ dense and as scipy.sparse (5 nonzeros a row), hmmlearn's dense.
#   kalman    KalmanFilter and filterpy's on filterpy_cv2d_1000.py's problem: batch_filter and
#             rts_smoother over 1000 steps (every tenth measurement missing).
#   mog       BackgroundSubtractorMOG and OpenCV bgsegm's MOG (history 200, 5 mixtures, ratio
#             0.7) on 100 grey 768 x 576 frames of a noisy background with a moving block.
#             The algorithms are the same; the masks are not bit-equal (docs/video.md).
#   doa       doa(weighting="phat") and pyroomacoustics' SRP-PHAT on 1 s of a 4-microphone
#             recording at 16 kHz: 512-sample frames, 36 beams, 200-4000 Hz; the peer's time
#             includes its STFT, as ours includes ours.
import resource
import subprocess
import sys
import time

import numpy as np

if not hasattr(np, "asfarray"):  # py-motmetrics 1.4.0 on NumPy 2
    np.asfarray = lambda a, dtype=np.float64: np.asarray(a, dtype=dtype)

import tracking_toolkit as tt


def best(f, k=5):
    ts = []
    for _ in range(k):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return min(ts)


def mot_sequence(frames=1000):
    rng = np.random.default_rng(7)
    gt, pr = [], []
    for o in range(20):
        x0, y0, vx, vy = rng.uniform(0, 1500), rng.uniform(0, 900), rng.uniform(-2, 2), rng.uniform(-1, 1)
        f = np.arange(1, frames + 1)
        x, y = x0 + vx * (f % 1000), y0 + vy * (f % 1000)
        gt.append(np.column_stack([f, np.full_like(f, o), x, y, np.full(frames, 40.0), np.full(frames, 90.0)]))
        seen = rng.random(frames) < 0.9
        jitter = rng.uniform(-3, 3, (2, frames))
        ids = o * 2 + (f // 200) % 2
        pr.append(np.column_stack([f, ids, x + jitter[0], y + jitter[1], np.full(frames, 40.0), np.full(frames, 90.0)])[seen])
    f = np.arange(1, frames + 1)
    pr.append(np.column_stack([f, 100000 + f, rng.uniform(0, 1500, frames), rng.uniform(0, 900, frames),
                               np.full(frames, 40.0), np.full(frames, 90.0)]))
    return np.concatenate(gt).astype(float), np.concatenate(pr).astype(float)


def motmetrics_run(gt, pr):
    import motmetrics as mm
    import pandas as pd

    cols = ["FrameId", "Id", "X", "Y", "Width", "Height"]
    g = pd.DataFrame(gt, columns=cols).astype({"FrameId": int, "Id": int}).set_index(["FrameId", "Id"])
    p = pd.DataFrame(pr, columns=cols).astype({"FrameId": int, "Id": int}).set_index(["FrameId", "Id"])
    g["Confidence"] = 1.0
    p["Confidence"] = 1.0
    acc = mm.utils.compare_to_groundtruth(g, p, "iou", distth=0.5)
    s = mm.metrics.create().compute(acc, metrics=["mota", "motp", "idf1", "num_switches"], name="x")
    return {k: float(s[k].iloc[0]) for k in ("mota", "idf1", "num_switches")}


def mot():
    import motmetrics as mm

    gt, pr = mot_sequence()
    ours, theirs = tt.evaluate(gt, pr), motmetrics_run(gt, pr)
    # IDF1 is one global assignment in both; CLEAR's frame-by-frame matching is TrackEval's in
    # ours (a bonus for the previous frame's pairs) and differs from py-motmetrics' (which
    # keeps an object's last match of any earlier frame) when a false box competes after a
    # miss, so their switch counts may differ by a few.
    assert abs(ours["idf1"] - theirs["idf1"]) < 1e-9
    t_ours, t_peer = best(lambda: tt.evaluate(gt, pr)), best(lambda: motmetrics_run(gt, pr), k=3)
    print(f"mot 1000 x 20 (py-motmetrics {mm.__version__}): ours {1e3 * t_ours:.1f} ms, "
          f"py-motmetrics {1e3 * t_peer:.0f} ms: {t_peer / t_ours:.0f}x (IDF1 {ours['idf1']:.4f} both; "
          f"MOTA {ours['mota']:.4f} / {theirs['mota']:.4f}, IDSW {ours['num_switches']:.0f} / "
          f"{theirs['num_switches']:.0f})")


def peak_rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def mot_long_side(side, folder):
    gt, pr = np.load(f"{folder}/gt.npy"), np.load(f"{folder}/pr.npy")
    base = peak_rss_mb()
    t = time.perf_counter()
    result = tt.evaluate(gt, pr) if side == "ours" else motmetrics_run(gt, pr)
    elapsed = time.perf_counter() - t
    print(f"{side} {elapsed:.3f} {peak_rss_mb() - base:.1f} {result['mota']:.9f} {len(gt)}")


def mot_long():
    import tempfile

    out = {}
    with tempfile.TemporaryDirectory() as folder:
        gt, pr = mot_sequence(15_000)
        np.save(f"{folder}/gt.npy", gt)
        np.save(f"{folder}/pr.npy", pr)
        for side in ("ours", "py-motmetrics"):
            line = subprocess.run([sys.executable, __file__, "mot-long-side", side, folder],
                                  check=True, capture_output=True, text=True).stdout.split()
            out[side] = (float(line[1]), float(line[2]), float(line[3]), int(line[4]))
    (t_o, m_o, a_o, n), (t_p, m_p, a_p, _) = out["ours"], out["py-motmetrics"]
    print(f"mot-long {n} true boxes: ours {t_o:.2f} s and {m_o:.0f} MB of peak memory above the "
          f"loaded arrays, py-motmetrics {t_p:.1f} s and {m_p:.0f} MB: {t_p / t_o:.0f}x the time, "
          f"{m_p / max(m_o, 1):.0f}x the memory (MOTA {a_o:.4f} / {a_p:.4f})")


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
    import hmmlearn
    import scipy.sparse as sp
    from hmmlearn import hmm as hl

    pi, A, B = grid_model()
    n = len(pi)

    def model(cls, a, **storage):
        m = cls(n_components=n, init_params="", params="ste", n_iter=1, tol=0, **storage)
        m.startprob_, m.transmat_, m.emissionprob_ = pi, a, B
        m.n_features = n
        return m

    def refit(m):
        extra = {} if isinstance(m, hl.CategoricalHMM) else {"transmat_storage": m.transmat_storage}
        return model(type(m), m.transmat_.copy(), **extra).fit(X)

    peer = model(hl.CategoricalHMM, A)
    X, _ = peer.sample(1000, random_state=1)
    # Ours stored dense (like for like with hmmlearn) and sparse (scipy.sparse, 5 nonzeros a row).
    dense = model(tt.CategoricalHMM, A, transmat_storage="dense")
    sparse = model(tt.CategoricalHMM, sp.csr_array(A))
    assert abs(dense.score(X) - peer.score(X)) < 1e-9 * abs(peer.score(X))
    for name, call in (
        ("decode (Viterbi)", lambda m: m.decode(X, algorithm="viterbi")),
        ("predict_proba", lambda m: m.predict_proba(X)),
        ("one Baum-Welch iteration", lambda m: refit(m)),
    ):
        t_peer = best(lambda: call(peer), k=3)
        t_dense, t_sparse = best(lambda: call(dense)), best(lambda: call(sparse))
        print(f"hmm grid400 {name} (hmmlearn {hmmlearn.__version__}): hmmlearn {1e3 * t_peer:.0f} ms, "
              f"ours dense {1e3 * t_dense:.1f} ms ({t_peer / t_dense:.1f}x), "
              f"sparse {1e3 * t_sparse:.1f} ms ({t_peer / t_sparse:.0f}x)")


def kalman():
    import filterpy
    from filterpy.kalman import KalmanFilter

    q, dt, r = 0.1, 1.0, 4.0
    F = np.array([[1, 0, dt, 0], [0, 1, 0, dt], [0, 0, 1, 0], [0, 0, 0, 1]], float)
    qa = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    Q = np.zeros((4, 4))
    Q[np.ix_([0, 2], [0, 2])] = qa
    Q[np.ix_([1, 3], [1, 3])] = qa
    H = np.eye(2, 4)
    rng = np.random.default_rng(1)
    zs = [None if k % 10 == 3 else np.array([k + 2 * rng.standard_normal(), k + 2 * rng.standard_normal()])
          for k in range(1000)]

    def setup(cls):
        kf = cls(dim_x=4, dim_z=2)
        kf.F, kf.Q, kf.H, kf.R = F, Q, H, r * np.eye(2)
        kf.x, kf.P = np.array([0.0, 0.0, 1.0, 1.0]), 10.0 * np.eye(4)
        return kf

    def run(cls):
        kf = setup(cls)
        mu, cov = kf.batch_filter(zs)[:2]
        return kf.rts_smoother(mu, cov)[:2]

    ours, theirs = run(tt.KalmanFilter), run(KalmanFilter)
    assert np.allclose(ours[0], np.asarray(theirs[0]).reshape(1000, 4), atol=1e-9)
    one_call = lambda: setup(tt.KalmanFilter).smooth(zs)
    assert np.allclose(one_call()[0], ours[0], atol=1e-9)
    t_ours, t_peer = best(lambda: run(tt.KalmanFilter)), best(lambda: run(KalmanFilter), k=3)
    t_one = best(one_call)
    print(f"kalman 1000 steps filter + RTS (filterpy {filterpy.__version__}): ours {1e3 * t_ours:.2f} ms "
          f"(batch_filter + rts_smoother; {1e3 * t_one:.2f} ms as one smooth call), filterpy "
          f"{1e3 * t_peer:.1f} ms: {t_peer / t_ours:.0f}x ({t_peer / t_one:.0f}x) (equal to 1e-9)")


def mog():
    import cv2

    rng = np.random.default_rng(3)
    base = rng.integers(60, 200, (576, 768), dtype=np.uint8)
    frames = []
    for t in range(100):
        f = np.clip(base + rng.normal(0, 3, base.shape), 0, 255).astype(np.uint8)
        f[200:300, 100 + 5 * t:160 + 5 * t] = 240
        frames.append(f)

    def ours():
        m = tt.BackgroundSubtractorMOG(history=200, n_mixtures=5, background_ratio=0.7)
        for f in frames:
            m.apply(f)

    def peer():
        m = cv2.bgsegm.createBackgroundSubtractorMOG(history=200, nmixtures=5, backgroundRatio=0.7, noiseSigma=0)
        for f in frames:
            m.apply(f)

    t_ours, t_peer = best(ours, k=3), best(peer, k=3)
    print(f"mog 768 x 576 grey (OpenCV {cv2.__version__}, {cv2.getNumThreads()} threads): ours "
          f"{1e3 * t_ours / 100:.2f} ms a frame, OpenCV {1e3 * t_peer / 100:.2f} ms: {t_peer / t_ours:.2f}x")


def doa():
    import pyroomacoustics as pra

    fs, c, nfft = 16_000, 343.0, 512
    mics = np.array([[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]])
    rng = np.random.default_rng(1)
    n = fs
    f = np.fft.rfftfreq(n, 1 / fs)
    spectrum = (rng.normal(size=f.size) + 1j * rng.normal(size=f.size)) * ((f > 300) & (f < 3500))
    u = np.array([np.cos(np.radians(40)), np.sin(np.radians(40))])
    signals = np.array([np.fft.irfft(spectrum * np.exp(2j * np.pi * f * t), n) for t in mics @ u / c])
    azimuth = np.arange(36) * 2 * np.pi / 36

    def peer():
        frames = signals[:, : (n // nfft) * nfft].reshape(4, -1, nfft)
        X = np.fft.rfft(frames * np.hanning(nfft), axis=2).transpose(0, 2, 1)
        d = pra.doa.algorithms["SRP"](mics.T, fs, nfft, c=c, num_src=1, azimuth=azimuth)
        d.locate_sources(X, freq_range=[200, 4000])
        return d.azimuth_recon

    def ours():
        return tt.doa(signals, mics, weighting="phat", band_hz=[200.0, 4000.0])[0]

    assert abs(np.degrees(ours()[0]) - 40) < 3 and abs(np.degrees(peer()[0]) - 40) < 6
    t_ours, t_peer = best(ours), best(peer)
    print(f"doa SRP-PHAT 1 s, 4 mics, 36 beams (pyroomacoustics {pra.__version__}): ours "
          f"{1e3 * t_ours:.2f} ms, pyroomacoustics {1e3 * t_peer:.2f} ms: {t_peer / t_ours:.1f}x")


ALL = {"mot": mot, "mot-long": mot_long, "hmm": hmm, "kalman": kalman, "mog": mog, "doa": doa}

if __name__ == "__main__":
    if sys.argv[1:2] == ["mot-long-side"]:
        mot_long_side(sys.argv[2], sys.argv[3])
        sys.exit(0)
    print("python", sys.version.split()[0], "numpy", np.__version__)
    for name in sys.argv[1:] or ALL:
        ALL[name]()
