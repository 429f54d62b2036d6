#!/usr/bin/env python3
"""Speed of HOTA + CLEAR + Identity against TrackEval, on one core, with identical numbers.

Inputs: a synthetic sequence (default 5,000 frames x 30 objects, deterministic) and TUD-Campus
from the shared data. Ours is timed in-process (reading the MOT files + preprocessing + the three
metric families, best of ``--repeat``); TrackEval runs in its own virtual environment through
``tools/trackeval_golden.py`` in a subprocess, which times ``Evaluator.evaluate`` (its file
loading + preprocessing + metrics, without interpreter start-up and imports).

    .venv/bin/python benchmarks/evaluate.py --trackeval-python /tmp/te-venv/bin/python

``--trackeval-python`` defaults to ``$TRACKEVAL_PYTHON``; without it only our times are printed.
The process (and so the subprocess) is pinned to one CPU and BLAS threads are set to 1.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from motiontrack.evaluate import mot  # noqa: E402
from motiontrack.io.mot import read_mot  # noqa: E402


def synthetic(frames: int, objects: int, seed: int = 0) -> tuple[str, str]:
    """MOT15-style gt and tracker text: ``objects`` walkers alive at a time (each lives 50-400
    frames, replaced on death), the tracker jitters boxes, misses 10 %, swaps ids now and then,
    and adds ~2 false positives per frame."""
    rng = np.random.default_rng(seed)
    gt_rows, tr_rows = [], []
    next_id = 1
    state = []  # [id, x, y, vx, vy, w, h, death, tracker id]
    for f in range(1, frames + 1):
        state = [s for s in state if s[7] > f]
        while len(state) < objects:
            w = rng.uniform(20, 60)
            state.append([next_id, rng.uniform(0, 1800), rng.uniform(0, 1000), rng.normal(0, 2),
                          rng.normal(0, 1), w, w * rng.uniform(2, 3), f + rng.integers(50, 400),
                          next_id + 100000])
            next_id += 1
        if f % 25 == 0 and len(state) > 2:  # an identity switch between two tracks
            i, j = rng.choice(len(state), 2, replace=False)
            state[i][8], state[j][8] = state[j][8], state[i][8]
        for s in state:
            s[1] += s[3]
            s[2] += s[4]
            gt_rows.append(f"{f},{s[0]},{s[1]:.2f},{s[2]:.2f},{s[5]:.2f},{s[6]:.2f},1,-1,-1,-1\n")
            if rng.random() < 0.9:
                j = rng.normal(0, 0.08, 4) * [s[5], s[6], s[5], s[6]]
                tr_rows.append(f"{f},{s[8]},{s[1] + j[0]:.2f},{s[2] + j[1]:.2f},"
                               f"{s[5] + abs(j[2]):.2f},{s[6] + abs(j[3]):.2f},1,-1,-1,-1\n")
        for k in range(rng.poisson(2)):
            tr_rows.append(f"{f},{900000 + f * 10 + k},{rng.uniform(0, 1800):.2f},"
                           f"{rng.uniform(0, 1000):.2f},40,100,1,-1,-1,-1\n")
    return "".join(gt_rows), "".join(tr_rows)


def ours(gt: Path, pred: Path, length: int, repeat: int) -> tuple[float, float, dict]:
    """Best-of-``repeat`` seconds for reading both files and for the metrics, and the results."""
    t_read = t_eval = float("inf")
    res: dict = {}
    for _ in range(repeat):
        t0 = time.perf_counter()
        g = read_mot(gt, kind="gt")
        p = read_mot(pred, kind="results")
        t1 = time.perf_counter()
        res = mot.evaluate_sequence(g, p, num_timesteps=length)
        t2 = time.perf_counter()
        t_read, t_eval = min(t_read, t1 - t0), min(t_eval, t2 - t1)
    return t_read, t_eval, res


def trackeval(python: str, gt: Path, pred: Path, length: int, benchmark: str) -> tuple[float, dict]:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "te.json"
        subprocess.run([python, str(REPO / "tools" / "trackeval_golden.py"), "--name", "bench",
                        "--benchmark", benchmark, "--gt", str(gt), "--pred", str(pred),
                        "--seq-name", "SEQ", "--length", str(length), "--keep-time",
                        "--out", str(out)], check=True, capture_output=True)
        d = json.loads(out.read_text())
    return d["elapsed_s"], d["sequences"]["SEQ"]


def max_diff(res: dict, ref: dict) -> float:
    ours_flat = {k: v for fam in res.values() for k, v in fam.items()}
    return max(float(np.max(np.abs(np.asarray(ours_flat[k], float) - np.asarray(v, float))))
               for k, v in ref.items())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=5000)
    ap.add_argument("--objects", type=int, default=30)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--data", type=Path,
                    default=Path(os.environ.get("MOTIONTRACK_DATA", REPO.parent / "shared" / "data")))
    ap.add_argument("--trackeval-python", default=os.environ.get("TRACKEVAL_PYTHON"))
    a = ap.parse_args(argv)
    try:
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        pass
    with tempfile.TemporaryDirectory() as tmp:
        gt_text, tr_text = synthetic(a.frames, a.objects)
        sg, sp = Path(tmp) / "gt.txt", Path(tmp) / "pred.txt"
        sg.write_text(gt_text)
        sp.write_text(tr_text)
        cases = [(f"synthetic {a.frames}x{a.objects}", sg, sp, a.frames, "MOT15")]
        tud = a.data / "tud-campus"
        if (tud / "gt.txt").is_file():
            cases.append(("TUD-Campus", tud / "gt.txt", tud / "test.txt", 71, "MOT15"))
        rows = []
        for name, g, p, length, bench in cases:
            t_read, t_eval, res = ours(g, p, length, a.repeat)
            t_ours = t_read + t_eval
            row = {"case": name, "gt boxes": len(read_mot(g, kind="gt")), "ours read s": t_read,
                   "ours metrics s": t_eval, "ours total s": t_ours,
                   "HOTA": float(np.mean(res["hota"]["HOTA"])), "MOTA": res["clear"]["MOTA"],
                   "IDF1": res["identity"]["IDF1"]}
            if a.trackeval_python:
                t_te, ref = trackeval(a.trackeval_python, g, p, length, bench)
                d = max_diff(res, ref)
                row.update({"TrackEval s": t_te, "speed-up": t_te / t_ours,
                            "speed-up metrics": t_te / t_eval,
                            "max |diff|": d, "identical (1e-6)": d <= 1e-6})
            rows.append(row)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    print("one core; 'speed-up' = TrackEval (load + preprocess + metrics) / ours (read_mot + "
          "metrics); 'speed-up metrics' leaves out our file reading")

    def fmt(v):
        if isinstance(v, bool):
            return "yes" if v else "NO"
        if isinstance(v, float):
            return f"{v:.3g}" if abs(v) < 1e-3 and v else f"{v:.3f}"
        return str(v)

    table = [keys] + [[fmt(r.get(k, "-")) for k in keys] for r in rows]
    w = [max(len(t[i]) for t in table) for i in range(len(keys))]
    for i, t in enumerate(table):
        print("  ".join(c.ljust(x) for c, x in zip(t, w)))
        if i == 0:
            print("-" * (sum(w) + 2 * (len(w) - 1)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
