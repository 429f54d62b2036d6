"""Reading TOML files (configs, cameras, sweep manifests) with one clear error."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from ..errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["read_toml", "parse_toml"]


def parse_toml(text: str, where: str) -> dict[str, Any]:
    """Parse TOML text; a syntax error raises :class:`InputError` naming ``where`` and the line."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"malformed {where}: {exc}") from None


def read_toml(path: str | Path, what: str = "TOML file") -> dict[str, Any]:
    """Read a TOML file; a missing, undecodable or malformed file raises :class:`InputError`
    (``what`` names the kind of file in the message, e.g. ``"camera TOML"``)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{what} not found: {p}")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"malformed {what} {p}: {exc}") from None
    return parse_toml(text, f"{what} {p}")
