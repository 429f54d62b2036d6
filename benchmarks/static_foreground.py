"""Cost of the dual background (static foreground for ``abandoned``) next to the motion detector.

Every frame of each source is decoded and preprocessed once (the pipeline's own preprocessing
at its processing scale); then the default motion detector and
:class:`motiontrack.motion.static.DualBackground` each run over all of them, ``--repeat`` times;
the best time per frame of each is printed (the machine may be busy: the best run is the one
least disturbed), and the dual background's share of the detector's time.

Run: .venv/bin/python benchmarks/static_foreground.py [--data ../shared/data] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from motiontrack.config import PipelineConfig
from motiontrack.motion import create_detector
from motiontrack.motion.static import DualBackground
from motiontrack.pipeline import Pipeline, open_configured_source

REPO = Path(__file__).resolve().parents[1]


def best_ms(make, frames, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        model = make()
        t = time.perf_counter()
        for f in frames:
            model.apply(f)
        best = min(best, (time.perf_counter() - t) / len(frames) * 1e3)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=os.environ.get("MOTIONTRACK_DATA",
                                                     str(REPO.parent / "shared" / "data")))
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    sources = ["synth:leftbag?seed=0"]
    pets = Path(args.data) / "pets09-s2l1" / "video.avi"
    if pets.exists():
        sources.append(str(pets))
    cfg = PipelineConfig()
    print(f"{'source':42s} {'size':>9s} {'detector ms':>11s} {'dual ms':>8s} {'share':>6s}")
    for spec in sources:
        src = open_configured_source(spec, cfg.source)
        fps = src.info.fps or 25.0
        pipe = Pipeline(cfg, (src.info.width, src.info.height), fps=fps)
        frames = [pipe.prepare(f) for f in src]
        src.close()
        det = best_ms(lambda: create_detector(cfg.motion), frames, args.repeat)
        dual = best_ms(lambda: DualBackground(fps, pipe.scale), frames, args.repeat)
        h, w = frames[0].shape[:2]
        print(f"{spec[-42:]:42s} {w:>4d}x{h:<4d} {det:11.2f} {dual:8.2f} {dual / det:6.0%}")


if __name__ == "__main__":
    main()
