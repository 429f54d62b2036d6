"""The scene-file tables of ``docs/analytics.md``, rendered from the rules
(:data:`.rule.RULES`): every key of the scene file, listed from the schemas that check them
(:class:`.scene.SceneTop` and each rule's :attr:`.rule.Rule.schema`), and every event type with
its fields.

``tools/scene_table.py`` prints them; a test keeps the docs equal to them.
"""

from __future__ import annotations

import typing
from dataclasses import MISSING
from typing import Any, Iterator

from ..schema import leaf_fields
from .rule import SceneKey
from .rules import RULES
from .scene import SceneTop
from .specs import COORD_LIMIT

__all__ = ["scene_keys_table", "event_types_table", "schema_keys"]

_NAMES = {bool: "true / false", int: "int", float: "float", str: "text"}


def _number(v: float) -> str:
    return f"{v:g}"


def _type_text(typ: Any, m: typing.Mapping[str, Any]) -> str:
    args = [a for a in typing.get_args(typ) if a is not type(None)]
    if typing.get_origin(typ) is not tuple and type(None) in typing.get_args(typ):
        typ = args[0]                        # optional: "none" is its default
    if typing.get_origin(typ) is tuple and typing.get_args(typ)[-1] is not Ellipsis:
        n, lo, hi = len(typing.get_args(typ)), m.get("lo"), m.get("hi")
        return f"{n} numbers in [{_number(lo)}, {_number(hi)}]"   # a pair such as clip_s
    if typing.get_origin(typ) is tuple:     # an array of points, or of names
        return ("array of text" if typing.get_args(typ)[0] is str else "array of `[x, y]`")
    if m.get("choices"):
        return " \\| ".join(f"`{c}`" for c in m["choices"])
    text = _NAMES.get(typ, getattr(typ, "__name__", str(typ)))
    lo, hi = m.get("lo"), m.get("hi")
    if hi is not None and hi < COORD_LIMIT:
        return f"{text} in {'(' if m.get('lo_open') else '['}{_number(lo)}, {_number(hi)}]"
    if lo is not None:
        text += f" {'>' if m.get('lo_open') else '≥'} {_number(lo)}"
    return text


def _default_text(default: Any) -> str:
    if default is MISSING:
        return "required"
    if default is None:
        return "—"
    if isinstance(default, str):
        return f"`{default}`"
    if isinstance(default, bool):
        return "true" if default else "false"
    if isinstance(default, tuple):
        return "[" + ", ".join(_default_text(v) for v in default) + "]"
    return _number(default) if isinstance(default, (int, float)) else str(default)


def schema_keys(schema: type, prefix: str = "") -> Iterator[SceneKey]:
    """The docs' rows of a scene schema's keys, each after ``prefix`` (``line[i].``)."""
    for key, f, typ in leaf_fields(schema, prefix):
        yield SceneKey(key, _type_text(typ, f.metadata), _default_text(f.default),
                       f.metadata.get("doc", ""))


def _rule_keys(rule: type) -> Iterator[SceneKey]:
    if rule.schema is None:
        yield from rule.keys
        return
    prefix = f"{rule.section}[i]." if rule.many else f"{rule.section}."
    yield from schema_keys(rule.schema, prefix)


def scene_keys_table() -> str:
    """The markdown table of the scene file's keys: the top level, then each rule's table in
    registry order."""
    rows = ["| key | type | default | meaning |", "|---|---|---|---|"]
    keys = list(schema_keys(SceneTop)) + [k for r in RULES.ordered() for k in _rule_keys(r)]
    rows += [f"| `{k.key}` | {k.type} | {k.default} | {k.meaning} |" for k in keys]
    return "\n".join(rows) + "\n"


def event_types_table() -> str:
    """The markdown table of the event types: the scene table whose rule emits each, its
    fields beyond ``type, frame, t, track, x, y`` (``X, Y``) and what it means."""
    rows = ["| type | scene table | fields | meaning |", "|---|---|---|---|"]
    for r in RULES.ordered():
        for e in r.events:
            fields = [f"`{f}`" for f in e.required] + [f"`{f}` (optional)" for f in e.optional]
            rows.append(f"| `{e.name}` | `{r.section}` | {', '.join(fields) or '—'} | "
                        f"{e.meaning} |")
    return "\n".join(rows) + "\n"
