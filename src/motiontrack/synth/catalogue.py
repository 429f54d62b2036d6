"""The built-in scene types: each name's builder, default length and one-line summary."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .analytics_scenes import build_leftbag, build_loiter, build_mixed
from .building import Ctx
from .walkway import (build_column, build_crossing, build_crowd, build_lighting, build_runner,
                      build_walker)

__all__ = ["SCENES", "SCENE_TYPES", "SceneType", "scene_summaries"]


@dataclass(frozen=True)
class SceneType:
    """A built-in scene type: its builder, default length in frames and one-line summary."""

    build: Callable[[Ctx], dict]
    n_frames: int
    summary: str


#: The built-in scene types by name, in the order ``motiontrack list`` shows them.
SCENE_TYPES: dict[str, SceneType] = {
    "walker": SceneType(build_walker, 250, "type 1: one person walking across the image"),
    "runner": SceneType(build_runner, 150, "type 2: one person running across the image"),
    "column": SceneType(build_column, 220,
                        "type 3: one person passing behind a column (full occlusion)"),
    "crossing": SceneType(build_crossing, 250,
                          "type 4: two people crossing, walking in opposite directions"),
    "crowd": SceneType(build_crowd, 250, "5-8 people walking (one may run), many occlusions"),
    "lighting": SceneType(build_lighting, 250,
                          "a walker with a gradual and a sudden illumination change"),
    "loiter": SceneType(build_loiter, 520,
                        "one person walks in, lingers 7-9 s in the zone plaza, then leaves"),
    "leftbag": SceneType(build_leftbag, 360,
                         "one person sets a bag down and walks off out of view; the bag stays"),
    "mixed": SceneType(build_mixed, 300,
                       "three people on the pavement and two cars on the road behind them"),
}

#: Names of the built-in scene types.
SCENES: tuple[str, ...] = tuple(SCENE_TYPES)


def scene_summaries() -> dict[str, str]:
    """``{name: one-line summary}`` for every built-in scene (cheap: renders nothing)."""
    return {name: st.summary for name, st in SCENE_TYPES.items()}
