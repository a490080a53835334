#!/usr/bin/env python3
"""roboflow `trackers` 2.6.1 (Apache-2.0): SORT, ByteTrack and OC-SORT with their defaults, on
MOTChallenge detection files, for the box-trackers crate.

    python3 docs/comparisons/roboflow_trackers.py record OUT_DIR DETS.txt ...
        Runs the three trackers on each file as the package's own `trackers track
        --detections` does (every frame from 1 to the last, detections as sv.Detections with
        the file's scores), and writes OUT_DIR/<name>.<tracker>.txt: one line `frame,row,id`
        per output row with an id (row: the detection's 0-based line in the file, found by its
        box, which must equal an input box exactly). crates/box-trackers/tests/reference.rs
        compares the Rust trackers with these files.
    python3 docs/comparisons/roboflow_trackers.py time DETS.txt ...
        The median over 5 runs of the time spent in `tracker.update` per frame, per tracker.
    python3 docs/comparisons/roboflow_trackers.py time-scene N ...
        The same on the scene of crates/box-trackers/benches/association.rs: 30 frames of N
        walkers (the same boxes and scores, from the same formula).

It creates /tmp/roboflow-trackers-venv and installs trackers==2.6.1 from PyPI the first time.
"""
import math, os, subprocess, sys, time

VENV = "/tmp/roboflow-trackers-venv"
if sys.prefix != VENV:
    if not os.path.exists(VENV):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
        subprocess.check_call([VENV + "/bin/pip", "install", "-q", "trackers==2.6.1"])
    os.execv(VENV + "/bin/python", [VENV + "/bin/python", __file__] + sys.argv[1:])

import numpy as np
import supervision as sv
import importlib.metadata
from trackers import ByteTrackTracker, OCSORTTracker, SORTTracker

TRACKERS = {"sort": SORTTracker, "bytetrack": ByteTrackTracker, "ocsort": OCSORTTracker}


def load(path):
    """Rows per frame as (row number, xyxy, score); frames 1-based as in the file."""
    frames = {}
    with open(path) as f:
        rows = [line.strip().split(",") for line in f if line.strip()]
    for i, r in enumerate(rows):
        x, y, w, h = (float(v) for v in r[2:6])
        frames.setdefault(int(float(r[0])), []).append((i, [x, y, x + w, y + h], float(r[6])))
    return frames


def detections(rows):
    if not rows:
        return sv.Detections.empty()
    return sv.Detections(
        xyxy=np.array([r[1] for r in rows], dtype=np.float64),
        confidence=np.array([r[2] for r in rows], dtype=np.float64),
        class_id=np.ones(len(rows), dtype=int),
    )


def run(name, frames):
    tracker = TRACKERS[name]()
    out, spent = [], 0.0
    for frame in range(1, max(frames) + 1):
        rows = frames.get(frame, [])
        dets = detections(rows)
        by_box = {}
        for r in rows:
            by_box.setdefault(tuple(r[1]), []).append(r[0])
        start = time.perf_counter()
        result = tracker.update(dets)
        spent += time.perf_counter() - start
        for box, tid in zip(result.xyxy, result.tracker_id):
            if tid < 0:
                continue
            hits = by_box.get(tuple(float(v) for v in box), [])
            assert len(hits) == 1, f"frame {frame}: output box {box} is not one input box"
            out.append((frame, hits[0], int(tid)))
    return out, spent / max(frames)


def record(out_dir, paths):
    os.makedirs(out_dir, exist_ok=True)
    for path in paths:
        frames = load(path)
        stem = os.path.basename(path).rsplit(".", 1)[0]
        for name in TRACKERS:
            rows, per_frame = run(name, frames)
            with open(os.path.join(out_dir, f"{stem}.{name}.txt"), "w") as f:
                f.write("".join(f"{fr},{row},{tid}\n" for fr, row, tid in sorted(rows)))
            ids = len({r[2] for r in rows})
            print(f"{stem} {name}: {len(rows)} rows, {ids} ids, {per_frame * 1e3:.3f} ms/frame")


def scene(n):
    """The bench's scene: walkers on a grid, 1-3 px a frame, every tenth box scoring 0.4."""
    side = math.ceil(math.sqrt(n))
    frames = {}
    for f in range(1, 31):
        rows = []
        for i in range(n):
            row, col = i // side, i % side
            speed = 1.0 + i % 3
            jitter = math.sin(0.7 * f + i)
            left, top = 40.0 * col + speed * f + jitter, 80.0 * row + jitter
            score = 0.4 if (i + f) % 10 == 0 else 0.9
            rows.append((i, [left, top, left + 20.0, top + 50.0], score))
        frames[f] = rows
    return frames


def timing(named_frames):
    print(f"trackers {importlib.metadata.version('trackers')}, numpy {np.__version__}, supervision {sv.__version__}")
    for label, frames in named_frames:
        n = sum(len(v) for v in frames.values())
        for name in TRACKERS:
            per_frame = sorted(run(name, frames)[1] for _ in range(5))[2]
            print(f"{label} ({n} boxes, {max(frames)} frames) {name}: {per_frame * 1e3:.3f} ms/frame")


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "record":
        record(sys.argv[2], sys.argv[3:])
    elif len(sys.argv) >= 3 and sys.argv[1] == "time":
        timing([(os.path.basename(p), load(p)) for p in sys.argv[2:]])
    elif len(sys.argv) >= 3 and sys.argv[1] == "time-scene":
        timing([(f"scene {n}", scene(int(n))) for n in sys.argv[2:]])
    else:
        sys.exit(__doc__)
