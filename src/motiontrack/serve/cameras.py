"""The cameras file of ``motiontrack serve``: which cameras to run and how.

A TOML file with one ``[[camera]]`` table per camera::

    [[camera]]
    name = "gate"                 # 1-40 letters, digits, '_' or '-': in URLs and folder names
    source = "rtsp://10.0.0.5/1"  # anything `track` accepts: file, camera index, URL, synth:NAME
    scene = "gate-scene.toml"     # optional: lines and zones; the web editor writes this file
    config = "gate.toml"          # optional: pipeline config (applied after preset)
    preset = "people"             # optional: shipped settings
    camera = "View_001.xml"       # optional: calibration (world positions, rules in metres)
    loop = true                   # optional: a video file starts again at its end
    fps = 10                      # optional: the frame rate to play and analyse at

Relative paths are relative to the cameras file. Every problem is one :class:`ConfigError`
naming the key as written (``camera[2].source``).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import ConfigError, printable
from ..io.tomlfile import read_toml

__all__ = ["CameraSpec", "load_cameras", "parse_cameras"]

_NAME = re.compile(r"[A-Za-z0-9_-]{1,40}\Z")
_KEYS = ("name", "source", "config", "preset", "scene", "camera", "loop", "fps")
_URL = re.compile(r"[A-Za-z][A-Za-z0-9+.-]*://")


@dataclass(frozen=True)
class CameraSpec:
    """One camera of the cameras file, its paths resolved against the file's folder."""

    name: str
    source: str
    config: Path | None = None
    preset: str | None = None
    scene: Path | None = None
    camera: Path | None = None
    loop: bool = False
    fps: float | None = None


def _string(t: dict, key: str, where: str, required: bool = False) -> str | None:
    v = t.get(key)
    if v is None:
        if required:
            raise ConfigError(f"{where}.{key} is required")
        return None
    if not isinstance(v, str) or not v.strip():
        raise ConfigError(f"{where}.{key} must be a non-empty string, got {printable(repr(v))[:60]}")
    return v


def _path(base: Path, t: dict, key: str, where: str) -> Path | None:
    v = _string(t, key, where)
    if v is None:
        return None
    p = Path(v).expanduser()
    return p if p.is_absolute() else base / p


def _source(base: Path, v: str) -> str:
    """A file or folder source relative to the cameras file; schemes, URLs, camera indexes as
    written."""
    scheme = v.partition(":")[0]
    if v.isdigit() or _URL.match(v) or (":" in v and scheme.isalpha() and len(scheme) > 1):
        return v
    p = Path(v).expanduser()
    return str(p if p.is_absolute() else base / p)


def _camera(t: Any, where: str, base: Path) -> CameraSpec:
    if not isinstance(t, dict):
        raise ConfigError(f"{where} must be a table, got {type(t).__name__}")
    unknown = sorted(set(t) - set(_KEYS))
    if unknown:
        raise ConfigError(f"{where}: unknown key {printable(unknown[0])!r}; valid keys: "
                          f"{', '.join(_KEYS)}")
    name = _string(t, "name", where, required=True)
    if not _NAME.match(name):
        raise ConfigError(f"{where}.name must be 1 to 40 letters, digits, '_' or '-', got "
                          f"{printable(name)[:60]!r}")
    loop = t.get("loop", False)
    if not isinstance(loop, bool):
        raise ConfigError(f"{where}.loop must be true or false, got {printable(repr(loop))[:40]}")
    fps = t.get("fps")
    if fps is not None and (isinstance(fps, bool) or not isinstance(fps, (int, float))
                            or not math.isfinite(fps) or not 0 < fps <= 1000):
        raise ConfigError(f"{where}.fps must be a number in (0, 1000], got "
                          f"{printable(repr(fps))[:40]}")
    return CameraSpec(name=name, source=_source(base, _string(t, "source", where, required=True)),
                      config=_path(base, t, "config", where), preset=_string(t, "preset", where),
                      scene=_path(base, t, "scene", where), camera=_path(base, t, "camera", where),
                      loop=loop, fps=None if fps is None else float(fps))


def parse_cameras(data: Any, base: str | Path = ".") -> tuple[CameraSpec, ...]:
    """The cameras a parsed cameras file lists (paths relative to ``base``)."""
    if not isinstance(data, dict):
        raise ConfigError("the cameras file must be a TOML table")
    unknown = sorted(set(data) - {"camera"})
    if unknown:
        raise ConfigError(f"unknown key {printable(unknown[0])!r} in the cameras file; cameras "
                          "are [[camera]] tables")
    tables = data.get("camera")
    if not isinstance(tables, list) or not tables:
        raise ConfigError("the cameras file lists no cameras: add [[camera]] tables with name "
                          "and source")
    cams = tuple(_camera(t, f"camera[{i}]", Path(base)) for i, t in enumerate(tables, 1))
    seen: set[str] = set()
    for i, c in enumerate(cams, 1):
        if c.name in seen:
            raise ConfigError(f"camera[{i}].name {c.name!r} is used by an earlier camera")
        seen.add(c.name)
    return cams


def load_cameras(path: str | Path) -> tuple[CameraSpec, ...]:
    """Read and validate a cameras file; problems name the file."""
    data = read_toml(path, "cameras file")
    try:
        return parse_cameras(data, Path(path).resolve().parent)
    except ConfigError as exc:
        raise ConfigError(f"cameras file {Path(path).name}: {exc}") from None
