"""Sequences manifests: the TOML files that name the videos of a study or a batch.

A manifest is a list of ``[[sequence]]`` tables, each a source and optionally its name, its
ground truth, its group and, for ``motiontrack batch``, more files per entry (``scene``,
``camera``)::

    [[sequence]]
    name = "pets-s2l1"              # optional (default: derived from the source)
    source = "pets09-s2l1/video.avi" # relative paths are relative to the manifest
    gt = "pets09-s2l1/gt_mot15.txt"  # optional for synth: sources
    group = "outdoor, medium crowd"  # optional: the sequence type (thesis table 4.1)

:func:`read_manifest_entries` reads the tables as they are (whether an entry needs ground truth
is the caller's rule); :func:`read_manifest` reads them as :class:`SequenceSpec` values, the
sequences of a study, which need ground truth unless synthetic.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from ..errors import ConfigError, InputError, printable
from .tomlfile import read_toml

__all__ = ["SequenceSpec", "read_manifest", "read_manifest_entries", "default_sequence_name",
           "absolute_path"]


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
    p = Path(path)
    data = read_toml(p, "sequences manifest")
    shown = printable(p)
    items = data.get("sequence")
    if not isinstance(items, list) or not items:
        raise InputError(f"{shown}: expected one or more [[sequence]] tables")
    out = []
    valid = ("name", "source", "gt", "group", *files)
    for i, it in enumerate(items, 1):
        if not isinstance(it, dict):
            raise InputError(f"{shown}: sequence {i} is not a table")
        unknown = sorted(set(it) - set(valid))
        if unknown:
            raise InputError(f"{shown}: sequence {i}: unknown key(s) "
                             f"{printable(', '.join(unknown))}; valid: {', '.join(valid)}")
        if not isinstance(it.get("source"), str):
            raise InputError(f"{shown}: sequence {i} needs source = \"...\"")
        for key in ("name", "gt", "group", *files):
            if key in it and not isinstance(it[key], str):
                raise InputError(f"{shown}: sequence {i}: {key} must be a string, got {it[key]!r}")
        try:
            entry = {"name": it.get("name") or default_sequence_name(it["source"]),
                     "source": absolute_path(it["source"], p.parent),  # synth: as written
                     "gt": absolute_path(it.get("gt"), p.parent), "group": it.get("group", "")}
            entry.update({k: absolute_path(it[k], p.parent) for k in files if k in it})
        except ValueError as exc:  # a NUL in a path
            raise InputError(f"{shown}: sequence {i}: {printable(exc)}") from None
        out.append(entry)
    names = [s["name"] for s in out]
    if len(set(names)) != len(names):
        raise InputError(f"{shown}: sequence names must be unique, got {names}")
    return out
