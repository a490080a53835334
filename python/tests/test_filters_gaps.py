"""KalmanFilter against the textbook filter and RTS smoother written out in numpy (filterpy's
own steps: predict, then a Joseph-form update), and gap recovery against scipy and closed
forms."""

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

import tracking_toolkit as tt


def cv_model(dt=1.0, q=0.1, r=4.0):
    F = np.array([[1, 0, dt, 0], [0, 1, 0, dt], [0, 0, 1, 0], [0, 0, 0, 1]], float)
    qa = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    Q = np.zeros((4, 4))
    Q[np.ix_([0, 2], [0, 2])] = qa
    Q[np.ix_([1, 3], [1, 3])] = qa
    H = np.eye(2, 4)
    return F, Q, H, r * np.eye(2)


def textbook(F, Q, H, R, x, P, zs):
    """filterpy's batch_filter and rts_smoother, step by step."""
    means, covs = [], []
    for z in zs:
        x, P = F @ x, F @ P @ F.T + Q
        if z is not None:
            S = H @ P @ H.T + R
            K = P @ H.T @ np.linalg.inv(S)
            x = x + K @ (np.reshape(z, (-1, 1)) - H @ x)
            A = np.eye(len(x)) - K @ H
            P = A @ P @ A.T + K @ R @ K.T
        means.append(x.ravel())
        covs.append(P)
    ms, ps = [m.copy() for m in means], [p.copy() for p in covs]
    for k in range(len(zs) - 2, -1, -1):
        Pp = F @ covs[k] @ F.T + Q
        C = covs[k] @ F.T @ np.linalg.inv(Pp)
        ms[k] = means[k] + C @ (ms[k + 1] - F @ means[k])
        ps[k] = covs[k] + C @ (ps[k + 1] - Pp) @ C.T
    return np.array(means), np.array(covs), np.array(ms), np.array(ps)


def test_kalman_filter_and_rts_equal_the_textbook():
    F, Q, H, R = cv_model()
    rng = np.random.default_rng(1)
    zs = [None if k % 10 == 3 else np.array([k + 2 * rng.normal(), k + 2 * rng.normal()]) for k in range(200)]
    kf = tt.KalmanFilter(dim_x=4, dim_z=2)
    kf.F, kf.Q, kf.H, kf.R = F, Q, H, R
    x0, p0 = np.array([[0.0], [0.0], [1.0], [1.0]]), 10.0 * np.eye(4)
    kf.x, kf.P = x0, p0
    mu, cov = kf.batch_filter(zs)
    # As filterpy, the filter is left at its last estimate.
    np.testing.assert_array_equal(kf.x.ravel(), mu[-1])
    want_mu, want_cov, want_smu, want_scov = textbook(F, Q, H, R, x0, p0, zs)
    np.testing.assert_allclose(mu, want_mu, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(cov, want_cov, rtol=1e-9, atol=1e-9)
    smu, scov = kf.rts_smoother(mu, cov)
    np.testing.assert_allclose(smu, want_smu, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(scov, want_scov, rtol=1e-9, atol=1e-9)
    kf.x, kf.P = x0, p0
    smu2, scov2 = kf.smooth(zs)
    np.testing.assert_allclose(smu2, want_smu, rtol=1e-9, atol=1e-9)
    assert np.isfinite(kf.log_likelihood_) and kf.log_likelihood_ < 0


def test_a_one_state_filter_equals_its_closed_form():
    # x constant, observed with variance r: the filter is the running weighted mean.
    kf = tt.KalmanFilter(dim_x=1, dim_z=1)
    kf.F, kf.Q, kf.H, kf.R = np.eye(1), np.zeros((1, 1)), np.eye(1), 4.0 * np.eye(1)
    kf.x, kf.P = np.zeros((1, 1)), 1e6 * np.eye(1)
    zs = [3.0, 5.0, 4.0, 8.0]
    mu, cov = kf.batch_filter([np.array([z]) for z in zs])
    for k in range(4):
        w = 1 / 1e6 + (k + 1) / 4.0
        assert mu[k, 0] == pytest.approx(sum(zs[: k + 1]) / 4.0 / w, rel=1e-9)
        assert cov[k, 0, 0] == pytest.approx(1 / w, rel=1e-9)


def test_bad_models_raise():
    kf = tt.KalmanFilter(dim_x=2, dim_z=1)
    kf.H = np.array([[1.0, 0.0]])
    kf.R = -np.eye(1)
    with pytest.raises(tt.TrackingError, match="measurement noise"):
        kf.batch_filter([np.array([1.0])])
    kf.R = np.eye(1)
    # A 3-state F, Q, x and P with a 2-state H: the Rust side names the mismatch.
    kf.F, kf.Q, kf.x, kf.P = np.eye(3), np.eye(3), np.zeros((3, 1)), np.eye(3)
    with pytest.raises(tt.TrackingError, match="H must be 1 x 3"):
        kf.batch_filter([np.array([1.0])])
    kf = tt.KalmanFilter(dim_x=2, dim_z=2)
    with pytest.raises(ValueError, match="dim_z"):
        kf.batch_filter([np.array([1.0, 2.0, 3.0])])
    with pytest.raises(ValueError, match=r"shape \(T, 2\)"):
        kf.batch_filter(np.zeros((5, 4)))
    with pytest.raises(ValueError):
        tt.KalmanFilter(dim_x=9, dim_z=2)


# ---------------------------------------------------------------------------------------
# Gap recovery


def segments(f):
    """Observations of x = f(t), y = 2 t at frames 0-19 and 31-50 (gap 20-30)."""
    ta, tb = np.arange(0, 20), np.arange(31, 51)
    seg = lambda t: np.column_stack([t, f(t), 2.0 * t]).astype(float)
    return seg(ta), seg(tb), np.arange(20, 31)


def test_linear_and_gdt_recover_a_straight_line():
    a, b, gap = segments(lambda t: 5.0 + 1.5 * t)
    line, covs = tt.recover_gap(a, b, method="linear")
    assert covs is None
    np.testing.assert_array_equal(line[:, 0], gap)
    np.testing.assert_allclose(line[:, 1:], np.column_stack([5 + 1.5 * gap, 2.0 * gap]), atol=1e-9)
    # Noise-free constant velocity: GDT's goal-directed smoother stays on the line.
    gdt, covs = tt.recover_gap(a, b, method="gdt", measurement_variance=0.01)
    np.testing.assert_allclose(gdt[:, 1:], line[:, 1:], atol=0.05)
    assert covs.shape == (len(gap), 2, 2) and (covs[:, 0, 0] > 0).all()
    # Its uncertainty is largest in the middle of the gap.
    assert covs[:, 0, 0].argmax() in (4, 5, 6)


def test_natural_cubic_spline_equals_scipy():
    a, b, gap = segments(lambda t: 0.02 * t**3 - 0.5 * t**2 + 3 * t)
    got, _ = tt.recover_gap(a, b, method="natural_cubic_spline")
    t = np.concatenate([a[:, 0], b[:, 0]])
    for axis in (1, 2):
        spline = CubicSpline(t, np.concatenate([a[:, axis], b[:, axis]]), bc_type="natural")
        np.testing.assert_allclose(got[:, axis], spline(gap), rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("method", ["least_squares_b_spline", "smoothing_spline", "window_cubic", "window_b_spline"])
def test_the_other_baselines_recover_a_cubic_closely(method):
    a, b, gap = segments(lambda t: 0.001 * t**3 - 0.05 * t**2 + t)
    got, _ = tt.recover_gap(a, b, method=method)
    truth = 0.001 * gap**3 - 0.05 * gap**2 + gap
    # Noise-free cubic data: every cubic fit should come close.
    assert np.abs(got[:, 1] - truth).max() < 1.0, method


def test_bad_gaps_raise():
    a, b, _ = segments(lambda t: t)
    with pytest.raises(tt.TrackingError, match="variant|unknown"):
        tt.recover_gap(a, b, method="akima")
    with pytest.raises(tt.TrackingError):
        tt.recover_gap(b, a)
    with pytest.raises(tt.TrackingError, match="settings"):
        tt.recover_gap(a, b, method="linear", knots=3)
    with pytest.raises(ValueError, match="frame"):
        bad = a.copy()
        bad[0, 0] = 0.5
        tt.recover_gap(bad, b)
