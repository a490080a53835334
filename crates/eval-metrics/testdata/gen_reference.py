# Generates a synthetic MOT sequence and scores it with py-motmetrics, as an independent
# reference for eval-metrics' CLEAR and identity metrics. Run once; outputs are committed.
import json, numpy as np
if not hasattr(np, "asfarray"):  # py-motmetrics 1.4 predates NumPy 2
    np.asfarray = lambda a, dtype=float: np.asarray(a, dtype=dtype)
import motmetrics as mm
rng = np.random.default_rng(2026)
n_obj, n_frames = 8, 60
gt_rows, pr_rows = [], []
for o in range(n_obj):
    x0, y0 = rng.uniform(0, 400), rng.uniform(0, 300)
    vx, vy = rng.uniform(-4, 4), rng.uniform(-3, 3)
    start, end = rng.integers(1, 15), rng.integers(45, n_frames + 1)
    for f in range(start, end + 1):
        x, y = x0 + vx * f, y0 + vy * f
        gt_rows.append((f, o + 1, x, y, 30.0, 60.0))
        if rng.random() < 0.88:
            pid = o + 1 if f < 30 or o % 3 else o + 101   # some objects change id half-way
            if o == 5 and 20 <= f < 26: continue         # a fragment
            pr_rows.append((f, pid, x + rng.normal(0, 4), y + rng.normal(0, 4), 30.0 + rng.normal(0, 2), 60.0 + rng.normal(0, 3)))
    # swap ids of objects 1 and 2 for some frames
for f in range(1, n_frames + 1):
    for _ in range(rng.poisson(0.7)):
        pr_rows.append((f, 500 + f * 10 + _, rng.uniform(0, 400), rng.uniform(0, 300), 30.0, 60.0))
def write(path, rows, conf):
    with open(path, "w") as fh:
        for r in sorted(rows):
            fh.write("%d,%d,%.3f,%.3f,%.3f,%.3f,%s,-1,-1,-1\n" % (r[0], r[1], r[2], r[3], r[4], r[5], conf))
write("synthetic-gt.txt", gt_rows, "1")
write("synthetic-pred.txt", pr_rows, "1")
gt = mm.io.loadtxt("synthetic-gt.txt", fmt="mot15-2D", min_confidence=1)
ts = mm.io.loadtxt("synthetic-pred.txt", fmt="mot15-2D")
acc = mm.utils.compare_to_groundtruth(gt, ts, "iou", distth=0.5)
mh = mm.metrics.create()
names = ["mota", "motp", "idf1", "idp", "idr", "num_switches", "num_false_positives", "num_misses",
         "num_detections", "num_objects", "precision", "recall", "idtp", "idfp", "idfn"]
s = mh.compute(acc, metrics=names, name="seq")
out = {k: float(s[k].iloc[0]) for k in names}
out["generator"] = "py-motmetrics %s, compare_to_groundtruth(iou, distth=0.5)" % mm.__version__
with open("synthetic-motmetrics.json", "w") as fh:
    json.dump(out, fh, indent=2, sort_keys=True)
print(json.dumps(out, indent=1))
