"""Framewise (ViPER-style) metrics speed: 800 frames x 10 objects, target < 1 s.

Run: .venv/bin/python benchmarks/framewise.py
"""

from __future__ import annotations

import time

import numpy as np

from motiontrack.evaluate.framewise import evaluate_framewise
from motiontrack.types import Annotations


def main() -> None:
    rng = np.random.default_rng(0)
    frames = np.repeat(np.arange(1, 801), 10)
    ids = np.tile(np.arange(1, 11), 800)
    boxes = np.c_[rng.uniform(0, 700, (8000, 2)), rng.uniform(10, 120, (8000, 2))]
    gt = Annotations.from_columns(frames, ids, boxes)
    pred = Annotations.from_columns(frames, ids, boxes + rng.normal(0, 3, boxes.shape))
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        evaluate_framewise(gt, pred)
        times.append(time.perf_counter() - t0)
    best, median = min(times), float(np.median(times))
    print(f"framewise 800 frames x 10 objects: best {best:.3f} s, median {median:.3f} s "
          f"(target < 1 s: {'met' if median < 1.0 else 'MISSED'})")


if __name__ == "__main__":
    main()
