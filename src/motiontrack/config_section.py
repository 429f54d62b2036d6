"""The base of every pipeline config section: its schema noun and the key path users write.

A section's key path (``KNNParams`` → ``"motion.knn"``) is found by walking the fields of the
root config class, which :mod:`motiontrack.config` names with :func:`set_root` once it is
defined; the sections themselves may live in any module.
"""

from __future__ import annotations

import functools
import typing
from dataclasses import is_dataclass
from typing import ClassVar

from .schema import Section

__all__ = ["ConfigSection", "section_path", "section_paths", "set_root"]

_ROOT: list[type] = []


def set_root(cls: type) -> None:
    """The config class whose fields are the sections (``PipelineConfig``)."""
    _ROOT[:] = [cls]
    section_paths.cache_clear()


class ConfigSection(Section):
    """A section of the pipeline config: unknown keys are "config" keys, and a message names the
    section by the key path users write (:func:`section_path`)."""

    schema_noun: ClassVar[str] = "config "

    @classmethod
    def schema_where(cls) -> str:
        return section_path(cls)


def section_path(cls: type) -> str:
    """A section's key path as users write it (``KNNParams`` → ``"motion.knn"``), so that a
    message names the key rather than the class, however the section was built; the class name
    for a class outside the root config."""
    return section_paths().get(cls, cls.__name__)


@functools.cache
def section_paths() -> dict[type, str]:
    """Every section class of the root config → its key path."""
    paths: dict[type, str] = {}

    def walk(cls: type, prefix: str) -> None:
        for name, typ in typing.get_type_hints(cls).items():
            if is_dataclass(typ):
                paths.setdefault(typ, prefix + name)
                walk(typ, f"{prefix}{name}.")

    for root in _ROOT:
        walk(root, "")
    return paths
