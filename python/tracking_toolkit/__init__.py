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

Every error from the Rust side is a ``TrackingError`` (a ``ValueError``) with its message.
"""

from ._native import TrackingError, evaluate, track, track_file, tracker_names
from .hmm import CategoricalHMM
from .trackers import ByteTrackTracker, OcSortTracker, SortTracker

__all__ = [
    "ByteTrackTracker",
    "CategoricalHMM",
    "OcSortTracker",
    "SortTracker",
    "TrackingError",
    "evaluate",
    "track",
    "track_file",
    "tracker_names",
]
