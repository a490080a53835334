"""Shared paths: the tests read the files the Rust tests read, from the repository."""

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
BOX_DATA = ROOT / "crates" / "box-trackers" / "testdata"
EVAL_DATA = ROOT / "crates" / "eval-metrics" / "testdata"
FIXTURES = ROOT / "fixtures"


def read_mot(path) -> np.ndarray:
    """A MOTChallenge text file as a float array (one row per line)."""
    return np.loadtxt(path, delimiter=",", ndmin=2)


def frames_of(rows: np.ndarray):
    """(frame, row numbers, (N, 6) x1, y1, x2, y2, score, class) for frames 1..last, empty
    frames included, rows in file order."""
    last = int(rows[:, 0].max())
    for frame in range(1, last + 1):
        index = np.flatnonzero(rows[:, 0] == frame)
        r = rows[index]
        dets = np.column_stack(
            [r[:, 2], r[:, 3], r[:, 2] + r[:, 4], r[:, 3] + r[:, 5], r[:, 6], np.zeros(len(r))]
        )
        yield frame, index, dets.reshape(-1, 6)
