"""Type stubs of the Rust extension module (the public API is re-exported by the package)."""

from os import PathLike
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
import numpy.typing as npt

class TrackingError(ValueError):
    """Bad input or settings for a tracker, a metric or a model; the Rust error's message."""

class BoxTracker:
    """SORT ("sort"), ByteTrack ("bytetrack") or OC-SORT ("ocsort") with `params`."""

    def __init__(self, kind: str, params: Mapping[str, Any] | None = None) -> None: ...
    def update(self, dets: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """(N, 6) x1, y1, x2, y2, score, class -> (M, 8) x1, y1, x2, y2, id, score, class,
        detection index."""
    @property
    def frame_count(self) -> int: ...

class PhdTracker:
    """SMC-PHD ("smc", seeded) or GM-PHD ("gm", with `gm`, the mixture's settings) on boxes."""

    def __init__(
        self,
        kind: str,
        params: Mapping[str, Any] | None = None,
        gm: Mapping[str, Any] | None = None,
        seed: int = 0,
    ) -> None: ...
    def update(self, dets: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """(N, 6) x1, y1, x2, y2, score, class -> (M, 8) x1, y1, x2, y2, label, weight,
        class, detection index (-1 for GM-PHD)."""
    @property
    def frame_count(self) -> int: ...

class McmcdaOnline:
    """Online MCMCDA with `model` (McmcdaConfig's fields) and `params` (OnlineConfig's)."""

    def __init__(
        self,
        model: Mapping[str, Any] | None = None,
        params: Mapping[str, Any] | None = None,
        seed: int = 0,
    ) -> None: ...
    def update(self, points: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """(N, 2) x, y -> (M, 3) x, y, label."""
    @property
    def frame_count(self) -> int: ...

def tracker_names() -> list[str]:
    """The detection-file trackers: mcmcda, mcmcda-online, gnn, gnn-online, phd, sort,
    bytetrack, ocsort."""

def track(
    dets_by_frame: Iterable[npt.ArrayLike],
    tracker: str = "mcmcda",
    config: Mapping[str, Any] | str | PathLike[str] | None = None,
    seed: int = 0,
) -> npt.NDArray[np.float64]:
    """Tracks frames of detections (frame i + 1 is ``dets_by_frame[i]``, each (N, 6):
    x1, y1, x2, y2, score, class) with a detection-file tracker, as ``cargo xtask track``
    does (its model fitted to the detections; ``config`` holds the TOML tables, as a dict or
    a path). Returns MOTChallenge rows (K, 6): frame, id, left, top, width, height, by
    frame, which ``evaluate`` reads as they are."""

def track_file(
    path: str | PathLike[str],
    tracker: str = "mcmcda",
    config: Mapping[str, Any] | str | PathLike[str] | None = None,
    seed: int = 0,
    out: str | PathLike[str] | None = None,
) -> npt.NDArray[np.float64]:
    """``cargo xtask track --input path --tracker tracker [--config] [--seed] --out out``:
    tracks a MOTChallenge detection file, writes the tracks to ``out`` when given (the same
    text) and returns them as ``track`` does."""

def evaluate(
    gt: npt.ArrayLike | str | PathLike[str],
    pred: npt.ArrayLike | str | PathLike[str],
    iou: float = 0.5,
    distance: float | None = None,
    ospa_cutoff: float | None = None,
) -> dict[str, Any]:
    """Scores tracker output against ground truth, each a MOTChallenge file or an array
    (K, 6..10): frame, id, left, top, width, height[, conf, x, y, z] (ground-truth rows of
    conf 0 are ignored, as TrackEval does).

    Boxes match at IoU >= ``iou``, or box centres within ``distance``. Returns CLEAR MOT and
    identity metrics under py-motmetrics' names (num_frames, num_objects, num_predictions,
    num_unique_objects, num_detections, num_matches, num_switches, num_false_positives,
    num_misses, mota, motp (1 - IoU, with IoU matching only), precision, recall, idtp,
    idfp, idfn, idp, idr, idf1), the same and HOTA under TrackEval's (HOTA, DetA, AssA, LocA,
    DetRe, DetPr, AssRe, AssPr, MOTA, MOTP, MODA, CLR_Re, CLR_Pr, CLR_TP, CLR_FN, CLR_FP,
    IDSW, MT, PT, ML, Frag, IDF1, IDR, IDP, IDTP, IDFN, IDFP), SR and FAF (Yoon et al.
    2016), with ``ospa_cutoff`` (or ``distance``) the mean OSPA and GOSPA (p = 2) over the
    frames on box centres, and ``notes`` (a skipped header, an empty output).

    The CLEAR counts (and so MOTA) come from TrackEval's frame-by-frame matching, which
    favours the previous frame's pairs; py-motmetrics keeps an object's last match from any
    earlier frame, so its switch count can differ by a few when a false box competes after a
    miss (equal on the bundled sequences; docs/benchmarks.md). ``motp`` is NaN without a
    match, as py-motmetrics gives it."""

class Hmm:
    """A checked categorical HMM (pi, A, B)."""

    @staticmethod
    def dense(
        startprob: npt.ArrayLike,
        transmat: npt.ArrayLike,
        emissionprob: npt.ArrayLike,
        storage: str = "auto",
    ) -> Hmm: ...
    @staticmethod
    def sparse(
        startprob: npt.ArrayLike,
        indptr: npt.ArrayLike,
        col: npt.ArrayLike,
        data: npt.ArrayLike,
        emissionprob: npt.ArrayLike,
    ) -> Hmm: ...
    @property
    def startprob(self) -> npt.NDArray[np.float64]: ...
    @property
    def emissionprob(self) -> npt.NDArray[np.float64]: ...
    @property
    def is_sparse(self) -> bool: ...
    def transmat_dense(self) -> npt.NDArray[np.float64]: ...
    def transmat_csr(self) -> tuple[list[int], list[int], list[float]]: ...
    def score(self, x: npt.ArrayLike, lengths: Sequence[int] | None = None) -> float: ...
    def decode(
        self, x: npt.ArrayLike, lengths: Sequence[int] | None = None
    ) -> tuple[float, npt.NDArray[np.int64]]: ...
    def posteriors(
        self, x: npt.ArrayLike, lengths: Sequence[int] | None = None
    ) -> npt.NDArray[np.float64]: ...
    def fit(
        self,
        x: npt.ArrayLike,
        lengths: Sequence[int] | None,
        n_iter: int,
        tol: float,
        params: str,
        priors: tuple[float, float, float],
    ) -> tuple[Hmm, list[float], bool]: ...

class BackgroundSubtractor:
    """Mixture-of-Gaussians background subtraction with `params` (MogConfig's fields)."""

    def __init__(self, params: Mapping[str, Any] | None = None) -> None: ...
    def apply(self, frame: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]: ...
    @property
    def frame_count(self) -> int: ...

def beamform(
    signals: npt.ArrayLike, mics: npt.ArrayLike, params: Mapping[str, Any] | None = None
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(frame centre times (F,), beam energies (F, B))."""

def doa(
    signals: npt.ArrayLike,
    mics: npt.ArrayLike,
    max_peaks: int = 1,
    min_relative: float = 0.1,
    params: Mapping[str, Any] | None = None,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(bearings in radians (P,), their summed energies (P,))."""

def kalman(
    f: npt.ArrayLike,
    q: npt.ArrayLike,
    h: npt.ArrayLike,
    r: npt.ArrayLike,
    x: npt.ArrayLike,
    p: npt.ArrayLike,
    zs: npt.ArrayLike,
    rts: bool = False,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], float]:
    """Filtered (or with `rts` smoothed) means (T, N), covariances (T, N * N), log-likelihood;
    (x, P) is the prior at the first step; a NaN row of zs is missing."""

def rts_smooth(
    f: npt.ArrayLike, q: npt.ArrayLike, means: npt.ArrayLike, covs: npt.ArrayLike
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], float]:
    """RTS over filtered means (T, N) and covariances (T, N * N)."""

def recover_gap(
    a: npt.ArrayLike,
    b: npt.ArrayLike,
    method: str = "gdt",
    params: Mapping[str, Any] | None = None,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(recovered (G, 3) frame, x, y; covariances (G, 4), empty for a baseline)."""

def track_plot_rows(
    plots: npt.ArrayLike | str | PathLike[str],
    filter: str = "imm",
    params: Mapping[str, Any] | None = None,
) -> npt.NDArray[np.float64]:
    """(R, 7): time_s, id, x, y, vx, vy, hit."""
