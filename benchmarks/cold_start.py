"""Cold starts and the seed spread on PETS 2009 S2L1: the default pipeline started at several
frames of the clip, with several seeds of the KNN model.

A run started at frame S learns its background from the frames it sees, so people standing in
frame S become background (missed while they stand; a ghost where they stood once they walk), and
people who move in the first frames leave short ghosts. This is what footage that starts with
people in view looks like; a run from frame 1 is the special case of a nearly empty first frame.
Each run is scored on the frames it processed (S+1 to the last), CLEAR-MOT at IoU 0.5, Identity
and HOTA against gt_mot15.txt (rows with consider = 0 are ignore regions).

The KNN model draws random numbers (``motion.knn.seed``): the rows average over ``--seeds``
seeds, and the last line gives the range over every run, since one identity swap of a long track
moves IDF1 and HOTA by a few hundredths.

Run: .venv/bin/python benchmarks/cold_start.py [--data ../shared/data] [--starts 0,50,100,150]
     [--seeds 5] [--set stage.param=value ...] [--jobs 2]
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from motiontrack.config import load_config
from motiontrack.io.mot import read_mot

from _pets import KEYS, add_data_argument, pets_video, score_tracks  # benchmarks/ is on sys.path when a script here runs



def one(video: str, gt_path: str, start: int, seed: int, overrides: list[str]) -> dict[str, float]:
    """Scores of the default pipeline (plus ``overrides``) started at frame ``start`` (0-based)."""
    cfg = load_config(None, [*overrides, f"source.start={start}", f"motion.knn.seed={seed}"])
    gt = read_mot(gt_path, kind="gt")
    # the run goes to the end of the clip (and of its gt)
    return score_tracks(video, cfg, gt.select(gt.frames > start))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_data_argument(ap)
    ap.add_argument("--starts", default="0,50,100,150", help="0-based first frames")
    ap.add_argument("--seeds", type=int, default=5, help="KNN seeds 0 .. N-1")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="STAGE.PARAM=VALUE")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    video = pets_video(args.data)
    gt = video.parent / "gt_mot15.txt"
    starts = [int(s) for s in args.starts.split(",")]
    cases = [(s, k) for s in starts for k in range(args.seeds)]
    with ProcessPoolExecutor(args.jobs) as ex:
        futures = [ex.submit(one, str(video), str(gt), s, k, args.overrides) for s, k in cases]
        results = [f.result() for f in futures]
    print(f"PETS09-S2L1 frames 1-300, default pipeline{' with ' + ' '.join(args.overrides) if args.overrides else ''}, "
          f"mean of KNN seeds 0-{args.seeds - 1}")
    print(f"{'first frame':<14}" + "".join(f"{k:>10}" for k in KEYS))

    def row(name: str, rs: list[dict[str, float]]) -> None:
        print(f"{name:<14}" + "".join(f"{np.mean([r[k] for r in rs]):>10.3f}" if k != "IDSW"
                                      else f"{np.mean([r[k] for r in rs]):>10.1f}" for k in KEYS))

    for s in starts:
        row(f"{s + 1}", [r for (ss, _), r in zip(cases, results) if ss == s])
    row("all", results)
    print("range over runs: " + ", ".join(
        f"{k} {min(r[k] for r in results):.3f}-{max(r[k] for r in results):.3f}" for k in KEYS[:3]))


if __name__ == "__main__":
    main()
