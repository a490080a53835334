#!/usr/bin/env python3
"""Stone Soup's GNN with its EKF and UKF on the adsb-radar scenario's radar plots, against
ours (`cargo xtask track --plots`), each tuned on the same tuning run and scored by the same
evaluator (`cargo xtask eval --distance`), with the time per scan.

    cargo xtask export-plots --out /tmp/adsb-plots      # the real collection when fetched
    python3 docs/comparisons/stonesoup_adsb.py /tmp/adsb-plots [SEED,SEED,... [SECONDS [WHICH]]]

WHICH is all (the default), stonesoup or ours: one side only. SECONDS keeps only the first
SECONDS of each run (tuning and reported), for both sides: Stone
Soup takes about 0.1 s a dwell on the stand-in, so its whole runs take hours.

Protocol (the same for both sides):
- Plots: range and bearing from the one radar, σ_r 50 m and σ_θ 1.5 mrad, as the scenario.
- Stone Soup: `GNNWith2DAssignment` over a `DistanceHypothesiser` (Mahalanobis, missed
  distance 4, our χ² gate of 16), CV per axis (`ConstantVelocity(q)`) through
  `ExtendedKalmanPredictor`/`Updater` or the unscented pair (α 0.5, β 2, κ 3 − n), start by a
  `MultiMeasurementInitiator` with 3 plots (the prior's velocity σ 250 m/s), deletion 35 s
  after the last update (our 3 missed revolutions at 10 s), holding tracks 15 s after theirs. It has no notion of the beam: every
  track is predicted and missed at every dwell, which costs time and nothing else.
- Ours: `--filter ekf`, `ukf` (the coordinated turn with ω in the state) and `imm` (CV and
  ±3°/s), their other settings `PlotTrackConfig::default()`'s, the clutter density the
  scenario's. The plot files carry each dwell's sector (`beam_rad`, `beam_width_rad`), so ours
  predicts and misses a track only where the beam looked; Stone Soup reads past them.
- q (white-acceleration density, the same for each axis) is chosen from one grid (0.3, 3, 30:
  three values, because Stone Soup is slow) by mean OSPA
  on the tuning run, for every tracker. The reported runs are scored with q fixed.
- Scored on hits only (estimates at the dwells where a plot updated the track): Stone Soup's
  tracks carry a prediction at every dwell, ours a coast only where the beam looked, so the
  updates are what both write alike. Matching within 1000 m, OSPA with c = 1000 m, p = 2.
- Time: the wall time of the tracking loop over a reported run, divided by its revolutions
  (12 dwells each); ours is the time `cargo xtask track` prints (a release build's is lower).

It creates /tmp/stonesoup-venv and installs stonesoup from PyPI the first time.
"""
import datetime, json, math, os, subprocess, sys, time

VENV = "/tmp/stonesoup-venv"
if sys.prefix != VENV:
    if not os.path.exists(VENV + "/bin/python"):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
        subprocess.check_call([VENV + "/bin/pip", "install", "-q", "stonesoup"])
    os.execv(VENV + "/bin/python", [VENV + "/bin/python", __file__] + sys.argv[1:])

import numpy as np
import stonesoup
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.deleter.time import UpdateTimeDeleter
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.initiator.simple import MultiMeasurementInitiator
from stonesoup.measures import Mahalanobis
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, ConstantVelocity
from stonesoup.predictor.kalman import ExtendedKalmanPredictor, UnscentedKalmanPredictor
from stonesoup.tracker.simple import MultiTargetTracker
from stonesoup.types.detection import Detection
from stonesoup.types.state import GaussianState
from stonesoup.types.update import Update
from stonesoup.updater.kalman import ExtendedKalmanUpdater, UnscentedKalmanUpdater

SIGMA_R, SIGMA_B = 50.0, 0.0015
Q_GRID = [0.3, 3.0, 30.0]
DISTANCE = 1000.0
EPOCH = datetime.datetime(2026, 1, 1)
REVOLUTION_S = 10.0
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def read_dwells(path):
    """[(time_s, [(range, bearing, sensor_x, sensor_y)])] in order of time."""
    dwells, current, t_last = [], [], None
    with open(path) as f:
        header = f.readline().strip().split(",")
        col = {n: i for i, n in enumerate(header)}
        for line in f:
            v = line.strip().split(",")
            if not v[0]:
                continue
            t = float(v[col["time_s"]])
            if t != t_last and current:
                dwells.append((t_last, current))
                current = []
            t_last = t
            current.append((float(v[col["range"]]), float(v[col["bearing"]]),
                            float(v[col["sensor_x"]]), float(v[col["sensor_y"]])))
    if current:
        dwells.append((t_last, current))
    return dwells


def stonesoup_run(dwells, q, unscented):
    """The tracks' updates as CSV text, and the tracking loop's wall time."""
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])
    if unscented:
        predictor = UnscentedKalmanPredictor(transition, alpha=0.5, beta=2.0, kappa=-1.0)
        updater = UnscentedKalmanUpdater(None, alpha=0.5, beta=2.0, kappa=-1.0)
    else:
        predictor = ExtendedKalmanPredictor(transition)
        updater = ExtendedKalmanUpdater(None)
    hypothesiser = DistanceHypothesiser(predictor, updater, measure=Mahalanobis(), missed_distance=4)
    associator = GNNWith2DAssignment(hypothesiser)
    deleter = UpdateTimeDeleter(datetime.timedelta(seconds=35))
    prior = GaussianState([[0], [0], [0], [0]], np.diag([0, 250.0**2, 0, 250.0**2]))
    # A holding track that has missed a revolution and a half cannot reach 3 of 4 (ours drops it
    # then too).
    initiator = MultiMeasurementInitiator(
        prior, measurement_model=None, deleter=UpdateTimeDeleter(datetime.timedelta(seconds=15)),
        data_associator=GNNWith2DAssignment(hypothesiser), updater=updater, min_points=3)
    models = {}
    feed = []
    seconds_of = {}
    for t, plots in dwells:
        stamp = EPOCH + datetime.timedelta(seconds=t)
        # datetime keeps microseconds: the exact dwell time is written back out.
        seconds_of[stamp] = t
        dets = set()
        for r, b, sx, sy in plots:
            model = models.get((sx, sy))
            if model is None:
                model = CartesianToBearingRange(
                    ndim_state=4, mapping=(0, 2), noise_covar=np.diag([SIGMA_B**2, SIGMA_R**2]),
                    translation_offset=np.array([[sx], [sy]]))
                models[(sx, sy)] = model
            dets.add(Detection(np.array([[b], [r]]), timestamp=stamp, measurement_model=model))
        feed.append((stamp, dets))
    tracker = MultiTargetTracker(initiator=initiator, deleter=deleter, detector=feed,
                                 data_associator=associator, updater=updater)
    rows, ids = ["time_s,track_id,x,y,vx,vy,hit"], {}
    start = time.perf_counter()
    for stamp, tracks in tracker:
        t = seconds_of[stamp]
        for track in tracks:
            state = track.state
            if isinstance(state, Update) and state.timestamp == stamp:
                k = ids.setdefault(track.id, len(ids) + 1)
                x = [float(v) for v in np.asarray(state.state_vector, dtype=float).ravel()]
                rows.append("%r,%d,%r,%r,%r,%r,1" % (t, k, x[0], x[2], x[1], x[3]))
    return "\n".join(rows) + "\n", time.perf_counter() - start


def ours_run(plots_path, q, filt, out):
    """Runs `cargo xtask track --plots` with q; returns the tracking time it reports (s)."""
    config = out + ".toml"
    with open(config, "w") as f:
        f.write("q_accel = %r\n" % q)
    res = subprocess.run(["cargo", "xtask", "track", "--plots", plots_path, "--filter", filt,
                          "--config", config, "--out", out], cwd=ROOT, capture_output=True, text=True,
                         check=True)
    ms = float(res.stdout.strip().split(";")[-1].split()[0])
    hits = [l for i, l in enumerate(open(out).read().splitlines()) if i == 0 or l.endswith(",1")]
    open(out, "w").write("\n".join(hits) + "\n")
    return ms / 1e3


def score(truth_path, tracks_path):
    res = subprocess.run(["cargo", "xtask", "eval", "--gt", truth_path, "--pred", tracks_path,
                          "--distance", str(DISTANCE), "--json"], cwd=ROOT, capture_output=True,
                         text=True, check=True)
    m = json.loads(res.stdout)
    return dict(ospa=m["ospa_mean"], mota=m["clear"]["mota"], idf1=m["identity"]["idf1"])


def truncate(folder, name, seconds):
    """A copy of NAME-plots.csv and NAME-truth.csv with the first `seconds` only; the new name."""
    if seconds is None:
        return name
    short = "%s-first%g" % (name, seconds)
    for kind in ("plots", "truth"):
        lines = open("%s/%s-%s.csv" % (folder, name, kind)).read().splitlines()
        t0 = float(lines[1].split(",")[0])
        keep = [lines[0]] + [l for l in lines[1:] if float(l.split(",")[0]) < t0 + seconds]
        open("%s/%s-%s.csv" % (folder, short, kind), "w").write("\n".join(keep) + "\n")
    return short


def main(folder, seeds, seconds, which):
    trackers = [("Stone Soup GNN + EKF (CV)", "ss", False), ("Stone Soup GNN + UKF (CV)", "ss", True),
                ("ours GNN + EKF (CT, ω in state)", "ekf", None), ("ours GNN + UKF (CT, ω in state)", "ukf", None),
                ("ours GNN + IMM CV/CT±3°/s", "imm", None)]
    print("stonesoup %s, numpy %s" % (stonesoup.__version__, np.__version__))
    results = []
    tune = truncate(folder, "tune", seconds)
    reported = [truncate(folder, "report-%s" % s, seconds) for s in seeds]
    for name, kind, flag in trackers:
        if which != "all" and (kind == "ss") != (which == "stonesoup"):
            continue
        grid = []
        for q in Q_GRID:
            out = "%s/%s-%s-%s-%g.csv" % (folder, tune, kind, flag, q)
            if kind == "ss":
                text, _ = stonesoup_run(read_dwells("%s/%s-plots.csv" % (folder, tune)), q, flag)
                open(out, "w").write(text)
            else:
                ours_run("%s/%s-plots.csv" % (folder, tune), q, kind, out)
            grid.append((score("%s/%s-truth.csv" % (folder, tune), out)["ospa"], q))
        q = min(grid)[1]
        per_seed = []
        for run in reported:
            plots = "%s/%s-plots.csv" % (folder, run)
            out = "%s/%s-%s-%s.csv" % (folder, run, kind, flag)
            dwells = read_dwells(plots)
            if kind == "ss":
                text, seconds = stonesoup_run(dwells, q, flag)
                open(out, "w").write(text)
            else:
                seconds = ours_run(plots, q, kind, out)
            s = score("%s/%s-truth.csv" % (folder, run), out)
            revolutions = (dwells[-1][0] - dwells[0][0]) / REVOLUTION_S
            s["ms_per_scan"] = 1e3 * seconds / revolutions
            per_seed.append(s)
        mean = {k: float(np.mean([s[k] for s in per_seed])) for k in per_seed[0]}
        results.append((name, q, mean, [g for g in grid]))
        print("%-34s q %-5g OSPA %7.1f MOTA %.3f IDF1 %.3f  %8.2f ms per scan   (tuning OSPA %s)" % (
            name, q, mean["ospa"], mean["mota"], mean["idf1"], mean["ms_per_scan"],
            ", ".join("%g: %.1f" % (q, o) for o, q in grid)))


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    folder = sys.argv[1]
    seeds = sys.argv[2].split(",") if len(sys.argv) > 2 else ["7202", "7203", "7204", "7205", "7206"]
    seconds = float(sys.argv[3]) if len(sys.argv) > 3 else None
    which = sys.argv[4] if len(sys.argv) > 4 else "all"
    main(folder, seeds, seconds, which)
