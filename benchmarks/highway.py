"""Cars on CDnet 2014 baseline/highway (320x240): detection of the default pipeline at its automatic
processing scale, at the old fixed scale 0.5, with the ``fast`` preset's smaller KNN model, with
each motion model (KNN without its hold, the sample-based ``vibe`` with and without selective
update), and the tutorial baseline, side by side.

Ground-truth boxes: connected components (8-connected, >= 200 px) of the gt masks' foreground
(value 255) in the temporal ROI, frames 470-1000. Touching cars form one component, so the numbers
are a lower bound for every row alike. Per frame, boxes are matched one-to-one (Hungarian) at
IoU >= 0.5; recall = matched / gt boxes, precision = matched / output boxes (tracks for the
pipeline rows, contours for the baseline). The baseline is the recipe of benchmarks/throughput.py
with its minimum contour area (500 px at 768x576) scaled to this frame size (87 px).

Box F is the harmonic mean of recall and precision. Pixel F is CDnet's F-measure of the mask the
pipeline reports (``FrameResult.mask``, what ``--mask-video`` writes: the regions' silhouettes,
or with ``regions.silhouettes=false`` the mask the regions are found in, after clean-up and the
ghost filter; ``motiontrack evaluate-masks`` rules, ROI.bmp and label 170 excluded, shadow
negative), over the same frames.

The last rows hold KNN's shadow test (a pixel at least ``shadow_threshold`` of the background's
brightness, its colour kept, is a shadow) at one threshold, where the default takes 0.7 once the
tracks are mostly vehicles. ``--shadows`` prints instead where the shadows and the
cars fall on that scale.

Run: .venv/bin/python benchmarks/highway.py [--data ../shared/data] [--shadows]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment

from motiontrack.config import load_config
from motiontrack.evaluate.masks import MaskCounts, compare_masks, read_roi
from motiontrack.pipeline import run
from motiontrack.tracking.association import iou_matrix

FIRST, LAST = 470, 1000
MIN_GT_AREA = 200


def gt_boxes(folder: Path, frame: int) -> np.ndarray:
    g = cv2.imread(str(folder / "groundtruth" / f"gt{frame:06d}.png"), cv2.IMREAD_GRAYSCALE)
    n, _, stats, _ = cv2.connectedComponentsWithStats((g == 255).astype(np.uint8), connectivity=8)
    return np.array([stats[i, :4] for i in range(1, n) if stats[i, 4] >= MIN_GT_AREA],
                    float).reshape(-1, 4)


def matched(gt: np.ndarray, pred: np.ndarray) -> int:
    iou = iou_matrix(gt, pred)
    if not iou.size:
        return 0
    r, c = linear_sum_assignment(-iou)
    return int((iou[r, c] >= 0.5).sum())


def score(folder: Path, boxes_by_frame) -> tuple[float, float]:
    tp = n_gt = n_pred = 0
    for frame, pred in boxes_by_frame:
        if FIRST <= frame <= LAST:
            g = gt_boxes(folder, frame)
            tp += matched(g, pred)
            n_gt += len(g)
            n_pred += len(pred)
    return tp / max(n_gt, 1), tp / max(n_pred, 1)


def pipeline_boxes(folder: Path, overrides: list[str], preset: str | None = None,
                   pixels: list[MaskCounts] | None = None):
    """Each frame's track boxes; with ``pixels``, the masks' pixel counts are appended to it."""
    cfg = load_config(None, [f"source.max_frames={LAST}", *overrides], preset=preset)
    roi = read_roi(folder / "ROI.bmp") if pixels is not None else None
    for res in run(str(folder / "input" / "*.jpg"), cfg):
        frame = res.index + 1
        if pixels is not None and FIRST <= frame <= LAST and res.mask is not None:
            g = cv2.imread(str(folder / "groundtruth" / f"gt{frame:06d}.png"), cv2.IMREAD_GRAYSCALE)
            m = res.mask
            if m.shape != g.shape:
                m = cv2.resize(m, (g.shape[1], g.shape[0]), interpolation=cv2.INTER_NEAREST)
            pixels.append(compare_masks(g, m, roi))
        yield frame, np.array([t.box.as_array() for t in res.tracks]).reshape(-1, 4)


def baseline_boxes(folder: Path):
    sub = cv2.createBackgroundSubtractorMOG2(500, 16, True)
    k3 = np.ones((3, 3), np.uint8)
    min_area = 500 * (320 * 240) / (768 * 576)
    for k, name in enumerate(sorted((folder / "input").glob("in*.jpg"))[:LAST]):
        frame = cv2.imread(str(name))
        gray = cv2.GaussianBlur(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), (5, 5), 0)
        _, fg = cv2.threshold(sub.apply(gray), 254, 255, cv2.THRESH_BINARY)
        fg = cv2.dilate(cv2.erode(fg, k3, iterations=1), k3, iterations=3)
        contours, _ = cv2.findContours(fg, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        yield k + 1, np.array([cv2.boundingRect(c) for c in contours
                               if cv2.contourArea(c) >= min_area], float).reshape(-1, 4)


def shadow_ratios(folder: Path) -> None:
    """What tells cast shadows from cars, pixel by pixel, over every 5th frame of FIRST-LAST
    (OpenCV's KNN with the pipeline's 3x3 blur at full size): percentiles of the brightness of
    frame / background (sum of the channels), and medians of the shift of the blue share of the
    colour (a shadow is lit by the sky) and of |Laplacian| (texture), for the ground truth's
    shadow pixels (label 50), car pixels (255) KNN marks as shadow (127), car pixels darker than
    0.4 of the background, and all car pixels."""
    sub = cv2.createBackgroundSubtractorKNN(500, 300.0, True)
    names = ("cast shadows (gt 50)", "car pixels KNN calls shadow", "car pixels below 0.4",
             "car pixels")
    parts: dict[str, list[np.ndarray]] = {n: [] for n in names}
    for k, name in enumerate(sorted((folder / "input").glob("in*.jpg"))[:LAST]):
        frame = k + 1
        image = cv2.GaussianBlur(cv2.imread(str(name)), (3, 3), 0)
        raw = sub.apply(image)
        if frame < FIRST or frame % 5:
            continue
        g = cv2.imread(str(folder / "groundtruth" / f"gt{frame:06d}.png"), cv2.IMREAD_GRAYSCALE)
        bg = sub.getBackgroundImage()
        f32, b32 = image.astype(np.float32) + 1, bg.astype(np.float32) + 1
        ratio = f32.sum(2) / b32.sum(2)
        blue = f32[..., 0] / f32.sum(2) - b32[..., 0] / b32.sum(2)
        lap = np.abs(cv2.Laplacian(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), cv2.CV_32F, ksize=3))
        for key, where in zip(names, (g == 50, (g == 255) & (raw == 127),
                                      (g == 255) & (ratio < 0.4), g == 255)):
            parts[key].append(np.c_[ratio[where], blue[where], lap[where]])
    print("frame / background brightness: percentiles 5 25 50 75 95 (KNN's shadows: 0.5-1); "
          "medians of the blue shift and |Laplacian|")
    for key, values in parts.items():
        v = np.concatenate(values)
        print(f"{key:<30}{len(v):>8} px " + " ".join(f"{q:5.2f}" for q in
                                                     np.percentile(v[:, 0], [5, 25, 50, 75, 95]))
              + f"   blue {np.median(v[:, 1]):+.3f}   |lap| {np.median(v[:, 2]):5.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default=os.environ.get("MOTIONTRACK_DATA",
                                                     Path(__file__).resolve().parents[2] / "shared" / "data"))
    ap.add_argument("--shadows", action="store_true",
                    help="only the brightness ratios of shadows and of cars KNN calls shadow")
    args = ap.parse_args()
    folder = Path(args.data) / "cdnet-highway"
    if not (folder / "input").is_dir():
        sys.exit(f"CDnet highway not found: {folder} (set MOTIONTRACK_DATA or --data)")
    rows = [
        ("tutorial baseline", None, None),
        ("pipeline, scale 0.5 (old default)", ["preprocess.scale=0.5"], None),
        ("pipeline, automatic scale (1.0 here)", [], None),
        ("pipeline, --preset fast", [], "fast"),
        ("knn, hold=false", ["motion.method=knn", "motion.knn.hold=false"], None),
        ("pipeline, motion.method=vibe", ["motion.method=vibe"], None),
        ("vibe, protect=false", ["motion.method=vibe", "motion.vibe.protect=false"], None),
        ("knn, shadow threshold 0.5 always", ["motion.knn.vehicle_shadow_threshold=0.5"], None),
        ("knn, shadow threshold 0.7 always", ["motion.knn.shadow_threshold=0.7",
                                              "motion.knn.vehicle_shadow_threshold=0.7"], None),
        ("knn, shadow threshold 0.8 always", ["motion.knn.shadow_threshold=0.8",
                                              "motion.knn.vehicle_shadow_threshold=0.8"], None),
        ("knn, detect_shadows=false", ["motion.knn.detect_shadows=false"], None),
        ("no light test", ["motion.light_share=0"], None),
        ("mask as cleaned, no silhouettes", ["regions.silhouettes=false"], None),
        ("neither", ["motion.light_share=0", "regions.silhouettes=false"], None),
    ]
    if args.shadows:
        shadow_ratios(folder)
        return
    print(f"CDnet highway 320x240, frames {FIRST}-{LAST}, cars = gt mask components >= {MIN_GT_AREA} px")
    print(f"{'run':<38}{'recall':>8}{'prec':>8}{'box F':>7}{'pixel F':>8}{'s':>7}")
    for name, overrides, preset in rows:
        t = time.perf_counter()
        pixels: list[MaskCounts] = []
        boxes = (baseline_boxes(folder) if overrides is None
                 else pipeline_boxes(folder, overrides, preset, pixels))
        rec, prec = score(folder, boxes)
        f_box = 2 * rec * prec / max(rec + prec, 1e-9)
        f_pix = sum(pixels, MaskCounts()).metrics()["f_measure"] if pixels else float("nan")
        print(f"{name:<38}{rec:>8.3f}{prec:>8.3f}{f_box:>7.3f}{f_pix:>8.3f}"
              f"{time.perf_counter() - t:>7.1f}")


if __name__ == "__main__":
    main()
