"""Sequences manifests: the TOML files that name the videos of a study or a batch.

A manifest is a list of ``[[sequence]]`` tables, each a source and optionally its name, its
ground truth, its group and, for ``motiontrack batch``, more files per entry (``scene``,
``camera``)::

    [[sequence]]
    name = "pets-s2l1"              # optional (default: derived from the source)
    source = "pets09-s2l1/video.avi" # relative paths are relative to the manifest
    gt = "pets09-s2l1/gt_mot15.txt"  # optional for synth: sources
    group = "outdoor, medium crowd"  # optional: the sequence type (thesis table 4.1)

:class:`ManifestEntry` is the schema of one table (:mod:`motiontrack.schema`: each key's type
and meaning, one-line messages naming ``sequence[2].gt``), :class:`BatchEntry` that of a batch's,
which may name its ``scene`` and ``camera`` too; :func:`manifest_json_schema` exports it.
:func:`read_manifest_entries` reads the tables as they are (whether an entry needs ground truth
is the caller's rule); :func:`read_manifest` reads them as :class:`SequenceSpec` values, the
sequences of a study, which need ground truth unless synthetic.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Sequence

from ..errors import ConfigError, InputError, printable
from ..schema import REQUIRED, Section, from_dict, json_schema, param
from .tomlfile import read_toml

__all__ = ["SequenceSpec", "ManifestEntry", "BatchEntry", "read_manifest",
           "read_manifest_entries", "default_sequence_name", "absolute_path",
           "manifest_json_schema"]


@dataclass(frozen=True, kw_only=True)
class ManifestEntry(Section):
    """One ``[[sequence]]`` table of a manifest, as written."""

    name: str | None = param(None, doc="short unique name (default: from the source: a synth: "
                                       "scene's name, else the file's stem or its folder's)")
    source: str = param(REQUIRED, nonblank=True,
                        doc="video, image folder or synth:NAME; relative paths are relative to "
                            "the manifest")
    gt: str | None = param(None, doc="ground-truth file (any supported format); a study needs "
                                     "it unless the source is synth:")
    group: str = param("", doc="the sequence type; plots average per group")


@dataclass(frozen=True, kw_only=True)
class BatchEntry(ManifestEntry):
    """One ``[[sequence]]`` table of a ``motiontrack batch`` manifest: an entry may name its
    own scene file and camera calibration."""

    scene: str | None = param(None, doc="scene file for this sequence (motiontrack batch)")
    camera: str | None = param(None, doc="camera calibration for this sequence "
                                         "(motiontrack batch)")


_BATCH_FILES = tuple(f.name for f in fields(BatchEntry)
                     if f.name not in {g.name for g in fields(ManifestEntry)})


@dataclass(frozen=True)
class SequenceSpec:
    """One sequence of a study.

    Parameters
    ----------
    name : str
        Short unique name (table column ``sequence``).
    source : str
        Anything :func:`~motiontrack.io.sources.open_source` accepts (file, folder, ``synth:...``).
    gt : str or None
        Ground-truth file (any supported format); ``None`` only for ``synth:`` sources, whose
        exact ground truth is rendered with the scene.
    group : str
        Sequence type (the thesis' table 4.1 groups sequences by type); plots average per study.
    """

    name: str
    source: str
    gt: str | None = None
    group: str = ""

    def __post_init__(self) -> None:
        for what, value in (("name", self.name), ("source", self.source), ("group", self.group)):
            if not isinstance(value, str):
                raise ConfigError(f"sequence {what} must be a string, got {value!r}")
        if self.gt is not None and not isinstance(self.gt, str):
            raise ConfigError(f"sequence {self.name!r}: gt must be a file name, got {self.gt!r}")
        # the name is a folder of runs/rNNN/: one plain path component
        if (not self.name or self.name in (".", "..") or any(c in self.name for c in "/\\")
                or not self.name.isprintable()):
            raise ConfigError(f"sequence name must be non-empty, not . or .., without slashes or "
                              f"control characters, got {self.name!r}")
        if not self.source:
            raise ConfigError(f"sequence {self.name!r} has no source")
        if self.gt is None and not self.source.startswith("synth:"):
            raise ConfigError(f"sequence {self.name!r}: --gt is required for non-synthetic source "
                              f"{self.source!r}")

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.name, "source": self.source, "gt": self.gt, "group": self.group}


def default_sequence_name(source: str) -> str:
    """The name of a sequence given none: a ``synth:`` scene's name, else the file's stem, or
    the folder's name for a file named as benchmarks name theirs (``video``, ``input``,
    ``img1``)."""
    if source.startswith("synth:"):
        return source[len("synth:"):].split("?")[0] or "synth"
    p = Path(source)
    named_by_folder = p.stem in ("video", "input", "img1") and p.parent.name
    return (p.parent.name if named_by_folder else p.stem) or "seq"


def absolute_path(path: str | None, base: Path | None = None) -> str | None:
    """``path`` made absolute (a relative one taken relative to ``base`` when given, else to the
    working folder); ``None`` and ``synth:`` sources as they are."""
    if path is None or str(path).startswith("synth:"):
        return path
    p = Path(path)
    if not p.is_absolute() and base is not None:
        p = base / p
    return str(p.resolve())


def read_manifest(path: str | Path) -> tuple[SequenceSpec, ...]:
    """The sequences of a manifest (the format is in the module's description), each a study's
    :class:`SequenceSpec`; :class:`InputError` naming the file and the entry otherwise."""
    out = []
    for i, entry in enumerate(read_manifest_entries(path), 1):
        try:
            out.append(SequenceSpec(**entry))
        except ConfigError as exc:
            raise InputError(f"{printable(Path(path))}: sequence {i}: {printable(exc)}") from None
    return tuple(out)


def read_manifest_entries(path: str | Path, files: Sequence[str] = ()) -> list[dict[str, Any]]:
    """The ``[[sequence]]`` tables of a manifest as dicts of ``name``, ``source``, ``gt``,
    ``group`` and, when given, the keys ``files`` (more file names per entry, such as ``scene``
    and ``camera`` for ``motiontrack batch``), paths made absolute (relative ones are relative to
    the manifest). Whether a sequence needs ground truth is the caller's rule."""
    if files and set(files) != set(_BATCH_FILES):
        raise ValueError(f"a manifest entry names the files {', '.join(_BATCH_FILES)} or none")
    p = Path(path)
    data = read_toml(p, "sequences manifest")
    shown = printable(p)
    items = data.get("sequence")
    if not isinstance(items, list) or not items:
        raise InputError(f"{shown}: expected one or more [[sequence]] tables")
    schema = BatchEntry if files else ManifestEntry
    out = []
    for i, it in enumerate(items, 1):
        where = f"sequence[{i}]"
        try:
            t = from_dict(schema, it, where)
            entry = {"name": t.name or default_sequence_name(t.source),
                     "source": absolute_path(t.source, p.parent),  # synth: as written
                     "gt": absolute_path(t.gt, p.parent), "group": t.group}
            entry.update({k: absolute_path(getattr(t, k), p.parent) for k in files
                          if getattr(t, k) is not None})
        except ConfigError as exc:
            raise InputError(f"{shown}: {printable(exc)}") from None
        except ValueError as exc:  # a NUL in a path
            raise InputError(f"{shown}: {where}: {printable(exc)}") from None
        out.append(entry)
    names = [s["name"] for s in out]
    if len(set(names)) != len(names):
        raise InputError(f"{shown}: sequence names must be unique, got {names}")
    return out


def manifest_json_schema() -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of a sequences manifest, for editors: one or more
    ``[[sequence]]`` tables (``scene`` and ``camera`` are read by ``motiontrack batch`` only);
    other top-level keys are left to the reader."""
    entry = json_schema(BatchEntry)
    del entry["$schema"]
    return {"$schema": "https://json-schema.org/draft/2020-12/schema",
            "title": "motiontrack sequences manifest", "type": "object",
            "properties": {"sequence": {"type": "array", "items": entry, "minItems": 1,
                                        "description": "[[sequence]] tables, one per "
                                                       "sequence"}},
            "required": ["sequence"]}
