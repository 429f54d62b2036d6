"""The parsed sections of a scene file, in source pixels: one frozen dataclass per rule's table.

Each rule module (:mod:`.rules`) parses its table of the scene file into one of these
(:meth:`.rule.Rule.parse`); the array functions (:mod:`.lines`, :mod:`.zones`,
:mod:`.abandoned`) take them as they are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["LineSpec", "ZoneSpec", "StationarySpec", "AbandonedSpec", "SpeedSpec"]


@dataclass(frozen=True)
class LineSpec:
    """A counting line from ``a`` to ``b`` (source pixels); see :func:`.geometry.side`."""

    name: str
    a: tuple[float, float]
    b: tuple[float, float]

    @property
    def length(self) -> float:
        return math.hypot(self.b[0] - self.a[0], self.b[1] - self.a[1])


@dataclass(frozen=True)
class ZoneSpec:
    """A zone: a simple polygon (source pixels), and the dwell after which ``loiter`` fires."""

    name: str
    polygon: tuple[tuple[float, float], ...]
    loiter_s: float | None = None

    def vertices(self) -> np.ndarray:
        """(K, 2) float64 vertices."""
        return np.asarray(self.polygon, dtype=np.float64)


@dataclass(frozen=True)
class StationarySpec:
    """A track that stays within a radius (pixels or metres: exactly one) for ``after_s``."""

    after_s: float
    radius_px: float | None = None
    radius_m: float | None = None


@dataclass(frozen=True)
class AbandonedSpec:
    """An object left static while its owner is farther than a distance, for ``after_s``."""

    after_s: float
    distance_m: float | None = None
    distance_heights: float | None = None


@dataclass(frozen=True)
class SpeedSpec:
    """A speed limit (metres or pixels per second: exactly one) over a ``window_s`` window."""

    limit_mps: float | None = None
    limit_px_s: float | None = None
    window_s: float = 1.0
