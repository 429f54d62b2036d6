"""Synthetic vehicles: a car seen from the side, driving along a road at constant velocity."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .render import Sprite

__all__ = ["Vehicle", "render_vehicle", "vehicle_position"]

#: sprite labels of a car's parts (palette rows of :meth:`Vehicle.palette`)
LABEL_BODY, LABEL_WINDOW, LABEL_WHEEL = 1, 2, 3


@dataclass(frozen=True)
class Vehicle:
    """A car seen from the side, its bottom centre (where the wheels touch the road) at
    ``(x0 + vx * (i - t0), y0)`` at 0-based frame index ``i``.

    Attributes
    ----------
    id : int
        Ground-truth identity, >= 1 (not a person's or a bag's).
    x0, y0 : float
        Bottom centre at frame index ``t0``, pixels.
    vx : float
        Velocity, pixels per frame (negative: right to left).
    length, height : float
        Bumper to bumper and road to roof, pixels (a car is about 4.5 m long and 1.5 m tall).
    t0 : float
        Reference frame index for ``x0``.
    colour : tuple of int
        BGR of the body.
    """

    id: int
    x0: float
    y0: float
    vx: float
    length: float
    height: float
    t0: float = 0.0
    colour: tuple[int, int, int] = (40, 40, 170)

    def __post_init__(self) -> None:
        if self.id < 1:
            raise ValueError(f"vehicle id must be >= 1, got id={self.id}")
        if not (self.length > 4 and self.height > 4):
            raise ValueError(f"vehicle length and height must be > 4 px, got "
                             f"{self.length}x{self.height}")

    def palette(self) -> np.ndarray:
        """``(8, 3) uint8`` BGR colour per sprite label."""
        pal = np.zeros((8, 3), dtype=np.uint8)
        pal[LABEL_BODY] = self.colour
        pal[LABEL_WINDOW] = (150, 120, 90)
        pal[LABEL_WHEEL] = (20, 20, 20)
        return pal


def vehicle_position(v: Vehicle, i: float) -> tuple[float, float]:
    """The bottom centre at frame index ``i``."""
    return v.x0 + v.vx * (i - v.t0), v.y0


def render_vehicle(v: Vehicle, i: int) -> Sprite:
    """The car at frame index ``i`` as a label :class:`Sprite`: a body over the lower 60% of
    its height, a cabin with windows over the middle half of its length, two wheels."""
    cx, bottom = vehicle_position(v, i)
    L, H = v.length, v.height
    ox, oy = int(math.floor(cx - L / 2)) - 2, int(math.floor(bottom - H)) - 2
    lab = np.zeros((int(math.ceil(H)) + 5, int(math.ceil(L)) + 5), dtype=np.uint8)

    def pt(x: float, y: float) -> tuple[int, int]:
        return int(round(x - ox)), int(round(y - oy))

    wheel = 0.16 * H
    body_top, body_bottom = bottom - 0.62 * H, bottom - wheel
    cv2.rectangle(lab, pt(cx - L / 2, body_top), pt(cx + L / 2, body_bottom), LABEL_BODY, -1)
    cabin = np.array([pt(cx - 0.28 * L, body_top), pt(cx - 0.18 * L, bottom - H),
                      pt(cx + 0.20 * L, bottom - H), pt(cx + 0.30 * L, body_top)], np.int32)
    cv2.fillConvexPoly(lab, cabin, LABEL_BODY)
    inset = max(1.0, 0.08 * H)
    glass = np.array([pt(cx - 0.24 * L, body_top), pt(cx - 0.16 * L, bottom - H + inset),
                      pt(cx + 0.18 * L, bottom - H + inset), pt(cx + 0.26 * L, body_top)],
                     np.int32)
    cv2.fillConvexPoly(lab, glass, LABEL_WINDOW)
    r = max(1, int(round(wheel)))
    for fx in (-0.30, 0.30):
        cv2.circle(lab, pt(cx + fx * L, bottom - r), r, LABEL_WHEEL, -1)
    return Sprite(ox, oy, lab)
