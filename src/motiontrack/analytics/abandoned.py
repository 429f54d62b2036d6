"""Abandoned objects: a recently stopped object that came from a person who then went away.

The static objects of each frame (:class:`~motiontrack.types.StaticFrame`, from the dual
background of :mod:`motiontrack.motion.static`) are followed from frame to frame by overlap. When
one is first seen, its **owner** is the track whose box (widened by a fifth of its height)
touched it most recently within the last :data:`OWNER_S` seconds, among tracks at least
``1 / BAG_RATIO`` times as tall as the object: the object split from that person. An object
without such a track (something that stopped on its own, a person who stood still) has no owner
and is never abandoned.

The owner is **away** while its anchor is farther from the object's anchor than the scene's
``distance_heights`` times the owner's box height (``distance_m`` on the ground plane with a
camera), and while it is out of sight after it was last seen away: an owner lost from sight
next to the object does not count as away (the track of a person who stops may end there while
the person stays). ``abandoned`` is emitted once per object, in the first frame the owner has
been away for ``after_s`` without a break, if the object is seen, at most :data:`BAG_RATIO` of
the owner's height, and **still**: its ``change`` (mean difference from the short-term
background) below :data:`STILL_LEVELS` in this frame and in :data:`STILL_FRACTION` of the
frames of that time. A bag lies still to the pixel; the visible legs of someone standing behind
an obstacle, which look like an object left by whoever walked past them, shift now and then.

The event's ``track`` is the id of a track lying on the object (the tracker may follow the
object itself) or else a new id from :data:`OBJECT_IDS` up, apart from the tracker's ids;
``duration_s`` is how long the object has been static foreground.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Callable

import numpy as np

from ..types import StaticFrame
from .scene import AbandonedSpec

__all__ = ["AbandonedRule", "OBJECT_IDS", "OWNER_S", "BAG_RATIO"]

#: ids of abandoned objects no track lies on start here, apart from the tracker's
OBJECT_IDS = 1_000_001
#: seconds back in which the owner's box must have touched a newly static object
OWNER_S = 3.0
#: an object may be at most this fraction of its owner's box height (a bag, not a person)
BAG_RATIO = 0.6
#: largest mean difference from the short-term background (levels) of a still object, and the
#: fraction of the owner's time away in which the object must have been seen still
STILL_LEVELS = 6.0
STILL_FRACTION = 0.8
#: overlap (IoU) of a static object with the object of the previous frame that makes them one
_SAME_IOU = 0.3
#: widening of an owner's box, fraction of its height, for touching the object
_TOUCH = 0.2


def _iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of box ``a`` (4,) with each of ``b`` (N, 4), ``x, y, w, h``."""
    if not len(b):
        return np.zeros(0)
    x1 = np.maximum(a[0], b[:, 0])
    y1 = np.maximum(a[1], b[:, 1])
    x2 = np.minimum(a[0] + a[2], b[:, 0] + b[:, 2])
    y2 = np.minimum(a[1] + a[3], b[:, 1] + b[:, 3])
    inter = np.clip(x2 - x1, 0, None) * np.clip(y2 - y1, 0, None)
    return inter / (a[2] * a[3] + b[:, 2] * b[:, 3] - inter)


class _Object:
    __slots__ = ("box", "last_seen", "owner", "owner_h", "away_since", "owner_away", "done",
                 "frames", "still", "still_frames")

    def __init__(self, box: np.ndarray, frame: int, owner: int | None, owner_h: float) -> None:
        self.box = box
        self.last_seen = frame
        self.owner, self.owner_h = owner, owner_h
        self.away_since: int | None = None
        self.owner_away = False    # the owner was away when last seen
        self.done = False
        self.frames = 0
        self.still = False         # seen still in this frame
        self.still_frames = 0      # frames seen still since the owner went away


class AbandonedRule:
    """``abandoned`` events of one scene from each frame's tracks and static objects.

    Parameters
    ----------
    spec : AbandonedSpec
    fps : float
    forget_frames : float
        An object not seen for longer is forgotten (the scene's ``forget_s`` in frames).
    anchors : callable
        ``(N, 4)`` boxes → ``(N, 2)`` anchor points (the scene's anchor).
    world : callable or None
        ``(N, 4)`` boxes → ``(N, 2)`` ground-plane metres (with a camera); needed for
        ``distance_m``.
    """

    def __init__(self, spec: AbandonedSpec, fps: float, forget_frames: float,
                 anchors: Callable[[np.ndarray], np.ndarray],
                 world: Callable[[np.ndarray], np.ndarray | None] | None = None) -> None:
        self.spec, self.fps = spec, float(fps)
        self.forget_frames = forget_frames
        self.after_frames = spec.after_s * self.fps
        self.anchors, self.world = anchors, world
        self.objects: list[_Object] = []
        self.history: deque[tuple[int, np.ndarray, np.ndarray]] = deque()
        self.next_id = OBJECT_IDS

    def step(self, frame: int, ids: np.ndarray, boxes: np.ndarray,
             static: StaticFrame | None) -> list[tuple[int, int, np.ndarray, float]]:
        """One frame: ``(object id, owner id, object box, static seconds)`` of every object
        abandoned in it."""
        self.history.append((frame, ids, boxes))
        while self.history and frame - self.history[0][0] > OWNER_S * self.fps:
            self.history.popleft()
        seen = self._follow(frame, static)
        self.objects = [o for o in self.objects if frame - o.last_seen <= self.forget_frames]
        out = []
        for o in self.objects:
            if o.owner is None or o.done:
                continue
            self._away(o, frame, ids, boxes)
            still = id(o) in seen and o.still
            if o.away_since is None:
                o.still_frames = 0
                continue
            o.still_frames += still
            away = frame - o.away_since
            if (away >= self.after_frames - 1e-9 and still and o.box[3] <= BAG_RATIO * o.owner_h
                    and o.still_frames >= STILL_FRACTION * (away + 1)):
                o.done = True
                out.append((self._object_id(o, ids, boxes), o.owner, o.box.copy(),
                            o.frames / self.fps))
        return out

    # ---------------------------------------------------------------------------- helpers
    def _follow(self, frame: int, static: StaticFrame | None) -> set[int]:
        """Match this frame's static objects to the known ones; new ones get their owner.
        Returns the ``id()`` of the known objects seen in this frame."""
        seen: set[int] = set()
        if static is None or not static.objects:
            return seen
        known = np.array([o.box for o in self.objects]).reshape(-1, 4)
        for so in sorted(static.objects, key=lambda s: -s.area):
            box = so.box.as_array()
            iou = _iou(box, known)
            free = np.array([id(o) not in seen for o in self.objects], bool)
            iou = np.where(free, iou, 0.0) if len(iou) else iou
            if len(iou) and iou.max() >= _SAME_IOU:
                o = self.objects[int(iou.argmax())]
            else:
                owner, owner_h = self._owner(box)
                o = _Object(box, frame, owner, owner_h)
                self.objects.append(o)
                known = np.vstack([known, box[None]])
            o.box, o.last_seen, o.frames = box, frame, so.frames
            o.still = so.change < STILL_LEVELS
            seen.add(id(o))
        return seen

    def _owner(self, box: np.ndarray) -> tuple[int | None, float]:
        """The track that touched ``box`` most recently (largest overlap among those of that
        frame), at least ``1 / BAG_RATIO`` times as tall; ``(None, 0)`` when none did."""
        for _, ids, boxes in reversed(self.history):
            if not len(ids):
                continue
            tall = boxes[:, 3] * BAG_RATIO >= box[3]
            m = _TOUCH * boxes[:, 3]
            ox = (np.minimum(box[0] + box[2], boxes[:, 0] + boxes[:, 2] + m)
                  - np.maximum(box[0], boxes[:, 0] - m))
            oy = (np.minimum(box[1] + box[3], boxes[:, 1] + boxes[:, 3] + m)
                  - np.maximum(box[1], boxes[:, 1] - m))
            touch = tall & (ox > 0) & (oy > 0)
            if touch.any():
                k = int(np.argmax(np.where(touch, np.clip(ox, 0, None) * np.clip(oy, 0, None), -1)))
                return int(ids[k]), float(boxes[k, 3])
        return None, 0.0

    def _away(self, o: _Object, frame: int, ids: np.ndarray, boxes: np.ndarray) -> None:
        """Update whether the owner of ``o`` is away, and since when."""
        k = np.flatnonzero(ids == o.owner)
        if len(k):
            ob = boxes[k[:1]]
            o.owner_h = float(ob[0, 3])
            pair = np.vstack([ob, o.box[None]])
            if self.spec.distance_m is not None:
                w = self.world(pair)
                d = math.hypot(*(w[0] - w[1]))
                # an owner whose feet are above the horizon cannot be placed: not away
                o.owner_away = bool(np.isfinite(d) and d > self.spec.distance_m)
            else:
                p = self.anchors(pair)
                d = math.hypot(*(p[0] - p[1]))
                o.owner_away = d > self.spec.distance_heights * o.owner_h
        # out of sight: away only if it was away when last seen
        if o.owner_away:
            if o.away_since is None:
                o.away_since = frame
        else:
            o.away_since = None

    def _object_id(self, o: _Object, ids: np.ndarray, boxes: np.ndarray) -> int:
        """A track lying on the object (not its owner), else a new object id."""
        if len(ids):
            iou = _iou(o.box, boxes)
            iou[ids == o.owner] = 0.0
            if iou.max() >= _SAME_IOU:
                return int(ids[int(iou.argmax())])
        self.next_id += 1
        return self.next_id - 1
