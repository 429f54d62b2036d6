"""The building blocks every built-in scene shares: the clothing palette, the :class:`Ctx` a
builder receives, people entering across the image border, and the scene file's line and zone
layout."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .render import Person

__all__ = ["BELOW", "EMPTY_FRAMES", "Ctx", "clothing", "entering", "scene_layout",
           "street_layout"]

EMPTY_FRAMES = 15  # at least this many frames of empty background before anyone enters

# Clothing colours (BGR). Saturated, and chosen by luminance Y = 0.299 R + 0.587 G + 0.114 B
# (ITU-R BT.601) to be either clearly brighter than the paving (Y ~ 155) or darker than half of it:
# a grey-level background subtractor with shadow detection (MOG2: shadow = darker by a factor in
# [0.5, 1]) would otherwise label mid-dark clothing as shadow. Y is given in each comment.
_SHIRTS = [
    (30, 220, 240),   # yellow        Y 205
    (230, 230, 90),   # turquoise     Y 188
    (25, 25, 150),    # dark red      Y 62
    (60, 230, 160),   # lime          Y 190
    (110, 25, 20),    # navy          Y 33
    (200, 170, 255),  # pink          Y 199
    (30, 90, 15),     # dark green    Y 61
    (20, 165, 255),   # orange        Y 175
    (120, 20, 100),   # purple        Y 55
    (240, 180, 120),  # sky blue      Y 169
    (235, 235, 235),  # white         Y 235
]
_TROUSERS = [
    (70, 40, 25),     # dark blue     Y 39
    (35, 35, 35),     # black         Y 35
    (40, 60, 90),     # brown         Y 67
    (140, 190, 200),  # khaki         Y 188
    (90, 50, 50),     # dark purple   Y 54
    (30, 45, 30),     # dark green    Y 39
]
_SKINS = [(150, 185, 230), (120, 160, 210), (90, 125, 170), (60, 90, 130), (170, 200, 235)]
_HAIR = [(25, 25, 30), (30, 50, 80), (40, 90, 140), (80, 170, 210)]


@dataclass(frozen=True)
class Ctx:
    """What a scene builder needs: size, length, random generator and scale factors."""

    rng: np.random.Generator
    width: int
    height: int
    n_frames: int
    horizon: float

    @property
    def sx(self) -> float:  # horizontal scale vs the 640-px design size
        return self.width / 640.0

    @property
    def sy(self) -> float:  # vertical scale vs the 480-px design size
        return self.height / 480.0


def clothing(rng: np.random.Generator, n: int) -> list[dict]:
    """One outfit per person for ``n`` people: shirts all different while there are enough."""
    shirts = rng.permutation(len(_SHIRTS))
    out = []
    for k in range(n):
        out.append(dict(
            shirt=_SHIRTS[int(shirts[k % len(_SHIRTS)])],
            trousers=_TROUSERS[int(rng.integers(len(_TROUSERS)))],
            skin=_SKINS[int(rng.integers(len(_SKINS)))],
            hair=_HAIR[int(rng.integers(len(_HAIR)))],
        ))
    return out


def entering(ctx: Ctx, pid: int, t_enter: float, from_left: bool, foot_y: float,
             height_ref: float, speed: float, vy: float = 0.0, gait: str = "walk",
             colours: dict | None = None) -> Person:
    """A person whose leading edge reaches the image border at about frame index ``t_enter``.

    ``height_ref`` is the height (px) a person would have with feet at the bottom of the image;
    the actual height follows the perspective of the scene's horizon.
    """
    h_at = height_ref * (foot_y - ctx.horizon) / (ctx.height - ctx.horizon)
    lead = 0.22 * h_at  # foot point to the leading extremity (swinging foot / arm), about
    x0 = -lead if from_left else ctx.width + lead
    vx = speed if from_left else -speed
    return Person(
        id=pid, x0=x0, y0=foot_y, vx=vx, vy=vy, height=h_at, t0=t_enter, gait=gait,
        phase0=float(ctx.rng.uniform(0, 2 * math.pi)), horizon=ctx.horizon,
        **(colours or clothing(ctx.rng, 1)[0]),
    )



# Lines and zones reach this far below the image (fraction of its height): a horizontal edge at the
# bottom border would be crossed back and forth by the feet of people walking along it.
BELOW = 1.25


def _q(v: float) -> float:
    """A coordinate a quarter pixel past an integer: box anchors are whole or half pixels, so no
    anchor ever lies exactly on a line or a zone edge placed here (no ties in the event rules)."""
    return math.floor(v) + 0.25


def _rect(x1: float, y1: float, x2: float, y2: float) -> list[list[float]]:
    return [[_q(x1), _q(y1)], [_q(x2), _q(y1)], [_q(x2), _q(y2)], [_q(x1), _q(y2)]]


def _gate(ctx: Ctx, x: float) -> dict:
    """A vertical line at column ``x`` across the walkway, drawn bottom to top, so that walking
    left to right is ``in`` (the crossing rule of :mod:`motiontrack.synth.events`). It runs on
    below the image: feet at the bottom border still cross it."""
    return {"name": "gate",
            "points": [[_q(x), _q(BELOW * ctx.height)], [_q(x), _q(0.45 * ctx.height)]]}


def scene_layout(ctx: Ctx, gate_x: float, zone: tuple[float, float, float, float],
                 loiter_s: float) -> dict:
    """A scene file: the line ``gate`` at column ``gate_x``, the rectangular zone ``plaza``
    ``(x1, y1, x2, y2)`` and the stationary and abandoned rules every synthetic scene shares."""
    return {
        "anchor": "bottom_center",
        "hysteresis_px": 5.0,
        "line": [_gate(ctx, gate_x)],
        "zone": [{"name": "plaza", "polygon": _rect(*zone), "loiter_s": float(loiter_s)}],
        "stationary": {"after_s": 3.0, "radius_px": 8.0},
        "abandoned": {"after_s": 4.0, "distance_heights": 1.5},
    }


def street_layout(ctx: Ctx, loiter_s: float = 10.0) -> dict:
    """The scene file of the walkway scenes: the line ``gate`` across the middle and the zone
    ``plaza`` around it (wider than any walker needs ``loiter_s`` to cross)."""
    W, H = ctx.width, ctx.height
    return scene_layout(ctx, 0.5 * W, (0.3 * W, 0.45 * H, 0.7 * W, BELOW * H), loiter_s)

