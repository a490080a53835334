"""Times pyroomacoustics' SRP-PHAT and MUSIC on the WAV files that sensors-audio's simulator
wrote, and prints their mean absolute bearing errors, to set beside ours (docs/audio.md,
docs/benchmarks.md).

    cargo run --release -p sensors-audio --example doa_wavs -- simulate /tmp/doa-wavs 50 10
    cargo run --release -p sensors-audio --example doa_wavs -- estimate /tmp/doa-wavs
    python -m venv /tmp/pra-venv && /tmp/pra-venv/bin/pip install pyroomacoustics scipy
    /tmp/pra-venv/bin/python docs/comparisons/pyroomacoustics_doa.py /tmp/doa-wavs

Same files, same array (the papers' 10 cm x 6 cm rectangle, microphones counter-clockwise
from (+x, +y)), same 512-sample Hann frames without overlap and the same 200-4000 Hz band.
pyroomacoustics searches a grid and has no refinement between grid points, so it gets a 1°
grid (360 directions), its best fair configuration for accuracy, and for timing parity also our
36-direction grid.
The time per file counts the DOA step only (STFT included on both sides), best of 5 passes.
"""

import sys
import time
from pathlib import Path

import numpy as np
import pyroomacoustics as pra
from scipy.io import wavfile

NFFT = 512
FREQ_RANGE = [200.0, 4000.0]
MICS = np.array([[0.05, -0.05, -0.05, 0.05], [0.03, 0.03, -0.03, -0.03]])


def stft(x):
    """x: (samples, mics) -> (mics, NFFT/2+1, frames), Hann, hop = NFFT."""
    n_frames = x.shape[0] // NFFT
    win = np.hanning(NFFT + 1)[:NFFT]  # periodic Hann, as on the Rust side
    frames = x[: n_frames * NFFT].T.reshape(x.shape[1], n_frames, NFFT) * win
    return np.fft.rfft(frames, axis=-1).transpose(0, 2, 1)


def main(directory):
    directory = Path(directory)
    rows = [line.split(",") for line in (directory / "truth.csv").read_text().splitlines()[1:]]
    runs = []
    for run, deg in rows:
        fs, x = wavfile.read(directory / f"run_{int(run):03d}.wav")
        runs.append((x.astype(np.float64), float(deg)))
    for name, n_grid in [("SRP", 360), ("MUSIC", 360), ("SRP", 36), ("MUSIC", 36)]:
        azimuth = np.deg2rad(np.arange(n_grid) * 360.0 / n_grid)
        doa = pra.doa.algorithms[name](MICS, fs, NFFT, c=343.0, num_src=1, azimuth=azimuth)
        best = np.inf
        errors = []
        for rep in range(5):
            start = time.perf_counter()
            for x, deg in runs:
                doa.locate_sources(stft(x), freq_range=FREQ_RANGE)
                if rep == 0:
                    est = np.rad2deg(doa.azimuth_recon[0])
                    errors.append(abs((est - deg + 180.0) % 360.0 - 180.0))
            best = min(best, time.perf_counter() - start)
        print(
            f"pyroomacoustics {pra.__version__} {'SRP-PHAT' if name == 'SRP' else name}, {n_grid}-point grid:",
            f"mean |error| {np.mean(errors):.2f}° over {len(errors)} files,",
            f"{1e3 * best / len(runs):.3f} ms per file (best of 5)",
        )


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/doa-wavs")
