"""Checks of the scene file's values, shared by the scene's top level (:mod:`.scene`) and every
rule's table (:mod:`.rules`): each problem is one :class:`~motiontrack.errors.ConfigError`
naming the key as written (tables of an array counted from 1: ``line[2].points``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import ConfigError, excerpt

__all__ = ["COORD_LIMIT", "kind", "table", "number", "one_of", "points", "geometry", "name",
           "array_of_tables"]

#: largest coordinate accepted (pixels or metres): far beyond any frame, small enough for float maths
COORD_LIMIT = 1e7


def kind(v: Any) -> str:
    """What ``v`` is, as an error message shows it: the value itself, or its kind."""
    if isinstance(v, bool) or isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return excerpt(v)
    return {dict: "a table", list: "an array"}.get(type(v), f"a {type(v).__name__}")


def table(data: Any, where: str, keys: tuple[str, ...]) -> dict:
    """``data`` checked to be a table with no key outside ``keys``."""
    if not isinstance(data, dict):
        raise ConfigError(f"{where} must be a table, got {kind(data)}")
    unknown = sorted(str(k) for k in data if k not in keys)
    if unknown:
        prefix = f"{where}." if where != "the scene" else ""
        k = unknown[0]
        shown = k if len(k) <= 40 and k.isprintable() else excerpt(k)
        raise ConfigError(f"unknown scene key {prefix}{shown}; valid keys"
                          f"{'' if where == 'the scene' else ' in ' + where}: {', '.join(keys)}")
    return data


def number(data: dict, key: str, where: str, default: Any = None, *, positive: bool = True,
           required: bool = False) -> float | None:
    """``data[key]`` as a finite float (``> 0``, or ``>= 0`` with ``positive=False``), or
    ``default`` when absent."""
    key_path = f"{where}.{key}" if where else key
    if key not in data:
        if required:
            raise ConfigError(f"{key_path} is required")
        return default
    v = data[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError(f"{key_path} must be a number, got {kind(v)}")
    v = float(v)
    if not math.isfinite(v) or abs(v) > COORD_LIMIT:
        raise ConfigError(f"{key_path} must be a finite number, got {kind(v)}")
    if positive and not v > 0:
        raise ConfigError(f"{key_path} must be > 0, got {kind(v)}")
    if not positive and v < 0:
        raise ConfigError(f"{key_path} must be >= 0, got {kind(v)}")
    return v


def one_of(data: dict, keys: tuple[str, str], where: str) -> str:
    """The one of the two ``keys`` present in ``data``."""
    present = [k for k in keys if k in data]
    if len(present) != 1:
        raise ConfigError(f"{where} needs exactly one of {keys[0]} and {keys[1]}")
    return present[0]


def points(v: Any, where: str) -> np.ndarray:
    """``[[x, y], ...]`` → (K, 2) float64; anything else is an error naming ``where``."""
    if not isinstance(v, list):
        raise ConfigError(f"{where} must be an array of [x, y] points, got {kind(v)}")
    for i, p in enumerate(v, 1):
        ok = isinstance(p, list) and len(p) == 2 and all(
            isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
            and abs(c) <= COORD_LIMIT for c in p)
        if not ok:
            raise ConfigError(f"{where} point {i} must be [x, y] with two finite numbers, "
                              f"got {kind(p)}")
    return np.asarray(v, dtype=np.float64).reshape(-1, 2)


def geometry(data: dict, key: str, where: str, camera: Any) -> np.ndarray:
    """The table's pixel geometry: ``key`` as written, or ``world`` projected by ``camera``."""
    used = one_of(data, (key, "world"), where)
    pts = points(data[used], f"{where}.{used}")
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


def name(data: dict, where: str, seen: set[str]) -> str:
    """The table's ``name``: printable, at most 100 characters, not in ``seen`` (then added)."""
    value = data.get("name")
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f"{where}.name must be a non-empty string, got "
                          f"{'nothing' if value is None else kind(value)}")
    if not value.isprintable() or len(value) > 100:
        raise ConfigError(f"{where}.name must be printable text of at most 100 characters")
    if value in seen:
        raise ConfigError(f"{where}.name {excerpt(value)} is used twice")
    seen.add(value)
    return value


def array_of_tables(v: Any, key: str) -> list:
    """The scene's ``[[key]]`` tables (``v`` absent: none)."""
    v = [] if v is None else v
    if not isinstance(v, list):
        raise ConfigError(f"{key} must be an array of tables ([[{key}]]), got {kind(v)}")
    return v
