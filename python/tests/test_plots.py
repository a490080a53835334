"""track_plots: the README's two-aircraft example (a radar's range-bearing plots with false
alarms) and position plots from an array."""

import numpy as np
import pytest

import tracking_toolkit as tt
from conftest import FIXTURES

PLOTS, TRUTH = FIXTURES / "plots" / "two-aircraft-plots.csv", FIXTURES / "plots" / "two-aircraft-truth.csv"


@pytest.mark.parametrize("filter", ["ekf", "ukf", "imm"])
def test_both_aircraft_are_followed(filter):
    tracks = tt.track_plots(PLOTS, filter=filter)
    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)
    assert tracks.shape[1] == 7
    # Each true position (after the first minute) has an estimate within 500 m at its time.
    later = truth[truth[:, 0] >= 60]
    near = 0
    for t, _, x, y in later:
        at = tracks[tracks[:, 0] == t]
        near += len(at) and np.hypot(at[:, 2] - x, at[:, 3] - y).min() < 500
    assert near / len(later) > 0.95, (filter, near / len(later))


def test_position_plots_from_an_array():
    t = np.arange(0, 100, 5.0)
    plots = np.column_stack([t, np.ones_like(t), 0 * t, 0 * t, 1000 + 50 * t, -200 + 20 * t])
    # The default clutter density is per metre-radian, for range-bearing plots; x, y plots
    # need one per square metre (with the default, every plot is likelier clutter than a
    # newborn's next position, and no track is confirmed).
    tracks = tt.track_plots(
        plots, filter="kf", sigma_position_m=10.0, clutter_log_density=float(np.log(1e-10))
    )
    ids = np.unique(tracks[:, 1])
    assert len(ids) == 1
    last = tracks[-1]
    np.testing.assert_allclose(last[4:6], [50, 20], atol=1.0)


def test_bad_plots_raise(tmp_path):
    with pytest.raises(tt.TrackingError, match="kf, ekf, ukf, imm"):
        tt.track_plots(PLOTS, filter="particle")
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,sensor\n0,1\n")
    with pytest.raises(tt.TrackingError, match="bad.csv"):
        tt.track_plots(bad)
    with pytest.raises(tt.TrackingError, match="gate_chi"):
        tt.track_plots(PLOTS, gate_chi=3)
    with pytest.raises(tt.TrackingError, match="not finite"):
        tt.track_plots(np.array([[0, 1, 0, 0, np.nan, 0.0]]))
