"""Background subtraction and direction finding on inputs whose answer is known."""

import numpy as np
import pytest

import tracking_toolkit as tt

# ---------------------------------------------------------------------------------------
# Background subtraction


def test_a_bright_block_on_a_learnt_background_is_exactly_the_foreground():
    mog = tt.BackgroundSubtractorMOG()
    background = np.full((24, 32), 100, dtype=np.uint8)
    for _ in range(30):
        assert mog.apply(background).max() == 0
    frame = background.copy()
    frame[5:10, 7:15] = 250
    mask = mog.apply(frame)
    want = np.zeros_like(mask)
    want[5:10, 7:15] = 255
    np.testing.assert_array_equal(mask, want)
    assert mask.dtype == np.uint8 and mog.frame_count == 31


def test_colour_channel_order_does_not_matter():
    rng = np.random.default_rng(4)
    frames = [rng.integers(90, 110, (16, 20, 3), dtype=np.uint8) for _ in range(25)]
    frames[-1][4:9, 4:12] = (250, 40, 10)
    rgb, bgr = tt.BackgroundSubtractorMOG(), tt.BackgroundSubtractorMOG()
    for f in frames:
        a, b = rgb.apply(f), bgr.apply(np.ascontiguousarray(f[:, :, ::-1]))
        np.testing.assert_array_equal(a, b)
    assert (a[4:9, 4:12] == 255).all()


def test_bad_frames_raise():
    mog = tt.BackgroundSubtractorMOG()
    with pytest.raises(TypeError, match="uint8"):
        mog.apply(np.zeros((4, 4)))
    with pytest.raises(ValueError, match="shape"):
        mog.apply(np.zeros((4, 4, 4), dtype=np.uint8))
    mog.apply(np.zeros((4, 4), dtype=np.uint8))
    with pytest.raises(tt.TrackingError):
        mog.apply(np.zeros((5, 4), dtype=np.uint8))
    with pytest.raises(tt.TrackingError, match="history"):
        tt.BackgroundSubtractorMOG(history=0)


# ---------------------------------------------------------------------------------------
# Direction of arrival

FS, C = 16_000, 343.0
MICS = np.array([[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]])


def plane_wave(bearing_deg, seed, n=16_000):
    """White noise in 300-3500 Hz from a far source at `bearing_deg`: microphone m hears it
    tau_m = (r_m . u) / c early, an exact phase shift of the periodic signal."""
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n, 1 / FS)
    spectrum = (rng.normal(size=f.size) + 1j * rng.normal(size=f.size)) * ((f > 300) & (f < 3500))
    u = np.array([np.cos(np.radians(bearing_deg)), np.sin(np.radians(bearing_deg))])
    tau = MICS @ u / C
    return np.array([np.fft.irfft(spectrum * np.exp(2j * np.pi * f * t), n) for t in tau])


def angle_error(a_rad, b_deg):
    d = (np.degrees(a_rad) - b_deg + 180) % 360 - 180
    return abs(d)


@pytest.mark.parametrize(
    "params",
    [{}, {"weighting": "phat"}, {"method": "mvdr"}, {"method": "time_domain"}],
)
def test_one_source_is_found_where_it_is(params):
    bearings, energies = tt.doa(plane_wave(40, seed=1), MICS, **params)
    assert bearings.shape == energies.shape == (1,)
    assert angle_error(bearings[0], 40) < 3.0


def test_two_sources_give_two_peaks():
    signals = plane_wave(30, seed=2) + plane_wave(210, seed=3)
    bearings, _ = tt.doa(signals, MICS, max_peaks=2, n_beams=72)
    assert len(bearings) == 2
    assert min(angle_error(b, 30) for b in bearings) < 5
    assert min(angle_error(b, 210) for b in bearings) < 5


def test_beamform_gives_every_frame():
    times, energies = tt.beamform(plane_wave(100, seed=5), MICS, n_beams=24)
    # 16 000 samples in frames of 512 without overlap: 31 full frames, centres 16 ms apart.
    assert energies.shape == (31, 24) and times.shape == (31,)
    np.testing.assert_allclose(np.diff(times), 512 / FS)
    assert angle_error(2 * np.pi * energies.sum(0).argmax() / 24, 100) <= 7.5


def test_bad_input_raises():
    x = plane_wave(0, seed=6)
    with pytest.raises(ValueError, match="microphones"):
        tt.doa(x, MICS[:3])
    with pytest.raises(tt.TrackingError, match="method|variant"):
        tt.doa(x, MICS, method="music")
    with pytest.raises(ValueError, match="min_relative"):
        tt.doa(x, MICS, min_relative=2.0)
    with pytest.raises(tt.TrackingError):
        tt.doa(x, MICS, n_beams=0)
