"""Zone membership with hysteresis, for many points and zones at once.

A track is *inside* a zone once its anchor is inside the polygon and more than
``hysteresis_px`` from its edges, *outside* once it is outside and as far; in the band along
the edges it keeps its state. A track first seen in the band takes the plain point-in-polygon
answer.
"""

from __future__ import annotations

import numpy as np

from .specs import ZoneSpec

__all__ = ["ZoneEdges"]

#: most (point, edge) pairs of one block of :meth:`ZoneEdges.classify` (32 MiB per float array)
_BLOCK = 1 << 22


class ZoneEdges:
    """The edges of all zones packed into one array, so that one frame's test of ``N`` points
    against ``Z`` zones is a handful of array operations.

    Parameters
    ----------
    zones : the scene's zones.
    """

    def __init__(self, zones: tuple[ZoneSpec, ...]) -> None:
        self.n = len(zones)
        verts = [z.vertices() for z in zones]
        self.p0 = np.concatenate(verts) if verts else np.zeros((0, 2))
        self.p1 = (np.concatenate([np.roll(v, -1, axis=0) for v in verts]) if verts
                   else np.zeros((0, 2)))
        counts = np.array([len(v) for v in verts], dtype=np.int64)
        # each zone's edges are one run of columns: per-zone sums and minima by reduceat
        self.starts = np.concatenate([[0], np.cumsum(counts)[:-1]]) if verts else counts
        e = self.p1 - self.p0
        self.e = e
        self.ee = np.maximum(np.sum(e * e, axis=1), 1e-12)

    def classify(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Inside (even-odd rule) and distance to the nearest edge of every zone.

        Parameters
        ----------
        points : (N, 2) float64

        Returns
        -------
        inside : (N, Z) bool
        distance : (N, Z) float64 pixels
        """
        n = len(points)
        if n == 0 or self.n == 0:
            return np.zeros((n, self.n), dtype=bool), np.zeros((n, self.n))
        # blocks of points, so that the (points, edges) arrays stay within _BLOCK numbers
        rows = max(1, _BLOCK // len(self.p0))
        if n > rows:
            parts = [self.classify(points[i:i + rows]) for i in range(0, n, rows)]
            return (np.concatenate([p[0] for p in parts]),
                    np.concatenate([p[1] for p in parts]))
        x, y = points[:, 0:1], points[:, 1:2]
        x0, y0, x1, y1 = self.p0[:, 0], self.p0[:, 1], self.p1[:, 0], self.p1[:, 1]
        straddles = (y0 > y) != (y1 > y)
        dy = np.where(y1 != y0, y1 - y0, 1.0)  # only straddling edges are used: never 0 there
        hits = straddles & (x < x0 + (y - y0) * (x1 - x0) / dy)
        inside = (np.add.reduceat(hits.astype(np.int32), self.starts, axis=1) % 2) == 1
        t = np.clip(((x - x0) * self.e[:, 0] + (y - y0) * self.e[:, 1]) / self.ee, 0.0, 1.0)
        dist = np.hypot(x - (x0 + t * self.e[:, 0]), y - (y0 + t * self.e[:, 1]))
        return inside, np.minimum.reduceat(dist, self.starts, axis=1)

    def membership(self, was_in: np.ndarray, known: np.ndarray, points: np.ndarray,
                   hysteresis_px: float) -> np.ndarray:
        """Who is inside which zone after this frame.

        Parameters
        ----------
        was_in : (N, Z) bool the state before this frame.
        known : (N,) bool whether the track had a state (false: first seen now).
        points : (N, 2) float64 anchors.

        Returns
        -------
        (N, Z) bool
        """
        inside, dist = self.classify(points)
        decided = np.where(dist > hysteresis_px, inside, was_in)
        return np.where(known[:, None], decided, inside)
