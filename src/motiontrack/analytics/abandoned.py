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

The event's ``track`` is the object's id (:mod:`.objects`: a track lying on the object, or a
new id from :data:`OBJECT_IDS` up, the same as its ``stationary`` events);
``duration_s`` is how long the object has been static foreground.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .objects import BAG_RATIO, OBJECT_IDS, OWNER_S, STILL_LEVELS, StaticObjects, TrackedObject
from .specs import AbandonedSpec

__all__ = ["AbandonedRule", "OBJECT_IDS", "OWNER_S", "BAG_RATIO", "STILL_LEVELS"]

#: the fraction of the owner's time away in which the object must have been seen still
STILL_FRACTION = 0.8


class AbandonedRule:
    """``abandoned`` events of one scene from each frame's tracks and static objects.

    Parameters
    ----------
    spec : AbandonedSpec
    fps : float
    objects : StaticObjects
        The scene's static objects, stepped by the caller before :meth:`step` each frame.
    anchors : callable
        ``(N, 4)`` boxes → ``(N, 2)`` anchor points (the scene's anchor).
    world : callable or None
        ``(N, 4)`` boxes → ``(N, 2)`` ground-plane metres (with a camera); needed for
        ``distance_m``.
    """

    def __init__(self, spec: AbandonedSpec, fps: float, objects: StaticObjects,
                 anchors: Callable[[np.ndarray], np.ndarray],
                 world: Callable[[np.ndarray], np.ndarray | None] | None = None) -> None:
        self.spec, self.fps = spec, float(fps)
        self.objects = objects
        self.after_frames = spec.after_s * self.fps
        self.anchors, self.world = anchors, world

    def step(self, frame: int, ids: np.ndarray,
             boxes: np.ndarray) -> list[tuple[int, int, np.ndarray, float]]:
        """One frame: ``(object id, owner id, object box, static seconds)`` of every object
        abandoned in it."""
        out = []
        for o in self.objects.objects:
            if o.owner is None or o.done:
                continue
            self._away(o, frame, ids, boxes)
            still = o.seen and o.still
            if o.away_since is None:
                o.still_frames = 0
                continue
            o.still_frames += still
            away = frame - o.away_since
            if (away >= self.after_frames - 1e-9 and still and o.box[3] <= BAG_RATIO * o.owner_h
                    and o.still_frames >= STILL_FRACTION * (away + 1)):
                o.done = True
                out.append((self.objects.object_id(o, ids, boxes), o.owner, o.box.copy(),
                            o.frames / self.fps))
        return out

    def _away(self, o: TrackedObject, frame: int, ids: np.ndarray, boxes: np.ndarray) -> None:
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
