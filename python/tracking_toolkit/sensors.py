"""Sensors on numpy arrays: background subtraction and microphone-array direction finding."""

from __future__ import annotations

import numpy as np

from . import _native

__all__ = ["BackgroundSubtractorMOG", "beamform", "doa"]


class BackgroundSubtractorMOG:
    """Mixture-of-Gaussians background subtraction (Stauffer & Grimson 1999), in OpenCV's
    ``apply(frame) -> mask`` shape, with the defaults of OpenCV's bgsegm MOG.

    Settings (``sensors_video::MogConfig``): ``history=200``, ``n_mixtures=5``,
    ``background_ratio=0.7``, ``match_sigmas=2.5``, ``initial_sigma=30``,
    ``initial_weight=0.05``, ``min_sigma=15``, and ``shadows={"enabled": True,
    "min_brightness": 0.5, "max_brightness": 1.0, "max_chromaticity_sigmas": 1.5}``.
    It is not OpenCV's bit for bit (see docs/video.md); shadows are labelled 127, as in
    OpenCV's MOG2.
    """

    def __init__(self, **params):
        self._native = _native.BackgroundSubtractor(params)

    def apply(self, frame) -> np.ndarray:
        """Classifies a uint8 frame, (H, W) grey or (H, W, 3) colour in any channel order
        (BGR as OpenCV reads it works the same), and learns from it. Returns the mask (H, W)
        uint8: 0 background, 127 shadow, 255 foreground. Every frame must have the first
        frame's size and channels."""
        return self._native.apply(frame)

    @property
    def frame_count(self) -> int:
        """Frames learnt so far."""
        return self._native.frame_count


def beamform(signals, mics, **params):
    """Beam energies of a recording, frame by frame.

    ``signals`` (M, T): one row per microphone, at ``sample_rate_hz`` (16000 by default);
    ``mics`` (M, 2): their positions in metres. Settings (``sensors_audio::BeamformConfig``):
    ``n_beams=36``, ``sample_rate_hz=16000``, ``frame_len=512``, ``hop=512``,
    ``band_hz=[200, 4000]`` (both edges inclusive), ``sound_speed_mps=343``,
    ``method="frequency_domain"`` (delay-and-sum; or ``"time_domain"``, or ``"mvdr"``),
    ``weighting="plain"`` (or ``"phat"``: SRP-PHAT), ``window="hann"``, ``mvdr_forgetting``,
    ``mvdr_loading``. Returns (frame centre times in s (F,), energies (F, B)); beam b points
    at b * 2 pi / B, anticlockwise from the array's x axis.
    """
    return _native.beamform(signals, mics, params)


def doa(signals, mics, max_peaks: int = 1, min_relative: float = 0.1, **params):
    """Directions of arrival over a whole recording: every frame's beam energies summed, then
    up to ``max_peaks`` peaks, strongest first, each at least ``min_relative`` of the range
    above the minimum and refined between beams. Settings as ``beamform``. Returns (bearings
    in radians in [0, 2 pi), their energies)."""
    return _native.doa(signals, mics, max_peaks, min_relative, params)
