"""Multi-target tracking, data association and evaluation, in Rust.

Trackers
    ``SortTracker``, ``ByteTrackTracker``, ``OcSortTracker``: ``update(dets)`` once per frame,
    ``dets`` of shape (N, 6) ``x1, y1, x2, y2, score, class``, giving (M, 8)
    ``x1, y1, x2, y2, id, score, class, detection index`` (boxmot's and trackforge's shape).
    ``track(dets_by_frame, tracker=...)`` and ``track_file(path, tracker=...)`` run every
    detection-file tracker (offline and online MCMCDA, GNN, SMC-PHD, SORT, ByteTrack, OC-SORT)
    as ``cargo xtask track`` does.
Metrics
    ``evaluate(gt, pred, iou=0.5)``: CLEAR MOT and identity metrics under py-motmetrics'
    names, HOTA and its parts under TrackEval's, SR/FAF, and OSPA/GOSPA on request.
HMM
    ``CategoricalHMM``: hmmlearn's shape, with sparse (scipy.sparse) transition matrices.
Filters
    ``KalmanFilter``: filterpy's shape, ``batch_filter`` and ``rts_smoother``.
Gap recovery
    ``recover_gap(a, b, method="gdt")``: goal-directed tracking and the spline baselines.
Sensors
    ``BackgroundSubtractorMOG``: ``apply(frame) -> mask`` as OpenCV's; ``beamform`` and
    ``doa``: delay-and-sum, SRP-PHAT and MVDR on (M, T) signals from an (M, 2) array.

Every error from the Rust side is a ``TrackingError`` (a ``ValueError``) with its message.
"""

from ._native import TrackingError, evaluate, track, track_file, tracker_names
from .filters import KalmanFilter
from .gaps import recover_gap
from .hmm import CategoricalHMM
from .sensors import BackgroundSubtractorMOG, beamform, doa
from .trackers import (
    ByteTrackTracker,
    GmPhdTracker,
    OcSortTracker,
    OnlineMcmcdaTracker,
    SmcPhdTracker,
    SortTracker,
    track_plots,
)

__all__ = [
    "BackgroundSubtractorMOG",
    "ByteTrackTracker",
    "CategoricalHMM",
    "GmPhdTracker",
    "KalmanFilter",
    "OcSortTracker",
    "OnlineMcmcdaTracker",
    "SmcPhdTracker",
    "SortTracker",
    "TrackingError",
    "beamform",
    "doa",
    "evaluate",
    "recover_gap",
    "track",
    "track_file",
    "track_plots",
    "tracker_names",
]
