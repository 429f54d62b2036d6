"""Walking speeds on PETS 2009 S2L1 against the ground truth's world positions.

Tracks the clip with the PETS calibration (``track --camera View_001.xml``, no video), or reads
a given ``tracks.txt`` with world columns, pairs every track with its majority ground-truth
person and prints both mean speeds over the frames where they are matched
(:mod:`motiontrack.evaluate.speeds`) and the median absolute difference.

Run: .venv/bin/python benchmarks/pets_speeds.py [--data ../shared/data] [--tracks tracks.txt]
"""

from __future__ import annotations

import argparse
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from motiontrack.config import PipelineConfig
from motiontrack.evaluate.speeds import speed_pairs
from motiontrack.io.mot import read_mot
from motiontrack.run import track_job

from _pets import add_data_argument, pets_video  # benchmarks/ is on sys.path when a script here runs


def pets_tracks_with_world(video: Path, out: Path) -> Path:
    """``track VIDEO --camera View_001.xml --no-video -o out``; returns ``tracks.txt``."""
    cfg = PipelineConfig()
    cfg = replace(cfg, output=replace(cfg.output, video=False),
                  measure=replace(cfg.measure, camera=str(video.parent / "View_001.xml")))
    track_job(str(video), cfg, out, force=True).run()
    return out / "tracks.txt"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    add_data_argument(ap)
    ap.add_argument("--tracks", type=Path, default=None,
                    help="tracks.txt with world columns (default: track the clip now)")
    ap.add_argument("--window-s", type=float, default=1.0,
                    help="window of each speed, seconds (default 1; 0.1 is one frame at 10 fps)")
    args = ap.parse_args()
    video = pets_video(args.data)
    gt = read_mot(video.parent / "gt_mot15.txt", kind="gt")
    with tempfile.TemporaryDirectory() as d:
        tracks = args.tracks or pets_tracks_with_world(video, Path(d))
        pred = read_mot(tracks)
    fps = 10.0   # the clip's stored rate, used for both: see the module docstring of speeds
    rows = speed_pairs(gt, pred, fps, window_s=args.window_s)
    print(f"{'track':>5} {'gt':>4} {'frames':>6} {'ours m/s':>9} {'gt m/s':>7} {'diff':>6}")
    for r in rows:
        print(f"{r['track']:>5} {r['gt']:>4} {r['frames']:>6} {r['speed_mps']:>9.2f} "
              f"{r['gt_speed_mps']:>7.2f} {r['diff_mps']:>+6.2f}")
    d = np.abs([r["diff_mps"] for r in rows])
    print(f"{len(rows)} tracks; median |difference| {np.median(d):.3f} m/s "
          f"(window {args.window_s:g} s)")


if __name__ == "__main__":
    main()
