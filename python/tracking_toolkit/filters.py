"""Linear Kalman filtering and RTS smoothing in filterpy's shape, on tracker-model's filter."""

from __future__ import annotations

import numpy as np

from . import _native

__all__ = ["KalmanFilter"]


class KalmanFilter:
    """filterpy's ``KalmanFilter(dim_x, dim_z)``: set ``x``, ``P``, ``F``, ``Q``, ``H`` and
    ``R`` as there, then ``batch_filter(zs)`` and ``rts_smoother(Xs, Ps)``.

    As filterpy's ``batch_filter``, each step predicts and then updates, so ``x`` and ``P``
    are the state one step before the first measurement; a missing measurement is ``None``
    (or a row with a NaN or an infinity) and only predicts. The update is in Joseph form, as
    filterpy's. Up to 6 states and 4 measured values. Unlike filterpy's, ``batch_filter`` and
    ``rts_smoother`` return only (means, covariances), the means as (T, dim_x), not
    (T, dim_x, 1), and ``log_likelihood_`` holds the sum of the measurements'
    log-likelihoods of the last run.
    """

    def __init__(self, dim_x: int, dim_z: int):
        if not (1 <= dim_x <= 6 and 1 <= dim_z <= 4):
            raise ValueError(f"dim_x = {dim_x}, dim_z = {dim_z}: 1-6 states and 1-4 measured values")
        self.dim_x, self.dim_z = dim_x, dim_z
        self.x = np.zeros((dim_x, 1))
        self.P = np.eye(dim_x)
        self.F = np.eye(dim_x)
        self.Q = np.eye(dim_x)
        self.H = np.zeros((dim_z, dim_x))
        self.R = np.eye(dim_z)
        self.log_likelihood_ = 0.0

    def _measurements(self, zs) -> np.ndarray:
        if isinstance(zs, np.ndarray):
            z = np.asarray(zs, dtype=float)
        else:
            missing = np.full(self.dim_z, np.nan)
            rows = [missing if z is None else np.asarray(z, dtype=float) for z in zs]
            if any(r.size != self.dim_z for r in rows):
                raise ValueError(f"every measurement must hold dim_z = {self.dim_z} values")
            z = np.array([r.reshape(self.dim_z) for r in rows], dtype=float)
        # (T, dim_z), (T, dim_z, 1), or (T,) with one measured value.
        if z.ndim == 3 and z.shape[2] == 1:
            z = z[:, :, 0]
        if z.ndim == 1 and self.dim_z == 1:
            z = z[:, None]
        if z.ndim != 2 or z.shape[1] != self.dim_z:
            raise ValueError(f"zs must have shape (T, {self.dim_z}); it has shape {z.shape}")
        return z

    def _prior(self):
        # filterpy's batch_filter predicts before the first update: the prior is F x, F P F' + Q.
        x = np.asarray(self.x, dtype=float).reshape(-1, 1)
        F, P, Q = (np.asarray(a, dtype=float) for a in (self.F, self.P, self.Q))
        return F @ x, F @ P @ F.T + Q

    def _run(self, zs, rts: bool):
        x, P = self._prior()
        zs = self._measurements(zs)
        means, covs, ll = _native.kalman(self.F, self.Q, self.H, self.R, x, P, zs, rts)
        self.log_likelihood_ = ll
        return np.asarray(means), np.asarray(covs).reshape(-1, self.dim_x, self.dim_x)

    def batch_filter(self, zs):
        """Filtered means (T, dim_x) and covariances (T, dim_x, dim_x). As filterpy, ``x``
        and ``P`` are left at the last step's estimate."""
        means, covs = self._run(zs, rts=False)
        if len(means):
            self.x, self.P = means[-1].reshape(self.dim_x, 1), covs[-1]
        return means, covs

    def rts_smoother(self, Xs, Ps):
        """RTS-smoothed means and covariances of filtered ``Xs`` (T, dim_x[, 1]) and ``Ps``
        (T, dim_x, dim_x), with ``F`` and ``Q`` (filterpy's ``rts_smoother``)."""
        Xs = np.asarray(Xs, dtype=float).reshape(-1, self.dim_x)
        Ps = np.asarray(Ps, dtype=float).reshape(len(Xs), self.dim_x * self.dim_x)
        means, covs, _ = _native.rts_smooth(self.F, self.Q, Xs, Ps)
        return np.asarray(means), np.asarray(covs).reshape(-1, self.dim_x, self.dim_x)

    def smooth(self, zs):
        """``batch_filter`` then RTS in one call (the smoother on the filter's own
        predictions)."""
        return self._run(zs, rts=True)
