"""OpenCV's legacy `TrackerBoosting` (Grabner, Grabner & Bischof's online-boosting tracker, the
one Yoon et al.'s local detector follows) against image-detector's `ImageDetector` on the same
rendered sequence: the 200-frame textured sprite wandering over a cluttered 320 x 240
background of image-detector's test (`follows_a_textured_sprite_on_clutter_for_200_frames`).

Run from the workspace root (needs network to PyPI the first time):

    python3 docs/comparisons/opencv_tracker_boosting.py

It creates a venv in /tmp/imagedet-venv, pip-installs `opencv-contrib-python-headless<5` (it has
`cv2.legacy.TrackerBoosting_create`) and numpy, re-runs itself inside it, builds
`cargo build --release -p image-detector --example boosting_sequence`, writes the reported
sequence (seed 11, the test's) and a tuning sequence (seed 12: the same path, another background
and noise) as PNGs, runs both trackers and prints a Markdown table.

Protocol (the same for both): initialised on frame 0's true box; then each tracker runs on its
own (ours is confirmed wherever it finds itself, as in the test, with no global detector);
success = IoU >= 0.5 with the true box on frames 1..199 (a frame where a tracker reports nothing
is a failure); time = median and mean ms per frame of the tracker's update alone (PNG decoding
excluded), one thread each (RAYON_NUM_THREADS=1, cv2.setNumThreads(1)).

Fairness: TrackerBoosting's parameters (numClassifiers, samplerSearchFactor) are chosen on the
tuning sequence, from a small grid around OpenCV's defaults (highest success, then fastest); ours runs at its defaults (they
were set on the crate's tests, which use this very sequence, so ours has the advantage of
having been developed on it: the table says so).
"""
import os
import statistics
import subprocess
import sys
import time

VENV = "/tmp/imagedet-venv"
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
WORK = "/tmp/imagedet-boosting"


def ensure_venv():
    py = os.path.join(VENV, "bin", "python")
    if os.path.abspath(sys.executable) == os.path.abspath(py):
        return
    if not os.path.exists(py):
        subprocess.run([sys.executable, "-m", "venv", VENV], check=True)
    subprocess.run([py, "-m", "pip", "install", "-q", "opencv-contrib-python-headless<5", "numpy"],
                   check=True)
    os.execv(py, [py, os.path.abspath(__file__)] + sys.argv[1:])


def iou(a, b):
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    w = max(0.0, min(ax + aw, bx + bw) - max(ax, bx))
    h = max(0.0, min(ay + ah, by + bh) - max(ay, by))
    inter = w * h
    union = aw * ah + bw * bh - inter
    return inter / union if union > 0 else 0.0


def read_truth(d):
    out = []
    with open(os.path.join(d, "truth.txt")) as f:
        for line in f:
            _, l, t, w, h = line.strip().split(",")
            out.append((float(l), float(t), float(w), float(h)))
    return out


def success(boxes, truth):
    ok = sum(1 for b, t in zip(boxes[1:], truth[1:]) if b is not None and iou(b, t) >= 0.5)
    return ok / (len(truth) - 1)


def run_ours(example, d):
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    out = subprocess.run([example, "track", d], check=True, capture_output=True, text=True,
                         env=env).stdout
    boxes, med, mean = [], None, None
    for line in out.splitlines():
        if line.startswith("# ms_per_frame"):
            _, _, med, mean = line.split()
            continue
        f = line.split(",")
        boxes.append(None if f[1] == "" else tuple(float(v) for v in f[1:5]))
    return boxes, float(med), float(mean)


def run_opencv(d, truth, n_classifiers=100, search_factor=1.8):
    import cv2

    cv2.setNumThreads(1)
    tracker = cv2.legacy.TrackerBoosting_create()
    # The Python binding does not expose TrackerBoosting::Params; the tracker's `read` takes them
    # from a FileStorage node (the keys its `write` produces; the other values are the defaults).
    path = os.path.join(WORK, "boosting_params.yml")
    with open(path, "w") as f:
        f.write(f"%YAML:1.0\n---\nnumClassifiers: {n_classifiers}\noverlap: 0.99\n"
                f"searchFactor: {search_factor}\niterationInit: 50\n"
                f"samplerSearchFactor: {search_factor}\nfeatureSetNumFeatures: 1050\n")
    fs = cv2.FileStorage(path, cv2.FILE_STORAGE_READ)
    tracker.read(fs.root())
    fs.release()
    frames = [cv2.imread(os.path.join(d, f"{k:06d}.png"), cv2.IMREAD_COLOR)
              for k in range(len(truth))]
    tracker.init(frames[0], tuple(truth[0]))
    boxes, ms = [truth[0]], []
    for k in range(1, len(frames)):
        t0 = time.perf_counter()
        ok, b = tracker.update(frames[k])
        ms.append(1e3 * (time.perf_counter() - t0))
        boxes.append(tuple(float(v) for v in b) if ok else None)
    return boxes, statistics.median(ms), statistics.mean(ms)


def main():
    ensure_venv()
    import cv2

    subprocess.run(["cargo", "build", "--release", "-p", "image-detector", "--example",
                    "boosting_sequence"], cwd=ROOT, check=True)
    example = os.path.join(ROOT, "target", "release", "examples", "boosting_sequence")
    report, tune = os.path.join(WORK, "report"), os.path.join(WORK, "tune")
    subprocess.run([example, "write", report, "11"], check=True)
    subprocess.run([example, "write", tune, "12"], check=True)
    truth_r, truth_t = read_truth(report), read_truth(tune)

    print(f"OpenCV {cv2.__version__}; tuning TrackerBoosting on the seed-12 sequence:")
    best = None
    for n in (25, 50, 100):  # 200 crashes OpenCV 4.14 (segmentation fault)
        for s in (1.5, 1.8, 2.5):
            boxes, med, _ = run_opencv(tune, truth_t, n, s)
            sr = success(boxes, truth_t)
            print(f"  numClassifiers {n}, samplerSearchFactor {s}: success {100 * sr:.1f} %, "
                  f"{med:.2f} ms/frame")
            # Highest success; among equals, the fastest.
            if best is None or (sr, -med) > (best[0], -best[3]):
                best = (sr, n, s, med)
    _, n, s, _ = best
    theirs, t_med, t_mean = run_opencv(report, truth_r, n, s)
    theirs_def, td_med, td_mean = run_opencv(report, truth_r)
    ours, o_med, o_mean = run_ours(example, report)
    ours_t, _, _ = run_ours(example, tune)
    print()
    print("| tracker | success (IoU >= 0.5), frames 1-199, seed 11 | same, tuning seed 12 "
          "| ms/frame median (mean) |")
    print("|---|---|---|---|")
    print(f"| image-detector `ImageDetector` (defaults) | {100 * success(ours, truth_r):.1f} % | "
          f"{100 * success(ours_t, truth_t):.1f} % | {o_med:.2f} ({o_mean:.2f}) |")
    print(f"| OpenCV {cv2.__version__} `legacy.TrackerBoosting` (numClassifiers {n}, "
          f"samplerSearchFactor {s}, tuned) | {100 * success(theirs, truth_r):.1f} % | "
          f"{100 * best[0]:.1f} % | {t_med:.2f} ({t_mean:.2f}) |")
    print(f"| OpenCV `legacy.TrackerBoosting` (defaults: 100, 1.8) | "
          f"{100 * success(theirs_def, truth_r):.1f} % | - | {td_med:.2f} ({td_mean:.2f}) |")
    ious_o = [iou(b, t) if b else 0.0 for b, t in zip(ours[1:], truth_r[1:])]
    ious_t = [iou(b, t) if b else 0.0 for b, t in zip(theirs[1:], truth_r[1:])]
    print(f"\nmean IoU, frames 1-199: ours {statistics.mean(ious_o):.3f}, "
          f"TrackerBoosting {statistics.mean(ious_t):.3f}")


if __name__ == "__main__":
    main()
