"""Parameter values of studies: the ``--param`` text of ``sweep`` (and the values ``tune``
shares with it), and values written back as ``--set``-style overrides.

Values syntax (one ``--param`` per parameter)::

    motion.median.threshold=0.05,0.1,0.2      explicit values (TOML literals or bare strings)
    regions.min_size=0:0.004:0.001            a:b:step, both ends inclusive
"""

from __future__ import annotations

import json
import sys
from decimal import Decimal, DecimalException, InvalidOperation
from typing import Any

from ..errors import ConfigError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["parse_param", "format_value", "parse_literal", "range_values"]


def parse_literal(text: str) -> Any:
    """A TOML literal (``3``, ``0.5``, ``true``, ``"a"``) or, failing that, the bare string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def range_values(a: str, b: str, step: str, item: str) -> tuple[Any, ...]:
    """Inclusive arithmetic range ``a, a+step, ..., <= b`` computed in decimal (no float drift:
    ``0:0.3:0.1`` gives exactly 0, 0.1, 0.2, 0.3); ints when all three are written as integers.
    ``item``, the whole ``--param`` text, is what errors name."""
    try:
        da, db, ds = Decimal(a.strip()), Decimal(b.strip()), Decimal(step.strip())
    except InvalidOperation:
        raise ConfigError(f"--param {item!r}: a:b:step needs three numbers") from None
    if not all(d.is_finite() for d in (da, db, ds)):
        raise ConfigError(f"--param {item!r}: a, b and step must be finite")
    if ds <= 0:
        raise ConfigError(f"--param {item!r}: step must be > 0, got {step.strip()}")
    if db < da:
        raise ConfigError(f"--param {item!r}: a:b:step needs a <= b")
    try:
        n = int((db - da) / ds) + 1
    except DecimalException:  # (b - a) / step beyond what decimal represents: far too many
        raise ConfigError(f"--param {item!r}: far too many values (at most 10000)") from None
    if n > 10000:
        raise ConfigError(f"--param {item!r}: {n} values is too many (at most 10000)")
    is_int = all(d == d.to_integral_value() and "." not in t and "e" not in t.lower()
                 for d, t in ((da, a), (db, b), (ds, step)))
    vals = [da + i * ds for i in range(n)]
    return tuple(int(v) for v in vals) if is_int else tuple(float(v) for v in vals)


def parse_param(item: str) -> tuple[str, tuple[Any, ...]]:
    """Parse one ``--param``: ``stage.name=v1,v2,...`` or ``stage.name=a:b:step``.

    Returns
    -------
    key : str
        Dotted config key, e.g. ``"motion.median.threshold"``.
    values : tuple
        The values in the order given (ints, floats, bools or strings).

    Raises
    ------
    ConfigError
        Malformed text, empty or repeated values, a bad range.
    """
    if "=" not in item:
        raise ConfigError(f"--param expects stage.name=v1,v2,... or stage.name=a:b:step, got {item!r}")
    key, text = item.split("=", 1)
    key, text = key.strip(), text.strip()
    if not key or any(not p for p in key.split(".")):
        raise ConfigError(f"--param expects a dotted config key before '=', got {item!r}")
    if not text:
        raise ConfigError(f"--param {item!r} has no values")
    if text.count(":") == 2 and "," not in text and not text.startswith(("'", '"')):
        if text.rsplit(":", 1)[1].strip().lower() == "log":
            raise ConfigError(f"--param {item!r}: a grid needs a step, a:b:step (a:b:log is a "
                              "search range of motiontrack tune)")
        values = range_values(*text.split(":"), item=item)
    elif ":" in text and "," not in text and not text.startswith(("'", '"')) and text.count(":") == 1:
        raise ConfigError(f"--param {item!r}: a grid needs a step, a:b:step (a:b without a step "
                          "is a search range of motiontrack tune)")
    else:
        parts = [p.strip() for p in text.split(",")]
        if any(not p for p in parts):
            raise ConfigError(f"--param {item!r} has an empty value")
        values = tuple(parse_literal(p) for p in parts)
    if len(set(map(repr, values))) != len(values):
        raise ConfigError(f"--param {item!r} repeats a value")
    return key, values


def format_value(v: Any) -> str:
    """A value as a TOML literal for ``--set``-style overrides."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    return json.dumps(str(v))  # a TOML basic string
