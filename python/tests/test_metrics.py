"""evaluate() against py-motmetrics and TrackEval: their recorded numbers on the synthetic
sequence the Rust tests use, and py-motmetrics itself run here."""

import json

import motmetrics as mm
import numpy as np

if not hasattr(np, "asfarray"):
    # py-motmetrics 1.4.0 (its latest release) still calls np.asfarray, which NumPy 2
    # removed; this is that function, so the peer runs beside the NumPy users have.
    np.asfarray = lambda a, dtype=np.float64: np.asarray(a, dtype=dtype)
import pytest

import tracking_toolkit as tt
from conftest import EVAL_DATA, FIXTURES, read_mot

GT, PRED = EVAL_DATA / "synthetic-gt.txt", EVAL_DATA / "synthetic-pred.txt"


def test_equal_to_recorded_py_motmetrics():
    want = json.loads((EVAL_DATA / "synthetic-motmetrics.json").read_text())
    got = tt.evaluate(GT, PRED)
    for key, value in want.items():
        if key == "generator":
            continue
        assert got[key] == pytest.approx(value, rel=1e-12, abs=1e-12), key


def test_equal_to_recorded_trackeval():
    want = json.loads((EVAL_DATA / "synthetic-trackeval.json").read_text())
    want = want.get("synthetic", want)
    got = tt.evaluate(GT, PRED)
    compared = 0
    for key, value in want.items():
        if key in got and isinstance(value, (int, float)):
            assert got[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key
            compared += 1
    assert compared >= 20


def py_motmetrics(gt_rows, pred_rows, iou=0.5):
    """py-motmetrics on arrays, as its apps/eval_motchallenge.py scores MOT files."""
    acc = mm.MOTAccumulator(auto_id=False)
    frames = sorted(set(gt_rows[:, 0]) | set(pred_rows[:, 0]))
    for f in frames:
        g, p = gt_rows[gt_rows[:, 0] == f], pred_rows[pred_rows[:, 0] == f]
        dist = mm.distances.iou_matrix(g[:, 2:6], p[:, 2:6], max_iou=1 - iou)
        acc.update(g[:, 1].astype(int), p[:, 1].astype(int), dist, frameid=int(f))
    names = [
        "num_frames", "num_objects", "num_predictions", "num_unique_objects",
        "num_detections", "num_matches", "num_switches", "num_false_positives",
        "num_misses", "mota", "motp", "precision", "recall", "idtp", "idfp", "idfn",
        "idp", "idr", "idf1",
    ]
    summary = mm.metrics.create().compute(acc, metrics=names, name="seq")
    return {k: float(summary[k].iloc[0]) for k in names}


@pytest.mark.parametrize(
    "gt,pred",
    [
        (GT, PRED),
        (EVAL_DATA / "gaps-gt.txt", EVAL_DATA / "gaps-pred.txt"),
        (FIXTURES / "mot" / "tiny-gt.txt", FIXTURES / "mot" / "tiny-pred.txt"),
    ],
)
def test_equal_to_py_motmetrics_run_here(gt, pred):
    gt_rows, pred_rows = read_mot(gt), read_mot(pred)
    want = py_motmetrics(gt_rows, pred_rows)
    got = tt.evaluate(gt_rows, pred_rows)
    for key, value in want.items():
        assert got[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key


def test_arrays_and_files_agree():
    a, b = tt.evaluate(GT, PRED, iou=0.4), tt.evaluate(read_mot(GT), read_mot(PRED), iou=0.4)
    assert {k: v for k, v in a.items() if k != "notes"} == {
        k: v for k, v in b.items() if k != "notes"
    }


def test_distance_matching_and_ospa():
    gt = np.array([[1, 1, 0, 0, 10, 10], [2, 1, 1, 0, 10, 10]], dtype=float)
    pred = np.array([[1, 5, 3, 4, 10, 10], [2, 5, 30, 0, 10, 10]], dtype=float)
    got = tt.evaluate(gt, pred, distance=6.0)
    # Frame 1: centres 5 apart, matched; frame 2: 29 apart, a miss and a false track.
    assert (got["num_matches"], got["num_misses"], got["num_false_positives"]) == (1, 1, 1)
    # OSPA with c = 6, p = 2: frame 1 is the distance 5, frame 2 the cut-off 6.
    assert got["OSPA"] == pytest.approx((5 + 6) / 2)
    # GOSPA (alpha = 2): frame 1 is 5, frame 2 a miss and a false track, (2 c^2 / 2)^(1/2)
    # each, sqrt(c^2 / 2 + c^2 / 2) = c.
    assert got["GOSPA"] == pytest.approx((5 + 6) / 2)
    assert "motp" not in got and "MOTP" in got


def test_bad_input_raises():
    gt = read_mot(GT)
    with pytest.raises(tt.TrackingError, match="no ground truth"):
        tt.evaluate(gt[:0], gt)
    with pytest.raises(ValueError, match="shape"):
        tt.evaluate(gt[:, :5], gt)
    with pytest.raises(tt.TrackingError, match="not an integer"):
        bad = gt.copy()
        bad[0, 0] = 1.5
        tt.evaluate(bad, gt)
    with pytest.raises(tt.TrackingError):
        bad = gt.copy()
        bad[0, 4] = np.nan
        tt.evaluate(bad, gt)
    with pytest.raises(tt.TrackingError, match="threshold"):
        tt.evaluate(gt, gt, iou=1.5)
    with pytest.raises(tt.TrackingError, match="cannot read"):
        tt.evaluate("/nonexistent/gt.txt", gt)
