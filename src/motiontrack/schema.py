"""Typed schemas of the files users write: fields with type, range, default and meaning.

A schema is a frozen dataclass whose fields are declared with :func:`param`; a nested table is a
field whose type is another such dataclass, an array of tables a ``tuple[Table, ...]`` field.
:func:`from_dict` builds one from parsed TOML or JSON, and every problem is one
:class:`~motiontrack.errors.ConfigError` line naming the key as written (``camera[2].fps``), what
is expected and what arrived::

    unknown key(s) camera[1].sorce; valid keys in camera[1]: camera, config, fps, ...
    camera[1].loop must be true or false, got 'yes'
    camera[1].fps must be in (0, 1000], got 0.0

:func:`json_schema` exports any schema as JSON Schema (draft 2020-12), for editors and other
tools; :func:`leaf_fields` lists its keys for reference tables. A field's ``when`` names the
switches it needs to take effect; :mod:`motiontrack.config_activity` follows them to warn about
keys that have no effect.

The pipeline config (:mod:`motiontrack.config`), the scene file (its top level
:class:`motiontrack.analytics.scene.SceneTop` and each analytics rule's table, such as
:class:`motiontrack.analytics.specs.StationarySpec`), serve's cameras file and the entries of a
sequences manifest (:class:`motiontrack.io.manifest.ManifestEntry`) are declared in it::

    @dataclass(frozen=True)
    class StationarySpec(SceneSection):
        after_s: float = param(REQUIRED, lo=0.0, lo_open=True, hi=COORD_LIMIT, doc="...")
        radius_px: float | None = param(None, lo=0.0, lo_open=True, hi=COORD_LIMIT, doc="...")

    @dataclass(frozen=True, kw_only=True)
    class LineTable(SceneSection):
        name: str = param(REQUIRED, nonblank=True, doc="unique among lines")
        points: tuple[tuple[float, float], ...] | None = param(None, lo=-1e7, hi=1e7, doc="...")

    rule = from_dict(StationarySpec, table, where="stationary")
    entries = [from_dict(ManifestEntry, e, where=f"sequence[{i}]") for i, e in enumerate(seq, 1)]

A ``tuple[float, float]`` field is a fixed-length array (a point); the range of a field of
numbers or points holds for each of its numbers, named by place (``line[1].points[2][1]``).
"""

from __future__ import annotations

import functools
import math
import re
import types
import typing
from dataclasses import MISSING, Field, dataclass, field, fields, is_dataclass
from typing import Any, Iterable, Iterator

from .errors import EXCERPT_CHARS, ConfigError, excerpt

__all__ = ["INT_MIN", "INT_MAX", "REQUIRED", "Not", "param", "Section", "from_dict",
           "leaf_fields", "allowed_text", "json_schema", "shown"]

#: bounds of an integer field that gives none: what OpenCV's ``int`` parameters hold
INT_MIN, INT_MAX = -(2**31), 2**31 - 1

#: the default of a field the file must give (:func:`param`)
REQUIRED: Any = MISSING


@dataclass(frozen=True)
class Not:
    """A ``when`` condition of :func:`param`: the switch differs from ``value``; ``example`` is
    a value that meets it (named in the hint that says how to make the key take effect)."""

    value: Any
    example: Any


def param(default: Any, *, lo: float | None = None, hi: float | None = None,
          lo_open: bool = False, choices: Iterable[Any] | None = None, odd: bool = False,
          pattern: str | None = None, pattern_doc: str = "", nonblank: bool = False,
          doc: str = "", when: Any = None, max_items: int | None = None) -> Any:
    """A schema field with its allowed values: ``lo <= value <= hi`` (``lo < value`` with
    ``lo_open``), one of ``choices``, for kernel sizes ``odd`` (0 means "off" and is always
    allowed for odd fields); a string matching ``pattern`` whole (``pattern_doc`` says what that
    is in words, for the message) or, with ``nonblank``, not empty or blank; an array of at
    most ``max_items`` items (checked before any item is read, so that the work a file can ask
    for is bounded).

    ``default`` is :data:`REQUIRED` for a key the file must give (declare the dataclass
    ``kw_only`` so that required and optional fields may come in any order), ``None`` for an
    optional one typed ``X | None``. Every number must be finite. An integer field without
    ``lo``/``hi`` is bounded by :data:`INT_MIN`/:data:`INT_MAX`, so that no value reaches OpenCV
    (or a loop or an allocation) that a C ``int`` cannot hold.

    ``when`` names the switches of the same section that the field needs to take effect:
    ``{"name": value}`` (all must hold; ``Not(value, example)`` for "anything but value"), or a
    tuple of such tables (any one must hold).
    """
    if isinstance(default, int) and not isinstance(default, bool) and choices is None:
        lo = INT_MIN if lo is None else lo
        hi = INT_MAX if hi is None else hi
    if isinstance(when, dict):
        when = (when,)
    meta = {"lo": lo, "hi": hi, "lo_open": lo_open,
            "choices": tuple(choices) if choices is not None else None,
            "odd": odd, "pattern": pattern, "pattern_doc": pattern_doc, "nonblank": nonblank,
            "doc": doc, "when": tuple(when or ()), "max_items": max_items}
    if default is REQUIRED:
        return field(metadata=meta)
    if isinstance(default, (list, dict, set)):
        raise TypeError("a schema default must be immutable (a tuple, not a list)")
    return field(default=default, metadata=meta)


def shown(v: Any) -> str:
    """A value for a message: numbers as written, an integer too long to read by its size, text
    as a short excerpt (it may come from any file given by mistake), tables and arrays by kind."""
    if isinstance(v, bool) or isinstance(v, float):
        return repr(v)
    if isinstance(v, int):
        return f"an integer of {len(str(abs(v)))} digits" if abs(v) >= 10**30 else repr(v)
    if isinstance(v, str):
        return excerpt(v)
    return {dict: "a table", list: "an array", tuple: "an array"}.get(
        type(v), f"a {type(v).__name__}")


def _range_text(m: typing.Mapping[str, Any]) -> str:
    lo, hi = m.get("lo"), m.get("hi")
    return (f"{'(' if m.get('lo_open') else '['}{'-inf' if lo is None else lo}, "
            f"{'inf' if hi is None else hi}]")


def check_value(m: typing.Mapping[str, Any], v: Any, where: str) -> None:
    """Check one value against a field's :func:`param` metadata ``m``; ``where`` names the key."""
    if not m or v is None:
        return
    if m.get("choices") is not None and v not in m["choices"]:
        raise ConfigError(f"{where} must be one of {', '.join(map(str, m['choices']))}, "
                          f"got {shown(v)}")
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        lo, hi = m.get("lo"), m.get("hi")
        rng = _range_text(m)
        if isinstance(v, float) and not math.isfinite(v):
            raise ConfigError(f"{where} must be a finite number in {rng}, got {v!r}")
        # written as "not inside" so that a value no comparison holds for is refused too
        above = lo is None or (lo < v if m.get("lo_open") else lo <= v)
        if not (above and (hi is None or v <= hi)):
            raise ConfigError(f"{where} must be in {rng}, got {shown(v)}")
        if m.get("odd") and v != 0 and int(v) % 2 == 0:
            raise ConfigError(f"{where} must be 0 (off) or an odd kernel size, got {shown(v)}")
    if isinstance(v, str):
        if m.get("nonblank") and not v.strip():
            raise ConfigError(f"{where} must be a non-empty string, got {shown(v)}")
        if m.get("pattern") and not re.fullmatch(m["pattern"], v):
            raise ConfigError(f"{where} must be {m.get('pattern_doc') or 'like ' + m['pattern']}"
                              f", got {shown(v)}")


class Section:
    """Mixin of a schema dataclass: every field is checked against its :func:`param` metadata
    after construction, however the section was built.

    ``schema_noun`` goes before "key" in an unknown-key message (``"config "``);
    :meth:`schema_where` names the section in messages of a section built directly (a schema
    inside a larger one overrides it with the key path users write).
    """

    schema_noun: typing.ClassVar[str] = ""

    @classmethod
    def schema_where(cls) -> str:
        return cls.__name__

    def __post_init__(self) -> None:
        name = type(self).schema_where()
        for f in fields(self):  # type: ignore[arg-type]
            check_value(f.metadata, getattr(self, f.name), f"{name}.{f.name}")


# ----------------------------------------------------------------------------------- types
def _optional(typ: Any) -> Any:
    """``X`` of ``X | None`` (``None`` when ``typ`` is not optional)."""
    if typing.get_origin(typ) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(typ) if a is not type(None)]
        if len(args) == 1 and len(typing.get_args(typ)) == 2:
            return args[0]
    return None


def _items(typ: Any) -> Any:
    """``X`` of ``tuple[X, ...]`` (an array), else ``None``."""
    if typing.get_origin(typ) is tuple:
        args = typing.get_args(typ)
        if len(args) == 2 and args[1] is Ellipsis:
            return args[0]
    return None


def _fixed(typ: Any) -> tuple[Any, ...] | None:
    """The item types of ``tuple[X, X]`` (a fixed-length array such as a point), else ``None``."""
    if typing.get_origin(typ) is tuple:
        args = typing.get_args(typ)
        if args and Ellipsis not in args:
            return args
    return None


def _numeric(typ: Any) -> bool:
    """Whether ``typ`` holds numbers only: a number, or a fixed-length array of them."""
    fixed = _fixed(typ)
    return typ in (int, float) or (fixed is not None and all(map(_numeric, fixed)))


def _coerce(value: Any, typ: Any, where: str, item_meta: typing.Mapping[str, Any] = {}) -> Any:
    """Check a value against its field type; ints are accepted where floats are expected, an
    integral float where an int is; arrays of tables and nested tables are built in turn. The
    numbers inside an array of numbers (or of points) are each checked against the field's
    range, passed down as ``item_meta``."""
    inner = _optional(typ)
    if inner is not None:
        return None if value is None else _coerce(value, inner, where, item_meta)
    if is_dataclass(typ):
        return from_dict(typ, value, where)
    item = _items(typ)
    if item is not None:
        if not isinstance(value, (list, tuple)):
            fixed = _fixed(item)
            what = (f" of [{', '.join('xyz'[:len(fixed)])}] points"
                    if fixed and _numeric(item) and len(fixed) <= 3 else "")
            raise ConfigError(f"{where} must be an array{what}, got {shown(value)}")
        return tuple(_coerce(v, item, f"{where}[{i}]", item_meta) for i, v in enumerate(value, 1))
    fixed = _fixed(typ)
    if fixed is not None:
        if not isinstance(value, (list, tuple)) or len(value) != len(fixed):
            what = (f"[{', '.join('xyz'[:len(fixed)])}]: " if _numeric(typ) and len(fixed) <= 3
                    else "")
            raise ConfigError(f"{where} must be {what}an array of {len(fixed)} "
                              f"{'numbers' if _numeric(typ) else 'values'}, got {shown(value)}")
        return tuple(_coerce(v, t, f"{where}[{i}]", item_meta)
                     for i, (v, t) in enumerate(zip(value, fixed), 1))
    if typ in (int, float) and item_meta:
        number = _coerce(value, typ, where)
        check_value(item_meta, number, where)
        return number
    if typ is bool:
        if isinstance(value, bool):
            return value
        raise ConfigError(f"{where} must be true or false, got {shown(value)}")
    if typ is int:
        if isinstance(value, bool) or not isinstance(value, int):
            if isinstance(value, float) and value.is_integer():
                return int(value)
            raise ConfigError(f"{where} must be an integer, got {shown(value)}")
        return value
    if typ is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{where} must be a number, got {shown(value)}")
        try:
            return float(value)
        except OverflowError:   # an integer of over 308 digits
            raise ConfigError(f"{where} must be a finite number, got {shown(value)}") from None
    if typ is str:
        if not isinstance(value, str):
            raise ConfigError(f"{where} must be a string, got {shown(value)}")
        return value
    return value


def _check_length(m: typing.Mapping[str, Any], value: Any, typ: Any, where: str) -> None:
    """Refuse an array longer than the field's ``max_items``, before its items are read."""
    most = m.get("max_items")
    if most is None or not isinstance(value, (list, tuple)) or len(value) <= most:
        return
    item = _items(typ)
    fixed = _fixed(item) if item is not None else None
    what = (f"[{', '.join('xyz'[:len(fixed)])}] points" if fixed and _numeric(item)
            and len(fixed) <= 3 else "items")
    raise ConfigError(f"{where} must have at most {most:,} {what}, got {len(value):,}")


def keys_shown(keys: list[str], prefix: str = "", most: int = 5) -> str:
    """Key names from a file for a message: the first ``most``, each after ``prefix`` as written
    when short and printable, else as a short excerpt."""
    text = ", ".join(prefix + (k if len(k) <= EXCERPT_CHARS and k.isprintable() else excerpt(k))
                     for k in keys[:most])
    return text + (f" and {len(keys) - most} more" if len(keys) > most else "")


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def from_dict(cls: type, data: Any, where: str = "") -> Any:
    """Build schema dataclass ``cls`` from a parsed table (``dict``); ``where`` is the table's
    key path as users write it (empty for a whole file). Unknown keys, missing required keys,
    wrong types and values out of range are :class:`~motiontrack.errors.ConfigError`\\ s naming
    the key."""
    noun = getattr(cls, "schema_noun", "")
    if not isinstance(data, dict):
        raise ConfigError(f"{where or 'the ' + noun.strip() or 'the file'} must be a table, "
                          f"got {shown(data)}")
    hints = _hints(cls)
    known = {f.name for f in fields(cls)}
    unknown = sorted(str(k) for k in set(data) - known)
    if unknown:
        prefix = f"{where}." if where else ""
        raise ConfigError(
            f"unknown {noun}key(s) {keys_shown(unknown, prefix)}; "
            f"valid keys{' in ' + where if where else ''}: {', '.join(sorted(known))}"
        )
    required = {f.name for f in fields(cls)
                if f.default is MISSING and f.default_factory is MISSING}
    kwargs: dict[str, Any] = {}
    fields_meta = {f.name: f.metadata for f in fields(cls)}
    for name, value in data.items():
        if value is None and (name in required or _optional(hints[name]) is not None):
            continue   # none (JSON null) where none may stand: as if the key were absent
        typ = hints[name]
        inside = _optional(typ) or typ
        _check_length(fields_meta[name], value, inside, f"{where}.{name}" if where else name)
        # a field's range holds for each number of an array of numbers or points
        item_meta = fields_meta[name] if (_items(inside) or _fixed(inside)) and _numeric(
            _items(inside) or inside) else {}
        kwargs[name] = _coerce(value, typ, f"{where}.{name}" if where else name, item_meta)
    for f in fields(cls):
        key = f"{where}.{f.name}" if where else f.name
        if f.name not in kwargs:
            if f.name in required:
                raise ConfigError(f"{key} is required")
            continue
        check_value(f.metadata, kwargs[f.name], key)
    return cls(**kwargs)  # a section's own cross-field checks name its keys by path


# ------------------------------------------------------------------------------- reference
def leaf_fields(cls: type, prefix: str = "") -> Iterator[tuple[str, Field, Any]]:
    """``(dotted key, dataclass field, its type)`` of every leaf key of ``cls``, in declaration
    order (nested tables flattened; an array of tables is one key)."""
    hints = _hints(cls)
    for f in fields(cls):
        if is_dataclass(hints[f.name]):
            yield from leaf_fields(hints[f.name], f"{prefix}{f.name}.")
        else:
            yield prefix + f.name, f, hints[f.name]


def allowed_text(meta: typing.Mapping[str, Any]) -> str:
    """A field's allowed values in words: ``[lo, hi]``, ``a / b / c``, ``odd or 0`` or empty."""
    allowed = ""
    if meta.get("choices"):
        allowed = " / ".join(map(str, meta["choices"]))
    elif meta.get("lo") is not None or meta.get("hi") is not None:
        allowed = _range_text(meta)
    if meta.get("odd"):
        allowed += " odd or 0"
    if meta.get("pattern_doc"):
        allowed = meta["pattern_doc"]
    return allowed


_JSON_TYPES = {bool: "boolean", int: "integer", float: "number", str: "string"}


def _type_schema(typ: Any, m: typing.Mapping[str, Any]) -> dict[str, Any]:
    inner = _optional(typ)
    if inner is not None:
        return _type_schema(inner, m)   # an absent key is the file's way of saying "none"
    if is_dataclass(typ):
        return _object_schema(typ)
    item = _items(typ)
    if item is not None:
        out = {"type": "array", "items": _type_schema(item, m if _numeric(item) else {})}
        if m.get("max_items") is not None:
            out["maxItems"] = m["max_items"]
        return out
    fixed = _fixed(typ)
    if fixed is not None:
        return {"type": "array", "prefixItems": [_type_schema(t, m) for t in fixed],
                "items": False, "minItems": len(fixed), "maxItems": len(fixed)}
    out: dict[str, Any] = {"type": _JSON_TYPES[typ]} if typ in _JSON_TYPES else {}
    if m.get("choices") is not None:
        out["enum"] = list(m["choices"])
    if typ in (int, float):
        if m.get("lo") is not None:
            out["exclusiveMinimum" if m.get("lo_open") else "minimum"] = m["lo"]
        if m.get("hi") is not None:
            out["maximum"] = m["hi"]
    if typ is str:
        if m.get("pattern"):
            out["pattern"] = f"^(?:{m['pattern']})$"
        elif m.get("nonblank"):
            out["pattern"] = r"\S"
    return out


def _object_schema(cls: type) -> dict[str, Any]:
    hints = _hints(cls)
    props: dict[str, Any] = {}
    required = []
    for f in fields(cls):
        p = _type_schema(hints[f.name], f.metadata)
        if f.metadata.get("doc"):
            p["description"] = f.metadata["doc"]
        if f.default is not MISSING and f.default is not None:
            p["default"] = list(f.default) if isinstance(f.default, tuple) else f.default
        elif f.default is MISSING and f.default_factory is MISSING:
            required.append(f.name)
        props[f.name] = p
    out: dict[str, Any] = {"type": "object", "properties": props, "additionalProperties": False}
    if required:
        out["required"] = required
    if cls.__doc__ and not cls.__doc__.startswith(cls.__name__ + "("):
        out["description"] = cls.__doc__.strip().split("\n\n")[0].replace("\n", " ")
    return out


def json_schema(cls: type, title: str = "") -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of schema dataclass ``cls``: types, ranges, choices,
    defaults, meanings, required keys, no other keys."""
    out = {"$schema": "https://json-schema.org/draft/2020-12/schema"}
    if title:
        out["title"] = title
    out.update(_object_schema(cls))
    return out
