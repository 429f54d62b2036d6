"""Where tracks spent time: anchor points counted per frame, in the image and on the ground.

:class:`HeatGrid` counts, for every frame, one visit in the pixel under each reported track's
anchor (the scene's ``anchor``: the bottom centre or the centre of its box), so a pixel's count
is the number of track-frames spent there. :class:`WorldHeat` counts the same visits in cells
of the ground plane (metres) for a calibrated camera; its extent is the tracks' own, so it
grows with them and is fixed only when the map is drawn.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

__all__ = ["anchor_points", "HeatGrid", "WorldHeat", "world_extent"]


def anchor_points(boxes: np.ndarray, anchor: str = "bottom_center") -> np.ndarray:
    """(N, 4) ``x, y, w, h`` boxes → (N, 2) anchor pixels (``bottom_center`` or ``center``)."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    bottom = b[:, 1] + b[:, 3] if anchor == "bottom_center" else b[:, 1] + b[:, 3] / 2.0
    return np.column_stack([b[:, 0] + b[:, 2] / 2.0, bottom])


class HeatGrid:
    """Visits per pixel of a ``width`` x ``height`` frame.

    A point ``(x, y)`` falls in pixel ``(floor(x), floor(y))``; points outside the frame are
    not counted (:attr:`outside` says how many).
    """

    def __init__(self, width: int, height: int) -> None:
        if width < 1 or height < 1:
            raise ValueError(f"a heat map needs a size of at least 1x1 pixels, got {width}x{height}")
        self.width, self.height = int(width), int(height)
        self.counts = np.zeros((self.height, self.width), dtype=np.float64)
        self.visits = 0
        self.outside = 0

    def add(self, points: np.ndarray) -> None:
        """Count one visit at each of the (N, 2) pixel ``points``."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if not len(p):
            return
        ok = np.all(np.isfinite(p), axis=1)
        p = np.floor(p[ok])
        inside = (p[:, 0] >= 0) & (p[:, 0] < self.width) & (p[:, 1] >= 0) & (p[:, 1] < self.height)
        self.outside += int(np.count_nonzero(~inside))
        xi, yi = p[inside, 0].astype(np.int64), p[inside, 1].astype(np.int64)
        np.add.at(self.counts, (yi, xi), 1.0)
        self.visits += int(len(xi))


class WorldHeat:
    """Visits per ``cell_m`` x ``cell_m`` cell of the ground plane (metres).

    Cells are kept sparse (a counter of cell indices): the extent of the tracks is known only
    at the end, and the memory is bounded by the ground they covered, not by the run's length.
    Cell ``(i, j)`` covers ``i * cell_m <= X < (i + 1) * cell_m`` and likewise ``j`` for ``Y``.
    """

    def __init__(self, cell_m: float = 0.05) -> None:
        if not (math.isfinite(cell_m) and cell_m > 0):
            raise ValueError(f"a world heat map cell must be > 0 metres, got {cell_m!r}")
        self.cell_m = float(cell_m)
        self.cells: Counter[tuple[int, int]] = Counter()
        self.visits = 0

    def add(self, world: np.ndarray) -> None:
        """Count one visit at each of the (N, 2) ground positions ``X, Y`` (NaN: not counted,
        e.g. a foot point above the horizon)."""
        w = np.asarray(world, dtype=np.float64).reshape(-1, 2)
        w = w[np.all(np.isfinite(w), axis=1)]
        if not len(w):
            return
        ij = np.floor(w / self.cell_m).astype(np.int64)
        self.cells.update(map(tuple, ij.tolist()))
        self.visits += len(ij)

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """The visited cells' centres (K, 2) metres and their visits (K,)."""
        if not self.cells:
            return np.zeros((0, 2)), np.zeros(0)
        ij = np.array(list(self.cells.keys()), dtype=np.float64)
        n = np.array(list(self.cells.values()), dtype=np.float64)
        return (ij + 0.5) * self.cell_m, n


def world_extent(centres: np.ndarray, margin_m: float = 1.0) -> tuple[float, float, float, float]:
    """``(x0, x1, y0, y1)`` metres: the points' extent plus ``margin_m``, rounded out to whole
    metres (at least 1 m each way); ``(-5, 5, -5, 5)`` without points."""
    c = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
    if not len(c):
        return (-5.0, 5.0, -5.0, 5.0)
    x0, y0 = np.floor(c.min(axis=0) - margin_m)
    x1, y1 = np.ceil(c.max(axis=0) + margin_m)
    return (float(x0), float(max(x1, x0 + 1)), float(y0), float(max(y1, y0 + 1)))
