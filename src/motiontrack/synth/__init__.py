"""Synthetic surveillance scenes with exact ground truth (``synth:NAME`` sources).

>>> from motiontrack.synth import make_scene
>>> scene = make_scene("crossing", seed=3)
>>> img = scene.frame(0)            # (480, 640, 3) uint8 BGR
>>> gt = scene.ground_truth()       # Annotations, 1-based frames

See ``docs/synthetic.md`` for the scenes, their parameters and the ground-truth conventions.
"""

from __future__ import annotations

from .render import Bag, Column, Person
from .scenes import (
    MASK_PERSON,
    MASK_SHADOW,
    SCENES,
    Lighting,
    SyntheticScene,
    make_scene,
    parse_synth_spec,
    scene_summaries,
)
from .source import SyntheticSource

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
