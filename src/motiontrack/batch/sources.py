"""The videos of a batch: files, folders, globs and manifests expanded to named videos."""

from __future__ import annotations

import glob
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

from ..errors import ConfigError, printable
from ..run.folders import source_name
from ..studies.sweep import read_manifest_entries

__all__ = ["Video", "VIDEO_SUFFIXES", "expand_sources"]

#: the files a folder SOURCE contributes (case-insensitive)
VIDEO_SUFFIXES = (".avi", ".mp4", ".mov", ".mkv", ".m4v", ".mpg", ".mpeg", ".webm", ".wmv",
                  ".flv", ".ts", ".mjpeg", ".mjpg")


@dataclass(frozen=True)
class Video:
    """One video of a batch: its unique ``name`` (the folder ``RESULTS/<name>``), its source and
    the optional ground truth, scene and camera files (absolute paths)."""

    name: str
    source: str
    gt: str | None = None
    scene: str | None = None
    camera: str | None = None


def _videos_in(folder: Path) -> list[str]:
    return sorted(str(p) for p in folder.iterdir()
                  if p.is_file() and p.suffix.lower() in VIDEO_SUFFIXES)


def _expand_one(spec: str) -> list[Video]:
    if spec.endswith(".toml") and os.path.isfile(spec):
        return [Video(e["name"], e["source"], e["gt"], e.get("scene"), e.get("camera"))
                for e in read_manifest_entries(spec, files=("scene", "camera"))]
    if ":" in spec and not os.path.exists(spec) and spec.split(":", 1)[0].isalpha() \
            and len(spec.split(":", 1)[0]) > 1:   # synth:NAME and other schemes, never C:\
        return [Video(source_name(spec), spec)]
    p = Path(spec)
    if p.is_dir():
        found = _videos_in(p)
        if not found:
            raise ConfigError(f"no video files ({', '.join(VIDEO_SUFFIXES)}) in folder "
                              f"{printable(spec)}")
        return [Video(source_name(f), str(Path(f).resolve())) for f in found]
    if any(ch in spec for ch in "*?[") and not p.exists():
        found = sorted(f for f in glob.glob(spec, recursive=True) if os.path.isfile(f))
        if not found:
            raise ConfigError(f"no files match {printable(spec)}")
        return [Video(source_name(f), str(Path(f).resolve())) for f in found]
    # a file, or a path that does not exist: the latter becomes a failed row, not a refusal
    return [Video(Path(spec).stem or "video", str(p.resolve()))]


def expand_sources(sources: Iterable[str]) -> list[Video]:
    """The videos of ``sources`` in order, each name unique (``name``, ``name-2``, ...).

    A folder gives its video files (:data:`VIDEO_SUFFIXES`, sorted by name), a glob its matching
    files (``**`` crosses folders), a ``.toml`` file its ``[[sequence]]`` tables (``name``,
    ``source``, ``gt``, ``scene``, ``camera``), ``synth:...`` one synthetic scene, anything else
    one video file (one that does not exist fails in the batch, as a corrupt one does).
    """
    videos: list[Video] = []
    for spec in sources:
        videos += _expand_one(str(spec))
    if not videos:
        raise ConfigError("give one or more SOURCES (files, folders, globs or a manifest .toml)")
    seen: dict[str, int] = {}
    taken = {v.name for v in videos}
    out = []
    for v in videos:
        seen[v.name] = seen.get(v.name, 0) + 1
        name = v.name
        if seen[v.name] > 1:
            n = seen[v.name]
            while f"{v.name}-{n}" in taken:
                n += 1
            name = f"{v.name}-{n}"
            taken.add(name)
        out.append(Video(name, v.source, v.gt, v.scene, v.camera))
    return out
