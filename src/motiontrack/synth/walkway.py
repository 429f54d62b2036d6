"""The walkway scenes of tracking: Siebel's four sequence types of the Reading People Tracker
(PhD thesis, University of Reading 2003, ch. 6) — (1) one person walking across, (2) one person
running, (3) one person passing behind a column, (4) two people crossing — plus a small crowd and
a lighting-change scene."""

from __future__ import annotations

from .building import EMPTY_FRAMES, Ctx, clothing, entering
from .render import Column

__all__ = ["build_column", "build_crossing", "build_crowd", "build_lighting", "build_runner",
           "build_walker"]


def build_walker(ctx: Ctx, gait: str = "walk") -> dict:
    rng = ctx.rng
    if gait == "run":
        speed = rng.uniform(6.0, 7.5) * ctx.sx
    else:
        speed = rng.uniform(2.8, 3.0) * ctx.sx
    foot_y = rng.uniform(0.78, 0.86) * ctx.height
    from_left = bool(rng.integers(2))
    p = entering(ctx, 1, t_enter=EMPTY_FRAMES + 2 + int(rng.integers(0, 3)), from_left=from_left,
                  foot_y=foot_y, height_ref=rng.uniform(112, 122) * ctx.sy, speed=speed,
                  vy=rng.uniform(-0.12, 0.12) * ctx.sy, gait=gait)
    return {"people": (p,)}


def build_runner(ctx: Ctx) -> dict:
    return build_walker(ctx, gait="run")


def build_column(ctx: Ctx) -> dict:
    rng = ctx.rng
    from_left = bool(rng.integers(2))
    foot_y = rng.uniform(0.78, 0.84) * ctx.height
    speed = rng.uniform(2.2, 2.6) * ctx.sx
    p = entering(ctx, 1, t_enter=EMPTY_FRAMES + 3 + int(rng.integers(0, 4)), from_left=from_left,
                  foot_y=foot_y, height_ref=118 * ctx.sy, speed=speed, gait="walk")
    # Column centred near the middle, wide enough to hide the person for ~20 frames, tall enough
    # to hide the head, its base in front of (below) the person's feet.
    cw = int(round(100 * ctx.sx))
    cx = int(round(ctx.width * rng.uniform(0.42, 0.52)))
    col = Column(x=cx - cw // 2, y=0, w=cw, h=int(round(foot_y + 0.06 * ctx.height)))
    return {"people": (p,), "column": col}


def build_crossing(ctx: Ctx) -> dict:
    rng = ctx.rng
    cols = clothing(rng, 2)
    y_front = rng.uniform(0.80, 0.84) * ctx.height
    y_back = y_front - rng.uniform(0.06, 0.09) * ctx.height
    left_front = bool(rng.integers(2))
    t1 = EMPTY_FRAMES + 3 + int(rng.integers(0, 3))
    t2 = EMPTY_FRAMES + 3 + int(rng.integers(0, 6))
    a = entering(ctx, 1, t1, left_front, y_front, 118 * ctx.sy,
                  rng.uniform(1.8, 2.2) * ctx.sx, gait="walk", colours=cols[0])
    b = entering(ctx, 2, t2, not left_front, y_back, 118 * ctx.sy,
                  rng.uniform(1.8, 2.2) * ctx.sx, gait="walk", colours=cols[1])
    return {"people": (a, b)}


def build_crowd(ctx: Ctx) -> dict:
    rng = ctx.rng
    n = int(rng.integers(5, 9))
    cols = clothing(rng, n)
    people = []
    for k in range(n):
        t_enter = EMPTY_FRAMES + 3 if k == 0 else EMPTY_FRAMES + 3 + int(rng.integers(0, 120))
        gait = "run" if (k == n - 1 and rng.random() < 0.5) else "walk"
        speed = (rng.uniform(5.0, 6.5) if gait == "run" else rng.uniform(1.6, 3.0)) * ctx.sx
        foot_y = rng.uniform(0.68, 0.95) * ctx.height
        vy = rng.uniform(-0.25, 0.25) * ctx.sy
        people.append(entering(ctx, k + 1, t_enter, bool(rng.integers(2)), foot_y,
                                rng.uniform(102, 116) * ctx.sy, speed, vy, gait, cols[k]))
    return {"people": tuple(people)}


def build_lighting(ctx: Ctx) -> dict:
    d = build_walker(ctx)
    d["illumination"] = True
    return d
