"""Reading a small text file (configs, cameras, point lists) with one clear error."""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError, location, require_file

__all__ = ["read_text"]


def read_text(path: str | Path, what: str, max_bytes: int, encoding: str = "utf-8-sig") -> str:
    """The text of the file ``path``, refused with an :class:`InputError` naming ``what`` (the
    kind of file, e.g. ``"camera TOML"``) when it is missing, a folder, larger than
    ``max_bytes``, or not text in ``encoding`` (then with the line and column of the first byte
    that does not decode)."""
    p = require_file(path, what)
    size = p.stat().st_size
    if size > max_bytes:
        raise InputError(f"{what} {location(p)}: {size} bytes, more than the {max_bytes} such a "
                         "file may have")
    data = p.read_bytes()
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise InputError(f"{what} {location(p, line, column)}: not UTF-8 text (byte "
                         f"0x{data[exc.start]:02x})") from None
