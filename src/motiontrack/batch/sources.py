"""The videos of a batch: files, folders, globs and manifests expanded to named videos."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

from ..errors import ConfigError, printable
from ..run.folders import source_name
from ..io.manifest import read_manifest_entries
from ..io.paths import expand_paths, is_pattern

__all__ = ["Video", "VIDEO_SUFFIXES", "expand_sources", "with_files"]

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
    if is_pattern(spec):
        return [Video(source_name(str(f)), str(f.resolve())) for f in expand_paths([spec])]
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


def with_files(videos: Sequence[Video], *, scene: str | None = None, camera: str | None = None,
               gt_from: str | None = None) -> list[Video]:
    """``videos`` with the batch's own files: a video without a scene or camera file of its own
    (from a manifest) takes ``scene`` and ``camera``; ``gt_from``, a manifest of ``[[sequence]]``
    tables, gives a video the ground truth (and scene and camera, where it names them and the
    video has none) of the entry with the video's name or, failing that, its source. A
    ``gt_from`` that matches no video is refused: its names or sources are not this batch's."""
    for what, path in (("--scene", scene), ("--camera", camera)):
        if path is not None and not os.path.isfile(path):
            raise ConfigError(f"{what} {printable(path)}: no such file")
    by_name: dict[str, dict] = {}
    by_source: dict[str, dict] = {}
    if gt_from is not None:
        entries = read_manifest_entries(gt_from, files=("scene", "camera"))
        by_name = {e["name"]: e for e in entries}
        by_source = {_same_file(e["source"]): e for e in entries}
    out, matched = [], 0
    for v in videos:
        entry = by_name.get(v.name) or by_source.get(_same_file(v.source))
        gt, sc, cam = v.gt, v.scene, v.camera
        if entry is not None:
            matched += 1
            gt = gt or entry.get("gt")
            sc = sc or entry.get("scene")
            cam = cam or entry.get("camera")
        sc = sc or (str(Path(scene).resolve()) if scene else None)
        cam = cam or (str(Path(camera).resolve()) if camera else None)
        out.append(Video(v.name, v.source, gt, sc, cam))
    if gt_from is not None and not matched:
        raise ConfigError(f"--gt-from {printable(gt_from)}: none of its sequences is one of the "
                          f"{len(videos)} videos (matched by name, then by source path)")
    return out


def _same_file(source: str) -> str:
    """A key equal for two spellings of one file (synth: and stream sources as written)."""
    if ":" in source and not os.path.exists(source):
        return source
    return os.path.normcase(os.path.realpath(source))
