"""How a detector's boxes join a frame's motion regions (``detector.mode``)."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..tracking.association import iou_matrix
from ..types import Box, Region
from .onnx_yolo import Detections

__all__ = ["detector_regions", "matches"]


def matches(a: np.ndarray, b: np.ndarray, min_iou: float) -> list[tuple[int, int]]:
    """Pairs ``(i, j)`` of boxes ``a[i]``, ``b[j]`` (``x, y, w, h``) matched greedily by IoU,
    best first, each box at most once, IoU at least ``min_iou`` (and above 0)."""
    if not len(a) or not len(b):
        return []
    iou = iou_matrix(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    pairs, used_a, used_b = [], set(), set()
    for flat in np.argsort(-iou, axis=None, kind="stable"):
        i, j = divmod(int(flat), iou.shape[1])
        if iou[i, j] < min_iou or iou[i, j] <= 0:
            break
        if i in used_a or j in used_b:
            continue
        used_a.add(i)
        used_b.add(j)
        pairs.append((i, j))
    return pairs


def _region(box: np.ndarray, score: float) -> Region:
    x, y, w, h = (float(v) for v in box)
    return Region(box=Box(x, y, w, h), centroid=(x + w / 2, y + h / 2), area=w * h,
                  score=float(score))


def detector_regions(regions: Sequence[Region], dets: Detections, mode: str,
                     start_tracks: bool, match_iou: float) -> list[Region]:
    """The regions the tracker gets: ``replace`` the detections; ``fuse`` the motion regions,
    with the detections no region matches added when ``start_tracks``."""
    if mode == "replace":
        return [_region(b, s) for b, s in zip(dets.boxes, dets.scores)]
    out = list(regions)
    if start_tracks and len(dets):
        boxes = np.array([r.box.as_array() for r in regions]).reshape(-1, 4)
        matched = {j for _, j in matches(boxes, dets.boxes, match_iou)}
        out += [_region(dets.boxes[j], dets.scores[j]) for j in range(len(dets))
                if j not in matched]
    return out
