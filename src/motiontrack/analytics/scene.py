"""The scene file: named lines and zones of one camera view and the rules' thresholds.

A scene is TOML (``docs/analytics.md``)::

    anchor = "bottom_center"          # or "center": the point of a track that counts
    hysteresis_px = 5                 # a side changes only this far past a line or zone edge
    forget_s = 2                      # a track unseen this long has left
    [[line]]
    name = "gate"
    points = [[120, 410], [640, 430]] # pixels; or world = [[X, Y], [X, Y]] metres
    [[zone]]
    name = "plaza"
    polygon = [[0, 300], [400, 300], [400, 576], [0, 576]]  # or world = [...]
    loiter_s = 20
    [stationary]
    after_s = 10
    radius_px = 15                    # or radius_m
    [abandoned]
    after_s = 15
    distance_m = 3                    # or distance_heights
    [speed]
    limit_mps = 3.0                   # or limit_px_s
    window_s = 1.0

:func:`parse_scene` turns the parsed table into a frozen :class:`Scene` in source pixels,
projecting ``world`` geometry through a camera; every problem is one :class:`ConfigError`
naming the key as written (tables of an array counted from 1: ``line[2].points``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError, excerpt
from ..io.tomlfile import read_toml
from .geometry import polygon_area, polygon_is_simple

__all__ = [
    "ANCHORS",
    "LineSpec",
    "ZoneSpec",
    "StationarySpec",
    "AbandonedSpec",
    "SpeedSpec",
    "Scene",
    "parse_scene",
    "load_scene",
]

ANCHORS = ("bottom_center", "center")
_TOP_KEYS = ("anchor", "hysteresis_px", "forget_s", "line", "zone", "stationary", "abandoned", "speed")
#: largest coordinate accepted (pixels or metres): far beyond any frame, small enough for float maths
_COORD_LIMIT = 1e7


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


@dataclass(frozen=True)
class Scene:
    """Everything analytics needs to know about one camera view, in source pixels."""

    anchor: str = "bottom_center"
    hysteresis_px: float = 5.0
    forget_s: float = 2.0
    lines: tuple[LineSpec, ...] = ()
    zones: tuple[ZoneSpec, ...] = ()
    stationary: StationarySpec | None = None
    abandoned: AbandonedSpec | None = None
    speed: SpeedSpec | None = None
    source: str = ""

    @property
    def needs_camera(self) -> bool:
        """Whether a rule measures in metres (positions of events then carry ``X, Y`` too)."""
        return bool(
            (self.stationary and self.stationary.radius_m is not None)
            or (self.speed and self.speed.limit_mps is not None)
            or (self.abandoned and self.abandoned.distance_m is not None)
        )


# --------------------------------------------------------------------------------- validation
def _kind(v: Any) -> str:
    if isinstance(v, bool) or isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return excerpt(v)
    return {dict: "a table", list: "an array"}.get(type(v), f"a {type(v).__name__}")


def _table(data: Any, where: str, keys: tuple[str, ...]) -> dict:
    if not isinstance(data, dict):
        raise ConfigError(f"{where} must be a table, got {_kind(data)}")
    unknown = sorted(str(k) for k in data if k not in keys)
    if unknown:
        prefix = f"{where}." if where != "the scene" else ""
        k = unknown[0]
        shown = k if len(k) <= 40 and k.isprintable() else excerpt(k)
        raise ConfigError(f"unknown scene key {prefix}{shown}; valid keys"
                          f"{'' if where == 'the scene' else ' in ' + where}: {', '.join(keys)}")
    return data


def _number(data: dict, key: str, where: str, default: Any = None, *, positive: bool = True,
            required: bool = False) -> float | None:
    if where:
        key_path = f"{where}.{key}"
    else:
        key_path = key
    if key not in data:
        if required:
            raise ConfigError(f"{key_path} is required")
        return default
    v = data[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError(f"{key_path} must be a number, got {_kind(v)}")
    v = float(v)
    if not math.isfinite(v) or abs(v) > _COORD_LIMIT:
        raise ConfigError(f"{key_path} must be a finite number, got {_kind(v)}")
    if positive and not v > 0:
        raise ConfigError(f"{key_path} must be > 0, got {_kind(v)}")
    if not positive and v < 0:
        raise ConfigError(f"{key_path} must be >= 0, got {_kind(v)}")
    return v


def _one_of(data: dict, keys: tuple[str, str], where: str) -> str:
    present = [k for k in keys if k in data]
    if len(present) != 1:
        raise ConfigError(f"{where} needs exactly one of {keys[0]} and {keys[1]}")
    return present[0]


def _points(v: Any, where: str) -> np.ndarray:
    """``[[x, y], ...]`` → (K, 2) float64; anything else is an error naming ``where``."""
    if not isinstance(v, list):
        raise ConfigError(f"{where} must be an array of [x, y] points, got {_kind(v)}")
    for i, p in enumerate(v, 1):
        ok = isinstance(p, list) and len(p) == 2 and all(
            isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
            and abs(c) <= _COORD_LIMIT for c in p)
        if not ok:
            raise ConfigError(f"{where} point {i} must be [x, y] with two finite numbers, "
                              f"got {_kind(p)}")
    return np.asarray(v, dtype=np.float64).reshape(-1, 2)


def _geometry(data: dict, key: str, where: str, camera: Any) -> np.ndarray:
    """The table's pixel geometry: ``key`` as written, or ``world`` projected by ``camera``."""
    used = _one_of(data, (key, "world"), where)
    pts = _points(data[used], f"{where}.{used}")
    if used == "world":
        if camera is None:
            raise ConfigError(f"{where}.world is in metres and needs a camera calibration "
                              f"(--camera); or give {where}.{key} in pixels")
        px = np.asarray(camera.world_to_image(pts), dtype=np.float64).reshape(-1, 2)
        bad = np.flatnonzero(~np.all(np.isfinite(px), axis=1))
        if len(bad):
            raise ConfigError(f"{where}.world point {bad[0] + 1} is not in view of the camera")
        pts = px
    return pts


def _name(data: dict, where: str, seen: set[str]) -> str:
    name = data.get("name")
    if not isinstance(name, str) or not name.strip():
        raise ConfigError(f"{where}.name must be a non-empty string, got "
                          f"{'nothing' if name is None else _kind(name)}")
    if not name.isprintable() or len(name) > 100:
        raise ConfigError(f"{where}.name must be printable text of at most 100 characters")
    if name in seen:
        raise ConfigError(f"{where}.name {excerpt(name)} is used twice")
    seen.add(name)
    return name


def _line(data: Any, where: str, camera: Any, seen: set[str]) -> LineSpec:
    data = _table(data, where, ("name", "points", "world"))
    name = _name(data, where, seen)
    pts = _geometry(data, "points", where, camera)
    used = "points" if "points" in data else "world"
    if len(pts) != 2:
        raise ConfigError(f"{where}.{used} must be two [x, y] points, got {len(pts)}")
    if math.hypot(*(pts[1] - pts[0])) < 1.0:
        raise ConfigError(f"{where}.{used}: the two points are less than a pixel apart")
    return LineSpec(name, (float(pts[0, 0]), float(pts[0, 1])), (float(pts[1, 0]), float(pts[1, 1])))


def _zone(data: Any, where: str, camera: Any, seen: set[str]) -> ZoneSpec:
    data = _table(data, where, ("name", "polygon", "world", "loiter_s"))
    name = _name(data, where, seen)
    pts = _geometry(data, "polygon", where, camera)
    used = "polygon" if "polygon" in data else "world"
    if len(pts) < 3:
        raise ConfigError(f"{where}.{used} must have at least 3 [x, y] points, got {len(pts)}")
    if not polygon_is_simple(pts):
        raise ConfigError(f"{where}.{used} must be a simple polygon: two of its edges cross "
                          "or a point repeats")
    if abs(polygon_area(pts)) < 1.0:
        raise ConfigError(f"{where}.{used} encloses no area (its points lie on a line)")
    loiter = _number(data, "loiter_s", where)
    return ZoneSpec(name, tuple((float(x), float(y)) for x, y in pts), loiter)


def _array_of_tables(data: dict, key: str) -> list:
    v = data.get(key, [])
    if not isinstance(v, list):
        raise ConfigError(f"{key} must be an array of tables ([[{key}]]), got {_kind(v)}")
    return v


def parse_scene(data: Any, camera: Any = None, source: str = "") -> Scene:
    """The :class:`Scene` a parsed scene TOML table describes.

    Parameters
    ----------
    data : dict
        The parsed TOML.
    camera : optional
        A camera from :func:`motiontrack.calibrate.load_camera`, fitted to the video; needed by
        ``world`` geometry and by ``radius_m``, ``limit_mps`` and ``distance_m``.
    source : str
        The file's name, kept for outputs.

    Raises
    ------
    ConfigError
        One line naming the key path as written.
    """
    data = _table(data, "the scene", _TOP_KEYS)
    anchor = data.get("anchor", "bottom_center")
    if anchor not in ANCHORS:
        raise ConfigError(f"anchor must be one of {', '.join(ANCHORS)}, got {_kind(anchor)}")
    hyst = _number(data, "hysteresis_px", "", 5.0, positive=False)
    forget = _number(data, "forget_s", "", 2.0)
    names: set[str] = set()
    lines = tuple(_line(t, f"line[{i}]", camera, names)
                  for i, t in enumerate(_array_of_tables(data, "line"), 1))
    names = set()
    zones = tuple(_zone(t, f"zone[{i}]", camera, names)
                  for i, t in enumerate(_array_of_tables(data, "zone"), 1))
    stationary = abandoned = speed = None
    if "stationary" in data:
        t = _table(data["stationary"], "stationary", ("after_s", "radius_px", "radius_m"))
        r = _one_of(t, ("radius_px", "radius_m"), "stationary")
        stationary = StationarySpec(_number(t, "after_s", "stationary", required=True),
                                    **{r: _number(t, r, "stationary")})
    if "abandoned" in data:
        t = _table(data["abandoned"], "abandoned", ("after_s", "distance_m", "distance_heights"))
        d = _one_of(t, ("distance_m", "distance_heights"), "abandoned")
        abandoned = AbandonedSpec(_number(t, "after_s", "abandoned", required=True),
                                  **{d: _number(t, d, "abandoned")})
    if "speed" in data:
        t = _table(data["speed"], "speed", ("limit_mps", "limit_px_s", "window_s"))
        k = _one_of(t, ("limit_mps", "limit_px_s"), "speed")
        speed = SpeedSpec(**{k: _number(t, k, "speed")},
                          window_s=_number(t, "window_s", "speed", 1.0))
    scene = Scene(anchor, hyst, forget, lines, zones, stationary, abandoned, speed, source)
    if scene.needs_camera and camera is None:
        key = ("stationary.radius_m" if stationary and stationary.radius_m is not None else
               "speed.limit_mps" if speed and speed.limit_mps is not None else
               "abandoned.distance_m")
        raise ConfigError(f"{key} is in metres and needs a camera calibration (--camera); "
                          "give it in pixels (radius_px, limit_px_s, distance_heights) instead")
    return scene


def load_scene(path: str | Path, camera: Any = None) -> Scene:
    """Read and validate a scene TOML file (see :func:`parse_scene`); a missing or malformed
    file is an :class:`~motiontrack.errors.InputError`, bad content a :class:`ConfigError`
    that names the file."""
    data = read_toml(path, "scene file")
    try:
        return parse_scene(data, camera, source=str(path))
    except ConfigError as exc:
        raise ConfigError(f"scene file {Path(path).name}: {exc}") from None
