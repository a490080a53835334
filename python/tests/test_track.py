"""track() and track_file(): the detection-file trackers as `cargo xtask track` runs them,
scored against the metrics the Rust scenario mot-track-walkers pins."""

import json

import numpy as np
import pytest

import tracking_toolkit as tt
from conftest import FIXTURES, frames_of, read_mot

DETS, GT = FIXTURES / "mot" / "walkers-dets.txt", FIXTURES / "mot" / "walkers-gt.txt"
EXPECTED = json.loads((FIXTURES / "expected" / "mot-track-walkers.json").read_text())


@pytest.mark.parametrize("tracker", ["mcmcda", "mcmcda-online", "gnn", "phd"])
def test_the_scenario_metrics(tracker):
    # mot-track-walkers runs each tracker with the default configuration and seed 0.
    tracks = tt.track_file(DETS, tracker=tracker, seed=0)
    got = tt.evaluate(GT, tracks)
    for metric, key in (("mota", "MOTA"), ("idf1", "IDF1"), ("hota", "HOTA")):
        assert got[key] == pytest.approx(EXPECTED[f"{tracker}_{metric}"], rel=1e-9), metric
    assert len(np.unique(tracks[:, 1])) == EXPECTED[f"{tracker}_tracks"]


def test_arrays_equal_the_file_and_the_written_text(tmp_path):
    out = tmp_path / "tracks.txt"
    from_file = tt.track_file(DETS, tracker="gnn", out=out)
    rows = read_mot(DETS)
    from_arrays = tt.track([d for _, _, d in frames_of(rows)], tracker="gnn")
    np.testing.assert_array_equal(from_file, from_arrays)
    written = read_mot(out)
    np.testing.assert_allclose(written[:, :6], from_file, atol=5e-4)


def test_box_trackers_and_a_config():
    default = tt.track_file(DETS, tracker="bytetrack")
    # A config is the TOML tables as a dict: a stricter activation threshold starts fewer
    # tracks.
    strict = tt.track_file(DETS, tracker="bytetrack", config={"bytetrack": {"track_activation_threshold": 0.95}})
    assert len(strict) < len(default)
    assert set(tt.tracker_names()) >= {"mcmcda", "gnn", "phd", "sort", "bytetrack", "ocsort"}


def test_bad_input_raises(tmp_path):
    with pytest.raises(tt.TrackingError, match="kalman"):
        tt.track_file(DETS, tracker="kalman")
    with pytest.raises(tt.TrackingError, match="no_such_key.*expected one of `assignment`"):
        tt.track_file(DETS, tracker="gnn", config={"gnn": {"no_such_key": 1}})
    with pytest.raises(tt.TrackingError, match="cannot read"):
        tt.track_file(tmp_path / "missing.txt")
    with pytest.raises(tt.TrackingError, match="no detections|holds no|empty|detections"):
        tt.track([np.empty((0, 6))], tracker="gnn")
    with pytest.raises(ValueError, match="shape"):
        tt.track([np.zeros((2, 4))])
