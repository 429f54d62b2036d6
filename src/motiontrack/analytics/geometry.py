"""Plane geometry for scene analytics: pure functions over arrays of points.

Points are ``(N, 2) float64`` pixel arrays (``x`` right, ``y`` down); every function handles
``N = 0``. A line is the segment from ``A`` to ``B``; a polygon is a ``(K, 2)`` array of
vertices, closed implicitly, simple (no edge crosses another) and possibly concave.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "side",
    "segments_intersect",
    "segments_meet",
    "points_in_polygon",
    "distance_to_polygon",
    "polygon_is_simple",
    "polygon_area",
]


def _pts(points) -> np.ndarray:
    p = np.asarray(points, dtype=np.float64)
    return p.reshape(-1, 2)


def side(points, a, b) -> np.ndarray:
    """Signed side of each point with respect to the line from ``a`` to ``b``.

    ``s(p) = (Bx - Ax)(py - Ay) - (By - Ay)(px - Ax)``: the cross product ``AB x AP``. With ``y``
    pointing down, ``s > 0`` on the right of the direction A→B as seen on screen, ``s < 0`` on
    the left. ``s / |AB|`` is the signed distance to the line in pixels.

    Returns
    -------
    (N,) float64
    """
    p = _pts(points)
    (ax, ay), (bx, by) = a, b
    return (bx - ax) * (p[:, 1] - ay) - (by - ay) * (p[:, 0] - ax)


def segments_intersect(p0, p1, a, b) -> np.ndarray:
    """Whether each segment ``p0[i] → p1[i]`` meets the segment ``a → b`` (touching counts).

    Returns
    -------
    (N,) bool
    """
    p0, p1 = _pts(p0), _pts(p1)
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    d1 = side(p0, a, b)
    d2 = side(p1, a, b)
    # the sides of a and b with respect to each moving segment
    dx, dy = p1[:, 0] - p0[:, 0], p1[:, 1] - p0[:, 1]
    d3 = dx * (a[1] - p0[:, 1]) - dy * (a[0] - p0[:, 0])
    d4 = dx * (b[1] - p0[:, 1]) - dy * (b[0] - p0[:, 0])
    proper = (d1 * d2 <= 0) & (d3 * d4 <= 0)
    # collinear segments: all four cross products vanish; they meet only when their extents overlap
    collinear = (d1 == 0) & (d2 == 0)
    if np.any(collinear):
        axis = 0 if abs(b[0] - a[0]) >= abs(b[1] - a[1]) else 1
        lo, hi = min(a[axis], b[axis]), max(a[axis], b[axis])
        qlo = np.minimum(p0[:, axis], p1[:, axis])
        qhi = np.maximum(p0[:, axis], p1[:, axis])
        proper = np.where(collinear, (qlo <= hi) & (qhi >= lo), proper)
    return proper


def points_in_polygon(points, polygon) -> np.ndarray:
    """Even-odd (ray casting) test of each point against a simple polygon, convex or not.

    Returns
    -------
    (N,) bool
    """
    p = _pts(points)
    v = _pts(polygon)
    if len(p) == 0:
        return np.zeros(0, dtype=bool)
    x, y = p[:, 0:1], p[:, 1:2]  # (N, 1) against the (K,) edges
    x0, y0 = v[:, 0], v[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    straddles = (y0 > y) != (y1 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
    hits = straddles & (x < x_cross)
    return (np.count_nonzero(hits, axis=1) % 2) == 1


def distance_to_polygon(points, polygon) -> np.ndarray:
    """Distance (pixels) from each point to the nearest edge of the polygon.

    Returns
    -------
    (N,) float64
    """
    p = _pts(points)
    v = _pts(polygon)
    if len(p) == 0:
        return np.zeros(0)
    a = v[None, :, :]
    e = (np.roll(v, -1, axis=0) - v)[None, :, :]  # (1, K, 2) edge vectors
    ap = p[:, None, :] - a  # (N, K, 2)
    t = np.clip(np.sum(ap * e, axis=2) / np.sum(e * e, axis=2), 0.0, 1.0)
    nearest = a + t[:, :, None] * e
    return np.min(np.hypot(*(p[:, None, :] - nearest).transpose(2, 0, 1)), axis=1)


def polygon_area(polygon) -> float:
    """Signed area (shoelace formula); positive for vertices clockwise on screen (y down)."""
    v = _pts(polygon)
    x, y = v[:, 0], v[:, 1]
    return float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) / 2.0)


#: most (edge, edge) pairs :func:`polygon_is_simple` tests in one array operation
_PAIRS_PER_BLOCK = 1 << 20


def segments_meet(p0: np.ndarray, p1: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether segment ``p0 → p1`` meets segment ``a → b`` (touching counts), for arrays of
    points ``(..., 2)`` that broadcast against each other; the shape they broadcast to, bool."""
    x0, y0, x1, y1 = p0[..., 0], p0[..., 1], p1[..., 0], p1[..., 1]
    ax, ay, bx, by = a[..., 0], a[..., 1], b[..., 0], b[..., 1]
    d1 = (bx - ax) * (y0 - ay) - (by - ay) * (x0 - ax)
    d2 = (bx - ax) * (y1 - ay) - (by - ay) * (x1 - ax)
    d3 = (x1 - x0) * (ay - y0) - (y1 - y0) * (ax - x0)
    d4 = (x1 - x0) * (by - y0) - (y1 - y0) * (bx - x0)
    meet = (d1 * d2 <= 0) & (d3 * d4 <= 0)
    # collinear segments (all four products 0) meet only where their extents overlap; a segment
    # of zero length (a track standing still) is collinear with any other
    collinear = (d1 == 0) & (d2 == 0)
    if np.any(collinear):
        overlap = ((np.minimum(x0, x1) <= np.maximum(ax, bx))
                   & (np.maximum(x0, x1) >= np.minimum(ax, bx))
                   & (np.minimum(y0, y1) <= np.maximum(ay, by))
                   & (np.maximum(y0, y1) >= np.minimum(ay, by)))
        meet = np.where(collinear, overlap, meet)
    return meet


def polygon_is_simple(polygon) -> bool:
    """Whether no two non-adjacent edges of the polygon meet (and no edge has zero length).

    Every pair of edges is tested, in blocks of at most ``2**20`` pairs of array operations:
    ``K**2 / 2`` tests for ``K`` vertices, about 30 ms at the scene file's bound of 1,000
    (:data:`motiontrack.analytics.specs.MAX_POLYGON_POINTS`).
    """
    v = _pts(polygon)
    k = len(v)
    w = np.roll(v, -1, axis=0)
    if np.any(np.all(v == w, axis=1)):
        return False
    j = np.arange(k)
    rows = max(1, _PAIRS_PER_BLOCK // max(k, 1))
    for start in range(0, k, rows):
        i = np.arange(start, min(k, start + rows))[:, None]
        # each pair once (j > i); edges i and j are adjacent when they share a vertex:
        # j = i + 1, or the first and the last edge
        others = (j > i + 1) & ~((i == 0) & (j == k - 1))
        if not others.any():
            continue
        meet = segments_meet(v[i[:, 0]][:, None, :], w[i[:, 0]][:, None, :], v[None, :, :], w[None, :, :])
        if np.any(meet & others):
            return False
    return True
