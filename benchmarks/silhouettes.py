"""The mask a run reports: the regions' silhouettes against the mask as cleaned, scored pixel by
pixel on scenes with exact masks (CDnet's rules: shadow pixels negative).

Rows per scene:
  as cleaned         ``regions.silhouettes=false``: the mask the regions were found in
  not closed         its silhouettes without the closing (specks out, holes filled)
  closed             the same after a 3x3 closing
  default            what a run reports: closed while the scene's tracks are mostly vehicles

Scenes: the synthetic people scenes (walker, crossing, crowd, column; seed 0, frames from 30 on)
and ``mixed`` (people and cars), and CDnet highway frames 470-1000 (run from frame 1).

Run: .venv/bin/python benchmarks/silhouettes.py [--data ../shared/data] [--scenes walker,...,highway]
         [--frames N]
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import cv2
import numpy as np

from motiontrack.config import load_config
from motiontrack.evaluate.masks import MaskCounts, compare_masks, read_roi
from motiontrack.motion.regions import silhouettes, smallest_region
from motiontrack.pipeline import run
from motiontrack.synth import parse_synth_spec

SYNTH = ("walker", "crossing", "crowd", "column", "mixed")
ROWS = ("as cleaned", "not closed", "closed", "default")


def _scored(gt: np.ndarray, mask: np.ndarray, roi: np.ndarray | None) -> MaskCounts:
    if mask.shape != gt.shape:
        mask = cv2.resize(mask, (gt.shape[1], gt.shape[0]), interpolation=cv2.INTER_NEAREST)
    return compare_masks(gt, mask, roi)


def scene_counts(source: str, truth, first: int, roi=None,
                 overrides: tuple[str, ...] = ()) -> dict[str, MaskCounts]:
    """Counts of each row over the frames from index ``first`` on (``truth(i)`` is the gt mask of
    frame index ``i``)."""
    counts = {row: MaskCounts() for row in ROWS}
    cfg = load_config(None, ["regions.silhouettes=false", *overrides])
    with run(source, cfg) as r:
        for res in r:
            if res.index < first or res.mask is None:
                continue
            pipe = r.pipeline
            speck = smallest_region(cfg.regions, pipe.scale, pipe.image_size)
            gt = truth(res.index)
            counts["as cleaned"] += _scored(gt, res.mask, roi)
            counts["not closed"] += _scored(gt, silhouettes(res.mask, speck), roi)
            counts["closed"] += _scored(gt, silhouettes(res.mask, speck, close=True), roi)
    with run(source, load_config(None, list(overrides))) as r:
        for res in r:
            if res.index >= first and res.mask is not None:
                counts["default"] += _scored(truth(res.index), res.mask, roi)
    return counts


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default=os.environ.get(
        "MOTIONTRACK_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"))
    ap.add_argument("--scenes", default=",".join((*SYNTH, "highway")),
                    help="comma-separated: synthetic scene names and/or highway")
    ap.add_argument("--frames", type=int, default=0,
                    help="frames of each synthetic scene (0 = its own length)")
    args = ap.parse_args()
    wanted = args.scenes.split(",")
    print("pixel precision / recall / F of the reported mask (CDnet rules)")
    print(f"{'scene':<22}" + "".join(f"{row:>22}" for row in ROWS))
    scenes = []
    for name in (n for n in wanted if n != "highway"):
        spec = f"synth:{name}?seed=0"
        scene = parse_synth_spec(spec)
        frames = (f"source.max_frames={args.frames}",) if args.frames else ()
        scenes.append((name, spec, scene.foreground_mask, 30, None, frames))
    folder = Path(args.data) / "cdnet-highway"
    if "highway" in wanted and not (folder / "input").is_dir():
        print(f"(CDnet highway not found in {folder}: set MOTIONTRACK_DATA or --data)")
    elif "highway" in wanted:
        def truth(i: int, folder=folder) -> np.ndarray:
            return cv2.imread(str(folder / "groundtruth" / f"gt{i + 1:06d}.png"),
                              cv2.IMREAD_GRAYSCALE)
        scenes.append(("CDnet highway", str(folder / "input" / "*.jpg"), truth, 469,
                       read_roi(folder / "ROI.bmp"), ("source.max_frames=1000",)))
    for name, source, truth, first, roi, overrides in scenes:
        counts = scene_counts(source, truth, first, roi, overrides)
        cells = []
        for row in ROWS:
            m = counts[row].metrics()
            cells.append(f"{m['precision']:.3f}/{m['recall']:.3f}/{m['f_measure']:.3f}")
        print(f"{name:<22}" + "".join(f"{c:>22}" for c in cells), flush=True)


if __name__ == "__main__":
    main()
