"""A synthetic surveillance sequence with exact ground truth: :class:`SyntheticScene`.

A :class:`SyntheticScene` is a frozen description (size, people, column, noise, lighting) plus
lazily built caches (background, noise pool, ground truth). Frames are rendered on demand and
are a pure function of ``(scene parameters, seed, frame index)``: random access, bit-identical
across calls and processes. The built-in scenes that make them are :mod:`motiontrack.synth.scenes`.
"""

from __future__ import annotations

import copy
import logging
import zlib
from dataclasses import dataclass, field
from typing import Any, Mapping, NamedTuple

import cv2
import numpy as np

from ..types import Annotations, Event
from .catalogue import SCENE_TYPES
from .events import ground_truth_events, scene_toml
from .vehicles import Vehicle, render_vehicle
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

__all__ = ["Lighting", "MASK_PERSON", "MASK_SHADOW", "SyntheticScene", "stable_hash"]

log = logging.getLogger(__name__)

#: Labels in :meth:`SyntheticScene.foreground_mask` (CDnet 2014 convention).
MASK_PERSON = 255
MASK_SHADOW = 50

_SHADOW_GAIN = 0.58  # shadowed ground keeps 58 % of its brightness


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


def stable_hash(text: str) -> int:
    """A hash of ``text`` that is the same in every process (``hash()`` of a str is not)."""
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
    vehicles : tuple of Vehicle
        Cars driving through (ids after the people's and bags'; ground-truth class 3).
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
    vehicles: tuple[Vehicle, ...] = ()
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
        all_ids = ids + [b.id for b in self.bags] + [v.id for v in self.vehicles]
        if len(set(all_ids)) != len(all_ids):
            raise ValueError(f"person, bag and vehicle ids must be unique, got {all_ids}")

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
        st = SCENE_TYPES.get(self.name)
        return st.summary if st is not None else f"custom scene with {len(self.people)} people"

    def _check_index(self, i: int) -> int:
        if isinstance(i, (bool, np.bool_)) or not isinstance(i, (int, np.integer)):
            raise TypeError(f"frame index must be an integer, got {type(i).__name__}")
        i = int(i)
        if not 0 <= i < self.n_frames:
            raise IndexError(f"frame index must be in [0, {self.n_frames - 1}], got {i}")
        return i

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
            # MOTChallenge classes: 1 pedestrian (people, and bags as before), 3 car
            classes=np.where(np.isin(ids_a[order], [v.id for v in self.vehicles]), 3, 1),
            visibility=vis_a,
            # the scene's frames are all annotated, those without anyone in view too
            meta={"format": "synth", "kind": "gt", "source": self.spec,
                  "seq_length": self.n_frames},
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
        for v in self.vehicles:
            items.append((v.y0, _Item(v.id, v.palette(), render_vehicle(v, i))))
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

    def object_classes(self) -> dict[int, str]:
        """Each ground-truth id's class: ``person``, ``vehicle`` or ``other`` (a bag)."""
        return {**{p.id: "person" for p in self.people}, **{b.id: "other" for b in self.bags},
                **{v.id: "vehicle" for v in self.vehicles}}

    # ------------------------------------------------------------ analytics
    def ground_truth_events(self) -> list[Event]:
        """The exact scene-analytics events of :attr:`scene_file` on the ground truth (see
        :func:`motiontrack.synth.events.ground_truth_events`); empty without a scene file.

        The result is cached (a new list each call).
        """
        ev = self._cache.get("events")
        if ev is None:
            ev = [] if self.scene_file is None else ground_truth_events(
                self.scene_file, self.ground_truth(), self.fps, {b.id: b.owner for b in self.bags},
                self.object_classes())
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
        if self.vehicles:
            out["vehicles"] = [{"id": v.id, "length_px": round(v.length, 1),
                                "height_px": round(v.height, 1),
                                "speed_px_per_frame": round(abs(v.vx), 2),
                                "direction": "left to right" if v.vx >= 0 else "right to left"}
                               for v in self.vehicles]
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
