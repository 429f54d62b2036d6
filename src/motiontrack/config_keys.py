"""Every key of the configuration as users write it, with its type, range, default and meaning.

One source for the parameter table of docs/pipeline.md (``tools/config_table.py``) and for
``motiontrack config``: both read the :func:`~motiontrack.config.param` metadata of
:class:`~motiontrack.config.PipelineConfig`.
"""

from __future__ import annotations

import functools
import typing
from dataclasses import Field, dataclass, is_dataclass
from typing import Any, Iterable

from .config import PipelineConfig, to_dict
from .schema import allowed_text, leaf_fields

__all__ = ["KeyDoc", "config_fields", "key_docs", "markdown_table", "flatten"]


@dataclass(frozen=True)
class KeyDoc:
    """One key: ``key`` (dotted), ``type`` (``int``, ``float``, ``bool``, ``str``), ``default``,
    ``allowed`` (``[lo, hi]``, ``a / b / c`` or empty; ``odd or 0`` for kernel sizes) and
    ``meaning`` (one line, empty where the name says it)."""

    key: str
    type: str
    default: Any
    allowed: str
    meaning: str


def config_fields(cls: type = PipelineConfig, prefix: str = ""
                  ) -> Iterable[tuple[str, Field, type]]:
    """``(dotted key, dataclass field, its type)`` of every leaf key of ``cls``, in declaration
    order (:func:`motiontrack.schema.leaf_fields`)."""
    return leaf_fields(cls, prefix)


@functools.cache
def key_docs(cls: type = PipelineConfig) -> tuple[KeyDoc, ...]:
    """A :class:`KeyDoc` for every leaf key of ``cls``, in declaration order."""
    out = []
    for key, f, typ in config_fields(cls):
        out.append(KeyDoc(key, getattr(typ, "__name__", str(typ)), f.default,
                          allowed_text(f.metadata), f.metadata.get("doc", "")))
    return tuple(out)


def markdown_table(cls: type = PipelineConfig) -> str:
    """The parameter table of docs/pipeline.md ("Every parameter")."""
    rows = ["| key | default | allowed | meaning |", "|---|---|---|---|"]
    rows += [f"| `{d.key}` | `{d.default!r}` | {d.allowed} | {d.meaning} |" for d in key_docs(cls)]
    return "\n".join(rows)


def flatten(cfg: Any) -> dict[str, Any]:
    """``{dotted key: value}`` of a config (a dataclass or its nested dict)."""
    out: dict[str, Any] = {}

    def walk(d: typing.Mapping[str, Any], prefix: str) -> None:
        for k, v in d.items():
            if isinstance(v, dict):
                walk(v, f"{prefix}{k}.")
            else:
                out[prefix + k] = v

    walk(to_dict(cfg) if is_dataclass(cfg) else cfg, "")
    return out
