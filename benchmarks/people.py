"""People preset speed and accuracy on the 768x576 PETS clip; target >= 25 frames/s on 2 cores.

Rows (one process): the default pipeline, the preset without the shape tracker (head-based
splitting only), `--preset people` (heads, head-based splitting, active shape tracker), and the
preset with shape hypotheses and HOG in motion regions every 5th frame.
Frames are decoded inside the timing; no video is written. Each row is the fastest of --repeat
runs (this 2-core machine's timings vary by 20% or more from run to run), with the process's CPU
time per frame (user + system, every thread; the least of the runs): on a machine shared with
other work the CPU time is the steadier measure.

Run: .venv/bin/python benchmarks/people.py [--frames 300] [--repeat 3]
"""

from __future__ import annotations

import os
import time

import numpy as np

from motiontrack.config import load_config
from motiontrack.evaluate.mot import evaluate_tracking
from motiontrack.pipeline import run
from motiontrack.types import Annotations

from _pets import pets_args  # benchmarks/ is on sys.path when a script here runs

VARIANTS = (
    ("default pipeline", None, ()),
    ("people, heads only (no shapes)", "people", ("people.shapes=false",)),
    ("--preset people", "people", ()),
    ("people + hypotheses + HOG/5", "people",
     ("people.hypotheses=true", "people.hog=regions", "people.hog_every=5")),
)


def main() -> None:
    args, video, gt = pets_args(__doc__)
    gt = gt.select(gt.frames <= args.frames)
    print(f"PETS09-S2L1, {args.frames} frames of 768x576")
    print(f"{'variant':<30}{'fps':>8}{'CPU ms/f':>10}  {'recall':>7}{'prec':>7}{'MOTA':>7}"
          f"{'IDF1':>7}{'HOTA':>7}")
    for name, preset, overrides in VARIANTS:
        cfg = load_config(None, [f"source.max_frames={args.frames}", *overrides], preset=preset)
        fps, cpu_ms = 0.0, float("inf")
        for k in range(max(1, args.repeat)):
            rows = []
            c0, t0 = _cpu(), time.perf_counter()
            n = 0
            for res in run(str(video), cfg):
                rows += [(res.index + 1, t.id, *t.box.as_array()) for t in res.tracks]
                n += 1
            fps = max(fps, n / (time.perf_counter() - t0))
            cpu_ms = min(cpu_ms, 1000 * (_cpu() - c0) / max(n, 1))
        a = np.array(rows, float).reshape(-1, 6)
        r = evaluate_tracking(gt, Annotations.from_columns(a[:, 0], a[:, 1], a[:, 2:6]),
                              ignore_zero_marked=True)
        rec = r["TP"] / (r["TP"] + r["FN"])
        prec = r["TP"] / max(r["TP"] + r["FP"], 1)
        flag = "" if preset is None else ("  (target >= 25 fps: met)" if fps >= 25 else "  (MISSED)")
        print(f"{name:<30}{fps:>8.1f}{cpu_ms:>10.1f}  {rec:>7.3f}{prec:>7.3f}{r['MOTA']:>7.3f}"
              f"{r['IDF1']:>7.3f}{r['HOTA']:>7.3f}{flag}")


def _cpu() -> float:
    """CPU time of this process so far, every thread (s)."""
    t = os.times()
    return t.user + t.system


if __name__ == "__main__":
    main()
