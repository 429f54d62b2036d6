"""Reading TOML files (configs, cameras, sweep manifests) with one clear error."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from ..errors import InputError, printable
from .textfile import read_text

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["read_toml", "parse_toml", "MAX_TOML_BYTES"]

#: largest TOML file read (configs, cameras and manifests are a few kB)
MAX_TOML_BYTES = 16 * 2**20


def parse_toml(text: str, where: str) -> dict[str, Any]:
    """Parse TOML text; a syntax error raises :class:`InputError` naming ``where``, the line and
    the column (never the text: the file may be anything a user passed by mistake), and so does
    nesting deeper than the parser can follow (arrays in arrays thousands deep)."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        # tomllib's messages name the line and column and quote no content
        raise InputError(f"malformed {printable(where)}: {printable(exc)}") from None
    except ValueError:  # an integer literal of thousands of digits (int's conversion limit)
        raise InputError(f"malformed {printable(where)}: a number with too many digits") \
            from None
    except RecursionError:
        raise InputError(f"malformed {printable(where)}: arrays or tables nested too deeply") \
            from None


def read_toml(path: str | Path, what: str = "TOML file") -> dict[str, Any]:
    """Read a TOML file; a missing, undecodable or malformed file raises :class:`InputError`
    (``what`` names the kind of file in the message, e.g. ``"camera TOML"``)."""
    p = Path(path)
    text = read_text(p, what, MAX_TOML_BYTES, encoding="utf-8")
    return parse_toml(text, f"{what} {p}")
