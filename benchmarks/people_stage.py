"""The people stage alone: CPU time per frame of `--preset people`'s heads, head splitting and
active shapes on PETS, steady on a machine shared with other work.

The pipeline runs the clip once with the people preset and keeps what the people stage is given
each frame (mask, background, preprocessed frame, regions, the previous frame's tracks). Then the
stage is run on those inputs alone, in chunks of ``--chunk`` frames: each chunk ``--repeat``
times from a copy of the stage's state, its least thread CPU time kept; the report is the sum of
those minima per frame (the minimum filters out the time other processes take from this one),
for the whole stage and for its head detector and splitting alone. The outputs of every run are
checked equal to the pipeline's own.

Run: .venv/bin/python benchmarks/people_stage.py [--data ../shared/data] [--frames 300]
     [--repeat 5] [--chunk 10]
"""

from __future__ import annotations

import argparse
import copy
import sys
import time

import numpy as np

from motiontrack.config import load_config
from motiontrack.people import stage as people_stage
from motiontrack.pipeline import run

from _pets import add_data_argument, pets_video  # benchmarks/ is on sys.path when a script here runs


def record(video: str, frames: int) -> tuple[list[tuple], list[tuple]]:
    """The people stage's inputs and outputs of each frame of a ``--preset people`` run (the
    frame image itself as its shape: the preset's stage reads only its size)."""
    calls, outs = [], []
    process = people_stage.PeopleStage.process

    def copied(a):
        return None if a is None else a.copy()

    def recording(self, frame_img, background, mask, regions, tracks, work=None):
        out = process(self, frame_img, background, mask, regions, tracks, work=work)
        calls.append((frame_img.shape, copied(background), copied(mask), list(regions),
                      list(tracks), copied(work)))
        outs.append(out)
        return out

    people_stage.PeopleStage.process = recording
    try:
        for _ in run(video, load_config(None, [f"source.max_frames={frames}"], preset="people")):
            pass
    finally:
        people_stage.PeopleStage.process = process
    return calls, outs


def replay(calls: list[tuple], outs: list[tuple], repeat: int, chunk: int) -> tuple[float, float]:
    """Seconds of thread CPU of the stage and of its heads step over ``calls`` (see the module
    docstring); exits when a replay's outputs differ from the recorded ones."""
    cfg = load_config(None, [], preset="people").people
    stage = people_stage.PeopleStage(cfg)
    total = heads = 0.0
    for s in range(0, len(calls), chunk):
        part = calls[s:s + chunk]
        best = best_heads = float("inf")
        for _ in range(max(1, repeat)):
            st = copy.deepcopy(stage)
            got = []
            t = time.thread_time()
            for shape, bg, mask, regions, tracks, work in part:
                frame = np.broadcast_to(np.uint8(0), shape)
                got.append(st.process(frame, bg, mask, regions, tracks, work=work))
            best = min(best, time.thread_time() - t)
            t = time.thread_time()
            for shape, _, mask, regions, _, _ in part:
                st.split_regions(mask, regions, shape[1])
            best_heads = min(best_heads, time.thread_time() - t)
            if not _same(got, outs[s:s + chunk]):
                sys.exit(f"frames {s + 1}-{s + len(part)}: the replayed people stage differs")
        stage = st
        total += best
        heads += best_heads
    return total, heads


def _same(a, b) -> bool:
    """Whether two outputs of the stage are equal, arrays and every field included."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(a, b)
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if hasattr(a, "__dataclass_fields__"):
        return type(a) is type(b) and all(_same(getattr(a, k), getattr(b, k))
                                          for k in a.__dataclass_fields__)
    return a == b


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    add_data_argument(ap)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=5, help="runs per chunk; the least CPU counts")
    ap.add_argument("--chunk", type=int, default=10, help="frames per chunk")
    args = ap.parse_args()
    video = str(pets_video(args.data))
    calls, outs = record(video, args.frames)
    total, heads = replay(calls, outs, args.repeat, args.chunk)
    n = max(len(calls), 1)
    print(f"PETS09-S2L1, {len(calls)} frames, --preset people's people stage alone "
          f"(thread CPU, the least of {args.repeat} runs per {args.chunk} frames)")
    print(f"people stage          {1000 * total / n:6.2f} ms/frame")
    print(f"  heads + splitting   {1000 * heads / n:6.2f} ms/frame")
    print(f"  the rest (shapes)   {1000 * (total - heads) / n:6.2f} ms/frame")


if __name__ == "__main__":
    main()
