"""Drawing primitives for synthetic scenes: background, people sprites, shadows, sensor noise.

Everything here is a pure function of its arguments (plus a seeded ``numpy.random.Generator``
where stated): the same inputs give bit-identical pixels. People are drawn *without*
anti-aliasing (``cv2.LINE_8``) into a small label sprite, so the set of pixels that belong to a
person is known exactly; colours are looked up from the labels afterwards. Sub-pixel positions use
OpenCV's fixed-point ``shift`` argument (:data:`SHIFT` fractional bits).

Coordinates are pixels, ``x`` to the right and ``y`` down, pixel ``(x, y)`` covering
``[x, x + 1) × [y, y + 1)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = [
    "Person",
    "Bag",
    "Column",
    "Sprite",
    "SHIFT",
    "LABEL_SHIRT",
    "LABEL_TROUSERS",
    "LABEL_SKIN",
    "LABEL_HAIR",
    "LABEL_SHOES",
    "LABEL_SLEEVE_BACK",
    "LABEL_BAG",
    "person_position",
    "person_facing",
    "bag_box",
    "render_person",
    "render_bag",
    "draw_bag",
    "render_shadow",
    "render_background",
    "make_noise_pool",
]

#: Fixed-point fractional bits for sub-pixel drawing (1/16 px).
SHIFT = 4
_ONE = 1 << SHIFT

# Labels in a person sprite (0 = not the person). Colours come from Person.palette().
LABEL_SHIRT = 1
LABEL_TROUSERS = 2
LABEL_SKIN = 3
LABEL_HAIR = 4
LABEL_SHOES = 5
LABEL_SLEEVE_BACK = 6  # the far arm, a little darker than the shirt (reads as depth)
LABEL_BAG = 7  # a bag, carried (part of its owner's sprite) or left on the ground (a sprite of its own)

_GAITS = {
    # leg swing amplitude (rad), arm swing (rad), knee bend (rad), forward lean (rad),
    # vertical bob (fraction of height), distance covered per full gait cycle (fraction of height)
    "walk": dict(leg=0.42, arm=0.45, knee=0.30, lean=0.0, bob=0.012, cycle=0.85),
    "run": dict(leg=0.75, arm=0.95, knee=1.30, lean=0.16, bob=0.030, cycle=1.35),
}


@dataclass(frozen=True)
class Person:
    """A synthetic person moving at piecewise constant velocity (a straight line without ``turns``).

    The foot point (bottom centre, where the person touches the ground) at 0-based frame index
    ``i`` is ``(x0 + vx * (i - t0), y0 + vy * (i - t0))`` up to the first turn; from each turn
    ``(t, vx, vy)`` on, the foot point moves with that velocity (a velocity of 0 stands still).
    Positions are defined for every ``i``; the person is *in the scene* whenever any of its pixels
    falls inside the image.

    Attributes
    ----------
    id : int
        Ground-truth identity, >= 1.
    x0, y0 : float
        Foot point at frame index ``t0``, pixels.
    vx, vy : float
        Velocity, pixels per frame.
    height : float
        Nominal height (head top to soles) at ``y0``, pixels. With perspective
        (``horizon`` not None) the height scales with ``(y - horizon) / (y0 - horizon)``.
    t0 : float
        Reference frame index for ``x0, y0``.
    gait : {"walk", "run"}
    phase0 : float
        Gait phase at ``t0``, radians.
    shirt, trousers, skin, hair, shoes : tuple of int
        BGR colours, 0..255.
    horizon : float or None
        Image row of the horizon for perspective scaling (``< y0``); None = constant height.
    turns : tuple of (t, vx, vy)
        Velocity changes: from frame index ``t`` on the foot point moves by ``(vx, vy)`` pixels per
        frame; ``t`` strictly increasing and greater than ``t0``. Empty = a straight line.
    """

    id: int
    x0: float
    y0: float
    vx: float
    vy: float
    height: float
    t0: float = 0.0
    gait: str = "walk"
    phase0: float = 0.0
    shirt: tuple[int, int, int] = (40, 40, 200)
    trousers: tuple[int, int, int] = (60, 40, 30)
    skin: tuple[int, int, int] = (120, 160, 210)
    hair: tuple[int, int, int] = (30, 30, 40)
    shoes: tuple[int, int, int] = (25, 25, 25)
    horizon: float | None = None
    turns: tuple[tuple[float, float, float], ...] = ()

    def __post_init__(self) -> None:
        if self.id < 1:
            raise ValueError(f"person id must be >= 1, got id={self.id}")
        if self.gait not in _GAITS:
            raise ValueError(f"gait must be one of {sorted(_GAITS)}, got gait={self.gait!r}")
        if not (self.height >= 8):
            raise ValueError(f"person height must be >= 8 px, got height={self.height}")
        for name in ("x0", "y0", "vx", "vy", "t0", "phase0"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"person {name} must be finite, got {getattr(self, name)!r}")
        if self.horizon is not None and not self.horizon < self.y0:
            raise ValueError(
                f"horizon must lie above the foot point (horizon < y0), "
                f"got horizon={self.horizon}, y0={self.y0}"
            )
        for name in ("shirt", "trousers", "skin", "hair", "shoes"):
            c = getattr(self, name)
            if len(c) != 3 or not all(0 <= int(v) <= 255 for v in c):
                raise ValueError(f"person colour {name} must be 3 BGR values in 0..255, got {c!r}")
        last = self.t0
        for turn in self.turns:
            if len(turn) != 3 or not all(math.isfinite(v) for v in turn):
                raise ValueError(f"person turns must be finite (t, vx, vy) triples, got {turn!r}")
            if not turn[0] > last:
                raise ValueError(f"person turn times must increase after t0={self.t0}, "
                                 f"got {[t[0] for t in self.turns]}")
            last = turn[0]

    @property
    def speed(self) -> float:
        """Speed in pixels per frame (before the first turn)."""
        return math.hypot(self.vx, self.vy)

    def legs(self) -> list[tuple[float, float, float, float, float]]:
        """The path as ``(t_start, x, y, vx, vy)`` pieces: the foot point is ``(x, y)`` at frame
        index ``t_start`` and moves by ``(vx, vy)`` per frame until the next piece starts (the first
        piece also extends backwards in time)."""
        pieces = [(self.t0, self.x0, self.y0, self.vx, self.vy)]
        for t, vx, vy in self.turns:
            t_prev, x, y, pvx, pvy = pieces[-1]
            pieces.append((t, x + pvx * (t - t_prev), y + pvy * (t - t_prev), vx, vy))
        return pieces

    def travelled(self, i: float) -> float:
        """Distance walked since frame index ``t0`` (negative before it), pixels: the gait phase
        advances with it, so feet do not slide and a person standing still keeps its pose."""
        if not self.turns or i <= self.turns[0][0]:
            return self.speed * (i - self.t0)
        pieces = self.legs()
        d = 0.0
        for k, (t, _, _, vx, vy) in enumerate(pieces):
            end = pieces[k + 1][0] if k + 1 < len(pieces) else math.inf
            d += math.hypot(vx, vy) * (min(i, end) - t)
            if i <= end:
                break
        return d

    def palette(self) -> np.ndarray:
        """``(7, 3) uint8`` BGR colour for each sprite label (row 0 unused)."""
        sleeve = tuple(int(v * 0.72) for v in self.shirt)
        return np.array(
            [(0, 0, 0), self.shirt, self.trousers, self.skin, self.hair, self.shoes, sleeve],
            dtype=np.uint8,
        )


@dataclass(frozen=True)
class Column:
    """A static rectangular column (pillar) drawn *over* people: ``[x, x + w) × [y, y + h)``."""

    x: int
    y: int
    w: int
    h: int

    def __post_init__(self) -> None:
        if self.w <= 0 or self.h <= 0:
            raise ValueError(f"column must have w > 0 and h > 0, got w={self.w}, h={self.h}")


@dataclass(frozen=True)
class Bag:
    """A bag its owner carries in the near hand, lowers and leaves on the ground.

    Until frame index ``t_drop - lower`` it hangs beside the owner's hip; over the next ``lower``
    frames it goes down to the ground; from ``t_drop`` on it rests there, static, as an object of
    its own (ground-truth id ``id``). Its size follows the owner's height (perspective).

    Attributes
    ----------
    id : int
        Ground-truth identity once it rests on the ground, >= 1 and not a person's id.
    owner : int
        Id of the person carrying it.
    t_drop : int
        First frame index at which the bag rests on the ground.
    colour : tuple of int
        BGR.
    lower : int
        Frames the owner takes to set it down (the owner should stand still meanwhile).
    """

    id: int
    owner: int
    t_drop: int
    colour: tuple[int, int, int] = (40, 40, 40)
    lower: int = 8

    def __post_init__(self) -> None:
        if self.id < 1:
            raise ValueError(f"bag id must be >= 1, got id={self.id}")
        if self.lower < 1 or self.t_drop < self.lower:
            raise ValueError(f"bag needs 1 <= lower <= t_drop, got lower={self.lower}, "
                             f"t_drop={self.t_drop}")
        if len(self.colour) != 3 or not all(0 <= int(v) <= 255 for v in self.colour):
            raise ValueError(f"bag colour must be 3 BGR values in 0..255, got {self.colour!r}")

    def carried(self, i: int) -> bool:
        """Is the bag part of its owner's figure at frame index ``i``?"""
        return i < self.t_drop

    def palette(self) -> np.ndarray:
        """``(8, 3) uint8`` BGR colour per sprite label: only :data:`LABEL_BAG` is used."""
        pal = np.zeros((8, 3), dtype=np.uint8)
        pal[LABEL_BAG] = self.colour
        return pal


# A carried bag hangs from the hand with its bottom this far above the feet, its centre this far
# in front of the body (fractions of the owner's height); its body is BAG_W x BAG_H of the height.
_BAG_LIFT = 0.30
_BAG_FRONT = 0.17
BAG_W, BAG_H = 0.28, 0.20


def bag_box(bag: Bag, owner: Person, i: int) -> tuple[float, float, float, float, float]:
    """The bag's body at frame index ``i``: centre x, bottom y, width, height (pixels, floats) and
    the owner's height it is sized by; fixed from ``t_drop`` on."""
    k = min(i, bag.t_drop)
    fx, fy, h = person_position(owner, k)
    d = person_facing(owner, k)
    lift = _BAG_LIFT * min(1.0, max(0.0, (bag.t_drop - k) / bag.lower))
    return fx + d * _BAG_FRONT * h, fy - lift * h, BAG_W * h, BAG_H * h, h


def draw_bag(labels: np.ndarray, ox: int, oy: int, box: tuple[float, ...]) -> None:
    """Draw a bag (body and handle) with :data:`LABEL_BAG` into ``labels`` (in place), the
    label image's top-left pixel being ``(ox, oy)`` in the frame."""
    cx, bottom, w, hb, h = box
    x1, y1 = _pt(cx - w / 2, bottom - hb, ox, oy)
    x2, y2 = _pt(cx + w / 2, bottom, ox, oy)
    cv2.rectangle(labels, (x1, y1), (x2, y2), LABEL_BAG, -1, cv2.LINE_8, SHIFT)
    centre = _pt(cx, bottom - hb, ox, oy)
    axes = (int(0.25 * w * _ONE), int(0.09 * h * _ONE))
    cv2.ellipse(labels, centre, axes, 0, 180, 360, LABEL_BAG, max(1, int(round(0.02 * h))),
                cv2.LINE_8, SHIFT)


def render_bag(bag: Bag, owner: Person, i: int) -> Sprite:
    """The bag resting on the ground (frame index ``i >= t_drop``) as a :class:`Sprite`."""
    box = bag_box(bag, owner, i)
    cx, bottom, w, hb, h = box
    ox = int(math.floor(cx - w / 2)) - 2
    oy = int(math.floor(bottom - hb - 0.09 * h)) - 3
    lab = np.zeros((int(math.ceil(hb + 0.09 * h)) + 7, int(math.ceil(w)) + 5), dtype=np.uint8)
    draw_bag(lab, ox, oy, box)
    return Sprite(ox, oy, lab)


@dataclass(frozen=True, eq=False)
class Sprite:
    """A small label image placed in the frame with its top-left pixel at ``(ox, oy)``.

    ``labels`` is ``(h, w) uint8``; 0 = empty. The sprite may extend beyond the image.
    """

    ox: int
    oy: int
    labels: np.ndarray

    def bbox(self) -> tuple[int, int, int, int] | None:
        """Tight ``(x, y, w, h)`` of the non-zero pixels in frame coordinates (None if empty)."""
        rows = np.flatnonzero(self.labels.any(axis=1))
        if rows.size == 0:
            return None
        cols = np.flatnonzero(self.labels.any(axis=0))
        return (
            self.ox + int(cols[0]),
            self.oy + int(rows[0]),
            int(cols[-1] - cols[0] + 1),
            int(rows[-1] - rows[0] + 1),
        )


def person_position(p: Person, i: float) -> tuple[float, float, float]:
    """Foot point ``(x, y)`` and height (pixels) of ``p`` at frame index ``i``."""
    if not p.turns or i <= p.turns[0][0]:
        dt = i - p.t0
        fx = p.x0 + p.vx * dt
        fy = p.y0 + p.vy * dt
    else:
        t, x, y, vx, vy = [leg for leg in p.legs() if leg[0] < i][-1]
        fx, fy = x + vx * (i - t), y + vy * (i - t)
    h = p.height
    if p.horizon is not None:
        # Pinhole camera over a flat ground plane: apparent height is proportional to the
        # distance of the foot point below the horizon (Hartley & Zisserman, 2nd ed., §8.6).
        h = p.height * max(fy - p.horizon, 1.0) / (p.y0 - p.horizon)
    return fx, fy, h


def person_facing(p: Person, i: float) -> float:
    """+1 when ``p`` faces right at frame index ``i``, -1 left: the sign of the horizontal
    velocity, kept from the last piece that moved sideways while it walks straight up or down or
    stands."""
    d = 1.0 if p.vx >= 0 else -1.0
    for t, _, _, vx, _ in p.legs()[1:]:
        if t >= i:
            break
        if vx != 0:
            d = 1.0 if vx > 0 else -1.0
    return d


def _pt(x: float, y: float, ox: int, oy: int) -> tuple[int, int]:
    return (int(round((x - ox) * _ONE)), int(round((y - oy) * _ONE)))


def render_person(p: Person, i: int) -> Sprite:
    """Rasterise ``p`` at frame index ``i`` into a label :class:`Sprite`.

    The figure: two legs (thigh + shin as thick lines, with shoes), a torso ellipse, two arms
    swinging against the legs, a head circle with hair. Leg/arm angles follow a sinusoidal gait
    phase that advances in proportion to the distance walked, so feet do not slide.

    Returns
    -------
    Sprite
        Labels (see ``LABEL_*``) with no non-zero pixel on the sprite border.
    """
    fig = _Figure.at(p, i)
    # Far side first (painter's order within the figure).
    fig.arm(fig.phase + math.pi, LABEL_SLEEVE_BACK)
    fig.leg(fig.phase + math.pi, LABEL_TROUSERS)
    fig.torso()
    fig.leg(fig.phase, LABEL_TROUSERS)
    fig.arm(fig.phase, LABEL_SHIRT)
    fig.head()
    return Sprite(fig.ox, fig.oy, fig.lab)


@dataclass(frozen=True, eq=False)
class _Figure:
    """A person's pose at one frame and the label sprite it is drawn into (see
    :func:`render_person`); ``ox, oy`` is the sprite's top-left pixel in the image."""

    lab: np.ndarray
    ox: int
    oy: int
    g: dict
    run: bool
    fx: float
    fy: float
    h: float
    d: float        # facing direction, +1 right, -1 left
    phase: float
    bob: float
    lean: float
    hip: tuple[float, float]
    shoulder: tuple[float, float]
    thigh: float
    shin: float
    t_leg: int
    t_arm: int

    @classmethod
    def at(cls, p: Person, i: int) -> "_Figure":
        g = _GAITS[p.gait]
        fx, fy, h = person_position(p, i)
        d = person_facing(p, i)
        # Phase advances 2π per gait cycle (two steps) of length cycle·h.
        phase = p.phase0 + 2.0 * math.pi * p.travelled(i) / (g["cycle"] * p.height)
        bob = -g["bob"] * h * abs(math.sin(phase))  # up at mid-stance of either leg
        margin = 3
        ox = int(math.floor(fx - 0.62 * h)) - margin
        oy = int(math.floor(fy - 1.10 * h)) - margin
        pw = int(math.ceil(1.24 * h)) + 2 * margin + 1
        ph = int(math.ceil(1.22 * h)) + 2 * margin + 1
        t_leg = max(2, int(round(0.085 * h)))
        lean = g["lean"] * d
        leg_len = 0.50 * h - t_leg / 2.0
        return cls(lab=np.zeros((ph, pw), dtype=np.uint8), ox=ox, oy=oy, g=g,
                   run=p.gait == "run", fx=fx, fy=fy, h=h, d=d, phase=phase, bob=bob, lean=lean,
                   hip=(fx + 0.0, fy - 0.50 * h + bob),
                   shoulder=(fx + math.sin(lean) * 0.30 * h, fy - 0.80 * h + bob),
                   thigh=0.5 * leg_len, shin=0.5 * leg_len, t_leg=t_leg,
                   t_arm=max(2, int(round(0.058 * h))))

    def _pt(self, x: float, y: float) -> tuple[int, int]:
        return _pt(x, y, self.ox, self.oy)

    def leg(self, ph_k: float, label: int) -> None:
        g, d, h, hip = self.g, self.d, self.h, self.hip
        theta = g["leg"] * math.sin(ph_k) * d  # + = forward
        bend = g["knee"] * 0.5 * (1.0 - math.cos(ph_k))  # knee folds backwards
        knee = (hip[0] + self.thigh * math.sin(theta), hip[1] + self.thigh * math.cos(theta))
        a = theta - bend * d
        ankle = (knee[0] + self.shin * math.sin(a), knee[1] + self.shin * math.cos(a))
        cv2.line(self.lab, self._pt(*hip), self._pt(*knee), label, self.t_leg, cv2.LINE_8, SHIFT)
        cv2.line(self.lab, self._pt(*knee), self._pt(*ankle), label, self.t_leg, cv2.LINE_8,
                 SHIFT)
        toe = (ankle[0] + d * 0.055 * h, ankle[1])
        cv2.line(self.lab, self._pt(*ankle), self._pt(*toe), LABEL_SHOES,
                 max(2, int(round(0.05 * h))), cv2.LINE_8, SHIFT)

    def arm(self, ph_k: float, label: int) -> None:
        d, h, shoulder = self.d, self.h, self.shoulder
        alpha = -self.g["arm"] * math.sin(ph_k) * d
        arm_len = 0.33 * h
        elbow_bend = 0.9 * d if self.run else 0.15 * d
        elbow = (shoulder[0] + 0.5 * arm_len * math.sin(alpha),
                 shoulder[1] + 0.5 * arm_len * math.cos(alpha))
        b = alpha + elbow_bend
        hand = (elbow[0] + 0.5 * arm_len * math.sin(b), elbow[1] + 0.5 * arm_len * math.cos(b))
        cv2.line(self.lab, self._pt(*shoulder), self._pt(*elbow), label, self.t_arm, cv2.LINE_8,
                 SHIFT)
        cv2.line(self.lab, self._pt(*elbow), self._pt(*hand), label, self.t_arm, cv2.LINE_8,
                 SHIFT)
        cv2.circle(self.lab, self._pt(*hand), int(round(0.028 * h * _ONE)), LABEL_SKIN, -1,
                   cv2.LINE_8, SHIFT)

    def torso(self) -> None:
        """An ellipse from the hips to the shoulders, tilted by the lean."""
        h, lean = self.h, self.lean
        tc = (self.fx + math.sin(lean) * 0.16 * h, self.fy - 0.665 * h + self.bob)
        cv2.ellipse(self.lab, self._pt(*tc), (int(0.125 * h * _ONE), int(0.19 * h * _ONE)),
                    math.degrees(-lean), 0, 360, LABEL_SHIRT, -1, cv2.LINE_8, SHIFT)

    def head(self) -> None:
        """Head and hair."""
        h, d = self.h, self.d
        hc = (self.fx + math.sin(self.lean) * 0.42 * h + 0.01 * h * d,
              self.fy - 0.915 * h + self.bob)
        r = int(round(0.075 * h * _ONE))
        cv2.circle(self.lab, self._pt(*hc), r, LABEL_SKIN, -1, cv2.LINE_8, SHIFT)
        cv2.ellipse(self.lab, self._pt(hc[0] - 0.012 * h * d, hc[1] - 0.012 * h),
                    (int(0.072 * h * _ONE), int(0.058 * h * _ONE)), 0, 180, 360, LABEL_HAIR, -1,
                    cv2.LINE_8, SHIFT)


def render_shadow(p: Person, i: int, side: float = 1.0) -> Sprite:
    """A cast shadow: a flat ellipse on the ground from the feet towards ``side`` (+1 = right).

    Returns a :class:`Sprite` whose non-zero pixels (value 1) are the shadow.
    """
    fx, fy, h = person_position(p, i)
    cx, cy = fx + side * 0.30 * h, fy - 0.01 * h
    ax, ay = 0.42 * h, 0.075 * h
    ox = int(math.floor(cx - ax)) - 2
    oy = int(math.floor(cy - ax)) - 2
    size = int(math.ceil(2 * ax)) + 5
    lab = np.zeros((size, size), dtype=np.uint8)
    cv2.ellipse(lab, _pt(cx, cy, ox, oy), (int(ax * _ONE), int(ay * _ONE)), -6.0 * side, 0, 360,
                1, -1, cv2.LINE_8, SHIFT)
    return Sprite(ox, oy, lab)


def _smooth_noise(rng: np.random.Generator, width: int, height: int, cell: int,
                  channels: int = 1) -> np.ndarray:
    """Smooth random texture: ``(H, W, C) float32`` with std ~1, from bicubic-upsampled noise."""
    gw, gh = max(2, width // cell + 2), max(2, height // cell + 2)
    small = rng.standard_normal((gh, gw, channels)).astype(np.float32)
    big = cv2.resize(small, (gw * cell, gh * cell), interpolation=cv2.INTER_CUBIC)
    big = big.reshape(gh * cell, gw * cell, channels)
    return big[:height, :width]


def render_background(width: int, height: int, rng: np.random.Generator,
                      column: Column | None = None) -> np.ndarray:
    """A static street-like background: ``(H, W, 3) uint8`` BGR.

    Buildings with windows in the upper part, a paved ground with perspective tile joints and a
    kerb below, a smooth random texture over everything and, optionally, a textured stone
    column. Colours are muted (greys, beige, brown) so that clothing stands out.
    """
    W, H = width, height
    img = np.zeros((H, W, 3), dtype=np.float32)
    ground_y = int(round(0.40 * H))
    # Sky / far wall.
    img[:ground_y] = np.array([178, 170, 160], np.float32) + rng.uniform(-10, 10, 3)
    # Buildings: random widths, heights and muted colours, each with a window grid.
    x = -int(rng.integers(0, 40))
    while x < W:
        bw = int(rng.integers(max(8, W // 8), max(9, W // 3)))
        top = int(rng.integers(int(0.02 * H), max(int(0.02 * H) + 1, int(0.22 * H))))
        base = np.array([110, 120, 135], np.float32) + rng.uniform(-30, 30, 3)
        img[top:ground_y, max(x, 0):min(x + bw, W)] = base
        win = base * 0.55
        ww, wh = max(3, bw // 7), max(3, int(0.035 * H))
        for wy in range(top + wh, ground_y - wh, 2 * wh):
            for wx in range(x + ww // 2 + 2, x + bw - ww, int(1.8 * ww) + 1):
                x1, x2 = max(wx, 0), min(wx + ww, W)
                if x2 > x1:
                    img[wy:wy + wh, x1:x2] = win * (0.85 + 0.3 * rng.random())
        x += bw + int(rng.integers(0, max(2, W // 40)))
    # Ground: paving with perspective joints converging to a vanishing point above the image.
    pave = np.array([150, 158, 162], np.float32) + rng.uniform(-12, 12, 3)
    img[ground_y:] = pave
    vx, vy = W * rng.uniform(0.35, 0.65), -0.8 * H
    joint = tuple(float(v) for v in pave * 0.78)
    for k in range(-12, 25):
        xb = W * k / 12.0
        x_top = vx + (xb - vx) * (ground_y - vy) / (H - vy)
        cv2.line(img, (int(x_top), ground_y), (int(xb), H), joint, 1, cv2.LINE_AA)
    yy = float(ground_y)
    step = 0.035 * H
    while yy < H:
        cv2.line(img, (0, int(yy)), (W, int(yy)), joint, 1, cv2.LINE_AA)
        step *= 1.22
        yy += step
    kerb = int(round(0.43 * H))
    img[ground_y:kerb] = pave * 0.82
    img[ground_y:ground_y + 2] = pave * 0.6
    # Smooth texture (two scales, mostly luminance) for the whole scene.
    tex = 7.0 * _smooth_noise(rng, W, H, 24) + 3.0 * _smooth_noise(rng, W, H, 6)
    img += tex + 2.0 * _smooth_noise(rng, W, H, 40, 3)
    if column is not None:
        _draw_column(img, column, rng)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def _draw_column(img: np.ndarray, c: Column, rng: np.random.Generator) -> None:
    """Stone pillar with cylindrical shading, mortar joints and grain (in place, float image)."""
    H, W = img.shape[:2]
    x1, x2 = max(c.x, 0), min(c.x + c.w, W)
    y1, y2 = max(c.y, 0), min(c.y + c.h, H)
    if x2 <= x1 or y2 <= y1:
        return
    stone = np.array([168, 182, 196], np.float32) + rng.uniform(-10, 10, 3)
    u = (np.arange(x1, x2, dtype=np.float32) - c.x + 0.5) / c.w  # 0..1 across the column
    shade = 0.62 + 0.45 * np.sin(np.pi * u) ** 0.7  # lit from the front, darker at the sides
    block = stone[None, None, :] * shade[None, :, None] * np.ones((y2 - y1, 1, 1), np.float32)
    grain = 9.0 * _smooth_noise(rng, x2 - x1, y2 - y1, 5)
    block += grain
    # Mortar joints every ~0.05 H, blocks offset by half a width on alternate courses.
    course = max(6, int(0.05 * H))
    for k, yy in enumerate(range(c.y + course, c.y + c.h, course)):
        if y1 <= yy < y2:
            block[yy - y1] *= 0.7
        mid = c.x + (c.w // 2 if k % 2 else c.w // 4)
        if x1 <= mid < x2:
            block[max(yy - course, y1) - y1:min(yy, y2) - y1, mid - x1] *= 0.75
    img[y1:y2, x1:x2] = block


def make_noise_pool(rng: np.random.Generator, width: int, height: int, sigma: float,
                    size: int = 4, pad: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """Pre-computed Gaussian sensor noise, split into positive and negative parts.

    Returns
    -------
    pos, neg : (size, H + pad, W + pad, 3) uint8
        ``noise = pos - neg`` with ``noise ~ round(N(0, sigma²))`` per pixel and channel, so a frame
        is made noisy with two saturating OpenCV operations: ``subtract(add(img, pos), neg)``.
    """
    n = rng.standard_normal((size, height + pad, width + pad, 3), dtype=np.float32)
    n *= np.float32(sigma)
    q = np.clip(np.rint(n), -255, 255).astype(np.int16)
    pos = np.clip(q, 0, 255).astype(np.uint8)
    neg = np.clip(-q, 0, 255).astype(np.uint8)
    return pos, neg
