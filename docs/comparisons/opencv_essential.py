#!/usr/bin/env python3
"""OpenCV findEssentialMat + recoverPose on the camnet bench's data (500 correspondences,
30 % outliers, 0.5 px uniform noise at f = 1000), for comparison with
`cargo bench -p camnet --bench essential`.

The data are regenerated here from the same recipe (not the same random numbers: ChaCha8 is
not replicated): pose R = euler(0.2, -0.4, 0.1) (nalgebra roll-pitch-yaw), t = (-1, 0.3, 0.2)/|.|;
points uniform in [-3,3]² × [4,10]; every index i with i % 10 < 3 is replaced in view 2 by a
uniform point in [-0.6, 0.6]². Run: python3 docs/comparisons/opencv_essential.py
(creates /tmp/camnet-opencv-venv and installs opencv-python-headless and numpy from PyPI).
"""
import os, subprocess, sys, time

VENV = "/tmp/camnet-opencv-venv"
if sys.prefix != VENV:
    if not os.path.exists(VENV):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
        subprocess.check_call([VENV + "/bin/pip", "install", "-q", "opencv-python-headless", "numpy"])
    os.execv(VENV + "/bin/python", [VENV + "/bin/python", __file__])

import numpy as np
import cv2

def euler(r, p, y):
    # nalgebra Rotation3::from_euler_angles(roll, pitch, yaw) = Rz(yaw) Ry(pitch) Rx(roll)
    cx, sx, cy, sy, cz, sz = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx

rng = np.random.default_rng(5)
R = euler(0.2, -0.4, 0.1)
t = np.array([-1.0, 0.3, 0.2]); t /= np.linalg.norm(t)
x1, x2 = [], []
while len(x1) < 500:
    p = np.array([rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(4, 10)])
    q = R @ p + t
    if q[2] <= 0:
        continue
    i = len(x1)
    x1.append(p[:2] / p[2] + rng.uniform(-0.5, 0.5, 2) / 1000)
    x2.append(rng.uniform(-0.6, 0.6, 2) if i % 10 < 3 else q[:2] / q[2] + rng.uniform(-0.5, 0.5, 2) / 1000)
x1, x2 = np.array(x1), np.array(x2)
K = np.eye(3)
times = []
for _ in range(50):
    s = time.perf_counter()
    E, mask = cv2.findEssentialMat(x1, x2, K, method=cv2.RANSAC, prob=0.999, threshold=1.5e-3)
    _, Re, te, _ = cv2.recoverPose(E[:3], x1, x2, K, mask=mask)
    times.append(time.perf_counter() - s)
ang = np.degrees(np.arccos(np.clip((np.trace(Re @ R.T) - 1) / 2, -1, 1)))
dang = np.degrees(np.arccos(np.clip(float(te.ravel() @ t), -1, 1)))
print(f"OpenCV {cv2.__version__}: median {1e3 * np.median(times):.2f} ms, rotation error {ang:.4f} deg, "
      f"translation direction error {dang:.4f} deg, inliers {int(mask.sum())}/500")
