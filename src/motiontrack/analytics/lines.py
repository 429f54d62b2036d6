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

from .geometry import segments_meet

__all__ = ["LineSet", "steps_meet_lines"]


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
    return segments_meet(p0[:, None, :], p1[:, None, :], a[None, :, :], b[None, :, :])


class LineSet:
    """``L`` lines (end points ``a``, ``b``: (L, 2) float64) and one frame of the crossing rule
    for ``N`` tracks at once.

    The per-track state is columnar, one row per track, kept by the caller: ``side`` (N, L)
    int8 the confirmed side (+1, -1, 0 = not yet), ``touched`` (N, L) bool whether a step
    since the last confirmed position met the segment, and ``s`` (N, L) float64 the value of
    :func:`.geometry.side` at the track's previous anchor.
    """

    def __init__(self, a: np.ndarray, b: np.ndarray) -> None:
        self.a = np.asarray(a, dtype=np.float64).reshape(-1, 2)
        self.b = np.asarray(b, dtype=np.float64).reshape(-1, 2)
        self.n = len(self.a)
        self.ax, self.ay = self.a[None, :, 0], self.a[None, :, 1]
        self.dx = self.b[None, :, 0] - self.ax
        self.dy = self.b[None, :, 1] - self.ay
        self.length = np.hypot(self.dx, self.dy)

    def side_values(self, points: np.ndarray) -> np.ndarray:
        """``s(p)`` of (N, 2) points for every line: (N, L) float64."""
        return self.dx * (points[:, 1:2] - self.ay) - self.dy * (points[:, 0:1] - self.ax)

    def step(self, side: np.ndarray, touched: np.ndarray, s_prev: np.ndarray,
             prev: np.ndarray, has_prev: np.ndarray, points: np.ndarray,
             hysteresis_px: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """One frame of the rule.

        Parameters
        ----------
        side, touched, s_prev : the tracks' state (see the class docstring); not changed.
        prev : (N, 2) float64 each track's previous anchor (any value where ``has_prev`` is
            false); ``has_prev`` (N,) bool.
        points : (N, 2) float64 the anchors now.

        Returns
        -------
        crossing : (N, L) int8, +1 for an ``in`` crossing, -1 for ``out``, 0 for none.
        side, touched, s : the new state.
        """
        s = self.side_values(points)
        d = s / self.length
        beyond = np.abs(d) > hysteresis_px
        new_side = np.where(beyond, np.sign(d), 0).astype(np.int8)
        # a step can meet a segment only where its ends are not strictly on one side of the
        # line (s_prev * s <= 0): the full segment test runs for those few pairs only
        i, j = np.nonzero((s_prev * s <= 0) & has_prev[:, None])
        touched = touched.copy()
        if len(i):
            touched[i, j] |= segments_meet(prev[i], points[i], self.a[j], self.b[j])
        flips = beyond & (side != 0) & (new_side != side)
        crossing = np.where(flips & touched, new_side, 0).astype(np.int8)
        side = np.where(beyond, new_side, side)
        touched &= ~beyond
        return crossing, side, touched, s
