"""Checks of a scene file's tables beyond single keys, which the schemas of :mod:`.specs` cannot
state: exactly one of two keys, ``world`` geometry that needs a camera and in view of it, names
unique among the tables of an array. Each problem is one
:class:`~motiontrack.errors.ConfigError` naming the key as written (tables of an array counted
from 1: ``line[2].points``).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..errors import ConfigError, excerpt
from ..schema import shown
from .specs import MAX_TABLES

__all__ = ["one_of", "pixels", "unique_name", "array_of_tables"]


def one_of(section: Any, keys: Sequence[str], where: str) -> str:
    """The one of ``keys`` that ``section`` (a parsed table) gives."""
    present = [k for k in keys if getattr(section, k) is not None]
    if len(present) != 1:
        raise ConfigError(f"{where} needs exactly one of {' and '.join(keys)}")
    return present[0]


def pixels(section: Any, key: str, where: str, camera: Any) -> tuple[str, np.ndarray]:
    """The key used (``key`` or ``world``) and the table's geometry in pixels: ``key`` as
    written, or ``world`` metres projected by ``camera``."""
    used = one_of(section, (key, "world"), where)
    pts = np.asarray(getattr(section, used), dtype=np.float64).reshape(-1, 2)
    if used == "world":
        if camera is None:
            raise ConfigError(f"{where}.world is in metres and needs a camera calibration "
                              f"(--camera); or give {where}.{key} in pixels")
        px = np.asarray(camera.world_to_image(pts), dtype=np.float64).reshape(-1, 2)
        bad = np.flatnonzero(~np.all(np.isfinite(px), axis=1))
        if len(bad):
            raise ConfigError(f"{where}.world point {bad[0] + 1} is not in view of the camera")
        pts = px
    return used, pts


def unique_name(value: str, where: str, earlier: Sequence[str]) -> str:
    """A table's ``name``: printable, at most 100 characters, not one of ``earlier``."""
    if not value.isprintable() or len(value) > 100:
        raise ConfigError(f"{where}.name must be printable text of at most 100 characters")
    if value in earlier:
        raise ConfigError(f"{where}.name {excerpt(value)} is used twice")
    return value


def array_of_tables(v: Any, key: str) -> list:
    """The scene's ``[[key]]`` tables (``v`` absent: none), at most :data:`.specs.MAX_TABLES`."""
    v = [] if v is None else v
    if not isinstance(v, list):
        raise ConfigError(f"{key} must be an array of tables ([[{key}]]), got {shown(v)}")
    if len(v) > MAX_TABLES:
        raise ConfigError(f"{key} must have at most {MAX_TABLES:,} tables ([[{key}]]), "
                          f"got {len(v):,}")
    return v
