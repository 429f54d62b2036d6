"""The sections of a scene file: as written (:class:`SceneSection` schemas, checked by
:func:`motiontrack.schema.from_dict`) and as parsed, in source pixels.

Each rule module (:mod:`.rules`) declares the schema of its table (:attr:`.rule.Rule.schema`)
and builds one of these from it (:meth:`.rule.Rule.parse`); where the table as written is
already what the rule needs (``stationary``, ``abandoned``, ``speed``) the schema is the parsed
section too. The array functions (:mod:`.lines`, :mod:`.zones`, :mod:`.abandoned`) take them as
they are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..classify import CLASS_NAMES
from ..errors import ConfigError
from ..schema import REQUIRED, Section, param
from ..speed import SPEED_WINDOW_S

__all__ = ["CLASSES_DOC", "classes_param", "checked_classes",
           "COORD_LIMIT", "MAX_POLYGON_POINTS", "MAX_TABLES", "SceneSection", "LineSpec",
           "ZoneSpec", "StationarySpec", "AbandonedSpec", "SpeedSpec"]

#: largest number accepted (pixels, metres, seconds): far beyond any frame, small enough for
#: float maths
COORD_LIMIT = 10_000_000

#: most points of a zone's polygon: a vertex every 12 px along the border of a whole 4K frame,
#: far more than a drawn or traced zone needs; the simplicity check tests every pair of edges
#: (about 0.1 s at this bound) and each frame tests every track against every edge
MAX_POLYGON_POINTS = 1_000

#: most tables of one array (``[[zone]]``, ``[[line]]``): with :data:`MAX_POLYGON_POINTS` this
#: bounds the edges every frame's zone test goes through
MAX_TABLES = 1_000


class SceneSection(Section):
    """A schema of one table of the scene file: unknown keys are "scene keys" in messages."""

    schema_noun: ClassVar[str] = "scene "


#: the meaning of every rule's ``classes`` key
CLASSES_DOC = ("the track classes this applies to, of person, vehicle, other (needs classified "
               "tracks: `classes.enabled`, or a tracks file with a class column); none: every "
               "track")


def classes_param() -> tuple[str, ...] | None:
    """The ``classes = ["person", ...]`` key of a rule's table."""
    return param(None, max_items=len(CLASS_NAMES), doc=CLASSES_DOC)


def checked_classes(classes: tuple[str, ...] | None, where: str) -> tuple[str, ...] | None:
    """A rule's ``classes`` with each name checked (``where`` names the table), repeats
    dropped."""
    if classes is None:
        return None
    for i, name in enumerate(classes, 1):
        if name not in CLASS_NAMES:
            raise ConfigError(f"{where}.classes[{i}] must be one of {', '.join(CLASS_NAMES)}, "
                              f"got {name!r}")
    return tuple(dict.fromkeys(classes))


def positive(default: float | None, doc: str) -> float | None:
    """A number > 0 (and at most :data:`COORD_LIMIT`), as most scene keys are."""
    return param(default, lo=0.0, lo_open=True, hi=COORD_LIMIT, doc=doc)


@dataclass(frozen=True)
class LineSpec:
    """A counting line from ``a`` to ``b`` (source pixels); see :func:`.geometry.side`."""

    name: str
    a: tuple[float, float]
    b: tuple[float, float]
    #: the track classes the line counts (None = every track)
    classes: tuple[str, ...] | None = None

    @property
    def length(self) -> float:
        return math.hypot(self.b[0] - self.a[0], self.b[1] - self.a[1])


@dataclass(frozen=True)
class ZoneSpec:
    """A zone: a simple polygon (source pixels), and the dwell after which ``loiter`` fires."""

    name: str
    polygon: tuple[tuple[float, float], ...]
    loiter_s: float | None = None
    #: the track classes the zone holds (None = every track)
    classes: tuple[str, ...] | None = None

    def vertices(self) -> np.ndarray:
        """(K, 2) float64 vertices."""
        return np.asarray(self.polygon, dtype=np.float64)


@dataclass(frozen=True)
class StationarySpec(SceneSection):
    """A track that stays within a radius (pixels or metres: exactly one) for ``after_s``."""

    after_s: float = positive(REQUIRED, "seconds within the radius before `stationary_start`")
    radius_px: float | None = positive(None, "the radius in pixels (exactly one of radius_px "
                                             "and radius_m)")
    radius_m: float | None = positive(None, "the radius in metres on the ground; needs a camera")
    release: float = param(1.5, lo=1.0, hi=100.0,
                           doc="once stationary, a stay ends only beyond this many radii from "
                               "its centre (one alarm per stop while a person shifts on the "
                               "spot)")
    leave_s: float = param(1.0, lo=0.0, hi=COORD_LIMIT,
                           doc="seconds the position must stay out of reach before a stay ends "
                               "(a passer-by who hides the object for a moment ends nothing)")
    classes: tuple[str, ...] | None = param(
        None, max_items=3, doc=CLASSES_DOC + "; a static object the tracker lost has the class "
                                             "of the track it continues")


@dataclass(frozen=True)
class AbandonedSpec(SceneSection):
    """An object left static while its owner is farther than a distance, for ``after_s``."""

    after_s: float = positive(REQUIRED, "seconds the owner must be away before `abandoned`")
    distance_m: float | None = positive(None, "the owner is away farther than this on the "
                                              "ground (metres; needs a camera; exactly one of "
                                              "distance_m and distance_heights)")
    distance_heights: float | None = positive(None, "the owner is away farther than this many "
                                                    "of the owner's box heights")
    classes: tuple[str, ...] | None = param(
        None, max_items=3, doc="the classes of the track that left the object (its owner: "
                               "person, vehicle, other; needs classified tracks); none: any")


@dataclass(frozen=True)
class SpeedSpec(SceneSection):
    """A speed limit (metres or pixels per second: exactly one) over a ``window_s`` window."""

    limit_mps: float | None = positive(None, "limit in metres per second; needs a camera "
                                             "(exactly one of limit_mps and limit_px_s)")
    limit_px_s: float | None = positive(None, "limit in pixels per second")
    window_s: float = positive(SPEED_WINDOW_S, "window of the speed measurement, over the "
                                               "track's smoothed positions")
    min_s: float = param(1.0, lo=0.0, hi=COORD_LIMIT,
                         doc="seconds the speed must exceed the limit by two of its standard "
                             "deviations before `speeding` (0: at once)")
