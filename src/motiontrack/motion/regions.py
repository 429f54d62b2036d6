"""Mask → regions: connected components, size and shape filters, merging of nearby regions.

Region merging follows the Reading People Tracker's REGION_MERGE_THRESH rule: two regions are
merged when

    D = (dx + dy) / (max(W1, H1) + max(W2, H2) + 1)  <  merge_threshold

where W, H are the regions' box widths and heights and ``dx``, ``dy`` are the **gaps between the
two boxes** along x and y: ``dx = max(0, x2_left - x1_right)`` style, i.e. the number of pixels
between the nearer edges, 0 when the boxes overlap (or touch) along that axis. Overlapping boxes
therefore always have D = 0, and a gap of one region-size in both directions gives D ≈ 1. Merging
is transitive (single linkage) and repeats until no pair is below the threshold.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..config import RegionsConfig
from ..types import Box, Region

__all__ = ["find_regions", "components", "filter_regions", "merge_regions", "merge_distance",
           "smallest_region", "silhouettes"]


def components(mask: np.ndarray, connectivity: int = 8, scale: float = 1.0,
               min_pixels: int = 1) -> list[Region]:
    """Connected components of a 0/255 mask as regions in original-frame pixels.

    Parameters
    ----------
    mask : (h, w) uint8, non-zero = foreground, at processing resolution.
    connectivity : 4 or 8.
    scale : processing scale; boxes, centroids and areas are divided by it (areas by scale²).
    min_pixels : components smaller than this (in processing pixels) are dropped early.

    Notes
    -----
    For 8-connectivity the outer contours are traced (``cv2.findContours``, about 20x faster than
    labelling every pixel on sparse motion masks) and each component's pixel count and centroid
    come from the image moments of the mask inside its box, restricted to the filled contour when
    another component's box overlaps. Pixels of a separate component lying inside a hole of
    another are counted with the outer one. 4-connectivity uses full labelling.
    """
    if connectivity == 4:
        return _components_labelled(mask, 4, scale, min_pixels)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        return []
    rects = np.array([cv2.boundingRect(c) for c in contours], dtype=np.int64).reshape(-1, 4)
    keep = rects[:, 2] * rects[:, 3] >= min_pixels
    rects = rects[keep]
    contours = [c for c, k in zip(contours, keep) if k]
    x1, y1 = rects[:, 0], rects[:, 1]
    x2, y2 = x1 + rects[:, 2], y1 + rects[:, 3]
    overlap = ((x1[:, None] < x2[None, :]) & (x1[None, :] < x2[:, None])
               & (y1[:, None] < y2[None, :]) & (y1[None, :] < y2[:, None]))
    np.fill_diagonal(overlap, False)
    overlapped = overlap.any(axis=1).tolist()
    inv = 1.0 / scale
    out: list[Region] = []
    for c, (x, y, w, h), crossed in zip(contours, rects.tolist(), overlapped):
        roi = mask[y:y + h, x:x + w]
        if crossed:
            filled = np.zeros((h, w), np.uint8)
            cv2.drawContours(filled, [c], -1, 255, -1, offset=(-x, -y))
            roi = cv2.bitwise_and(roi, filled)
        m = cv2.moments(roi, binaryImage=True)
        area = m["m00"]
        if area < min_pixels or area == 0:
            continue
        # pixel i covers [i, i + 1): its centre is i + 0.5 (same convention as the box edges)
        cx = x + m["m10"] / area + 0.5
        cy = y + m["m01"] / area + 0.5
        out.append(Region(box=Box(x * inv, y * inv, w * inv, h * inv),
                          centroid=(cx * inv, cy * inv), area=float(area) * inv * inv))
    return out


def _components_labelled(mask: np.ndarray, connectivity: int, scale: float,
                         min_pixels: int) -> list[Region]:
    """Full connected-component labelling (any connectivity)."""
    n, _labels, stats, cents = cv2.connectedComponentsWithStats(
        mask, connectivity=connectivity, ltype=cv2.CV_32S)
    inv = 1.0 / scale
    out: list[Region] = []
    for i in range(1, n):
        x, y, w, h, area = (int(v) for v in stats[i])
        if area < min_pixels:
            continue
        out.append(Region(
            box=Box(x * inv, y * inv, w * inv, h * inv),
            centroid=(float((cents[i, 0] + 0.5) * inv), float((cents[i, 1] + 0.5) * inv)),
            area=float(area) * inv * inv,
        ))
    return out


#: components below this share of the minimum area are specks, dropped before merging
_SPECK = 0.25


def _least_area(cfg: RegionsConfig, image_area: float) -> float:
    """A region's minimum area in original pixels: the larger of ``min_area`` and ``min_size``."""
    return max(cfg.min_area, cfg.min_size * image_area)


def filter_regions(regions: list[Region], cfg: RegionsConfig, image_area: float) -> list[Region]:
    """Keep regions whose area and height/width ratio are within the limits of ``cfg``."""
    lo = _least_area(cfg, image_area)
    hi_px = [v for v in (cfg.max_area, cfg.max_size * image_area) if v > 0]
    hi = min(hi_px) if hi_px else np.inf
    out = []
    for r in regions:
        if not lo <= r.area <= hi:
            continue
        ratio = r.box.h / r.box.w
        if cfg.min_hw_ratio > 0 and ratio < cfg.min_hw_ratio:
            continue
        if cfg.max_hw_ratio > 0 and ratio > cfg.max_hw_ratio:
            continue
        out.append(r)
    return out


def merge_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pairwise merge distance D between boxes ``a`` (N, 4) and ``b`` (M, 4) (x, y, w, h) → (N, M).

    ``D = (dx + dy) / (max(W1, H1) + max(W2, H2) + 1)`` with ``dx``, ``dy`` the gaps between
    the boxes (0 when they overlap along that axis).
    """
    a = np.asarray(a, np.float64).reshape(-1, 4)
    b = np.asarray(b, np.float64).reshape(-1, 4)
    ax1, ay1, ax2, ay2 = a[:, 0:1], a[:, 1:2], a[:, 0:1] + a[:, 2:3], a[:, 1:2] + a[:, 3:4]
    bx1, by1, bx2, by2 = b[:, 0], b[:, 1], b[:, 0] + b[:, 2], b[:, 1] + b[:, 3]
    dx = np.maximum(0.0, np.maximum(bx1 - ax2, ax1 - bx2))
    dy = np.maximum(0.0, np.maximum(by1 - ay2, ay1 - by2))
    sa = np.maximum(a[:, 2:3], a[:, 3:4])
    sb = np.maximum(b[:, 2], b[:, 3])
    return (dx + dy) / (sa + sb + 1.0)


def _union(rs: list[Region]) -> Region:
    x1 = min(r.box.x for r in rs)
    y1 = min(r.box.y for r in rs)
    x2 = max(r.box.x2 for r in rs)
    y2 = max(r.box.y2 for r in rs)
    area = sum(r.area for r in rs)
    cx = sum(r.centroid[0] * r.area for r in rs) / area if area > 0 else (x1 + x2) / 2
    cy = sum(r.centroid[1] * r.area for r in rs) / area if area > 0 else (y1 + y2) / 2
    return Region(box=Box.from_xyxy(x1, y1, x2, y2), centroid=(cx, cy), area=area,
                  score=max(r.score for r in rs))


def merge_regions(regions: list[Region], threshold: float) -> list[Region]:
    """Merge regions whose pairwise distance D is below ``threshold`` (single linkage, repeated
    until stable because a merged box can come close to a further region)."""
    if threshold <= 0 or len(regions) < 2:
        return list(regions)
    current = list(regions)
    while True:
        boxes = np.array([r.box.as_array() for r in current])
        d = merge_distance(boxes, boxes)
        np.fill_diagonal(d, np.inf)
        close = d < threshold
        if not close.any():
            return current
        # connected components of the "close" graph
        n = len(current)
        parent = list(range(n))

        def find(i: int) -> int:
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for i, j in zip(*np.nonzero(np.triu(close))):
            ri, rj = find(int(i)), find(int(j))
            if ri != rj:
                parent[rj] = ri
        groups: dict[int, list[Region]] = {}
        for i in range(n):
            groups.setdefault(find(i), []).append(current[i])
        current = [g[0] if len(g) == 1 else _union(g) for g in groups.values()]


def find_regions(mask: np.ndarray, cfg: RegionsConfig, scale: float, image_size: tuple[int, int]) -> list[Region]:
    """Mask at processing scale → filtered, merged regions in original pixels.

    Small specks are dropped before merging (below a quarter of the minimum area) so they cannot
    glue real regions together; the area/shape filters apply to the merged regions.
    """
    width, height = image_size
    image_area = float(width * height)
    min_px = _least_area(cfg, image_area) * scale * scale * _SPECK
    regions = components(mask, cfg.connectivity, scale, min_pixels=max(1, int(min_px)))
    regions = merge_regions(regions, cfg.merge_threshold)
    return filter_regions(regions, cfg, image_area)


def smallest_region(cfg: RegionsConfig, scale: float, image_size: tuple[int, int]) -> float:
    """Pixels (at processing scale) of the smallest component :func:`find_regions` can make a
    region of: the minimum area, or a quarter of it when regions are merged (specks below that
    are dropped before merging)."""
    least = _least_area(cfg, float(image_size[0] * image_size[1])) * scale * scale
    return least * _SPECK if cfg.merge_threshold > 0 else least


#: the closing of :func:`silhouettes`: it joins parts of one object up to two pixels apart
_CLOSE = cv2.getStructuringElement(cv2.MORPH_RECT, (3, 3))


def silhouettes(mask: np.ndarray, min_pixels: float, close: bool = False) -> np.ndarray:
    """``mask`` (uint8 0/255) as the silhouettes of its regions: with ``close``, closed by a 3x3
    square first (gaps of up to two pixels joined: right for a car, which has none, wrong for a
    person's legs); without the 8-connected components of fewer than ``min_pixels`` pixels (no
    region comes from them); and with the holes of the others filled (an object's pixels the
    background model took for ground, such as a grey car's roof on grey asphalt). Always a new
    array.

    A component is counted by the mask's pixels in its bounding box, so a speck whose box
    another component reaches into may be kept (never the other way round)."""
    out = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, _CLOSE) if close else mask.copy()
    contours, tree = cv2.findContours(out, cv2.RETR_TREE, cv2.CHAIN_APPROX_SIMPLE)
    if tree is None:
        return out
    parents = tree[0][:, 3]
    specks, holes = set(), []
    for i, c in enumerate(contours):
        if parents[i] < 0:   # a component's outline (the others lie inside it)
            x, y, w, h = cv2.boundingRect(c)
            if w * h < min_pixels or cv2.countNonZero(out[y:y + h, x:x + w]) < min_pixels:
                specks.add(i)
    for i, c in enumerate(contours):
        # a hole of a component that stays: filled with whatever lies inside it
        if parents[i] >= 0 and parents[parents[i]] < 0 and parents[i] not in specks:
            holes.append(c)
    if holes:
        cv2.drawContours(out, holes, -1, 255, thickness=-1)
    if specks:
        cv2.drawContours(out, [contours[i] for i in sorted(specks)], -1, 0, thickness=-1)
    return out
