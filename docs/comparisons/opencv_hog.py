"""OpenCV `HOGDescriptor.compute` against image-detector's HOG on rendered frames.

Setup (once): python3 -m venv /tmp/hogvenv && /tmp/hogvenv/bin/pip install "opencv-python-headless<5" numpy
(OpenCV 5 moved HOGDescriptor out of the main package.)
Frames and our descriptors (whole 320 x 240 frame as one window):
  cargo run --release -p image-detector --example hog_dump -- /tmp/hog_cmp
Then: /tmp/hogvenv/bin/python docs/comparisons/opencv_hog.py /tmp/hog_cmp

OpenCV is configured as close to ours as its API allows: 16 x 16 blocks, stride 8, 8 x 8 cells,
9 unsigned bins, L2-Hys at 0.2, no gamma correction, and winSigma = 1e6 so the Gaussian block
window is flat (weights within 1e-10 of 1). What cannot be switched off: OpenCV splits each
pixel's vote bilinearly between the four cells of a block around it (the spatial part of
Dalal-Triggs' trilinear interpolation), where ours votes into its own cell only; OpenCV's L2
epsilon is 0.1 * 36 (ours 1e-3). Both take the channel with the largest gradient and reflect
the border (BORDER_REFLECT_101). So the per-cell orientation distribution agrees, the per-value
match is approximate; the script reports the correlation and the relative L2 difference of the
whole descriptor, and the same for the L1-normalised orientation histogram summed over all
blocks (spatial interpolation moves mass between cells but not between bins).

OpenCV orders blocks column by column (x outer) and, inside a block, cells column by column;
ours is row by row for both. The script reorders OpenCV's vector to ours.
"""
import glob
import os
import sys

import cv2
import numpy as np

d = sys.argv[1] if len(sys.argv) > 1 else "/tmp/hog_cmp"
rows = []
for png in sorted(glob.glob(os.path.join(d, "frame_*.png"))):
    img = cv2.imread(png, cv2.IMREAD_COLOR)
    h, w = img.shape[:2]
    with open(png.replace(".png", ".hog.txt")) as f:
        bx, by, n = (int(v) for v in f.readline().split())
        ours = np.array([float(v) for v in f], dtype=np.float64)
    assert ours.size == n == bx * by * 36
    hog = cv2.HOGDescriptor((w // 8 * 8, h // 8 * 8), (16, 16), (8, 8), (8, 8), 9, 1, 1e6,
                            cv2.HOGDescriptor_L2Hys, 0.2, False, 64, False)
    theirs = hog.compute(img[: h // 8 * 8, : w // 8 * 8]).astype(np.float64).ravel()
    assert theirs.size == n, (theirs.size, n)
    # OpenCV: block index = bx_index * by + by_index; cells inside a block (cx, cy) at cx * 2 + cy.
    t = theirs.reshape(bx, by, 2, 2, 9)  # [block x][block y][cell x][cell y][bin]
    t = t.transpose(1, 0, 3, 2, 4)  # -> [block y][block x][cell y][cell x][bin]
    t = t.reshape(-1)
    corr = float(np.corrcoef(ours, t)[0, 1])
    rel = float(np.linalg.norm(ours - t) / np.linalg.norm(t))
    ob = ours.reshape(-1, 9).sum(axis=0)
    tb = t.reshape(-1, 9).sum(axis=0)
    ob, tb = ob / ob.sum(), tb / tb.sum()
    bins_l1 = float(np.abs(ob - tb).sum())
    # Per block: the dominant bin agrees?
    om = ours.reshape(-1, 36).reshape(-1, 4, 9).sum(axis=1).argmax(axis=1)
    tm = t.reshape(-1, 36).reshape(-1, 4, 9).sum(axis=1).argmax(axis=1)
    dom = float(np.mean(om == tm))
    rows.append((os.path.basename(png), corr, rel, bins_l1, dom))
    print(f"{os.path.basename(png)}: {n} values, correlation {corr:.4f}, relative L2 difference "
          f"{rel:.4f}, L1 between orientation distributions {bins_l1:.4f}, blocks with the same "
          f"dominant bin {100 * dom:.1f} %")
c = np.array([r[1:] for r in rows])
print(f"mean over {len(rows)} frames: correlation {c[:, 0].mean():.4f}, relative L2 "
      f"{c[:, 1].mean():.4f}, orientation-distribution L1 {c[:, 2].mean():.4f}, same dominant "
      f"bin {100 * c[:, 3].mean():.1f} %")
