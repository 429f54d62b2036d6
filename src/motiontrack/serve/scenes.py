"""The scene files the web editor reads and writes: only those the cameras file names.

The editor sees a scene as ``{"lines": [{"name", "points"}], "zones": [{"name", "polygon",
"loiter_s"?}]}`` (pixels). Saving replaces the file's ``[[line]]`` and ``[[zone]]`` tables and
keeps its other settings (``anchor``, ``[stationary]``...); the result is validated as
``track --scene`` would read it (:func:`~motiontrack.analytics.parse_scene`, with the camera's
calibration when the cameras file gives one, so ``world`` geometry in metres is checked as the
camera will project it) and written under a temporary name then renamed, so the camera, which
reloads the file when it changes, never reads half a file.
"""

from __future__ import annotations

import math
import threading
from pathlib import Path
from typing import Any, Mapping

import tomli_w

from ..analytics import parse_scene
from ..errors import ConfigError, InputError
from ..io.atomic import atomic_write_text
from ..io.tomlfile import parse_toml, read_toml

__all__ = ["SceneFiles", "check_scene_files"]


def _clean(v: Any, where: str) -> Any:
    """``v`` as TOML can hold it: JSON null and non-finite numbers are refused."""
    if isinstance(v, dict):
        return {str(k): _clean(x, f"{where}.{k}") for k, x in v.items()}
    if isinstance(v, list):
        return [_clean(x, where) for x in v]
    if v is None:
        raise ConfigError(f"{where} must not be null")
    if isinstance(v, float) and not math.isfinite(v):
        raise ConfigError(f"{where} must be a finite number")
    return v


def _calibration(path: Path | None, size: tuple[int, int] | None) -> Any:
    """The camera model of the calibration file ``path`` (None: none), fitted to frames of
    ``size`` when it is known."""
    if path is None:
        return None
    from ..calibrate import fit_to_image, load_camera

    camera = load_camera(path)
    return fit_to_image(camera, *size, str(path)) if size else camera


class SceneFiles:
    """Camera name → its scene file (None: the camera has no scene file), and its calibration
    file (``cameras``; absent or None: none)."""

    def __init__(self, files: Mapping[str, Path | None],
                 cameras: Mapping[str, Path | None] | None = None) -> None:
        self.files = dict(files)
        self.cameras = dict(cameras or {})
        self._lock = threading.Lock()

    def path(self, name: str) -> Path | None:
        return self.files.get(name)

    def read(self, name: str) -> dict[str, Any]:
        """The editor's view of the camera's scene file (empty lists when the file is absent)."""
        path = self.path(name)
        if path is None:
            raise ConfigError(f"camera {name} has no scene file in the cameras file")
        data = read_toml(path, "scene file") if path.exists() else {}
        return {"lines": list(data.get("line", [])), "zones": list(data.get("zone", []))}

    def write(self, name: str, payload: Any, size: tuple[int, int] | None = None
              ) -> dict[str, Any]:
        """Validate the editor's ``payload`` merged into the scene file and write it atomically;
        the new editor's view. Bad geometry is a :class:`ConfigError` naming the key. ``size``:
        the camera's frame size, when known (its calibration is fitted to it)."""
        path = self.path(name)
        if path is None:
            raise ConfigError(f"camera {name} has no scene file in the cameras file")
        if not isinstance(payload, dict):
            raise ConfigError("the scene must be a JSON object with lines and zones")
        lines, zones = payload.get("lines", []), payload.get("zones", [])
        if not isinstance(lines, list) or not isinstance(zones, list):
            raise ConfigError("lines and zones must be arrays")
        with self._lock:
            data = read_toml(path, "scene file") if path.exists() else {}
            data["line"] = _clean(lines, "lines")
            data["zone"] = _clean(zones, "zones")
            if not data["line"]:
                del data["line"]
            if not data["zone"]:
                del data["zone"]
            parse_scene(data, _calibration(self.cameras.get(name), size), source=str(path))
            try:
                text = tomli_w.dumps(data)
            except (TypeError, ValueError) as exc:
                raise ConfigError(f"the scene cannot be written as TOML: {exc}") from None
            parse_toml(text, "scene file")   # what the camera will read back
            atomic_write_text(path, text)
        return self.read(name)


def check_scene_files(files: Mapping[str, Path | None],
                      cameras: Mapping[str, Path | None] | None = None) -> None:
    """Every named scene file readable and valid before any camera starts (an absent file is
    an error: the editor writes only files that exist), with the camera's calibration when
    ``cameras`` gives one."""
    cameras = cameras or {}
    for name, path in files.items():
        if path is None:
            continue
        if not path.is_file():
            raise InputError(f"camera {name}: scene file {path} does not exist")
        data = read_toml(path, "scene file")
        try:
            parse_scene(data, _calibration(cameras.get(name), None), source=str(path))
        except ConfigError as exc:
            if "needs a camera calibration" not in str(exc):
                raise ConfigError(f"camera {name}: scene file {path.name}: {exc}") from None
