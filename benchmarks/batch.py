"""``motiontrack batch``: what running many videos on Dask costs and gains.

16 short ``synth:`` scenes (``walker`` and ``crossing``, 8 seeds each, ``--frames`` frames,
no annotated video) are tracked three ways, each into a fresh folder:

1. serially in this process, ``track_job(...).run()`` one after another (no Dask), once with
   OpenCV's default threads and once with one OpenCV thread, as batch workers run;
2. ``run_batch(..., jobs=1)``: a local cluster of one worker process;
3. ``run_batch(..., jobs=2)``: a local cluster of two worker processes.

Reported: the wall time of each, the ratio ``-j 2`` / serial, and the batch machinery's
overhead per video, ``(batch -j 1 - serial with one OpenCV thread) / videos`` (task submission and results over the
scheduler, the partial folder and its rename, the index rewritten after each video, the
combined metrics). The batch times are of ``run_batch`` on a client already started, its
workers having imported the pipeline; starting that cluster is reported apart (once per
batch, not per video). The tracks of every video are checked identical across the three ways.

Run: .venv/bin/python benchmarks/batch.py [--frames 100] [--videos 16]
"""

from __future__ import annotations

import argparse
import json
import logging
import tempfile
import time
from pathlib import Path

import cv2

from motiontrack.batch import run_batch
from motiontrack.config import PipelineConfig, apply_overrides
from motiontrack.run.executor import dask_client
from motiontrack.run.jobs import track_job


def _warm() -> None:
    import motiontrack.batch.runner  # noqa: F401
    import motiontrack.run.jobs  # noqa: F401


def main() -> None:
    logging.getLogger("distributed").setLevel(logging.CRITICAL)   # shutdown chatter
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=100)
    ap.add_argument("--videos", type=int, default=16)
    args = ap.parse_args()
    cfg = apply_overrides(PipelineConfig(), ["output.video=false"])
    scenes = [f"synth:{kind}?n_frames={args.frames}&seed={seed}"
              for seed in range(args.videos // 2) for kind in ("walker", "crossing")]
    names = [f"v{i:02d}" for i in range(len(scenes))]
    with tempfile.TemporaryDirectory(prefix="mt-batch-bench-") as tmp:
        base = Path(tmp)
        # the batch names repeats synth-walker, synth-walker-2, ...: same order as scenes
        t0 = time.perf_counter()
        for name, src in zip(names, scenes):
            track_job(src, cfg, base / "serial" / name).run()
        serial = time.perf_counter() - t0
        threads = cv2.getNumThreads()
        cv2.setNumThreads(1)
        t0 = time.perf_counter()
        for name, src in zip(names, scenes):
            track_job(src, cfg, base / "serial1" / name).run()
        serial_one_thread = time.perf_counter() - t0
        cv2.setNumThreads(threads)

        walls, starts = {}, {}
        for jobs in (1, 2):
            t0 = time.perf_counter()
            with dask_client(jobs=jobs) as client:
                # each worker imports the pipeline once, as its first video would
                client.run(_warm)
                starts[jobs] = time.perf_counter() - t0
                t0 = time.perf_counter()
                rows = run_batch(scenes, base / f"j{jobs}", cfg, client=client, timeout_s=None)
                walls[jobs] = time.perf_counter() - t0
            assert all(r["status"] == "done" for r in rows), rows
            for name, row in zip(names, rows):
                assert ((base / f"j{jobs}" / row["name"] / "tracks.txt").read_bytes()
                        == (base / "serial" / name / "tracks.txt").read_bytes()), row["name"]
        n = len(scenes)
        print(json.dumps({
            "videos": n, "frames_per_video": args.frames,
            "serial_s": round(serial, 2), "serial_one_opencv_thread_s": round(serial_one_thread, 2),
            "batch_j1_s": round(walls[1], 2),
            "batch_j2_s": round(walls[2], 2),
            "ratio_j2_over_serial": round(walls[2] / serial, 3),
            "cluster_start_j1_s": round(starts[1], 2), "cluster_start_j2_s": round(starts[2], 2),
            "overhead_per_video_s": round((walls[1] - serial_one_thread) / n, 3),
        }, indent=2))


if __name__ == "__main__":
    main()
