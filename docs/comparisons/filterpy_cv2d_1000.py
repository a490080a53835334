# Times filterpy's Kalman filter + RTS smoother on the problem of
# crates/tracker-model/benches/kalman.rs `cv2d_filter_and_rts_1000_steps` (pip install filterpy numpy):
# constant-velocity 2-D model, state [x, y, vx, vy], dt = 1, white-acceleration noise q = 0.1
# (Q per axis q·[[dt³/3, dt²/2], [dt²/2, dt]]), position measurements with R = 4·I, every tenth
# scan (k % 10 == 3) missing, prior mean [0, 0, 1, 1] and covariance 10·I, 1000 steps.
# Same shape of data, not the same bytes (NumPy's generator, not ChaCha8).
# filterpy's batch_filter skips the update on None; rts_smoother runs on its outputs.
import time, numpy as np
import filterpy
from filterpy.kalman import KalmanFilter

q, dt, r = 0.1, 1.0, 4.0
F = np.array([[1, 0, dt, 0], [0, 1, 0, dt], [0, 0, 1, 0], [0, 0, 0, 1]], float)
qa = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
Q = np.zeros((4, 4))
Q[np.ix_([0, 2], [0, 2])] = qa
Q[np.ix_([1, 3], [1, 3])] = qa
H = np.array([[1, 0, 0, 0], [0, 1, 0, 0]], float)
rng = np.random.default_rng(1)
zs = [None if k % 10 == 3 else np.array([k + 2 * rng.standard_normal(), k + 2 * rng.standard_normal()])
      for k in range(1000)]

def run():
    kf = KalmanFilter(dim_x=4, dim_z=2)
    kf.F, kf.Q, kf.H, kf.R = F, Q, H, r * np.eye(2)
    kf.x = np.array([0.0, 0.0, 1.0, 1.0]); kf.P = 10.0 * np.eye(4)
    mu, cov, _, _ = kf.batch_filter(zs)
    return kf.rts_smoother(mu, cov)

def best(f, k=7):
    ts = []
    for _ in range(k):
        t = time.perf_counter(); f(); ts.append(time.perf_counter() - t)
    return sorted(ts)[len(ts) // 2], min(ts)

med, mn = best(run)
print("filterpy %s, numpy %s" % (filterpy.__version__, np.__version__))
print("filter + RTS, 1000 steps: median %.1f ms, best %.1f ms" % (med * 1e3, mn * 1e3))
