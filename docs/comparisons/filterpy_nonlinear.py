#!/usr/bin/env python3
"""filterpy 2.0.0 (MIT): its ExtendedKalmanFilter, UnscentedKalmanFilter (Merwe scaled sigma
points) and IMMEstimator on a turning aircraft seen by a range-bearing(-elevation) radar, for
tracker-model's EKF, UKF and IMM.

    python3 docs/comparisons/filterpy_nonlinear.py record crates/tracker-model/testdata/filterpy_nonlinear.json

writes the shared inputs (models, prior, measurement times and values) and filterpy's outputs
at every scan: the predicted mean, the posterior mean and covariance, the log-likelihood of
the measurement and, for the IMMs, each mode's predicted mean and the mode probabilities.
crates/tracker-model/tests/filterpy_reference.rs runs tracker-model on the same inputs and
requires every number to within 1e-9 (relative to the value's scale, absolute below 1).

The models below are written here from their textbook formulas (Bar-Shalom, Li &
Kirubarajan 2001; Li & Jilkov 2003), not from the Rust code. Angles: the bearing residual is
wrapped into (-pi, pi] and the UKF averages bearings on the circle, through filterpy's
residual_z and z_mean_fn hooks. filterpy's IMM weighs its combined *prior* by the posterior
probabilities of the last scan; tracker-model uses the predicted ones (Blom & Bar-Shalom
1988), so the combined prior is not compared: each mode's prior is.

    python3 docs/comparisons/filterpy_nonlinear.py time

times filterpy on the same 43 scans, a whole run per measurement (median of 21; filter
construction included, nothing recorded), for the EKF
and UKF with the turn rate in the state and the three-mode EKF IMM: what
crates/tracker-model/benches/kalman.rs times as ekf_turn_rate_43_scans,
ukf_turn_rate_43_scans and imm_ekf_cv_ct_43_scans.

It creates /tmp/filterpy-venv and installs filterpy==2.0.0 from PyPI the first time.
"""
import json, math, os, subprocess, sys

VENV = "/tmp/filterpy-venv"
if sys.prefix != VENV:
    if not os.path.exists(VENV):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
        subprocess.check_call([VENV + "/bin/pip", "install", "-q", "filterpy==2.0.0", "numpy", "scipy"])
    os.execv(VENV + "/bin/python", [VENV + "/bin/python", __file__] + sys.argv[1:])

import numpy as np
import filterpy
from filterpy.kalman import ExtendedKalmanFilter, IMMEstimator, MerweScaledSigmaPoints, UnscentedKalmanFilter

SCAN_S = 4.0
MISSING = {20, 21}          # scans without a measurement: the next prediction spans 12 s
RADAR = np.array([5000.0, 2500.0, 0.0])
SIGMA_R, SIGMA_B, SIGMA_E = 30.0, 0.003, 0.004
TURN = math.radians(3.0)    # rad/s, counter-clockwise
UKF_POINTS = dict(alpha=0.5, beta=2.0, kappa=-1.0)


def wrap(a):
    a = (a + math.pi) % (2 * math.pi) - math.pi
    return a + 2 * math.pi if a <= -math.pi else a


# ---- motion: textbook coordinated turn and white-acceleration noise ----
def turn_terms(w, dt):
    if abs(w * dt) < 1e-4:
        a = w * dt
        return dt * (1 - a * a / 6 + a**4 / 120), dt * a * (0.5 - a * a / 24 + a**4 / 720)
    return math.sin(w * dt) / w, (1 - math.cos(w * dt)) / w


def ct_matrix(w, dt):
    s, v = turn_terms(w, dt)
    c, sn = math.cos(w * dt), math.sin(w * dt)
    return np.array([[1, 0, s, -v], [0, 1, v, s], [0, 0, c, -sn], [0, 0, sn, c]])


def wna(q, dt, axes):
    n = 2 * axes
    Q = np.zeros((n, n))
    for i in range(axes):
        Q[i, i], Q[i, i + axes] = q * dt**3 / 3, q * dt**2 / 2
        Q[i + axes, i], Q[i + axes, i + axes] = q * dt**2 / 2, q * dt
    return Q


class CT4:      # known turn rate, [x, y, vx, vy]
    def __init__(self, w, q): self.w, self.q = w, q
    def f(self, x, dt): return ct_matrix(self.w, dt) @ x
    def jac(self, x, dt): return ct_matrix(self.w, dt)
    def Q(self, dt): return wna(self.q, dt, 2)


class CTRate:   # turn rate in the state, [x, y, vx, vy, w]
    def __init__(self, qa, qw): self.qa, self.qw = qa, qw
    def f(self, x, dt):
        out = np.empty(5)
        out[:4] = ct_matrix(x[4], dt) @ x[:4]
        out[4] = x[4]
        return out
    def jac(self, x, dt, h=1e-6):
        # derivative in w by the closed forms of d/dw sin(wT)/w and (1 - cos(wT))/w
        w, vx, vy = x[4], x[2], x[3]
        a = w * dt
        if abs(a) < 1e-4:
            ds, dv = dt * dt * a * (-1 / 3 + a * a / 30), dt * dt * (0.5 - a * a / 8 + a**4 / 144)
        else:
            ds = (a * math.cos(a) - math.sin(a)) / w**2
            dv = (a * math.sin(a) - (1 - math.cos(a))) / w**2
        J = np.eye(5)
        J[:4, :4] = ct_matrix(w, dt)
        J[0, 4] = ds * vx - dv * vy
        J[1, 4] = dv * vx + ds * vy
        J[2, 4] = -dt * (math.sin(a) * vx + math.cos(a) * vy)
        J[3, 4] = dt * (math.cos(a) * vx - math.sin(a) * vy)
        return J
    def Q(self, dt):
        Q = np.zeros((5, 5))
        Q[:4, :4] = wna(self.qa, dt, 2)
        Q[4, 4] = self.qw * dt
        return Q


class CVLayout(CTRate):  # straight flight in the turn layout, the turn rate reset to zero
    def f(self, x, dt):
        return np.array([x[0] + dt * x[2], x[1] + dt * x[3], x[2], x[3], 0.0])
    def jac(self, x, dt):
        J = np.eye(5)
        J[0, 2] = J[1, 3] = dt
        J[4, 4] = 0.0
        return J


class CV3:      # [x, y, z, vx, vy, vz]
    def __init__(self, q): self.q = q
    def f(self, x, dt): return self.jac(x, dt) @ x
    def jac(self, x, dt):
        J = np.eye(6)
        J[0, 3] = J[1, 4] = J[2, 5] = dt
        return J
    def Q(self, dt): return wna(self.q, dt, 3)


# ---- radar ----
class RangeBearing:
    dim = 2
    R = np.diag([SIGMA_R**2, SIGMA_B**2])
    def h(self, x):
        dx, dy = x[0] - RADAR[0], x[1] - RADAR[1]
        return np.array([math.hypot(dx, dy), math.atan2(dy, dx)])
    def H(self, x):
        dx, dy = x[0] - RADAR[0], x[1] - RADAR[1]
        r2 = dx * dx + dy * dy
        r = math.sqrt(r2)
        J = np.zeros((2, len(x)))
        J[0, 0], J[0, 1], J[1, 0], J[1, 1] = dx / r, dy / r, -dy / r2, dx / r2
        return J
    def residual(self, a, b):
        d = np.asarray(a, float).ravel() - np.asarray(b, float).ravel()
        d[1] = wrap(d[1])
        return d
    def mean(self, sigmas, wm):
        m = np.dot(wm, sigmas)
        m[1] = math.atan2(np.dot(wm, np.sin(sigmas[:, 1])), np.dot(wm, np.cos(sigmas[:, 1])))
        return m


class RangeBearingElevation(RangeBearing):
    dim = 3
    R = np.diag([SIGMA_R**2, SIGMA_B**2, SIGMA_E**2])
    def h(self, x):
        d = x[:3] - RADAR
        g = math.hypot(d[0], d[1])
        return np.array([math.hypot(g, d[2]), math.atan2(d[1], d[0]), math.atan2(d[2], g)])
    def H(self, x):
        dx, dy, dz = x[:3] - RADAR
        rho2 = dx * dx + dy * dy
        rho, r2 = math.sqrt(rho2), rho2 + dz * dz
        r = math.sqrt(r2)
        J = np.zeros((3, len(x)))
        J[0, :3] = [dx / r, dy / r, dz / r]
        J[1, :2] = [-dy / rho2, dx / rho2]
        J[2, :3] = [-dx * dz / (rho * r2), -dy * dz / (rho * r2), rho / r2]
        return J


# ---- filterpy filters bound to one model and one radar, as IMMEstimator calls them ----
class EKF(ExtendedKalmanFilter):
    def __init__(self, motion, radar, x, P):
        super().__init__(len(x), radar.dim)
        self.motion, self.radar, self.dt = motion, radar, SCAN_S
        self.x, self.P, self.R = x.reshape(-1, 1).copy(), P.copy(), radar.R
    def predict(self, u=0):
        x = self.x.ravel()
        self.F, self.Q = self.motion.jac(x, self.dt), self.motion.Q(self.dt)
        super().predict(u)
    def predict_x(self, u=0):
        self.x = self.motion.f(self.x.ravel(), self.dt).reshape(-1, 1)
    def update(self, z):
        super().update(np.asarray(z, float).reshape(-1, 1), lambda x: self.radar.H(x.ravel()),
                       lambda x: self.radar.h(x.ravel()).reshape(-1, 1),
                       residual=lambda a, b: self.radar.residual(a, b).reshape(-1, 1))
    def mean(self): return self.x.ravel()


class UKF(UnscentedKalmanFilter):
    def __init__(self, motion, radar, x, P):
        n = len(x)
        pts = MerweScaledSigmaPoints(n, **UKF_POINTS)
        super().__init__(n, radar.dim, SCAN_S, hx=radar.h, fx=motion.f, points=pts,
                         residual_z=radar.residual, z_mean_fn=radar.mean)
        self.motion = motion
        self.x, self.P, self.R = x.copy(), P.copy(), radar.R
    def predict(self, dt=None, **kw):
        self.Q = self.motion.Q(self._dt)
        super().predict(**kw)
    def mean(self): return self.x.ravel()


def log_normal(y, S):
    y = np.asarray(y, float).ravel()
    _, logdet = np.linalg.slogdet(S)
    return -0.5 * (len(y) * math.log(2 * math.pi) + logdet + y @ np.linalg.solve(S, y))


# ---- the shared scene ----
def truth(t):
    """Straight east at 150 m/s for 60 s, a 3 deg/s left turn for 60 s, straight again; climbing
    at 5 m/s from 3000 m."""
    v = 150.0
    x0 = np.array([-8000.0, 2000.0])
    if t <= 60:
        p, vel = x0 + [v * t, 0], [v, 0]
    else:
        tt = min(t - 60, 60.0)
        s, c = math.sin(TURN * tt), math.cos(TURN * tt)
        p = x0 + [v * 60, 0] + np.array([v * s / TURN, v * (1 - c) / TURN])
        vel = [v * c, v * s]
        if t > 120:
            p = p + np.array(vel) * (t - 120)
    return np.array([p[0], p[1], 3000.0 + 5.0 * t, vel[0], vel[1], 5.0])


def scene():
    rng = np.random.default_rng(2026)
    times, zs2, zs3 = [], [], []
    for k in range(1, 46):
        t = k * SCAN_S
        z3 = RangeBearingElevation().h(truth(t)) + rng.standard_normal(3) * [SIGMA_R, SIGMA_B, SIGMA_E]
        z3[1] = wrap(z3[1])
        z2 = RangeBearing().h(truth(t)) + rng.standard_normal(2) * [SIGMA_R, SIGMA_B]
        z2[1] = wrap(z2[1])
        if k in MISSING:
            continue
        times.append(t); zs2.append(z2.tolist()); zs3.append(z3.tolist())
    return times, zs2, zs3


def run_single(flt, times, zs, keep=True):
    out, t_last = [], 0.0
    for t, z in zip(times, zs):
        flt.dt = flt._dt = t - t_last
        flt.predict()
        if not keep:
            flt.update(z)
            t_last = t
            continue
        prior = flt.mean().tolist()
        flt.update(z)
        out.append(dict(prior_mean=prior, mean=flt.mean().tolist(), cov=np.asarray(flt.P).tolist(),
                        log_likelihood=float(flt.log_likelihood)))
        t_last = t
    return out


def run_imm(filters, switching, mu0, times, zs, keep=True):
    imm = IMMEstimator(filters, np.array(mu0), np.array(switching))
    out, t_last = [], 0.0
    for t, z in zip(times, zs):
        for f in filters:
            f.dt = f._dt = t - t_last
        imm.predict()
        if not keep:
            imm.update(z)
            t_last = t
            continue
        priors = [f.mean().tolist() for f in filters]
        c_bar = imm.cbar.copy()
        imm.update(z)
        lik = sum(c * math.exp(f.log_likelihood) for c, f in zip(c_bar, filters))
        out.append(dict(mode_prior_means=priors, probabilities=imm.mu.tolist(),
                        mean=imm.x.ravel().tolist(), cov=np.asarray(imm.P).tolist(),
                        log_likelihood=math.log(lik)))
        t_last = t
    return out


def record(path):
    times, zs2, zs3 = scene()
    t0 = truth(0.0)
    prior5 = np.array([t0[0] + 50, t0[1] - 40, t0[3] + 5, t0[4] - 3, 0.0])
    cov5 = np.diag([100.0**2, 100.0**2, 20.0**2, 20.0**2, 0.05**2])
    prior4, cov4 = prior5[:4], cov5[:4, :4]
    prior6 = np.array([t0[0] + 50, t0[1] - 40, t0[2] + 30, t0[3] + 5, t0[4] - 3, 0.0])
    cov6 = np.diag([100.0**2, 100.0**2, 100.0**2, 20.0**2, 20.0**2, 5.0**2])
    ct_rate = dict(q_accel=1.0, q_turn=1e-5)
    cv4 = dict(q=0.5)
    ct4 = [dict(turn_rate_rad_s=TURN, q=0.5), dict(turn_rate_rad_s=-TURN, q=0.5)]
    cv3 = dict(q=0.5)
    switch3 = [[0.90, 0.05, 0.05], [0.10, 0.85, 0.05], [0.10, 0.05, 0.85]]
    switch2 = [[0.95, 0.05], [0.10, 0.90]]
    rb, rbe = RangeBearing(), RangeBearingElevation()
    mk_rate = lambda: CTRate(ct_rate["q_accel"], ct_rate["q_turn"])
    runs = {
        "ekf_turn_rate": run_single(EKF(mk_rate(), rb, prior5, cov5), times, zs2),
        "ukf_turn_rate": run_single(UKF(mk_rate(), rb, prior5, cov5), times, zs2),
        "ekf_cv3": run_single(EKF(CV3(cv3["q"]), rbe, prior6, cov6), times, zs3),
        "ukf_cv3": run_single(UKF(CV3(cv3["q"]), rbe, prior6, cov6), times, zs3),
        "imm_ekf_cv_ct": run_imm(
            [EKF(m, rb, prior4, cov4) for m in
             [CT4(0.0, cv4["q"])] + [CT4(c["turn_rate_rad_s"], c["q"]) for c in ct4]],
            switch3, [0.8, 0.1, 0.1], times, zs2),
        "imm_ukf_turn_layout": run_imm(
            [UKF(CVLayout(**{"qa": ct_rate["q_accel"], "qw": ct_rate["q_turn"]}), rb, prior5, cov5),
             UKF(mk_rate(), rb, prior5, cov5)],
            switch2, [0.9, 0.1], times, zs2),
    }
    doc = dict(
        filterpy=filterpy.__version__, numpy=np.__version__,
        radar=RADAR.tolist(), sigma_range_m=SIGMA_R, sigma_bearing_rad=SIGMA_B,
        sigma_elevation_rad=SIGMA_E, sigma_points=UKF_POINTS,
        turn_rate=ct_rate, cv=cv4, turns=ct4, cv3=cv3,
        switching_cv_ct=switch3, start_cv_ct=[0.8, 0.1, 0.1],
        switching_turn_layout=switch2, start_turn_layout=[0.9, 0.1],
        prior5=dict(mean=prior5.tolist(), cov=cov5.tolist()),
        prior6=dict(mean=prior6.tolist(), cov=cov6.tolist()),
        times=times, range_bearing=zs2, range_bearing_elevation=zs3, runs=runs)
    with open(path, "w") as f:
        json.dump(doc, f, indent=0)
    print("filterpy %s, numpy %s: %d scans, %d runs -> %s" % (
        filterpy.__version__, np.__version__, len(times), len(runs), path))


def time_runs():
    import time
    times, zs2, _ = scene()
    t0 = truth(0.0)
    prior5 = np.array([t0[0] + 50, t0[1] - 40, t0[3] + 5, t0[4] - 3, 0.0])
    cov5 = np.diag([100.0**2, 100.0**2, 20.0**2, 20.0**2, 0.05**2])
    rb = RangeBearing()
    switch3 = [[0.90, 0.05, 0.05], [0.10, 0.85, 0.05], [0.10, 0.05, 0.85]]
    cases = {
        "ekf_turn_rate_43_scans": lambda: run_single(
            EKF(CTRate(1.0, 1e-5), rb, prior5, cov5), times, zs2, keep=False),
        "ukf_turn_rate_43_scans": lambda: run_single(
            UKF(CTRate(1.0, 1e-5), rb, prior5, cov5), times, zs2, keep=False),
        "imm_ekf_cv_ct_43_scans": lambda: run_imm(
            [EKF(CT4(w, 0.5), rb, prior5[:4], cov5[:4, :4]) for w in (0.0, TURN, -TURN)],
            switch3, [0.8, 0.1, 0.1], times, zs2, keep=False),
    }
    print("filterpy %s, numpy %s" % (filterpy.__version__, np.__version__))
    for name, f in cases.items():
        ts = []
        for _ in range(21):
            t = time.perf_counter(); f(); ts.append(time.perf_counter() - t)
        print("%s: median %.3f ms" % (name, sorted(ts)[10] * 1e3))


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "record":
        record(sys.argv[2])
    elif len(sys.argv) == 2 and sys.argv[1] == "time":
        time_runs()
    else:
        sys.exit(__doc__)
