"""Sweep scale-out: 8 runs with ``-j 2`` against the same 8 runs serially, on 2 cores.

Both are measured in this process, one after the other, on the same machine; the ratio
parallel / serial is printed (target <= 0.6x; the ideal on 2 cores is 0.5x plus the cost of
spawning the worker processes). The tables of both executors must be identical.

Run: .venv/bin/python benchmarks/sweep.py [--frames 250] [--repeat 2]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from motiontrack.config import load_config
from motiontrack.studies.sweep import run_sweep, study_from_args


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=250, help="frames per run (synth:walker)")
    ap.add_argument("--repeat", type=int, default=2, help="repeats; the best of each is used")
    args = ap.parse_args()
    study = study_from_args(
        [f"synth:walker?n_frames={args.frames}"], None,
        ["motion.median.threshold=0.04:0.32:0.04"],               # 8 values → 8 runs
        load_config(None, ["motion.method=median"]))
    assert len(study.points()) == 8
    serial, parallel = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(args.repeat):
            for jobs, times in ((1, serial), (2, parallel)):
                out = Path(tmp) / f"j{jobs}-{rep}"
                t0 = time.perf_counter()
                run_sweep(study, out, jobs=jobs, figures=False)
                times.append(time.perf_counter() - t0)
        same = all((Path(tmp) / f"j2-{r}" / "results.csv").read_bytes()
                   == (Path(tmp) / "j1-0" / "results.csv").read_bytes() for r in range(args.repeat))
    s, p = min(serial), min(parallel)
    ratio = p / s
    print(f"sweep 8 runs x {args.frames} frames on {os.cpu_count()} cores: serial {s:.2f} s, "
          f"-j 2 {p:.2f} s, ratio {ratio:.2f}x (target <= 0.6x: {'met' if ratio <= 0.6 else 'MISSED'}); "
          f"tables identical: {same}")


if __name__ == "__main__":
    main()
