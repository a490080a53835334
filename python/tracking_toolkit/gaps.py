"""Recovering the missing frames between two segments of one track."""

from __future__ import annotations

import numpy as np

from . import _native

__all__ = ["recover_gap", "METHODS"]

METHODS = (
    "gdt",
    "linear",
    "natural_cubic_spline",
    "least_squares_b_spline",
    "smoothing_spline",
    "window_cubic",
    "window_b_spline",
)


def recover_gap(a, b, method: str = "gdt", **params):
    """The positions at the frames between segment ``a`` and segment ``b`` (each (N, 3):
    frame, x, y; ``a`` ends before ``b`` starts).

    ``method``: ``"gdt"``, goal-directed tracking (Oh & Jung 2015; settings ``accel_psd=0.05``,
    ``measurement_variance=4``, ``initial_velocity_variance=25``), or a baseline:
    ``"linear"``, ``"natural_cubic_spline"``, ``"least_squares_b_spline"``
    (``interior_knots_per_side``), ``"smoothing_spline"`` (lambda by GCV: ``log10_min``,
    ``log10_max``, ``grid_points``, ``refine_iterations``), ``"window_cubic"`` and
    ``"window_b_spline"`` (``candidates``: window sizes chosen by cross-validation).
    Returns (recovered (G, 3): frame, x, y; covariances (G, 2, 2) for GDT, None for a
    baseline).
    """
    points, covs = _native.recover_gap(a, b, method, params)
    covs = np.asarray(covs)
    return np.asarray(points), (covs.reshape(-1, 2, 2) if method == "gdt" else None)
