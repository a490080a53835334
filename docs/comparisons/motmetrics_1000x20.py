# Times py-motmetrics on a sequence shaped like crates/eval-metrics/benches/metrics.rs (pip install motmetrics).
import time, numpy as np
if not hasattr(np, "asfarray"):
    np.asfarray = lambda a, dtype=float: np.asarray(a, dtype=dtype)
import motmetrics as mm, pandas as pd
rng = np.random.default_rng(7)
gt, pr = [], []
for o in range(20):
    x0, y0, vx, vy = rng.uniform(0,1500), rng.uniform(0,900), rng.uniform(-2,2), rng.uniform(-1,1)
    for f in range(1, 1001):
        x, y = x0+vx*f, y0+vy*f
        gt.append((f, o, x, y, 40., 90.))
        if rng.random() < 0.9:
            pr.append((f, o*2 + (f//200)%2, x+rng.uniform(-3,3), y+rng.uniform(-3,3), 40., 90.))
for f in range(1, 1001):
    pr.append((f, 100000+f, rng.uniform(0,1500), rng.uniform(0,900), 40., 90.))
cols = ["FrameId","Id","X","Y","Width","Height"]
g = pd.DataFrame(gt, columns=cols).set_index(["FrameId","Id"]); g["Confidence"]=1.0
p = pd.DataFrame(pr, columns=cols).set_index(["FrameId","Id"]); p["Confidence"]=1.0
t = time.perf_counter()
acc = mm.utils.compare_to_groundtruth(g, p, "iou", distth=0.5)
s = mm.metrics.create().compute(acc, metrics=["mota","motp","idf1","num_switches"], name="x")
print("py-motmetrics CLEAR+IDF1 on 1000x20: %.2f s" % (time.perf_counter()-t)); print(s)
