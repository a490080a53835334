# Scores the synthetic sequence of gen_reference.py (synthetic-gt.txt, synthetic-pred.txt: boxes
# with noise, so IoU < 1 and LocA is exercised), and a small sequence with empty frames that it
# writes (gaps-gt.txt, gaps-pred.txt), with TrackEval (Luiten et al.), the reference
# implementation of HOTA, as an external reference for eval-metrics' HOTA, CLEAR (MOTA, MOTP,
# IDSW, Frag, MT/PT/ML) and Identity metrics. Run once in this folder; the output,
# synthetic-trackeval.json, is committed.
#
#   python -m venv /tmp/venv && /tmp/venv/bin/pip install sn-trackeval numpy scipy
#   /tmp/venv/bin/python gen_trackeval_reference.py
#
# sn-trackeval 0.4.0 on PyPI packages TrackEval's code (its metrics/clear.py is byte-identical
# to JonathonLuiten/TrackEval's; hota.py and identity.py differ only in np.float → float and
# np.int → int for NumPy 2). The sequence is handed to TrackEval's metric classes in the form
# its MotChallenge2DBox dataset produces after loading and preprocessing a sequence with no
# distractor classes and no zero-marked boxes: per timestep 1..T the truth and tracker ids
# relabelled to 0..n−1 in sorted order (as its np.unique relabelling), and the IoU matrix from
# TrackEval's own _BaseDataset._calculate_box_ious (box format xywh).
import json
import numpy as np
import trackeval
from trackeval.datasets._base_dataset import _BaseDataset
from trackeval.metrics import HOTA, CLEAR, Identity


def load(path):
    rows = {}
    with open(path) as fh:
        for line in fh:
            f = line.strip().split(",")
            if len(f) < 6:
                continue
            rows.setdefault(int(f[0]), []).append((int(f[1]), [float(v) for v in f[2:6]]))
    return rows


def sequence(gt_path, pred_path):
    gt, pred = load(gt_path), load(pred_path)
    n_t = max(max(gt), max(pred))
    gt_ids = sorted({i for r in gt.values() for i, _ in r})
    pr_ids = sorted({i for r in pred.values() for i, _ in r})
    gmap = {v: k for k, v in enumerate(gt_ids)}
    pmap = {v: k for k, v in enumerate(pr_ids)}
    data = {"gt_ids": [], "tracker_ids": [], "similarity_scores": [], "num_timesteps": n_t,
            "num_gt_ids": len(gt_ids), "num_tracker_ids": len(pr_ids), "num_gt_dets": 0,
            "num_tracker_dets": 0}
    for t in range(1, n_t + 1):
        g, p = gt.get(t, []), pred.get(t, [])
        data["gt_ids"].append(np.array([gmap[i] for i, _ in g], dtype=int))
        data["tracker_ids"].append(np.array([pmap[i] for i, _ in p], dtype=int))
        gb = np.array([b for _, b in g], dtype=float).reshape(-1, 4)
        pb = np.array([b for _, b in p], dtype=float).reshape(-1, 4)
        data["similarity_scores"].append(_BaseDataset._calculate_box_ious(gb, pb, box_format="xywh"))
        data["num_gt_dets"] += len(g)
        data["num_tracker_dets"] += len(p)
    return data


def score(data):
    out = {}
    hota = HOTA().eval_sequence(data)
    for k in ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr"):
        out[k] = float(np.mean(hota[k]))  # averaged over α = 0.05 … 0.95, as TrackEval reports
    out["HOTA_per_alpha"] = [float(v) for v in hota["HOTA"]]
    clear = CLEAR({"THRESHOLD": 0.5, "PRINT_CONFIG": False}).eval_sequence(data)
    for k in ("MOTA", "MOTP", "MODA", "CLR_Re", "CLR_Pr"):
        out[k] = float(clear[k])
    for k in ("CLR_TP", "CLR_FN", "CLR_FP", "IDSW", "Frag", "MT", "PT", "ML"):
        out[k] = int(clear[k])
    ident = Identity({"THRESHOLD": 0.5, "PRINT_CONFIG": False}).eval_sequence(data)
    for k in ("IDF1", "IDP", "IDR"):
        out[k] = float(ident[k])
    for k in ("IDTP", "IDFP", "IDFN"):
        out[k] = int(ident[k])
    out["num_gt_ids"] = data["num_gt_ids"]
    return out


def write_gaps():
    """A small sequence for the conventions around empty frames, which the long one never has:
    frame 6 has truth but no tracker boxes, frame 9 tracker boxes but no truth, frame 12 nothing;
    the tracks run across all three. Boxes are offset by a few pixels, so IoU < 1."""
    gt, pr = [], []
    for f in range(1, 16):
        for o, (x0, y0) in enumerate(((10.0, 20.0), (200.0, 40.0), (90.0, 150.0))):
            x, y = x0 + 3.0 * f, y0 + 1.5 * f
            if f not in (9, 12):
                gt.append((f, o + 1, x, y, 40.0, 80.0))
            if f in (6, 12) or (o == 2 and f in (3, 4)):
                continue
            pid = o + 11 if not (o == 1 and f >= 10) else 21   # object 2 changes id at frame 10
            pr.append((f, pid, x + 2.0 + 0.5 * o, y - 3.0 + 0.25 * f, 41.0, 78.0))
        if f in (5, 9):
            pr.append((f, 99, 300.0, 300.0, 40.0, 80.0))      # a false positive
    for path, rows in (("gaps-gt.txt", gt), ("gaps-pred.txt", pr)):
        with open(path, "w") as fh:
            for r in sorted(rows):
                fh.write("%d,%d,%.3f,%.3f,%.3f,%.3f,1,-1,-1,-1\n" % r)


if __name__ == "__main__":
    write_gaps()
    gaps = score(sequence("gaps-gt.txt", "gaps-pred.txt"))
    out = score(sequence("synthetic-gt.txt", "synthetic-pred.txt"))
    out["gaps"] = gaps
    out["generator"] = ("TrackEval (sn-trackeval %s) HOTA, CLEAR and Identity metric classes, "
                        "THRESHOLD 0.5, numpy %s" % (getattr(trackeval, "__version__", "0.4.0"), np.__version__))
    with open("synthetic-trackeval.json", "w") as fh:
        json.dump(out, fh, indent=2, sort_keys=True)
    print(json.dumps(out, indent=1))
