"""The scenes made for scene analytics: loitering in a zone, a bag left behind, and people and
cars passing (classes), each with the scene file whose rules they exercise."""

from __future__ import annotations

import math

from .building import BELOW, EMPTY_FRAMES, Ctx, _q, clothing, entering, scene_layout
from .render import Bag, Person
from .vehicles import Vehicle

__all__ = ["build_leftbag", "build_loiter", "build_mixed"]

#: colours of the cars of ``mixed`` (BGR)
_CAR_COLOURS = [(40, 40, 170), (160, 90, 30), (200, 200, 200), (30, 120, 30)]


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


def build_mixed(ctx: Ctx) -> dict:
    """Three people walk along the pavement near the camera while two cars drive by on the road
    behind them, one each way; the scene file's ``gate`` counts every track, ``crossing`` (a
    line with ``classes = ["person"]``) the people only."""
    rng, W, H = ctx.rng, ctx.width, ctx.height
    height_ref = rng.uniform(112, 122) * ctx.sy
    cols = clothing(rng, 3)
    people = tuple(
        entering(ctx, pid, EMPTY_FRAMES + t, from_left, foot * H, height_ref,
                 rng.uniform(2.6, 3.0) * ctx.sx, colours=cols[pid - 1])
        for pid, t, from_left, foot in ((1, 2, True, 0.86), (2, 70, False, 0.92),
                                        (3, 140, True, 0.82)))
    colours = rng.permutation(len(_CAR_COLOURS))
    vehicles = []
    for k, (t, from_left, road) in enumerate(((10, True, 0.55), (120, False, 0.62))):
        # a car 4.5 m long and 1.5 m tall next to a person of 1.7 m at the same depth
        person_h = height_ref * (road * H - ctx.horizon) / (H - ctx.horizon)
        length, height = person_h * 4.5 / 1.7, person_h * 1.5 / 1.7
        speed = rng.uniform(9.0, 11.0) * ctx.sx                 # about 30 km/h
        x0 = -length / 2 if from_left else W + length / 2
        vehicles.append(Vehicle(id=4 + k, x0=x0, y0=road * H, vx=speed if from_left else -speed,
                                length=length, height=height, t0=float(EMPTY_FRAMES + t),
                                colour=_CAR_COLOURS[int(colours[k])]))
    layout = scene_layout(ctx, 0.62 * W, (0.1 * W, 0.72 * H, 0.3 * W, BELOW * H), 10.0)
    layout["line"].append({"name": "crossing", "classes": ["person"],
                           "points": [[_q(0.38 * W), _q(BELOW * H)], [_q(0.38 * W), _q(0.3 * H)]]})
    layout["line"][0]["points"][1][1] = _q(0.3 * H)   # the gate across the road too
    return {"people": people, "vehicles": tuple(vehicles), "scene_file": layout}
