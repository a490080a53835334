"""OpenCV `bgsegm` MOG (KaewTraKulPong & Bowden 2001) against sensors-video on the same frames.

Setup (once): python3 -m venv /tmp/cvvenv && /tmp/cvvenv/bin/pip install opencv-contrib-python-headless numpy
Frames and our masks:
  cargo run --release -p sensors-video --example mog_compare -- /tmp/mogcmp WIDTH HEIGHT FRAMES grey|rgb
Then: /tmp/cvvenv/bin/python docs/comparisons/opencv_bgsegm_mog.py /tmp/mogcmp [SKIP]

OpenCV's defaults are the ones sensors-video copies (history 200, 5 mixtures, ratio 0.7,
noise sigma 15 -> variance floor, 2.5 sigma match, initial weight 0.05, initial sigma 30).
OpenCV's MOG has no shadow labels, so a pixel agrees when OpenCV's foreground equals our
foreground-or-shadow. Frames before SKIP (default 100) are excluded from the agreement.
Timing: OpenCV's median apply() time per frame, single process, cv2.setNumThreads(2).
"""
import glob
import os
import sys
import time

import cv2
import numpy as np

d = sys.argv[1]
skip = int(sys.argv[2]) if len(sys.argv) > 2 else 100
cv2.setNumThreads(2)
frames = sorted(glob.glob(os.path.join(d, "frames", "*.png")))
ours = sorted(glob.glob(os.path.join(d, "ours", "*.png")))
mog = cv2.bgsegm.createBackgroundSubtractorMOG()
times, agree, total, both_fg, either_fg = [], 0, 0, 0, 0
for k, (fp, op) in enumerate(zip(frames, ours)):
    img = cv2.imread(fp, cv2.IMREAD_UNCHANGED)
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)  # same channel order as ours (irrelevant to MOG)
    t = time.perf_counter()
    m = mog.apply(img)
    times.append(time.perf_counter() - t)
    if k < skip:
        continue
    o = cv2.imread(op, cv2.IMREAD_UNCHANGED) > 0
    c = m > 0
    agree += int(np.sum(o == c))
    total += o.size
    both_fg += int(np.sum(o & c))
    either_fg += int(np.sum(o | c))
print(f"opencv {cv2.__version__} frames {len(frames)} shape {img.shape}")
print(f"opencv_median_ms {1e3 * float(np.median(times)):.3f}")
print(f"per_pixel_agreement {agree / max(total, 1):.5f}")
print(f"foreground_jaccard {both_fg / max(either_fg, 1):.4f}")
