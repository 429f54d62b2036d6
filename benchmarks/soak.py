"""Soak test: 20,000 synthetic frames through the whole `track` job; memory must stay flat.

A crowd scene is replayed in a loop (people keep entering, crossing and leaving, so tracks are
born and deleted all the time) through the `track` job (`motiontrack.run.track_job`) with the tracks file and summary written as in
`motiontrack track --no-video`. Peak RSS is reported at 1k, 10k and 20k frames; the target is a
growth under 10% from 1k to 20k frames.

With --video the annotated video (the default codec) is written too, and the resident memory is
printed every 1,000 frames: the encoder's queue and state must not grow either.

Run: .venv/bin/python benchmarks/soak.py [--frames 20000] [--video]
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from typing import Iterator

from motiontrack.config import load_config
from motiontrack.io.sources import Source, SourceInfo
from motiontrack.run import track_job
from motiontrack.synth import make_scene
from motiontrack.types import Frame


class LoopedScene(Source):
    """A synthetic scene replayed end to end for ``n`` frames (no ground truth)."""

    def __init__(self, n: int) -> None:
        super().__init__()
        self.scene = make_scene("crowd", seed=1)
        self.n = n
        s = self.scene
        self.info = SourceInfo(name="looped synth:crowd", width=s.width, height=s.height,
                               fps=float(s.fps), frame_count=n)

    def __iter__(self) -> Iterator[Frame]:
        period = self.scene.n_frames
        for i in range(self.n):
            yield Frame(index=i, image=self.scene.frame(i % period), timestamp=i / self.scene.fps)


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux


def rss_mb() -> float:
    """The resident memory now (Linux), MB."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() / 1024.0 / 1024.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=20000)
    ap.add_argument("--video", action="store_true", help="write the annotated video too")
    args = ap.parse_args()
    checkpoints = sorted({c for c in (1000, 10000, 20000, args.frames) if c <= args.frames})
    marks: dict[int, float] = {}
    done = 0

    def progress(k: int) -> None:
        nonlocal done
        done += k
        if args.video and done % 1000 == 0:
            print(f"  {done:>6} frames: RSS {rss_mb():.1f} MB, peak {peak_rss_mb():.1f} MB",
                  flush=True)
        if done in checkpoints:
            marks[done] = peak_rss_mb()
            print(f"  {done:>6} frames: peak RSS {marks[done]:.1f} MB "
                  f"({time.perf_counter() - t0:.0f} s)", flush=True)

    cfg = load_config(None, [f"output.video={'true' if args.video else 'false'}"])
    with tempfile.TemporaryDirectory() as out:
        job = track_job(LoopedScene(args.frames), cfg, out, force=True)
        t0 = time.perf_counter()
        summary = job.run(progress=progress)
    first, last = marks[checkpoints[0]], marks[checkpoints[-1]]
    growth = (last - first) / first
    print(f"soak: {summary.frames} frames, {summary.tracks} track ids, {summary.fps:.0f} fps; "
          f"peak RSS {first:.1f} MB at {checkpoints[0]} frames -> {last:.1f} MB at "
          f"{checkpoints[-1]} frames: growth {growth * 100:.1f}% (target < 10%: "
          f"{'met' if growth < 0.10 else 'MISSED'})")


if __name__ == "__main__":
    main()
