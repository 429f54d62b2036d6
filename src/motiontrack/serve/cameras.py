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
    speed = 20                    # optional: a file plays 20 times faster than its frame rate

Relative paths are relative to the cameras file. The file's schema is :class:`CameraTable`
(:mod:`motiontrack.schema`); every problem is one :class:`ConfigError` naming the key as written
(``camera[2].source``), what is expected and what arrived.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import ConfigError
from ..io.tomlfile import read_toml
from ..schema import REQUIRED, Section, from_dict, json_schema, param

__all__ = ["CameraSpec", "CameraTable", "load_cameras", "parse_cameras", "cameras_json_schema"]

_URL = re.compile(r"[A-Za-z][A-Za-z0-9+.-]*://")


@dataclass(frozen=True, kw_only=True)
class CameraTable(Section):
    """One ``[[camera]]`` table as written (paths not yet resolved)."""

    name: str = param(REQUIRED, pattern=r"[A-Za-z0-9_-]{1,40}",
                      pattern_doc="1 to 40 letters, digits, '_' or '-'",
                      doc="the camera's name in URLs and folder names")
    source: str = param(REQUIRED, nonblank=True,
                        doc="anything `track` accepts: file, camera index, URL, synth:NAME")
    scene: str | None = param(None, nonblank=True, doc="scene file: lines and zones")
    config: str | None = param(None, nonblank=True,
                               doc="pipeline config file (applied after preset)")
    preset: str | None = param(None, nonblank=True, doc="shipped settings to start from")
    camera: str | None = param(None, nonblank=True,
                               doc="calibration file (world positions, rules in metres)")
    loop: bool = param(False, doc="a video file starts again at its end")
    fps: float | None = param(None, lo=0, lo_open=True, hi=1000,
                              doc="the frame rate to play and analyse at")
    speed: float = param(1.0, lo=0, lo_open=True, hi=1000,
                         doc="a video file, image folder or synth: scene plays this many times "
                             "faster than its frame rate (its times stay those of the frame "
                             "rate); a live source comes as it comes")


@dataclass(frozen=True, kw_only=True)
class CamerasFile(Section):
    """The cameras file of ``motiontrack serve``."""

    camera: tuple[CameraTable, ...] = param((), doc="one table per camera")


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
    speed: float = 1.0


def _path(base: Path, v: str | None) -> Path | None:
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


def parse_cameras(data: Any, base: str | Path = ".") -> tuple[CameraSpec, ...]:
    """The cameras a parsed cameras file lists (paths relative to ``base``)."""
    if not isinstance(data, dict):
        raise ConfigError("the cameras file must be a TOML table")
    if isinstance(data.get("camera"), list) and not data["camera"] or "camera" not in data:
        raise ConfigError("the cameras file lists no cameras: add [[camera]] tables with name "
                          "and source")
    tables = from_dict(CamerasFile, data).camera
    base = Path(base)
    cams = tuple(CameraSpec(name=t.name, source=_source(base, t.source),
                            config=_path(base, t.config), preset=t.preset,
                            scene=_path(base, t.scene), camera=_path(base, t.camera),
                            loop=t.loop, fps=t.fps, speed=t.speed)
            for t in tables)
    seen: set[str] = set()
    for i, c in enumerate(cams, 1):
        if c.name in seen:
            raise ConfigError(f"camera[{i}].name {c.name!r} is used by an earlier camera")
        seen.add(c.name)
    return cams


def cameras_json_schema() -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of the cameras file, for editors."""
    out = json_schema(CamerasFile, title="motiontrack serve cameras file")
    out["properties"]["camera"]["minItems"] = 1
    out["required"] = ["camera"]
    return out


def load_cameras(path: str | Path) -> tuple[CameraSpec, ...]:
    """Read and validate a cameras file; problems name the file."""
    data = read_toml(path, "cameras file")
    try:
        return parse_cameras(data, Path(path).resolve().parent)
    except ConfigError as exc:
        raise ConfigError(f"cameras file {Path(path).name}: {exc}") from None
