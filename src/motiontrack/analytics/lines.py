"""Line crossings with hysteresis: per track and line, the confirmed side and the path since.

Rule (``docs/analytics.md``): for a line from A to B, ``s(p)`` is :func:`.geometry.side`; the
signed distance ``d = s / |AB|``. A track's side of a line is *confirmed* only where
``|d| > hysteresis_px``; between, it keeps the side it had. A crossing is counted when the
confirmed side flips and one of the track's steps since the last confirmed position met the
segment AB: ``in`` from ``s < 0`` to ``s > 0``, ``out`` the other way. Jitter inside the band
therefore never counts, and a track passing beside the segment (across the line's extension)
neither.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LineState", "cross_lines", "steps_meet_lines"]


class LineState:
    """One track's state for ``L`` lines: confirmed side (+1, -1, 0 = not yet) and whether a
    step since the last confirmed position met the segment."""

    __slots__ = ("side", "touched")

    def __init__(self, n_lines: int) -> None:
        self.side = np.zeros(n_lines, dtype=np.int8)
        self.touched = np.zeros(n_lines, dtype=bool)


def steps_meet_lines(p0: np.ndarray, p1: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether each step ``p0[i] → p1[i]`` meets each segment ``a[j] → b[j]`` (touching counts).

    Parameters
    ----------
    p0, p1 : (N, 2) float64
    a, b : (L, 2) float64

    Returns
    -------
    (N, L) bool
    """
    ax, ay, bx, by = a[None, :, 0], a[None, :, 1], b[None, :, 0], b[None, :, 1]
    x0, y0, x1, y1 = p0[:, 0:1], p0[:, 1:2], p1[:, 0:1], p1[:, 1:2]
    d1 = (bx - ax) * (y0 - ay) - (by - ay) * (x0 - ax)
    d2 = (bx - ax) * (y1 - ay) - (by - ay) * (x1 - ax)
    d3 = (x1 - x0) * (ay - y0) - (y1 - y0) * (ax - x0)
    d4 = (x1 - x0) * (by - y0) - (y1 - y0) * (bx - x0)
    meet = (d1 * d2 <= 0) & (d3 * d4 <= 0)
    # a step along the line's own direction (all four products 0) meets it only where the
    # extents overlap; a step of zero length (a track standing still) is collinear with any line
    collinear = (d1 == 0) & (d2 == 0)
    if np.any(collinear):
        lo_x, hi_x = np.minimum(ax, bx), np.maximum(ax, bx)
        lo_y, hi_y = np.minimum(ay, by), np.maximum(ay, by)
        overlap = ((np.minimum(x0, x1) <= hi_x) & (np.maximum(x0, x1) >= lo_x)
                   & (np.minimum(y0, y1) <= hi_y) & (np.maximum(y0, y1) >= lo_y))
        meet = np.where(collinear, overlap, meet)
    return meet


def cross_lines(states: list[LineState], prev: np.ndarray, has_prev: np.ndarray,
                points: np.ndarray, a: np.ndarray, b: np.ndarray,
                hysteresis_px: float) -> np.ndarray:
    """One frame of the crossing rule for ``N`` tracks and ``L`` lines; updates ``states``.

    Parameters
    ----------
    states : N :class:`LineState`, one per track (changed in place).
    prev : (N, 2) float64 each track's previous anchor (any value where ``has_prev`` is false).
    has_prev : (N,) bool
    points : (N, 2) float64 the anchors now.
    a, b : (L, 2) float64 the lines' end points.

    Returns
    -------
    (N, L) int8: +1 for an ``in`` crossing, -1 for ``out``, 0 for none.
    """
    n, nl = len(points), len(a)
    if n == 0 or nl == 0:
        return np.zeros((n, nl), dtype=np.int8)
    side = np.stack([s.side for s in states])
    touched = np.stack([s.touched for s in states])
    length = np.hypot(b[:, 0] - a[:, 0], b[:, 1] - a[:, 1])
    s = ((b[None, :, 0] - a[None, :, 0]) * (points[:, 1:2] - a[None, :, 1])
         - (b[None, :, 1] - a[None, :, 1]) * (points[:, 0:1] - a[None, :, 0]))
    d = s / length[None, :]
    beyond = np.abs(d) > hysteresis_px
    new_side = np.where(beyond, np.sign(d), 0).astype(np.int8)
    touched |= steps_meet_lines(prev, points, a, b) & has_prev[:, None]
    flips = beyond & (side != 0) & (new_side != side)
    crossing = np.where(flips & touched, new_side, 0).astype(np.int8)
    side = np.where(beyond, new_side, side)
    touched &= ~beyond
    for i, st in enumerate(states):
        st.side = side[i]
        st.touched = touched[i]
    return crossing
