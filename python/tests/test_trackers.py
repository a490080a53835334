"""SORT, ByteTrack and OC-SORT through Python against roboflow `trackers` 2.6.1's recorded
output (the files crates/box-trackers/tests/reference.rs checks), and bad input."""

import numpy as np
import pytest

import tracking_toolkit as tt
from conftest import BOX_DATA, frames_of, read_mot

FILES = ["walkers-det", "realistic-301-det", "gaps-302-det", "realistic-10fps-303-det"]
TRACKERS = {
    "sort": tt.SortTracker,
    "bytetrack": tt.ByteTrackTracker,
    "ocsort": tt.OcSortTracker,
}


def reference(name, tracker):
    """(frame, row) -> the reference's id."""
    text = (BOX_DATA / "reference" / f"{name}.{tracker}.txt").read_text()
    out = {}
    for line in text.splitlines():
        frame, row, ident = (int(v) for v in line.split(","))
        out[(frame, row)] = ident
    return out


@pytest.mark.parametrize("tracker", sorted(TRACKERS))
@pytest.mark.parametrize("name", FILES)
def test_equal_to_the_reference(name, tracker):
    rows = read_mot(BOX_DATA / f"{name}.txt")
    model = TRACKERS[tracker]()
    got = {}
    for frame, index, dets in frames_of(rows):
        out = model.update(dets)
        assert out.shape[1] == 8
        for x1, y1, x2, y2, ident, score, cls, det in out:
            det = int(det)
            # The detection's own box, score and class, exactly.
            assert (x1, y1, x2, y2, score, cls) == tuple(dets[det])
            got[(frame, int(index[det]))] = int(ident)
    want = reference(name, tracker)
    assert set(got) == set(want)
    # Ids equal up to renaming: a bijection.
    pairs = {(got[k], want[k]) for k in want}
    assert len(pairs) == len({a for a, _ in pairs}) == len({b for _, b in pairs})


def test_a_track_is_confirmed_after_its_hits():
    # SORT with the reference's defaults confirms at the third consecutive match; a box
    # moving 1 px a frame is matched every frame (IoU about 0.9 > 0.3).
    sort = tt.SortTracker()
    outs = [sort.update(np.array([[10.0 + t, 20, 50 + t, 100, 0.9, 3]])) for t in range(4)]
    assert [len(o) for o in outs] == [0, 0, 1, 1]
    np.testing.assert_array_equal(outs[2], [[12, 20, 52, 100, 1, 0.9, 3, 0]])
    assert sort.frame_count == 4
    sort.reset()
    assert sort.frame_count == 0 and len(sort.update(np.empty((0, 6)))) == 0


def test_bytetrack_second_stage_keeps_a_track_on_a_low_score_box():
    # Started by a box scoring >= 0.7 and confirmed at its second hit, the track then takes
    # a 0.3 box (below high_conf_det_threshold 0.6) in the second stage and keeps its id.
    bt = tt.ByteTrackTracker()
    boxes = [[100.0 + 2 * t, 50, 140 + 2 * t, 130] for t in range(5)]
    scores = [0.9, 0.9, 0.3, 0.9, 0.9]
    ids = []
    for b, s in zip(boxes, scores):
        out = bt.update(np.array([b + [s, 0]]))
        ids.append(out[:, 4].tolist())
    assert ids[0] == [] and ids[1] == [1.0] and ids[2] == [1.0] and ids[3] == [1.0]


def test_coasting_outputs_the_prediction_without_a_detection():
    sort = tt.SortTracker(coast_frames=2, minimum_consecutive_frames=1)
    sort.update(np.array([[0.0, 0, 10, 10, 0.9, 1]]))
    sort.update(np.array([[1.0, 0, 11, 10, 0.9, 1]]))
    out = sort.update(np.empty((0, 6)))
    assert out.shape == (1, 8)
    assert out[0, 4] == 1 and out[0, 7] == -1 and np.isnan(out[0, 5]) and out[0, 6] == -1


def test_any_numeric_dtype_and_layout_gives_the_same_tracks():
    rows = read_mot(BOX_DATA / "walkers-det.txt")
    frames = [d.astype(np.float32).astype(np.float64) for _, _, d in frames_of(rows)]
    runs = []
    for convert in (
        lambda d: d,
        lambda d: np.asfortranarray(d),
        lambda d: d.astype(np.float32),
        lambda d: d.tolist() if len(d) else np.empty((0, 6)),
    ):
        model = tt.ByteTrackTracker()
        runs.append([model.update(convert(d)) for d in frames])
    for run in runs[1:]:
        for a, b in zip(runs[0], run):
            np.testing.assert_array_equal(a, b)
    # A strided view (every other column of a wider array) is read through its strides.
    model, plain = tt.SortTracker(), tt.SortTracker()
    for _, _, d in frames_of(rows):
        wide = np.repeat(d, 2, axis=1)[:, ::2]
        assert not wide.flags.c_contiguous
        np.testing.assert_array_equal(model.update(wide), plain.update(d))


def test_bad_input_raises():
    sort = tt.SortTracker()
    with pytest.raises(ValueError, match=r"shape \(N, 6\)"):
        sort.update(np.zeros((2, 5)))
    with pytest.raises(ValueError, match="2-D"):
        sort.update(np.zeros(6))
    with pytest.raises(ValueError, match="2-D"):
        sort.update([0, 0, 10, 10, 0.9, 0])
    with pytest.raises(TypeError, match="numeric"):
        sort.update(np.array([["a"] * 6]))
    with pytest.raises(tt.TrackingError, match="not finite"):
        sort.update(np.array([[0, 0, np.nan, 10, 0.9, 0]]))
    with pytest.raises(tt.TrackingError, match="width"):
        sort.update(np.array([[10.0, 0, 5, 10, 0.9, 0]]))
    with pytest.raises(tt.TrackingError, match="minimum_iou_threshol"):
        tt.SortTracker(minimum_iou_threshol=0.3)
    with pytest.raises(tt.TrackingError, match="minimum_iou_threshold"):
        tt.SortTracker(minimum_iou_threshold=2.0)
    with pytest.raises(tt.TrackingError, match="lost_track_buffer"):
        tt.OcSortTracker(lost_track_buffer=10**9)
    assert issubclass(tt.TrackingError, ValueError)
