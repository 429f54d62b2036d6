"""The scene-file tables of ``docs/analytics.md``, rendered from the rules
(:data:`.rule.RULES`): every key of the scene file, and every event type with its fields.

``tools/scene_table.py`` prints them; a test keeps the docs equal to them.
"""

from __future__ import annotations

from .rules import RULES
from .scene import TOP_KEYS

__all__ = ["scene_keys_table", "event_types_table"]


def scene_keys_table() -> str:
    """The markdown table of the scene file's keys: the top level, then each rule's table in
    registry order."""
    rows = ["| key | type | default | meaning |", "|---|---|---|---|"]
    keys = list(TOP_KEYS) + [k for r in RULES.ordered() for k in r.keys]
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
