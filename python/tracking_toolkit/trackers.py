"""SORT, ByteTrack and OC-SORT, stepped once per frame."""

from __future__ import annotations

import numpy as np

from . import _native


class _BoxTracker:
    _kind = ""

    def __init__(self, **params):
        self._params = dict(params)
        self._native = _native.BoxTracker(self._kind, self._params)

    def update(self, dets) -> np.ndarray:
        """Steps one frame (call it for every frame, also with no detection: shape (0, 6)).

        ``dets``: (N, 6) ``x1, y1, x2, y2, score, class``, any numeric dtype.
        Returns (M, 8) float64 ``x1, y1, x2, y2, id, score, class, detection index``: each
        confirmed track given a detection this frame, at that detection's box, then (with
        ``coast_frames`` > 0) the confirmed tracks coasting on their prediction, with
        detection index -1, score NaN and class -1. Ids start at 1.
        """
        return self._native.update(dets)

    def reset(self) -> None:
        """Forgets every track: the next ``update`` is a first frame again."""
        self._native = _native.BoxTracker(self._kind, self._params)

    @property
    def frame_count(self) -> int:
        """Frames stepped since the tracker was made or reset."""
        return self._native.frame_count

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self._params.items())
        return f"{type(self).__name__}({args})"


class SortTracker(_BoxTracker):
    """SORT (Bewley et al. 2016) as roboflow ``trackers`` 2.6.1 runs it.

    Settings (keyword arguments, defaults the reference's): ``lost_track_buffer=30``,
    ``frame_rate=30.0``, ``track_activation_threshold=0.25``,
    ``minimum_consecutive_frames=3``, ``minimum_iou_threshold=0.3``, ``coast_frames=0``,
    ``state="corners"`` (the paper's ``"centre-area-aspect"``).
    """

    _kind = "sort"


class ByteTrackTracker(_BoxTracker):
    """ByteTrack (Zhang et al. 2022) as roboflow ``trackers`` 2.6.1 runs it.

    Settings: ``lost_track_buffer=30``, ``frame_rate=30.0``,
    ``track_activation_threshold=0.7``, ``minimum_consecutive_frames=2``,
    ``minimum_iou_threshold=0.1``, ``high_conf_det_threshold=0.6``,
    ``low_conf_det_threshold=0.0`` (the paper's 0.1), ``second_iou_threshold=None`` (the
    paper's 0.5), ``coast_frames=0``, ``state="corners"``.
    """

    _kind = "bytetrack"


class OcSortTracker(_BoxTracker):
    """OC-SORT (Cao et al. 2023) as roboflow ``trackers`` 2.6.1 runs it.

    Settings: ``lost_track_buffer=30``, ``frame_rate=30.0``,
    ``minimum_consecutive_frames=3``, ``minimum_iou_threshold=0.3``,
    ``direction_consistency_weight=0.2``, ``high_conf_det_threshold=0.6``, ``delta_t=3``,
    ``coast_frames=0``, ``state="centre-area-aspect"``.
    """

    _kind = "ocsort"


class SmcPhdTracker:
    """The SMC-PHD filter on boxes (Yoon, Hwang, Choi & Yoon 2016, global detections only),
    each estimate with its persistent label.

    ``seed`` seeds every random draw (the same seed gives the same output). Settings are
    ``phd_filter::PhdConfig``'s fields, defaults the paper's where it gives them, sized for
    pedestrians of 50-150 px in a 640 x 480 image: ``p_survive=0.99``, ``p_detect=0.95``,
    ``clutter_rate=1.0``, ``measurement_volume`` (640 * 480 * 100 * 200),
    ``birth_rate=0.1``, ``measurement_std=[4, 4, 3, 6]`` (centre x, y, width, height),
    ``motion={"random_walk": {"position_std": 4, "size_std": 1}}`` or
    ``{"constant_velocity": {"acceleration_std": ..., "size_std": ...}}``,
    ``birth_velocity_std=2``, ``particles_per_target=1000``, ``birth_particles=200``,
    ``max_particles=100000``, ``extraction_threshold=0.5``, ``label_min_share=0.05``.
    ``update`` gives (M, 8): x1, y1, x2, y2, label, weight W(z), class and index of the
    detection the estimate was extracted from.
    """

    _kind = "smc"

    def __init__(self, seed: int = 0, **params):
        self._args = dict(seed=seed, params=dict(params))
        self.reset()

    def reset(self) -> None:
        """Starts the filter afresh (with the same seed)."""
        self._native = _native.PhdTracker(self._kind, **self._args)

    def update(self, dets) -> np.ndarray:
        """One frame's detections (N, 6) -> the frame's estimates (M, 8)."""
        return self._native.update(dets)

    @property
    def frame_count(self) -> int:
        """Frames stepped since the tracker was made or reset."""
        return self._native.frame_count


class GmPhdTracker(SmcPhdTracker):
    """The GM-PHD filter (Vo & Ma 2006) on boxes, with the same settings as
    ``SmcPhdTracker`` (``seed`` aside) and the mixture's ``prune_below=1e-5``,
    ``merge_distance=4.0`` and ``max_components=100``. Its estimates are mixture components:
    detection index -1 and class -1."""

    _kind = "gm"
    _GM_KEYS = ("prune_below", "merge_distance", "max_components")

    def __init__(self, **params):
        gm = {k: params.pop(k) for k in self._GM_KEYS if k in params}
        self._args = dict(params=params, gm=gm)
        self.reset()


def track_plots(plots, filter: str = "imm", **params) -> np.ndarray:
    """Radar or point plots tracked by GNN with ``filter`` ("kf", "ekf", "ukf" or "imm"), as
    ``cargo xtask track --plots`` does.

    ``plots``: a plot file's path (CSV, ``time_s,sensor,sensor_x,sensor_y`` and ``x,y`` or
    ``range,bearing``, optionally their sigmas and the dwell's sector; docs/aircraft.md), or
    position plots as an array (K, 6): time_s, sensor, sensor_x, sensor_y, x, y. Settings are
    ``air_traffic::PlotTrackConfig``'s fields (``q_accel``, ``sigma_range_m``,
    ``sigma_bearing_rad``, ``gate_chi2``, ``confirm_hits``, ...). Returns (R, 7): time_s, id,
    x, y, vx, vy, hit (1 where a plot updated the track, 0 where it coasted).

    The default ``clutter_log_density`` is ln of false alarms per metre-radian, for
    range-bearing plots; for x, y plots give it per square metre (e.g. ``np.log(1e-10)``),
    else the default makes every plot likelier clutter than a track's next position.
    """
    return _native.track_plot_rows(plots, filter, params)


class OnlineMcmcdaTracker:
    """Online (sliding-window) MCMCDA (Oh, Russell & Sastry 2009) on point detections.

    ``model``: ``mcmcda::McmcdaConfig``'s fields as a dict (``volume``, ``births_per_scan``,
    ``clutter_per_scan``, ``p_detect``, ``measurement_noise`` as rows, ``max_gap``,
    ``max_speed``, ...); other keyword arguments are ``mcmcda::OnlineConfig``'s
    (``window=14``, ``samples_per_scan=2000``, ``coast_scans=2``, ``chains=1``, ...).
    ``seed`` seeds the chains. ``update(points)`` takes a scan's (N, 2) points and returns
    (M, 3): x, y, label of the tracks the window's MAP reports at that scan.
    """

    def __init__(self, seed: int = 0, model: dict | None = None, **params):
        self._args = dict(model=dict(model or {}), params=dict(params), seed=seed)
        self.reset()

    def reset(self) -> None:
        """Starts afresh (with the same seed)."""
        self._native = _native.McmcdaOnline(**self._args)

    def update(self, points) -> np.ndarray:
        """One scan's points (N, 2) -> the reported tracks (M, 3): x, y, label."""
        return self._native.update(points)

    @property
    def frame_count(self) -> int:
        """Scans stepped since the tracker was made or reset."""
        return self._native.frame_count
