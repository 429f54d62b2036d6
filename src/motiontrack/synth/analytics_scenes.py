"""The scenes made for scene analytics: loitering in a zone and a bag left behind, each with the
scene file whose rules they exercise."""

from __future__ import annotations

import math

from .building import BELOW, EMPTY_FRAMES, Ctx, clothing, scene_layout
from .render import Bag, Person

__all__ = ["build_leftbag", "build_loiter"]


def _walk_through(ctx: Ctx, pid: int, t_enter: float, start: tuple[float, float],
                  legs: list[tuple[float, float, float]], height_ref: float,
                  colours: dict) -> Person:
    """A person whose foot point starts at ``start`` at frame index ``t_enter`` and then walks to
    each ``(x, y)`` of ``legs`` at the leg's speed (px/frame), keeping the last velocity."""
    x, y = start
    t = float(t_enter)
    velocities = []
    for tx, ty, speed in legs:
        dist = math.hypot(tx - x, ty - y)
        velocities.append((t, (tx - x) / dist * speed, (ty - y) / dist * speed))
        t += dist / speed
        x, y = tx, ty
    h_at = height_ref * (start[1] - ctx.horizon) / (ctx.height - ctx.horizon)
    (_, vx, vy), turns = velocities[0], tuple(velocities[1:])
    return Person(id=pid, x0=start[0], y0=start[1], vx=vx, vy=vy, height=h_at, t0=float(t_enter),
                  gait="walk", phase0=float(ctx.rng.uniform(0, 2 * math.pi)), horizon=ctx.horizon,
                  turns=turns, **colours)


def build_loiter(ctx: Ctx) -> dict:
    """Someone walks in from the left, lingers in ``plaza`` (slow, turning walk for 7-9 s at
    25 fps), and leaves by either side."""
    rng, W, H = ctx.rng, ctx.width, ctx.height
    zone = (0.25 * W, 0.58 * H, 0.62 * W, BELOW * H)
    inner = (0.32 * W, 0.70 * H, 0.55 * W, 0.90 * H)  # where the lingering stays
    fast = rng.uniform(2.8, 3.0) * ctx.sx
    height_ref = rng.uniform(112, 122) * ctx.sy
    y_in = rng.uniform(0.74, 0.84) * H
    lead = 0.22 * height_ref
    linger = int(rng.integers(175, 226))  # frames between reaching the first and last point
    points = [(rng.uniform(inner[0], inner[0] + 0.3 * (inner[2] - inner[0])),
               rng.uniform(inner[1], inner[3]))]
    while len(points) < 4:
        cand = (rng.uniform(inner[0], inner[2]), rng.uniform(inner[1], inner[3]))
        d = math.hypot(cand[0] - points[-1][0], cand[1] - points[-1][1])
        if not 0.06 * W <= d <= 0.14 * W:
            continue
        if len(points) >= 2:
            # no sharp reversal: a lingering walk, never a spot stood on (the stationary rule)
            ax, ay = points[-1][0] - points[-2][0], points[-1][1] - points[-2][1]
            bx, by = cand[0] - points[-1][0], cand[1] - points[-1][1]
            if ax * bx + ay * by < -0.5 * math.hypot(ax, ay) * d:
                continue
        points.append(cand)
    legs = [(points[0][0], points[0][1], fast)]
    for a, b in zip(points[:-1], points[1:]):
        legs.append((b[0], b[1], math.hypot(b[0] - a[0], b[1] - a[1]) / (linger / 3)))
    leave_right = bool(rng.integers(2))
    legs.append((W + lead if leave_right else -lead, rng.uniform(0.74, 0.84) * H, fast))
    p = _walk_through(ctx, 1, EMPTY_FRAMES + 2 + int(rng.integers(0, 3)), (-lead, y_in), legs,
                      height_ref, clothing(rng, 1)[0])
    return {"people": (p,), "scene_file": scene_layout(ctx, 0.12 * W, zone, 5.0)}


def build_leftbag(ctx: Ctx) -> dict:
    """Someone carries a bag in, stops, sets it down and walks on out of view; the bag stays."""
    rng, W, H = ctx.rng, ctx.width, ctx.height
    cols = clothing(rng, 2)
    from_left = bool(rng.integers(2))
    speed = rng.uniform(2.6, 3.0) * ctx.sx
    height_ref = rng.uniform(112, 122) * ctx.sy
    foot_y = rng.uniform(0.78, 0.86) * H
    lead = 0.22 * height_ref
    drop_x = rng.uniform(0.30, 0.42) * W
    sign = 1.0 if from_left else -1.0
    x_start = -lead if from_left else W + lead
    x_stop = drop_x if from_left else W - drop_x
    t_enter = EMPTY_FRAMES + 2 + int(rng.integers(0, 3))
    t_stop = t_enter + abs(x_stop - x_start) / speed
    stand = 30  # frames standing: 4 to reach down, 8 lowering the bag, 18 before walking on
    h_at = height_ref * (foot_y - ctx.horizon) / (H - ctx.horizon)
    p = Person(id=1, x0=x_start, y0=foot_y, vx=sign * speed, vy=0.0, height=h_at,
               t0=float(t_enter), gait="walk", phase0=float(rng.uniform(0, 2 * math.pi)),
               horizon=ctx.horizon, turns=((t_stop, 0.0, 0.0), (t_stop + stand, sign * speed, 0.0)),
               **cols[0])
    bag = Bag(id=2, owner=1, t_drop=int(math.ceil(t_stop)) + 12, colour=cols[1]["shirt"], lower=8)
    # the zone lies on the far side of the gate, where the owner walks off, away from the bag
    zx = (0.58 * W, 0.88 * W) if from_left else (0.12 * W, 0.42 * W)
    layout = scene_layout(ctx, 0.5 * W, (zx[0], 0.45 * H, zx[1], BELOW * H), 10.0)
    return {"people": (p,), "bags": (bag,), "scene_file": layout}
