"""Synthetic surveillance scenes with exact ground truth.

A :class:`SyntheticScene` is a frozen description (size, people, column, noise, lighting) plus
lazily built caches (background, noise pool, ground truth). Frames are rendered on demand and
are a pure function of ``(scene parameters, seed, frame index)``: random access, bit-identical
across calls and processes.

Scene types follow the four sequence types used to evaluate the Reading People Tracker
(Siebel, PhD thesis, University of Reading 2003, ch. 6): (1) one person walking across,
(2) one person running, (3) one person passing behind a column, (4) two people crossing — plus a
small crowd and a lighting-change scene. See ``docs/synthetic.md``.
"""

from __future__ import annotations

import copy
import logging
import math
import zlib
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, NamedTuple

import cv2
import numpy as np

from ..errors import ConfigError
from ..types import Annotations, Event
from .events import ground_truth_events, scene_toml
from .render import (
    Bag,
    Column,
    Person,
    Sprite,
    bag_box,
    draw_bag,
    make_noise_pool,
    person_position,
    render_background,
    render_bag,
    render_person,
    render_shadow,
)

__all__ = [
    "SCENES",
    "SyntheticScene",
    "Lighting",
    "make_scene",
    "parse_synth_spec",
    "scene_summaries",
    "MASK_PERSON",
    "MASK_SHADOW",
]

log = logging.getLogger(__name__)

#: Labels in :meth:`SyntheticScene.foreground_mask` (CDnet 2014 convention).
MASK_PERSON = 255
MASK_SHADOW = 50

_SHADOW_GAIN = 0.58  # shadowed ground keeps 58 % of its brightness
_EMPTY_FRAMES = 15  # at least this many frames of empty background before anyone enters


@dataclass(frozen=True)
class Lighting:
    """Global illumination gain over time.

    The gain is 1 until frame index ``ramp_start``, changes linearly to ``ramp_gain`` at
    ``ramp_end`` (gradual change, e.g. a cloud), and is multiplied by ``jump_factor`` from
    ``jump_at`` on (sudden change, e.g. lights switched on).
    """

    ramp_start: int
    ramp_end: int
    ramp_gain: float
    jump_at: int
    jump_factor: float

    def __post_init__(self) -> None:
        if not 0 <= self.ramp_start < self.ramp_end:
            raise ValueError(
                f"lighting needs 0 <= ramp_start < ramp_end, got {self.ramp_start}, {self.ramp_end}"
            )
        if self.ramp_gain <= 0 or self.jump_factor <= 0:
            raise ValueError("lighting gains must be > 0")

    @classmethod
    def default(cls, n_frames: int) -> "Lighting":
        """Ramp 1.0 → 0.8 over 20–52 % of the sequence, then +20 % at 68 %."""
        n = max(int(n_frames), 4)
        return cls(int(0.20 * n), max(int(0.52 * n), int(0.20 * n) + 1), 0.80, int(0.68 * n), 1.20)

    def gain(self, i: int) -> float:
        """Gain at frame index ``i`` (1.0 = unchanged)."""
        if i <= self.ramp_start:
            g = 1.0
        elif i >= self.ramp_end:
            g = self.ramp_gain
        else:
            t = (i - self.ramp_start) / (self.ramp_end - self.ramp_start)
            g = 1.0 + t * (self.ramp_gain - 1.0)
        if i >= self.jump_at:
            g *= self.jump_factor
        return g


def _stable_hash(text: str) -> int:
    return zlib.crc32(text.encode("utf-8"))


class _Item(NamedTuple):
    """One object drawn in a frame: its ground-truth id, colour per label and label sprite."""

    id: int
    palette: np.ndarray
    sprite: Sprite


@dataclass(frozen=True, eq=False)
class SyntheticScene:
    """A synthetic surveillance sequence with exact ground truth.

    Attributes
    ----------
    name : str
        Scene type (one of :data:`SCENES`, or any label for a hand-built scene).
    seed : int
        Seed of all randomness (background, noise, people's paths and colours).
    width, height : int
        Frame size in pixels.
    fps : float
        Nominal frame rate (metadata: speeds are defined in pixels per frame).
    n_frames : int
        Number of frames; valid frame indices are ``0 .. n_frames - 1``.
    people : tuple of Person
        Who walks where (ids 1..).
    bags : tuple of Bag
        Bags people carry and leave (ids after the people's).
    column : Column or None
        Static occluder drawn over people.
    noise : float
        Sensor noise standard deviation in grey levels (0 = none).
    shadows : bool
        Draw cast shadows next to people's feet.
    lighting : Lighting or None
        Illumination changes (None = constant).
    shadow_side : float
        +1 shadows fall to the right of the feet, -1 to the left.
    overrides : mapping
        The overrides the scene was made with (for :attr:`spec`).
    scene_file : mapping or None
        The scene-analytics lines and zones of this scene, as the scene file's TOML tables
        (pixels; see :mod:`motiontrack.synth.events`); None = none.
    """

    name: str
    seed: int
    width: int
    height: int
    fps: float
    n_frames: int
    people: tuple[Person, ...] = ()
    column: Column | None = None
    noise: float = 3.5
    shadows: bool = False
    lighting: Lighting | None = None
    shadow_side: float = 1.0
    overrides: Mapping[str, Any] = field(default_factory=dict)
    bags: tuple[Bag, ...] = ()
    scene_file: Mapping[str, Any] | None = None
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.width < 16 or self.height < 16:
            raise ValueError(f"scene size must be at least 16x16, got {self.width}x{self.height}")
        if self.n_frames < 1:
            raise ValueError(f"n_frames must be >= 1, got n_frames={self.n_frames}")
        if not self.fps > 0:
            raise ValueError(f"fps must be > 0, got fps={self.fps}")
        if not 0 <= self.noise <= 64:
            raise ValueError(f"noise must be in [0, 64] grey levels, got noise={self.noise}")
        ids = [p.id for p in self.people]
        if len(set(ids)) != len(ids):
            raise ValueError(f"person ids must be unique, got {ids}")
        for b in self.bags:
            if b.owner not in ids:
                raise ValueError(f"bag {b.id} has no owner: no person has id {b.owner}")
        all_ids = ids + [b.id for b in self.bags]
        if len(set(all_ids)) != len(all_ids):
            raise ValueError(f"person and bag ids must be unique, got {all_ids}")

    # ------------------------------------------------------------------ basics
    def __getstate__(self) -> dict:
        # Pickle (e.g. for parallel sweeps) without the caches: they are rebuilt on demand.
        state = dict(self.__dict__)
        state["_cache"] = {}
        return state

    def __setstate__(self, state: dict) -> None:
        for k, v in state.items():
            object.__setattr__(self, k, v)

    def __len__(self) -> int:
        return self.n_frames

    @property
    def spec(self) -> str:
        """A ``synth:`` spec string that recreates this scene with :func:`parse_synth_spec`."""
        parts = [f"seed={self.seed}"] + [
            f"{k}={str(v).lower() if isinstance(v, bool) else v}"
            for k, v in sorted(self.overrides.items())
        ]
        return f"synth:{self.name}?" + "&".join(parts)

    @property
    def summary(self) -> str:
        """One line: what this scene type shows."""
        st = _SCENE_TYPES.get(self.name)
        return st.summary if st is not None else f"custom scene with {len(self.people)} people"

    def _check_index(self, i: int) -> int:
        if isinstance(i, (bool, np.bool_)) or not isinstance(i, (int, np.integer)):
            raise TypeError(f"frame index must be an integer, got {type(i).__name__}")
        i = int(i)
        if not 0 <= i < self.n_frames:
            raise IndexError(f"frame index must be in [0, {self.n_frames - 1}], got {i}")
        return i

    def _rng(self, purpose: int) -> np.random.Generator:
        return np.random.default_rng([self.seed, purpose, _stable_hash(self.name)])

    @property
    def background(self) -> np.ndarray:
        """The static background (with the column), ``(H, W, 3) uint8`` BGR, before lighting/noise.

        A read-only view of the cached image.
        """
        bg = self._cache.get("bg")
        if bg is None:
            # Background depends on the seed only (not the scene type) except for the column.
            rng = np.random.default_rng([self.seed, 1])
            bg = render_background(self.width, self.height, rng, self.column)
            log.debug("rendered background for %s (%dx%d)", self.spec, self.width, self.height)
            bg.setflags(write=False)
            self._cache["bg"] = bg
        return bg

    def _noise_pool(self) -> tuple[np.ndarray, np.ndarray]:
        pool = self._cache.get("noise")
        if pool is None:
            pool = make_noise_pool(np.random.default_rng([self.seed, 2]), self.width, self.height,
                                   self.noise)
            self._cache["noise"] = pool
        return pool

    # ----------------------------------------------------------- composition
    def _layers(self, i: int) -> tuple[list[_Item], list[Sprite]]:
        """People and bags touching the image, sorted back (far) to front, and people's shadows."""
        last = self._cache.get("layers")
        if last is not None and last[0] == i:
            return last[1]
        items = self._people_only(i)
        shadows: list[Sprite] = []
        if self.shadows:
            drawn = {it.id for it in items}
            shadows = [render_shadow(p, i, self.shadow_side) for p in self.people if p.id in drawn]
        result = (items, shadows)
        self._cache["layers"] = (i, result)
        return result

    @staticmethod
    def _clip(s: Sprite, W: int, H: int):
        """Overlap of a sprite with the image: (frame slices, sprite slices) or None."""
        lh, lw = s.labels.shape
        x1, y1 = max(s.ox, 0), max(s.oy, 0)
        x2, y2 = min(s.ox + lw, W), min(s.oy + lh, H)
        if x2 <= x1 or y2 <= y1:
            return None
        return ((slice(y1, y2), slice(x1, x2)),
                (slice(y1 - s.oy, y2 - s.oy), slice(x1 - s.ox, x2 - s.ox)))

    def frame(self, i: int) -> np.ndarray:
        """Render frame index ``i`` (0-based).

        Returns
        -------
        np.ndarray
            ``(H, W, 3) uint8`` BGR, a new array (callers may modify it).
        """
        i = self._check_index(i)
        W, H = self.width, self.height
        bg = self.background
        out = bg.copy()
        people, shadows = self._layers(i)
        for sh in shadows:
            c = self._clip(sh, W, H)
            if c is None:
                continue
            (fs, ss) = c
            m = sh.labels[ss].astype(bool)
            region = out[fs]
            region[m] = (region[m] * _SHADOW_GAIN).astype(np.uint8)
        for it in people:
            c = self._clip(it.sprite, W, H)
            if c is None:
                continue
            fs, ss = c
            lab = it.sprite.labels[ss]
            m = lab > 0
            out[fs][m] = it.palette[lab[m]]
        if self.column is not None and people:
            cs = self._column_slices()
            if cs is not None:
                out[cs] = bg[cs]  # the column is in front of everyone
        if self.lighting is not None:
            g = self.lighting.gain(i)
            if g != 1.0:
                out = cv2.convertScaleAbs(out, alpha=g)
        if self.noise > 0:
            pos, neg = self._noise_pool()
            k, dy, dx = self._noise_index(i, pos.shape[0], pos.shape[1] - H, pos.shape[2] - W)
            cv2.add(out, pos[k, dy:dy + H, dx:dx + W], dst=out)
            cv2.subtract(out, neg[k, dy:dy + H, dx:dx + W], dst=out)
        return out

    @staticmethod
    def _noise_index(i: int, size: int, pad_y: int, pad_x: int) -> tuple[int, int, int]:
        # Knuth's multiplicative hash spreads consecutive indices over pool entries and offsets.
        r = (i * 2654435761 + 12345) & 0xFFFFFFFF
        return (r >> 24) % size, (r >> 8) % (pad_y + 1), (r >> 16) % (pad_x + 1)

    def _column_slices(self):
        c = self.column
        if c is None:
            return None
        x1, y1 = max(c.x, 0), max(c.y, 0)
        x2, y2 = min(c.x + c.w, self.width), min(c.y + c.h, self.height)
        if x2 <= x1 or y2 <= y1:
            return None
        return (slice(y1, y2), slice(x1, x2))

    def frames(self):
        """Iterate over all frames in order (``(H, W, 3) uint8`` each)."""
        for i in range(self.n_frames):
            yield self.frame(i)

    def foreground_mask(self, i: int) -> np.ndarray:
        """Exact motion mask of frame index ``i``.

        Returns
        -------
        np.ndarray
            ``(H, W) uint8``: 255 = visible person pixel, 50 = visible cast-shadow pixel (CDnet 2014
            labels), 0 = static background (including the column and anything it hides).
        """
        i = self._check_index(i)
        W, H = self.width, self.height
        mask = np.zeros((H, W), dtype=np.uint8)
        people, shadows = self._layers(i)
        for sh in shadows:
            c = self._clip(sh, W, H)
            if c is not None:
                fs, ss = c
                mask[fs][sh.labels[ss] > 0] = MASK_SHADOW
        for it in people:
            c = self._clip(it.sprite, W, H)
            if c is not None:
                fs, ss = c
                mask[fs][it.sprite.labels[ss] > 0] = MASK_PERSON
        cs = self._column_slices()
        if cs is not None:
            mask[cs] = 0
        return mask

    # ---------------------------------------------------------- ground truth
    def _visibility(self, people: list[_Item]) -> list[tuple[int, tuple, float]]:
        """Per object: (id, full bbox, visible fraction) for one frame's back-to-front layers."""
        W, H = self.width, self.height
        cs = self._column_slices()
        rows = []
        for k, (pid, _, s) in enumerate(people):
            bbox = s.bbox()
            if bbox is None:
                continue
            own = s.labels > 0
            total = int(own.sum())
            vis = own.copy()
            lh, lw = vis.shape
            # Outside the image.
            x_lo, y_lo = max(0, -s.ox), max(0, -s.oy)
            x_hi, y_hi = min(lw, W - s.ox), min(lh, H - s.oy)
            if x_hi <= x_lo or y_hi <= y_lo:
                continue
            inside = np.zeros_like(vis)
            inside[y_lo:y_hi, x_lo:x_hi] = True
            vis &= inside
            if not vis.any():
                continue  # no pixel inside the image: no row
            # Hidden by the column.
            if cs is not None:
                ys, xs = cs
                a1, a2 = max(ys.start - s.oy, 0), min(ys.stop - s.oy, lh)
                b1, b2 = max(xs.start - s.ox, 0), min(xs.stop - s.ox, lw)
                if a2 > a1 and b2 > b1:
                    vis[a1:a2, b1:b2] = False
            # Hidden by people drawn later (in front).
            for _, _, q in people[k + 1:]:
                qh, qw = q.labels.shape
                a1, a2 = max(q.oy - s.oy, 0), min(q.oy + qh - s.oy, lh)
                b1, b2 = max(q.ox - s.ox, 0), min(q.ox + qw - s.ox, lw)
                if a2 > a1 and b2 > b1:
                    qa1, qb1 = a1 + s.oy - q.oy, b1 + s.ox - q.ox
                    vis[a1:a2, b1:b2] &= q.labels[qa1:qa1 + (a2 - a1), qb1:qb1 + (b2 - b1)] == 0
            rows.append((pid, bbox, float(vis.sum()) / total))
        return rows

    def ground_truth(self) -> Annotations:
        """Exact ground truth for every frame.

        Returns
        -------
        Annotations
            One row per person and frame in which any pixel of the person lies inside the image,
            sorted by frame, then id.
            ``frames`` 1-based (frame index ``i`` → ``i + 1``); ``ids`` = person ids (1..);
            ``boxes`` = tight ``x, y, w, h`` around *all* of the person's pixels (head to soles,
            swinging legs and arms included; may extend beyond the image), in pixels, where the
            box covers pixel columns ``x .. x + w - 1`` and rows ``y .. y + h - 1``;
            ``visibility`` = visible fraction of the person's pixels (hidden by the image border,
            the column or people in front); ``consider`` = ``visibility >= 0.5``; ``classes`` = 1
            (pedestrian); ``scores`` = 1; ``world`` = -1 (unknown).

        The result is cached; the arrays are read-only.
        """
        gt = self._cache.get("gt")
        if gt is not None:
            return gt
        frames, ids, boxes, vis = [], [], [], []
        for i in range(self.n_frames):
            people = self._people_only(i)
            for pid, bbox, v in self._visibility(people):
                frames.append(i + 1)
                ids.append(pid)
                boxes.append(bbox)
                vis.append(v)
        n = len(frames)
        frames_a = np.asarray(frames, dtype=np.int64)
        ids_a = np.asarray(ids, dtype=np.int64)
        order = np.lexsort((ids_a, frames_a))  # rows sorted by frame, then id
        vis_a = np.asarray(vis, dtype=np.float64)[order]
        gt = Annotations.from_columns(
            frames=frames_a[order],
            ids=ids_a[order],
            boxes=np.asarray(boxes, dtype=np.float64).reshape(n, 4)[order],
            scores=np.ones(n),
            consider=vis_a >= 0.5,
            classes=np.ones(n, dtype=np.int64),
            visibility=vis_a,
            meta={"format": "synth", "kind": "gt", "source": self.spec},
        )
        for name in ("frames", "ids", "boxes", "scores", "consider", "classes", "visibility",
                     "world"):
            getattr(gt, name).setflags(write=False)
        self._cache["gt"] = gt
        return gt

    def _people_only(self, i: int) -> list[_Item]:
        """Like :meth:`_layers` but without shadows and without touching the one-frame cache.

        A carried bag is drawn into its owner's sprite (it is part of the person); a bag on the
        ground is an object of its own.
        """
        W, H = self.width, self.height
        owners = {p.id: p for p in self.people}
        carried = {b.owner: b for b in self.bags if b.carried(i)}
        items: list[tuple[float, _Item]] = []
        for p in self.people:
            s = render_person(p, i)
            pal = p.palette()
            bag = carried.get(p.id)
            if bag is not None:
                draw_bag(s.labels, s.ox, s.oy, bag_box(bag, p, i))
                pal = np.vstack([pal, np.asarray(bag.colour, np.uint8)[None]])
            items.append((person_position(p, i)[1], _Item(p.id, pal, s)))
        for b in self.bags:
            if not b.carried(i):
                box = bag_box(b, owners[b.owner], i)
                items.append((box[1], _Item(b.id, b.palette(), render_bag(b, owners[b.owner], i))))
        visible = []
        for depth, it in items:
            lh, lw = it.sprite.labels.shape
            s = it.sprite
            if s.ox >= W or s.oy >= H or s.ox + lw <= 0 or s.oy + lh <= 0:
                continue
            visible.append((depth, it))
        # Painter's order: larger foot y = closer to the camera = drawn later.
        visible.sort(key=lambda t: (t[0], t[1].id))
        return [it for _, it in visible]

    # ------------------------------------------------------------ analytics
    def ground_truth_events(self) -> list[Event]:
        """The exact scene-analytics events of :attr:`scene_file` on the ground truth (see
        :func:`motiontrack.synth.events.ground_truth_events`); empty without a scene file.

        The result is cached (a new list each call).
        """
        ev = self._cache.get("events")
        if ev is None:
            ev = [] if self.scene_file is None else ground_truth_events(
                self.scene_file, self.ground_truth(), self.fps, {b.id: b.owner for b in self.bags})
            self._cache["events"] = ev
        return list(ev)

    def scene_toml(self) -> str:
        """:attr:`scene_file` as the TOML text ``track --scene`` and ``analyze --scene`` read."""
        if self.scene_file is None:
            raise ValueError(f"scene {self.name!r} has no scene file")
        return scene_toml(self.scene_file, f"lines and zones of {self.spec} (pixels)")

    # -------------------------------------------------------------- describe
    def describe(self) -> dict:
        """What the scene contains and what happens when (frame numbers 1-based, as in the gt)."""
        gt = self.ground_truth()
        events = self._background_events(gt)
        people = []
        for p in self.people:
            entry, person_events = self._person(p, gt)
            people.append(entry)
            events += person_events
        bags = []
        for b in self.bags:
            entry, bag_events = self._bag(b, gt)
            bags.append(entry)
            events += bag_events
        for a_id, b_id, a, b in self._overlaps(gt):
            kind = "persons" if {a_id, b_id} <= {p.id for p in self.people} else "objects"
            events.append({"frames": [a, b], "what": f"boxes of {kind} {a_id} and {b_id} overlap"})
        events += self._lighting_events()
        events.sort(key=lambda e: (e["frames"][0], e["frames"][1]))
        out = {**self._settings(), "people": people, "events": events}
        if bags:
            out["bags"] = bags
        if self.scene_file is not None:
            out["scene_file"] = copy.deepcopy(dict(self.scene_file))  # the caller's to change
            out["analytics_events"] = [e.to_json() for e in self.ground_truth_events()]
        return out

    def _bag(self, b: Bag, gt: Annotations) -> tuple[dict[str, Any], list[dict]]:
        """A bag's description, and when it is set down."""
        f = gt.frames[gt.ids == b.id]
        entry = {"id": b.id, "owner": b.owner, "colour_bgr": list(b.colour),
                 "dropped_frame": b.t_drop + 1,
                 "first_frame": int(f.min()) if f.size else None}
        events = [{"frames": [b.t_drop - b.lower + 1, b.t_drop],
                   "what": f"person {b.owner} sets bag {b.id} down"}]
        if f.size:
            events.append({"frames": [int(f.min()), int(f.max())],
                           "what": f"bag {b.id} lies on the ground (an object of its own)"})
        return entry, events

    def _background_events(self, gt: Annotations) -> list[dict]:
        """The frames before anyone appears."""
        first_any = int(gt.frames.min()) if len(gt) else None
        if first_any is None:
            return [{"frames": [1, self.n_frames], "what": "empty background only"}]
        if first_any > 1:
            return [{"frames": [1, first_any - 1], "what": "empty background"}]
        return []

    def _person(self, p: Person, gt: Annotations) -> tuple[dict[str, Any], list[dict]]:
        """A person's description, and when they enter, are fully hidden and leave."""
        sel = gt.ids == p.id
        f = gt.frames[sel]
        v = gt.visibility[sel]
        entry: dict[str, Any] = {
            "id": p.id,
            "gait": p.gait,
            "height_px": round(p.height, 1),
            "speed_px_per_frame": round(p.speed, 2),
            "direction": "left to right" if p.vx >= 0 else "right to left",
            "shirt_bgr": list(p.shirt),
            "first_frame": int(f.min()) if f.size else None,
            "last_frame": int(f.max()) if f.size else None,
        }
        if p.turns:
            # where the velocity changes: frame number, foot point, new velocity (px/frame)
            entry["path"] = [[round(t + 1, 2), round(x, 1), round(y, 1), round(vx, 3), round(vy, 3)]
                             for t, x, y, vx, vy in p.legs()]
        events: list[dict] = []
        if f.size:
            side = "left" if p.vx >= 0 else "right"
            events.append({"frames": [int(f.min()), int(f.min())],
                           "what": f"person {p.id} ({p.gait}) enters from the {side}"})
            for a, b in _runs(f[v == 0]):
                events.append({"frames": [a, b], "what": f"person {p.id} fully hidden"})
            if f.max() < self.n_frames:
                events.append({"frames": [int(f.max()), int(f.max())],
                               "what": f"person {p.id} leaves the image"})
        return entry, events

    def _lighting_events(self) -> list[dict]:
        if self.lighting is None:
            return []
        L = self.lighting
        return [{"frames": [L.ramp_start + 1, L.ramp_end + 1],
                 "what": f"gradual illumination change: gain 1.00 -> {L.ramp_gain:.2f}"},
                {"frames": [L.jump_at + 1, L.jump_at + 1],
                 "what": f"sudden illumination change: gain x{L.jump_factor:.2f}"}]

    def _settings(self) -> dict[str, Any]:
        """The scene's parameters, as :meth:`describe` lists them before people and events."""
        c = self.column
        return {
            "name": self.name,
            "summary": self.summary,
            "seed": self.seed,
            "spec": self.spec,
            "size": [self.width, self.height],
            "fps": self.fps,
            "n_frames": self.n_frames,
            "frame_numbering": "1-based (frame index i -> frame number i + 1)",
            "noise_sigma": self.noise,
            "shadows": self.shadows,
            "column": None if c is None else {"x": c.x, "y": c.y, "w": c.w, "h": c.h},
            "illumination": None if self.lighting is None else {
                "gradual": {"from_frame": self.lighting.ramp_start + 1,
                            "to_frame": self.lighting.ramp_end + 1,
                            "gain": self.lighting.ramp_gain},
                "sudden": {"frame": self.lighting.jump_at + 1,
                           "factor": self.lighting.jump_factor},
            },
        }

    @staticmethod
    def _overlaps(gt: Annotations) -> list[tuple[int, int, int, int]]:
        """(id_a, id_b, first, last) runs of frames where two gt boxes intersect."""
        out = []
        ids = np.unique(gt.ids)
        by = {int(k): v for k, v in gt.by_frame().items()}
        for ai, a in enumerate(ids):
            for b in ids[ai + 1:]:
                fr = []
                for f, rows in by.items():
                    ra = rows[gt.ids[rows] == a]
                    rb = rows[gt.ids[rows] == b]
                    if ra.size and rb.size and _box_intersect(gt.boxes[ra[0]], gt.boxes[rb[0]]):
                        fr.append(f)
                for s, e in _runs(np.asarray(sorted(fr), dtype=np.int64)):
                    out.append((int(a), int(b), s, e))
        return out


def _box_intersect(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3]
                and b[1] < a[1] + a[3])


def _runs(frames: np.ndarray) -> list[tuple[int, int]]:
    """Maximal runs of consecutive integers: ``[3, 4, 5, 9] -> [(3, 5), (9, 9)]``."""
    f = np.asarray(frames, dtype=np.int64)
    if f.size == 0:
        return []
    cuts = np.flatnonzero(np.diff(f) != 1) + 1
    return [(int(g[0]), int(g[-1])) for g in np.split(f, cuts)]


# =========================================================================== scene builders

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
class _Ctx:
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


def _colours(rng: np.random.Generator, n: int) -> list[dict]:
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


def _entering(ctx: _Ctx, pid: int, t_enter: float, from_left: bool, foot_y: float,
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
        **(colours or _colours(ctx.rng, 1)[0]),
    )


def _build_walker(ctx: _Ctx, gait: str = "walk") -> dict:
    rng = ctx.rng
    if gait == "run":
        speed = rng.uniform(6.0, 7.5) * ctx.sx
    else:
        speed = rng.uniform(2.8, 3.0) * ctx.sx
    foot_y = rng.uniform(0.78, 0.86) * ctx.height
    from_left = bool(rng.integers(2))
    p = _entering(ctx, 1, t_enter=_EMPTY_FRAMES + 2 + int(rng.integers(0, 3)), from_left=from_left,
                  foot_y=foot_y, height_ref=rng.uniform(112, 122) * ctx.sy, speed=speed,
                  vy=rng.uniform(-0.12, 0.12) * ctx.sy, gait=gait)
    return {"people": (p,)}


def _build_runner(ctx: _Ctx) -> dict:
    return _build_walker(ctx, gait="run")


def _build_column(ctx: _Ctx) -> dict:
    rng = ctx.rng
    from_left = bool(rng.integers(2))
    foot_y = rng.uniform(0.78, 0.84) * ctx.height
    speed = rng.uniform(2.2, 2.6) * ctx.sx
    p = _entering(ctx, 1, t_enter=_EMPTY_FRAMES + 3 + int(rng.integers(0, 4)), from_left=from_left,
                  foot_y=foot_y, height_ref=118 * ctx.sy, speed=speed, gait="walk")
    # Column centred near the middle, wide enough to hide the person for ~20 frames, tall enough
    # to hide the head, its base in front of (below) the person's feet.
    cw = int(round(100 * ctx.sx))
    cx = int(round(ctx.width * rng.uniform(0.42, 0.52)))
    col = Column(x=cx - cw // 2, y=0, w=cw, h=int(round(foot_y + 0.06 * ctx.height)))
    return {"people": (p,), "column": col}


def _build_crossing(ctx: _Ctx) -> dict:
    rng = ctx.rng
    cols = _colours(rng, 2)
    y_front = rng.uniform(0.80, 0.84) * ctx.height
    y_back = y_front - rng.uniform(0.06, 0.09) * ctx.height
    left_front = bool(rng.integers(2))
    t1 = _EMPTY_FRAMES + 3 + int(rng.integers(0, 3))
    t2 = _EMPTY_FRAMES + 3 + int(rng.integers(0, 6))
    a = _entering(ctx, 1, t1, left_front, y_front, 118 * ctx.sy,
                  rng.uniform(1.8, 2.2) * ctx.sx, gait="walk", colours=cols[0])
    b = _entering(ctx, 2, t2, not left_front, y_back, 118 * ctx.sy,
                  rng.uniform(1.8, 2.2) * ctx.sx, gait="walk", colours=cols[1])
    return {"people": (a, b)}


def _build_crowd(ctx: _Ctx) -> dict:
    rng = ctx.rng
    n = int(rng.integers(5, 9))
    cols = _colours(rng, n)
    people = []
    for k in range(n):
        t_enter = _EMPTY_FRAMES + 3 if k == 0 else _EMPTY_FRAMES + 3 + int(rng.integers(0, 120))
        gait = "run" if (k == n - 1 and rng.random() < 0.5) else "walk"
        speed = (rng.uniform(5.0, 6.5) if gait == "run" else rng.uniform(1.6, 3.0)) * ctx.sx
        foot_y = rng.uniform(0.68, 0.95) * ctx.height
        vy = rng.uniform(-0.25, 0.25) * ctx.sy
        people.append(_entering(ctx, k + 1, t_enter, bool(rng.integers(2)), foot_y,
                                rng.uniform(102, 116) * ctx.sy, speed, vy, gait, cols[k]))
    return {"people": tuple(people)}


def _build_lighting(ctx: _Ctx) -> dict:
    d = _build_walker(ctx)
    d["illumination"] = True
    return d


# Lines and zones reach this far below the image (fraction of its height): a horizontal edge at the
# bottom border would be crossed back and forth by the feet of people walking along it.
_BELOW = 1.25


def _q(v: float) -> float:
    """A coordinate a quarter pixel past an integer: box anchors are whole or half pixels, so no
    anchor ever lies exactly on a line or a zone edge placed here (no ties in the event rules)."""
    return math.floor(v) + 0.25


def _rect(x1: float, y1: float, x2: float, y2: float) -> list[list[float]]:
    return [[_q(x1), _q(y1)], [_q(x2), _q(y1)], [_q(x2), _q(y2)], [_q(x1), _q(y2)]]


def _gate(ctx: _Ctx, x: float) -> dict:
    """A vertical line at column ``x`` across the walkway, drawn bottom to top, so that walking
    left to right is ``in`` (the crossing rule of :mod:`motiontrack.synth.events`). It runs on
    below the image: feet at the bottom border still cross it."""
    return {"name": "gate",
            "points": [[_q(x), _q(_BELOW * ctx.height)], [_q(x), _q(0.45 * ctx.height)]]}


def _layout(ctx: _Ctx, gate_x: float, zone: tuple[float, float, float, float],
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


def _street_layout(ctx: _Ctx, loiter_s: float = 10.0) -> dict:
    """The scene file of the walkway scenes: the line ``gate`` across the middle and the zone
    ``plaza`` around it (wider than any walker needs ``loiter_s`` to cross)."""
    W, H = ctx.width, ctx.height
    return _layout(ctx, 0.5 * W, (0.3 * W, 0.45 * H, 0.7 * W, _BELOW * H), loiter_s)


def _walk_through(ctx: _Ctx, pid: int, t_enter: float, start: tuple[float, float],
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


def _build_loiter(ctx: _Ctx) -> dict:
    """Someone walks in from the left, lingers in ``plaza`` (slow, turning walk for 7-9 s at
    25 fps), and leaves by either side."""
    rng, W, H = ctx.rng, ctx.width, ctx.height
    zone = (0.25 * W, 0.58 * H, 0.62 * W, _BELOW * H)
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
    p = _walk_through(ctx, 1, _EMPTY_FRAMES + 2 + int(rng.integers(0, 3)), (-lead, y_in), legs,
                      height_ref, _colours(rng, 1)[0])
    return {"people": (p,), "scene_file": _layout(ctx, 0.12 * W, zone, 5.0)}


def _build_leftbag(ctx: _Ctx) -> dict:
    """Someone carries a bag in, stops, sets it down and walks on out of view; the bag stays."""
    rng, W, H = ctx.rng, ctx.width, ctx.height
    cols = _colours(rng, 2)
    from_left = bool(rng.integers(2))
    speed = rng.uniform(2.6, 3.0) * ctx.sx
    height_ref = rng.uniform(112, 122) * ctx.sy
    foot_y = rng.uniform(0.78, 0.86) * H
    lead = 0.22 * height_ref
    drop_x = rng.uniform(0.30, 0.42) * W
    sign = 1.0 if from_left else -1.0
    x_start = -lead if from_left else W + lead
    x_stop = drop_x if from_left else W - drop_x
    t_enter = _EMPTY_FRAMES + 2 + int(rng.integers(0, 3))
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
    layout = _layout(ctx, 0.5 * W, (zx[0], 0.45 * H, zx[1], _BELOW * H), 10.0)
    return {"people": (p,), "bags": (bag,), "scene_file": layout}


@dataclass(frozen=True)
class _SceneType:
    build: Callable[[_Ctx], dict]
    n_frames: int
    summary: str


_SCENE_TYPES: dict[str, _SceneType] = {
    "walker": _SceneType(_build_walker, 250, "type 1: one person walking across the image"),
    "runner": _SceneType(_build_runner, 150, "type 2: one person running across the image"),
    "column": _SceneType(_build_column, 220,
                         "type 3: one person passing behind a column (full occlusion)"),
    "crossing": _SceneType(_build_crossing, 250,
                           "type 4: two people crossing, walking in opposite directions"),
    "crowd": _SceneType(_build_crowd, 250, "5-8 people walking (one may run), many occlusions"),
    "lighting": _SceneType(_build_lighting, 250,
                           "a walker with a gradual and a sudden illumination change"),
    "loiter": _SceneType(_build_loiter, 520,
                         "one person walks in, lingers 7-9 s in the zone plaza, then leaves"),
    "leftbag": _SceneType(_build_leftbag, 360,
                          "one person sets a bag down and walks off out of view; the bag stays"),
}

#: Names of the built-in scene types.
SCENES: tuple[str, ...] = tuple(_SCENE_TYPES)


def scene_summaries() -> dict[str, str]:
    """``{name: one-line summary}`` for every built-in scene (cheap: renders nothing)."""
    return {name: st.summary for name, st in _SCENE_TYPES.items()}

# Override name -> (kind, check, description)
_OVERRIDES: dict[str, tuple[str, Callable[[Any], bool], str]] = {
    "n_frames": ("int", lambda v: 1 <= v <= 100_000, "an integer in [1, 100000]"),
    "width": ("int", lambda v: 64 <= v <= 4096, "an integer in [64, 4096]"),
    "height": ("int", lambda v: 64 <= v <= 4096, "an integer in [64, 4096]"),
    "fps": ("float", lambda v: 0 < v <= 1000, "a number in (0, 1000]"),
    "noise": ("float", lambda v: 0 <= v <= 64, "a number of grey levels in [0, 64]"),
    "shadows": ("bool", lambda v: True, "true or false"),
    "illumination": ("bool", lambda v: True, "true or false"),
}


def _coerce(key: str, value: Any) -> Any:
    kind, ok, what = _OVERRIDES[key]
    bad = ConfigError(f"synthetic scene parameter {key} must be {what}, got {value!r}")
    if kind == "bool":
        if isinstance(value, (bool, np.bool_)):
            return bool(value)
        if isinstance(value, (int, np.integer)) and value in (0, 1):
            return bool(value)
        raise bad
    if isinstance(value, (bool, np.bool_)):
        raise bad
    if kind == "int":
        if isinstance(value, (int, np.integer)):
            v = int(value)
        elif isinstance(value, (float, np.floating)) and float(value).is_integer():
            v = int(value)
        else:
            raise bad
    else:
        if not isinstance(value, (int, float, np.integer, np.floating)):
            raise bad
        v = float(value)
        if not math.isfinite(v):
            raise bad
    if not ok(v):
        raise bad
    return v


def make_scene(name: str, seed: int = 0, **overrides: Any) -> SyntheticScene:
    """Build a built-in synthetic scene.

    Parameters
    ----------
    name : str
        One of :data:`SCENES`.
    seed : int
        Non-negative seed; the same ``(name, seed, overrides)`` always gives the same scene.
    **overrides
        ``n_frames`` (int), ``width``/``height`` (int px; the layout, people's sizes and speeds
        scale with the frame), ``fps`` (float, metadata only), ``noise`` (sensor noise sigma in grey
        levels, default 3.5; 0 = none), ``shadows`` (bool, default False), ``illumination`` (bool,
        default True only in "lighting").

    Raises
    ------
    ConfigError
        Unknown scene name, unknown override or invalid value.
    """
    if name not in _SCENE_TYPES:
        raise ConfigError(f"unknown synthetic scene {name!r}; valid names: {', '.join(SCENES)}")
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigError(f"synthetic scene seed must be a non-negative integer, got {seed!r}")
    unknown = sorted(set(overrides) - set(_OVERRIDES))
    if unknown:
        raise ConfigError(
            f"unknown synthetic scene parameter(s) {', '.join(unknown)}; valid: seed, "
            + ", ".join(_OVERRIDES)
        )
    ov = {k: _coerce(k, v) for k, v in overrides.items()}
    st = _SCENE_TYPES[name]
    width = ov.get("width", 640)
    height = ov.get("height", 480)
    n_frames = ov.get("n_frames", st.n_frames)
    rng = np.random.default_rng([int(seed), 3, _stable_hash(name)])
    ctx = _Ctx(rng=rng, width=width, height=height, n_frames=n_frames, horizon=0.15 * height)
    built = st.build(ctx)
    illumination = ov.get("illumination", built.get("illumination", False))
    return SyntheticScene(
        name=name,
        seed=int(seed),
        width=width,
        height=height,
        fps=ov.get("fps", 25.0),
        n_frames=n_frames,
        people=built["people"],
        bags=built.get("bags", ()),
        scene_file=built.get("scene_file") or _street_layout(ctx),
        column=built.get("column"),
        noise=ov.get("noise", 3.5),
        shadows=ov.get("shadows", False),
        lighting=Lighting.default(n_frames) if illumination else None,
        shadow_side=1.0 if rng.random() < 0.5 else -1.0,
        overrides=ov,
    )


_TRUE = {"true", "1", "yes", "on"}
_FALSE = {"false", "0", "no", "off"}


def parse_synth_spec(spec: str) -> SyntheticScene:
    """Build a scene from a spec string: ``"synth:NAME"`` or ``"synth:NAME?key=value&..."``.

    Keys: ``seed`` and the overrides of :func:`make_scene`. Booleans accept
    ``true/false/1/0/yes/no/on/off``.

    Raises
    ------
    ConfigError
        Missing ``synth:`` prefix, unknown scene or key, repeated key, or a bad value.
    """
    if not isinstance(spec, str) or not spec.startswith("synth:"):
        raise ConfigError(f"a synthetic scene spec must look like 'synth:NAME[?key=value&...]', "
                          f"got {spec!r}")
    body = spec[len("synth:"):]
    name, _, query = body.partition("?")
    name = name.strip()
    if not name:
        raise ConfigError(f"synthetic scene spec {spec!r} has no scene name; valid names: "
                          + ", ".join(SCENES))
    if name not in _SCENE_TYPES:
        raise ConfigError(f"unknown synthetic scene {name!r}; valid names: {', '.join(SCENES)}")
    params = _spec_params(spec, query)
    seed = params.pop("seed", 0)
    return make_scene(name, seed, **params)


def _spec_params(spec: str, query: str) -> dict[str, Any]:
    """``{key: value}`` from the ``key=value&...`` part of ``spec``."""
    params: dict[str, Any] = {}
    for item in query.split("&") if query else []:
        if not item:
            continue
        key, eq, raw = item.partition("=")
        key, raw = key.strip(), raw.strip()
        if not eq or not key or not raw:
            raise ConfigError(f"synthetic scene spec {spec!r}: expected key=value, got {item!r}")
        if key in params:
            raise ConfigError(f"synthetic scene spec {spec!r}: parameter {key} given twice")
        params[key] = _spec_value(key, raw)
    return params


def _spec_value(key: str, raw: str) -> Any:
    """A spec value: ``seed`` an int, booleans from words, other overrides numbers (their
    ranges are checked by :func:`make_scene`)."""
    if key == "seed":
        try:
            return int(raw)
        except ValueError:
            raise ConfigError(f"synthetic scene seed must be a non-negative integer, "
                              f"got {raw!r}") from None
    if key not in _OVERRIDES:
        raise ConfigError(f"unknown synthetic scene parameter {key!r}; valid: seed, "
                          + ", ".join(_OVERRIDES))
    kind, _, what = _OVERRIDES[key]
    if kind == "bool":
        low = raw.lower()
        if low in _TRUE:
            return True
        if low in _FALSE:
            return False
        raise ConfigError(f"synthetic scene parameter {key} must be {what}, got {raw!r}")
    try:
        return float(raw)
    except ValueError:
        raise ConfigError(f"synthetic scene parameter {key} must be {what}, "
                          f"got {raw!r}") from None
