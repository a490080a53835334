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
