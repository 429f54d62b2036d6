"""The scene files the web editor reads and writes: only those the cameras file names.

The editor sees a scene as ``{"lines": [{"name", "points"}], "zones": [{"name", "polygon",
"loiter_s"?}]}`` (pixels). Saving changes only what was edited: the file is read as a TOML
document (``tomlkit``) that keeps its comments, order and formatting; a line or zone whose
name the file already has keeps its table, with only the keys whose values changed rewritten
(each keeping its trailing comment), new ones are appended, removed ones dropped, and the
tables are reordered only when the editor's order differs. Everything else (``anchor``,
``[stationary]``, comments...) stays byte for byte. The result is validated as
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

import tomlkit
from tomlkit.exceptions import TOMLKitError
from tomlkit.items import AoT, Item, Table

from ..analytics import parse_scene
from ..errors import ConfigError, InputError
from ..io.atomic import atomic_write_text
from ..io.textfile import read_text
from ..io.tomlfile import MAX_TOML_BYTES, parse_toml, read_toml

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


def _value(new: Any, old: Item | None = None) -> Item:
    """``new`` as a TOML item, with the comment and spacing of the item ``old`` it replaces."""
    item = tomlkit.item(new)
    if old is not None:
        for attr in ("indent", "comment_ws", "comment", "trail"):
            setattr(item.trivia, attr, getattr(old.trivia, attr))
    return item


def _update(table: Table, values: Mapping[str, Any]) -> None:
    """``table`` holding exactly ``values``: keys gone are removed, keys whose value changed
    rewritten in place, new keys appended; unchanged keys are not touched."""
    for key in [k for k in table if k not in values]:
        del table[key]
    for key, v in values.items():
        old = table.get(key)
        if old is None:
            table[key] = _value(v)
        elif not (isinstance(old, Item) and old.unwrap() == v):
            table[key] = _value(v, old if isinstance(old, Item) else None)


def _merge_tables(doc: tomlkit.TOMLDocument, key: str, items: list[dict]) -> None:
    """The array of tables ``[[key]]`` of ``doc`` set to ``items`` (matched by ``name``)."""
    old = doc.get(key)
    if not isinstance(old, AoT):   # absent, or written another way (an inline array)
        if key in doc:
            del doc[key]
        if items:
            doc.append(key, tomlkit.aot())
            for item in items:
                table = tomlkit.table()
                _update(table, item)
                doc[key].append(table)
        return
    by_name = {t.get("name"): t for t in old}
    tables = []
    for item in items:
        table = by_name.pop(item.get("name"), None)
        if table is None:
            table = tomlkit.table()
        _update(table, item)
        tables.append(table)
    if not tables:
        del doc[key]
    elif [id(t) for t in tables] != [id(t) for t in old]:
        while len(old):
            del old[0]
        for table in tables:
            old.append(table)


def _edited(path: Path, lines: list, zones: list) -> tuple[str, dict]:
    """The scene file's text with the editor's lines and zones, and its data."""
    text = (read_text(path, "scene file", MAX_TOML_BYTES, encoding="utf-8")
            if path.exists() else "")
    parse_toml(text, "scene file")   # a broken file is reported as reading it would
    try:
        doc = tomlkit.parse(text)
        _merge_tables(doc, "line", lines)
        _merge_tables(doc, "zone", zones)
        out = tomlkit.dumps(doc)
    except (TOMLKitError, TypeError, ValueError) as exc:
        raise ConfigError(f"the scene cannot be written as TOML: {exc}") from None
    return out, parse_toml(out, "scene file")   # what the camera will read back


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
            text, data = _edited(path, _clean(lines, "lines"), _clean(zones, "zones"))
            parse_scene(data, _calibration(self.cameras.get(name), size), source=str(path))
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
