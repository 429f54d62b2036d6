"""Still people, a left object, distant walkers and shadows on real footage: the four SBI2015
sequences with per-pixel ground truth (../shared/data/sbi, CDnet layout).

For each sequence and row of settings, ``track --scene`` is run in this process over every frame
(the pipeline with a scene of one ``[stationary]`` rule: 10 s within a twentieth of the frame's
height) and prints

* pixel precision, recall and F of the reported mask (``FrameResult.mask``, what
  ``--mask-video`` writes), as ``evaluate-masks`` counts them (ROI.bmp, label 170 not scored);
* tracks reported over at least 1 s (25 frames: the SBI clips were recorded at about 25 fps),
  and that number over the people in the sequence (counted by eye: HumanBody2 four people who
  walk in and out, HallAndMonitor two people and a bag, CAVIAR2 six walkers; HighwayII's cars
  are not counted);
* ``stationary_start`` alarms;
* CPU seconds a frame of the whole pipeline (this process, every thread).

``--row NAME=KEY=VALUE,KEY=VALUE`` adds a row with those ``--set`` overrides (repeatable; the
first row is the defaults); ``--seqs`` picks sequences.

Run: .venv/bin/python benchmarks/still_people.py [--data ../shared/data] [--seqs HumanBody2,...]
         [--row NAME=KEY=V,...] [-j 2]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import tomllib
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import cv2

from motiontrack.analytics import Analytics, parse_scene
from motiontrack.config import load_config
from motiontrack.evaluate.masks import MaskCounts, compare_masks, read_roi
from motiontrack.pipeline import open_configured_source
from motiontrack.run.processors import TrackProcessor
from motiontrack.types import frame_number

from _rows import parse_row  # benchmarks/ is on sys.path when a script here runs

#: the sequences and the people in each (None: not counted)
PEOPLE = {"HumanBody2": 4, "HallAndMonitor": 2, "CAVIAR2": 6, "HighwayII": None}
#: the clips' rate (not recorded with the data)
FPS = 25.0
#: frames a track must be reported over to count
LONG = 25


def scene_text(height: int) -> str:
    return f"[stationary]\nafter_s = 10\nradius_px = {height / 20:.1f}\n"


def run_sequence(folder: Path, sets: list[str]) -> dict:
    """One sequence through the pipeline with a stationary rule: mask counts, tracks, alarms."""
    cfg = load_config(None, [f"source.fps={FPS}", *sets])
    source = open_configured_source(str(folder / "input" / "*.jpg"), cfg.source)
    info = source.info
    analytics = Analytics(parse_scene(tomllib.loads(scene_text(info.height))), FPS)
    proc = TrackProcessor(cfg, info, analytics=analytics)
    roi = read_roi(folder / "ROI.bmp")
    counts = MaskCounts()
    spans: dict[int, list[int]] = {}
    alarms = 0
    t0 = time.process_time()
    try:
        for res in proc.results(source):
            f = frame_number(res.index)
            g = cv2.imread(str(folder / "groundtruth" / f"gt{f:06d}.png"), cv2.IMREAD_GRAYSCALE)
            m = res.mask
            if m is not None and g is not None:
                if m.shape != g.shape:
                    m = cv2.resize(m, (g.shape[1], g.shape[0]), interpolation=cv2.INTER_NEAREST)
                counts = counts + compare_masks(g, m, roi)
            for t in res.tracks:
                spans.setdefault(t.id, [f, f])[1] = f
            alarms += sum(e.type == "stationary_start" for e in res.scene.events)
    finally:
        source.close()
    cpu = time.process_time() - t0
    frames = max((s[1] for s in spans.values()), default=0)
    m = counts.metrics()
    return {"p": m["precision"], "r": m["recall"], "f": m["f_measure"],
            "long": sum(b - a + 1 >= LONG for a, b in spans.values()), "alarms": alarms,
            "cpu_ms": 1000 * cpu / max(info.frame_count or frames, 1)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=os.environ.get(
        "MOTIONTRACK_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"))
    ap.add_argument("--seqs", default=",".join(PEOPLE))
    ap.add_argument("--row", action="append", type=parse_row, default=[],
                    help="NAME=KEY=VALUE,...: a row with these --set overrides")
    ap.add_argument("-j", type=int, default=2, help="processes")
    args = ap.parse_args(argv)
    seqs = args.seqs.split(",")
    sbi = Path(args.data) / "sbi"
    for s in seqs:
        if not (sbi / s / "input").is_dir():
            sys.exit(f"SBI sequence not found: {sbi / s} (set MOTIONTRACK_DATA or --data)")
    rows = [("defaults", []), *args.row]
    jobs = [(name, s, sets) for name, sets in rows for s in seqs]
    with ProcessPoolExecutor(args.j) as pool:
        done = list(pool.map(run_sequence, [sbi / s for _, s, _ in jobs],
                             [sets for _, _, sets in jobs]))
    print("SBI2015 sequences at 25 fps: pixel P/R/F of the reported mask, tracks of >= 1 s "
          "(per person), stationary_start alarms (10 s within H/20), CPU ms a frame")
    print(f"{'row':<24}{'sequence':<16}{'P':>7}{'R':>7}{'F':>7}{'tracks':>8}{'/person':>9}"
          f"{'alarms':>8}{'cpu ms':>8}")
    for (name, s, _), r in zip(jobs, done):
        people = PEOPLE.get(s)
        per = f"{r['long'] / people:.1f}" if people else "-"
        print(f"{name[:23]:<24}{s:<16}{r['p']:>7.3f}{r['r']:>7.3f}{r['f']:>7.3f}{r['long']:>8}"
              f"{per:>9}{r['alarms']:>8}{r['cpu_ms']:>8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
