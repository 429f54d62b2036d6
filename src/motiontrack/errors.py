"""Exceptions that the CLI turns into one clear message and a non-zero exit code."""

from __future__ import annotations

import errno
import math
import re
import tempfile
from pathlib import Path


class MotionTrackError(Exception):
    """Base for errors caused by the user's input (files, parameters), not by a bug."""

    exit_code = 2


class InputError(MotionTrackError):
    """A source, annotation or config file is missing, empty, corrupt or malformed."""


class ConfigError(MotionTrackError, ValueError):
    """A parameter is unknown or out of its allowed range."""


class SourceError(MotionTrackError):
    """A video source cannot be opened or failed while reading."""

    exit_code = 3


# ------------------------------------------------------------------------------- safe messages
#: most characters of a file's content a message may quote (see :func:`excerpt`)
EXCERPT_CHARS = 20

#: characters that end the token an error message quotes (see :func:`token_at`)
_TOKEN_END = frozenset(" \t\r\n\f\v,;:=\"'<>{}[]()")


def printable(text: object) -> str:
    """``text`` made safe for one line of a message.

    Every character that is not printable (control characters such as ``\\n`` and ``\\x1b``, line
    and paragraph separators, bidirectional overrides, lone surrogates from undecodable file
    names) is written as its Python escape, so that neither a file name nor a file's content can
    start a new line, forge a log message or colour the terminal. Printable text, backslashes
    included, is left as it is, so applying this twice changes nothing.
    """
    s = str(text)
    if s.isprintable():
        return s
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in s)


def opencv_reason(exc: Exception) -> str:
    """The message of an OpenCV error without its source file and function: ``input 'x' is not
    found`` from ``OpenCV(5.0.0) /io/...cpp:1042: error: (-204:...) input 'x' is not found in
    function '...'``; one line, at most 120 characters."""
    text = " ".join(str(exc).split())
    m = re.search(r"error: \([-\d]+:[^)]*\) (.*?)(?: in function .*)?$", text)
    return printable((m.group(1) if m else text)[:120])


def excerpt(token: object, limit: int = EXCERPT_CHARS) -> str:
    """A short, quoted, escaped excerpt of a file's content for an error message.

    At most ``limit`` characters of ``token`` are quoted (``...`` marks a cut), escaped with
    :func:`printable`; a message never quotes more of a file than this, so an error about a file
    that was given by mistake (a secret, ``/etc/passwd``) does not print its content.
    """
    s = str(token)
    cut = len(s) > limit
    return "'" + printable(s[:limit]).replace("'", "\\'") + ("...'" if cut else "'")


def require_file(path: object, what: str) -> Path:
    """``path`` as a :class:`~pathlib.Path` when it names an existing regular file; otherwise an
    :class:`InputError` saying which ``what`` (e.g. ``"camera file"``) is missing, a folder, or
    a device, pipe or socket."""
    p = Path(path)
    if p.is_dir():
        raise InputError(f"{what} {location(p)}: is a folder, not a file")
    if not p.is_file():
        if p.exists():
            raise InputError(f"{what} {location(p)}: not a regular file (a device, pipe or "
                             "socket)")
        raise InputError(f"{what} not found: {location(p)}")
    return p


def finite_number(text: str, where: str, field: str = "") -> float:
    """A field of a text file as a finite float; otherwise an :class:`InputError` at ``where``
    (``file:line:column``) naming the ``field`` and quoting at most an :func:`excerpt` of it."""
    named = f" in {field}" if field else ""
    try:
        v = float(text)
    except ValueError:
        raise InputError(f"{where}: non-numeric value{named}: expected a number, got "
                         f"{excerpt(text)}") from None
    if not math.isfinite(v):
        raise InputError(f"{where}: non-finite value{named}: expected a finite number, got "
                         f"{excerpt(text)}")
    return v


def token_at(text: str, start: int = 0) -> str:
    """The token of ``text`` that starts at index ``start``: up to the next separator (space,
    comma, semicolon, colon, ``=``, a quote or a bracket), or the separator itself when ``text``
    has one there. An error message quotes this (through :func:`excerpt`) rather than the line."""
    end = start
    while end < len(text) and text[end] not in _TOKEN_END:
        end += 1
    return text[start:max(end, start + 1)]


def location(path: object, line: int | None = None, column: int | None = None) -> str:
    """``file:line:column`` for messages (line and column 1-based and optional), the file name
    escaped with :func:`printable`."""
    out = printable(path)
    if line is not None:
        out += f":{line}"
        if column is not None:
            out += f":{column}"
    return out


def describe_os_error(exc: OSError) -> str:
    """One line for a failed file operation, in the user's terms: which path, and what is wrong
    with it (a folder where a file was expected, a file where a folder was expected, no
    permission, a full disk, ...)."""
    name = exc.filename if exc.filename is not None else ""
    shown = printable(name)
    code = exc.errno
    if code == errno.ENOTDIR and name:
        for parent in Path(str(name)).parents:
            if parent.exists() and not parent.is_dir():
                return f"{shown}: {printable(parent)} is a file, not a folder"
        return f"{shown}: a part of this path is a file, not a folder"
    if code == errno.EEXIST and name and Path(str(name)).is_file():
        return f"{shown}: is a file, not a folder"
    reasons = {
        errno.EEXIST: "already exists",
        errno.EISDIR: "is a folder, not a file",
        errno.EACCES: "permission denied",
        errno.EPERM: "operation not permitted",
        errno.EROFS: "read-only file system",
        errno.ENOSPC: "no space left on the device",
        errno.EDQUOT: "disk quota exceeded",
        errno.ENOENT: "no such file or folder",
        errno.ENAMETOOLONG: "file name too long",
        errno.ELOOP: "too many levels of symbolic links",
    }
    reason = reasons.get(code) or printable(exc.strerror or type(exc).__name__)
    return f"{shown}: {reason}" if shown else reason


def check_output_path(path: object, what: str = "output", folder: bool = False) -> None:
    """Refuse, before any work is done, an output that cannot be written.

    ``path`` is the file (or, with ``folder``, the folder) a command will write; ``what`` names it
    in the message (e.g. ``"-o"``). Refused, as :class:`InputError`: a file output that names a
    folder, a folder output that names a file, a path under a file, and a folder in which nothing
    can be created (no permission, read-only file system: found by creating and removing a
    temporary file there, which also holds for root). ``-`` (standard output) passes. Whether an
    existing output may be overwritten is for the caller (``--force``).
    """
    if str(path) == "-":  # standard output
        return
    p = Path(str(path))
    shown = printable(p)
    if folder and p.exists() and not p.is_dir():
        raise InputError(f"{what} {shown}: is a file, not a folder")
    if not folder and p.is_dir():
        raise InputError(f"{what} {shown}: is a folder; name a file")
    base = p if folder else p.parent
    while not base.exists() and base.parent != base:
        base = base.parent
    if not base.is_dir():
        raise InputError(f"{what} {shown}: {printable(base)} is a file, not a folder")
    try:
        with tempfile.TemporaryFile(dir=base):
            pass
    except OSError as exc:
        exc.filename = None
        raise InputError(f"{what} {shown}: cannot write in {printable(base)}: "
                         f"{describe_os_error(exc)}") from None
