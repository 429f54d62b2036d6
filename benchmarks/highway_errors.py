"""What the default mask and boxes get wrong on CDnet highway (frames 470-1000, run from 1), and
what the light test sees there and on PETS.

  pixels   the reported mask's false positive pixels by ground-truth label (cast shadow 50, or
           static ground 0) and its false negatives
  merged   ground-truth cars (components >= 200 px) whose best track box has IoU < 0.5 and
           overlaps another car too (cars joined in one box), with KNN's vehicles' shadow
           threshold at 0.7 (the default) and at 0.8
  light    the regions whose mean colour passes the light test (``motion.light_share``'s first
           step): the share of their pixels lit one by one, and the spread of those pixels'
           gains, on highway and on PETS frames 1-795

Run: .venv/bin/python benchmarks/highway_errors.py [--data ../shared/data]
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import cv2
import numpy as np

from motiontrack.config import load_config
from motiontrack.evaluate.masks import read_roi
from motiontrack.motion import ghosts
from motiontrack.pipeline import run
from motiontrack.tracking.association import iou_matrix

# benchmarks/ is on sys.path when a script here runs
from highway import FIRST, LAST, gt_boxes


def pixel_errors(folder: Path) -> None:
    roi = read_roi(folder / "ROI.bmp")
    fp = {50: 0, 0: 0}
    fn = tp = 0
    with run(str(folder / "input" / "*.jpg"), load_config(None, [f"source.max_frames={LAST}"])) as r:
        for res in r:
            frame = res.index + 1
            if frame < FIRST:
                continue
            g = cv2.imread(str(folder / "groundtruth" / f"gt{frame:06d}.png"), cv2.IMREAD_GRAYSCALE)
            m, valid = res.mask > 0, roi & (g != 170) & (g != 85)
            for label in fp:
                fp[label] += int((m & valid & (g == label)).sum())
            tp += int((m & valid & (g == 255)).sum())
            fn += int((~m & valid & (g == 255)).sum())
    print(f"pixels: true positives {tp:,}, false negatives {fn:,}; false positives "
          f"{sum(fp.values()):,}: cast shadow (50) {fp[50]:,}, static ground (0) {fp[0]:,}")


def merged_cars(folder: Path, threshold: float) -> None:
    over = [f"source.max_frames={LAST}", f"motion.knn.vehicle_shadow_threshold={threshold}"]
    merged = found = cars = 0
    with run(str(folder / "input" / "*.jpg"), load_config(None, over)) as r:
        for res in r:
            frame = res.index + 1
            if frame < FIRST:
                continue
            gt = gt_boxes(folder, frame)
            boxes = np.array([t.box.as_array() for t in res.tracks], float).reshape(-1, 4)
            cars += len(gt)
            if not len(gt) or not len(boxes):
                continue
            iou = iou_matrix(gt, boxes)
            best = iou.argmax(1)
            for i, j in enumerate(best):
                if iou[i, j] >= 0.5:
                    found += 1
                elif (iou[:, j] > 0.05).sum() > 1:
                    merged += 1
    print(f"merged: vehicles' shadow threshold {threshold}: {cars} cars, {found} boxed at IoU >= "
          f"0.5, {merged} in a box with another car")


def light_regions(source: str, frames: int, label: str) -> None:
    """The regions whose means pass the light test, seen through GhostFilter._lit."""
    seen: list[tuple[float, float, float]] = []
    test = ghosts.GhostFilter._lit

    def recording(self, image, crop, held, window):
        lit = test(self, image, crop, held, window)
        if self._bgc8 is not None and image.ndim == 3:
            y1, y2, x1, x2 = window
            cur, bg = image[y1:y2, x1:x2], self._bgc8[y1:y2, x1:x2]
            if ghosts.lit_on_average(cur, bg, crop, self.lit_gain):
                mean = (np.add(cv2.mean(cur, mask=crop)[:3], 1)
                        / np.add(cv2.mean(bg, mask=crop)[:3], 1))
                on = crop > 0
                gains = ((cur[on].astype(np.float32) + 1) / (bg[on].astype(np.float32) + 1)).mean(1)
                share = ghosts.lit_share(cur, bg, crop, self.lit_gain,
                                         None if held is None else held[y1:y2, x1:x2])
                seen.append((share, float(np.percentile(gains, 90) - np.percentile(gains, 10)),
                             float(mean.mean())))
        return lit

    ghosts.GhostFilter._lit = recording
    try:
        with run(source, load_config(None, [f"source.max_frames={frames}"])) as r:
            for _ in r:
                pass
    finally:
        ghosts.GhostFilter._lit = test
    lit = [s for s in seen if s[0] >= 0.8]
    rest = [s for s in seen if s[0] < 0.8]
    line = (f"light: {label}: {len(seen)} region-frames pass the means; {len(lit)} with >= 0.8 of "
            "their pixels lit")
    if lit:
        shares, spreads, means = zip(*lit)
        line += (f" (shares {min(shares):.2f}-{max(shares):.2f}, mean gains {min(means):.3f}-"
                 f"{max(means):.3f}, their pixels' gains' 10-90% spread up to {max(spreads):.3f})")
    if rest:
        line += f"; the others' shares up to {max(s[0] for s in rest):.2f}"
    print(line)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default=os.environ.get(
        "MOTIONTRACK_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"))
    args = ap.parse_args()
    folder = Path(args.data) / "cdnet-highway"
    pixel_errors(folder)
    for threshold in (0.7, 0.8):
        merged_cars(folder, threshold)
    light_regions(str(folder / "input" / "*.jpg"), LAST, "CDnet highway 1-1000")
    light_regions(str(Path(args.data) / "pets09-s2l1" / "video.avi"), 795, "PETS 1-795")


if __name__ == "__main__":
    main()
