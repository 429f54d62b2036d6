"""File arguments given as paths or glob patterns: the one expansion every command that takes
several files uses (``calibrate chessboard``, ``gt-stats``, ``batch``).

A shell expands an unquoted ``left*.jpg`` itself; a quoted one (the only way on a shell that
does not, or for ``**``) reaches the command as the pattern, which :func:`expand_paths` expands
the same way: the matching files sorted in natural order (``left2`` before ``left10``), ``**``
crossing folders.
"""

from __future__ import annotations

import glob
import os
import re
from pathlib import Path
from typing import Any, Iterable

from ..errors import InputError, printable

__all__ = ["GLOB_CHARS", "is_pattern", "expand_paths", "natural_key"]

#: characters that make an argument that names no existing file a glob pattern
GLOB_CHARS = "*?["


def natural_key(text: str) -> list[Any]:
    """A sort key that orders the numbers inside names by value (``a2`` before ``a10``)."""
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", text)]


def is_pattern(arg: str | os.PathLike) -> bool:
    """Whether ``arg`` is a glob pattern: it holds ``*``, ``?`` or ``[`` and names no existing
    file or folder (``video[1080p].mp4`` that exists is that file)."""
    text = os.fspath(arg)
    return any(ch in text for ch in GLOB_CHARS) and not os.path.exists(text)


def expand_paths(args: Iterable[str | os.PathLike], what: str = "files") -> list[Path]:
    """The paths of ``args`` in order: an existing path, or one that is no pattern, as it is
    (a missing file is the command's to report, in its own words); a glob pattern as the
    files it matches, in natural order, ``**`` crossing folders.

    Raises
    ------
    InputError
        A pattern that matches no file (``what`` names what was looked for).
    """
    out: list[Path] = []
    for arg in args:
        if not is_pattern(arg):
            out.append(Path(arg))
            continue
        text = os.fspath(arg)
        found = sorted((f for f in glob.glob(text, recursive=True) if os.path.isfile(f)),
                       key=natural_key)
        if not found:
            raise InputError(f"no {what} match {printable(text)}")
        out += [Path(f) for f in found]
    return out
