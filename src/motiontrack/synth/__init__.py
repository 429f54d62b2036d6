"""Synthetic surveillance scenes with exact ground truth (``synth:NAME`` sources).

>>> from motiontrack.synth import make_scene
>>> scene = make_scene("crossing", seed=3)
>>> img = scene.frame(0)            # (480, 640, 3) uint8 BGR
>>> gt = scene.ground_truth()       # Annotations, 1-based frames

See ``docs/synthetic.md`` for the scenes, their parameters and the ground-truth conventions.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

# registers the synth: scheme; the scenes and their drawing load when first used (a name below,
# or a synth: source opened), so that the pipeline, which registers the scheme, starts without
from .source import SyntheticSource

#: the names offered here, by the submodule that defines them
_LAZY = {**dict.fromkeys(("Bag", "Column", "Person"), "render"),
         **dict.fromkeys(("SCENES", "scene_summaries"), "catalogue"),
         **dict.fromkeys(("MASK_PERSON", "MASK_SHADOW", "Lighting", "SyntheticScene"), "sequence"),
         **dict.fromkeys(("make_scene", "parse_synth_spec"), "scenes")}

if TYPE_CHECKING:  # pragma: no cover
    from .catalogue import SCENES, scene_summaries
    from .render import Bag, Column, Person
    from .scenes import make_scene, parse_synth_spec
    from .sequence import MASK_PERSON, MASK_SHADOW, Lighting, SyntheticScene

__all__ = [
    "SCENES",
    "SyntheticScene",
    "make_scene",
    "parse_synth_spec",
    "scene_summaries",
    "SyntheticSource",
    "Person",
    "Bag",
    "Column",
    "Lighting",
    "MASK_PERSON",
    "MASK_SHADOW",
]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
