"""Default output folders: each run without ``-o`` gets a folder of its own,
``runs/<command>/<name>``, named after its source and numbered when the name is taken
(``<name>-2``, ``<name>-3``, ...), so that a second run never meets "output exists"."""

from __future__ import annotations

import contextlib
import logging
import os
import re
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from .. import synth as _synth  # noqa: F401  (registers the synth: sources)
from ..io.sources import SCHEMES

__all__ = ["RUNS", "source_name", "new_run_folder"]

log = logging.getLogger(__name__)

#: the folder that holds the default run folders, relative to the working directory
RUNS = Path("runs")
#: longest folder name derived from a source (file systems allow 255 bytes)
_MAX_NAME = 60
_URL = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*://")
_SCHEME = re.compile(r"^([A-Za-z][A-Za-z0-9_]*):(.*)$")


def _sanitised(name: str) -> str:
    """Letters, digits, ``_``, ``.`` and ``-`` only (runs of anything else become one ``-``), no
    leading dot or dash (no hidden folder, no ``..``), at most :data:`_MAX_NAME` characters."""
    name = re.sub(r"[^\w.-]+", "-", name)
    name = re.sub(r"-{2,}", "-", name)[:_MAX_NAME].strip(".-")
    return name or "run"


def source_name(spec: Any) -> str:
    """A folder name for the source ``spec``: ``camera0`` for a camera index, ``synth-NAME`` for
    ``synth:NAME?...`` (any registered ``SCHEME:NAME`` likewise), the host of a stream URL (never
    its user name or password), the stem of a video file, the name of an image folder, or the
    folder of a glob (``input`` for ``input/*.jpg``); sanitised (:func:`_sanitised`)."""
    if isinstance(spec, int) or (isinstance(spec, str) and spec.isdigit()):
        return f"camera{int(spec)}"
    text = os.fspath(spec) if isinstance(spec, (str, os.PathLike)) else str(spec)
    if text.startswith("file://"):
        text = text[len("file://"):]
    elif _URL.match(text):
        try:
            return _sanitised(urlsplit(text).hostname or "stream")
        except ValueError:   # an unclosed [ of an IPv6 address: opening it fails later
            return "stream"
    scheme = _SCHEME.match(text)
    if scheme and scheme.group(1) in SCHEMES:
        name = scheme.group(2).split("?", 1)[0]
        return _sanitised(f"{scheme.group(1)}-{name}" if name else scheme.group(1))
    path = Path(text)
    with contextlib.suppress(OSError):   # a name too long for the file system: no such file
        if path.is_file():
            return _sanitised(path.stem)
        if path.is_dir():
            return _sanitised(path.resolve().name)
    wild = [i for i, part in enumerate(path.parts) if any(ch in part for ch in "*?[")]
    if wild:   # a glob: the folder it reads from, else its own letters
        folder = [p for p in path.parts[:wild[0]] if p not in (path.anchor, ".", "..")]
        return _sanitised(folder[-1] if folder
                          else re.sub(r"[*?\[\]]", "", Path(path.parts[wild[0]]).stem))
    return _sanitised(path.stem)


def new_run_folder(command: str, source: Any, root: str | Path = RUNS) -> Path:
    """The output folder of a run without ``-o``: the first of ``root/command/<name>``,
    ``<name>-2``, ``<name>-3``, ... that does not exist (``name`` from :func:`source_name`).

    It is created by the job's folder lock (:class:`~motiontrack.io.atomic.OutputLock`), which
    removes it again, with the parents it created, when the run leaves it empty; a second run
    that picks the same name at the same moment is refused by that lock."""
    parent = Path(root) / command
    name = source_name(source)
    for k in range(1, 1_000_000):
        folder = parent / (name if k == 1 else f"{name}-{k}")
        if not os.path.lexists(folder):
            log.info("output folder %s", folder)
            return folder
    raise RuntimeError(f"no free run folder for {name} in {parent}")  # pragma: no cover
