"""The PHD filters stepped from Python on a scene whose answer is known: two boxes moving at
constant velocity, detected every frame without clutter."""

import numpy as np
import pytest

import tracking_toolkit as tt


def scene(frames=30):
    """Per frame, (N, 6) detections of two 40 x 80 boxes moving +3 and -2 px a frame, with
    the true corners."""
    out = []
    for t in range(frames):
        a = [100.0 + 3 * t, 100.0, 140.0 + 3 * t, 180.0, 0.9, 0]
        b = [400.0 - 2 * t, 150.0, 440.0 - 2 * t, 230.0, 0.8, 1]
        out.append(np.array([a, b]))
    return out


SETTINGS = dict(
    clutter_rate=0.1,
    p_detect=0.99,
    measurement_std=[2.0, 2.0, 2.0, 2.0],
    motion={"constant_velocity": {"acceleration_std": 0.5, "size_std": 0.5}},
    birth_velocity_std=4.0,
)


@pytest.mark.parametrize("make", [lambda: tt.SmcPhdTracker(seed=3, **SETTINGS), lambda: tt.GmPhdTracker(**SETTINGS)])
def test_two_targets_are_found_and_keep_their_labels(make):
    tracker = make()
    labels = []
    for t, dets in enumerate(scene()):
        out = tracker.update(dets)
        if t < 10:
            continue
        assert out.shape == (2, 8), t
        # Each estimate within a few pixels of a true box, one estimate per box.
        order = np.argsort(out[:, 0])
        err = np.abs(out[order, :4] - dets[:, :4]).max()
        assert err < 6.0, (t, err)
        labels.append(tuple(out[order, 4]))
        if isinstance(tracker, tt.GmPhdTracker):
            assert (out[:, 7] == -1).all()
        else:
            # The detection each estimate came from, with its class.
            np.testing.assert_array_equal(out[order, 7], [0, 1])
            np.testing.assert_array_equal(out[order, 6], [0, 1])
    assert len(set(labels)) == 1 and len(set(labels[0])) == 2
    assert tracker.frame_count == 30


def test_the_same_seed_gives_the_same_bytes():
    runs = []
    for _ in range(2):
        tracker = tt.SmcPhdTracker(seed=11, **SETTINGS)
        runs.append(np.concatenate([tracker.update(d) for d in scene(15)]))
    assert runs[0].tobytes() == runs[1].tobytes()
    tracker.reset()
    assert tracker.frame_count == 0


def test_bad_settings_raise():
    with pytest.raises(tt.TrackingError, match="p_detect"):
        tt.SmcPhdTracker(p_detect=1.5)
    with pytest.raises(tt.TrackingError, match="particles_per_targe"):
        tt.SmcPhdTracker(particles_per_targe=10)
    with pytest.raises(tt.TrackingError, match="max_components"):
        tt.GmPhdTracker(max_components=0)
    with pytest.raises(ValueError, match="shape"):
        tt.GmPhdTracker().update(np.zeros((1, 4)))


# ---------------------------------------------------------------------------------------
# Online MCMCDA on points


def two_walkers(scans=30):
    """Two points moving 14 units a scan whose paths cross at (250, 250) at scan 15, seen
    every scan (their x coordinates are equal throughout)."""
    return [
        np.array([[100.0 + 10 * t, 100.0 + 10 * t], [100.0 + 10 * t, 400.0 - 10 * t]])
        for t in range(scans)
    ]


MODEL = dict(volume=1e6, clutter_per_scan=0.1, p_detect=0.99, measurement_noise=[[1.0, 0.0], [0.0, 1.0]])


def test_online_mcmcda_follows_two_targets_through_their_crossing():
    tracker = tt.OnlineMcmcdaTracker(seed=1, model=MODEL, samples_per_scan=500)
    labels = []
    for t, points in enumerate(two_walkers()):
        out = tracker.update(points)
        if t < 5:
            continue
        if t == 15:
            continue  # both targets at one point: one estimate or two
        assert out.shape == (2, 3), t
        for est in out:
            assert np.hypot(*(points - est[:2]).T).min() < 5.0
        # The label of the target moving up (y grows), wherever it is.
        rising = out[np.argmin(np.hypot(*(out[:, :2] - points[0]).T)), 2]
        labels.append(rising)
    assert len(set(labels)) == 1
    assert tracker.frame_count == 30


def test_online_mcmcda_is_reproducible_and_checks_its_settings():
    runs = []
    for _ in range(2):
        tracker = tt.OnlineMcmcdaTracker(seed=5, model=MODEL, samples_per_scan=200)
        runs.append(np.concatenate([tracker.update(p) for p in two_walkers(12)]))
    assert runs[0].tobytes() == runs[1].tobytes()
    with pytest.raises(tt.TrackingError, match="samples_per_scan"):
        tt.OnlineMcmcdaTracker(samples_per_scan=0)
    with pytest.raises(tt.TrackingError, match="p_detect"):
        tt.OnlineMcmcdaTracker(model=dict(p_detect=2.0))
    with pytest.raises(ValueError, match="shape"):
        tt.OnlineMcmcdaTracker().update(np.zeros((3, 6)))
    # A bad point is refused before anything is stored: the tracker goes on afterwards.
    tracker = tt.OnlineMcmcdaTracker(seed=5, model=MODEL, samples_per_scan=200)
    tracker.update(two_walkers(1)[0])
    with pytest.raises(tt.TrackingError, match="not finite"):
        tracker.update(np.array([[1.0, np.nan]]))
    assert tracker.update(two_walkers(2)[1]).shape[1] == 3 and tracker.frame_count == 2
