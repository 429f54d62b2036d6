"""Static objects followed from frame to frame, for the rules that use them (``abandoned``,
``stationary``).

The static objects of each frame (:class:`~motiontrack.types.StaticFrame`, from the dual
background of :mod:`motiontrack.motion.static`) are matched to the known ones by overlap
(IoU >= :data:`SAME_IOU`); one unseen for ``forget_s`` is forgotten. A new object gets the frame
it became static foreground (its first frame minus its frames of evidence) and its **owner**:
the track whose box, widened by a fifth of its height, touched it most recently within the last
:data:`OWNER_S` seconds, among tracks at least ``1 / BAG_RATIO`` times as tall as the object
(the person it split from). An object is **still** in a frame where its ``change`` (mean
difference from the short-term background) is below :data:`STILL_LEVELS`: a bag lies still to
the pixel, the legs of someone standing behind an obstacle shift now and then.

An object **continues a track** when a track other than its owner lay on it (IoU >=
``SAME_IOU``) within the last :data:`OWNER_S` seconds when it appeared, or in a frame since: the
track that stopped there and that the tracker then lost (a bag tracked for a moment after it was
set down, a person the tracker lost standing still). It keeps that track's id and class
(:attr:`TrackedObject.origin`, :attr:`TrackedObject.origin_label`).

An object has one event id for all rules: the track it continues, else the id of a track lying
on it (IoU >= ``SAME_IOU``, not its owner) when a rule first needs one, else a new id from
:data:`OBJECT_IDS` up, apart from the tracker's ids.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from ..types import StaticFrame

__all__ = ["StaticObjects", "TrackedObject", "OBJECT_IDS", "OWNER_S", "BAG_RATIO",
           "STILL_LEVELS", "SAME_IOU", "box_iou"]

#: ids of objects no track lies on start here, apart from the tracker's
OBJECT_IDS = 1_000_001
#: seconds back in which the owner's box must have touched a newly static object
OWNER_S = 3.0
#: an object may be at most this fraction of its owner's box height (a bag, not a person)
BAG_RATIO = 0.6
#: largest mean difference from the short-term background (levels) of a still object
STILL_LEVELS = 6.0
#: overlap (IoU) of a static object with the object of the previous frame that makes them one
SAME_IOU = 0.3
#: widening of an owner's box, fraction of its height, for touching the object
_TOUCH = 0.2


def box_iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of box ``a`` (4,) with each of ``b`` (N, 4), ``x, y, w, h``."""
    if not len(b):
        return np.zeros(0)
    x1 = np.maximum(a[0], b[:, 0])
    y1 = np.maximum(a[1], b[:, 1])
    x2 = np.minimum(a[0] + a[2], b[:, 0] + b[:, 2])
    y2 = np.minimum(a[1] + a[3], b[:, 1] + b[:, 3])
    inter = np.clip(x2 - x1, 0, None) * np.clip(y2 - y1, 0, None)
    return inter / (a[2] * a[3] + b[:, 2] * b[:, 3] - inter)


def _lying_on(o: "TrackedObject", ids: np.ndarray, boxes: np.ndarray) -> int | None:
    """The row of the track other than ``o``'s owner that overlaps ``o`` most, when that
    overlap is at least :data:`SAME_IOU` (a track lying on it); else None."""
    if not len(ids):
        return None
    iou = box_iou(o.box, boxes)
    iou[ids == o.owner] = 0.0
    k = int(iou.argmax())
    return k if iou[k] >= SAME_IOU else None


class TrackedObject:
    """One static object as the rules see it."""

    __slots__ = ("box", "first_seen", "last_seen", "since", "frames", "seen", "still",
                 "still_seen", "owner", "owner_h",
                 "oid", "away_since", "owner_away", "done", "still_frames", "stationary",
                 "stay_first", "merged", "origin", "origin_label")

    def __init__(self, box: np.ndarray, frame: int, evidence: int, owner: int | None,
                 owner_h: float) -> None:
        self.box = box
        self.first_seen = self.last_seen = frame
        self.still_seen = 0        # frames seen still since first seen
        self.since = frame - max(int(evidence), 1) + 1   # first frame of static foreground
        self.frames = evidence
        self.seen = False          # seen in this frame
        self.still = False         # seen still in this frame
        self.owner, self.owner_h = owner, owner_h
        self.oid: int | None = None
        # abandoned
        self.away_since: int | None = None
        self.owner_away = False    # the owner was away when last seen
        self.done = False
        self.still_frames = 0      # frames seen still since the owner went away
        # stationary: "open" once reported, "track" while a stationary track reports its place
        self.stationary: str | None = None
        self.stay_first = self.since
        self.merged: int | None = None   # the stationary track reporting this place
        #: the track it continues (a track other than its owner that lay on it), and its class
        self.origin: int | None = None
        self.origin_label = ""


class StaticObjects:
    """The static objects of a scene, followed from frame to frame.

    Parameters
    ----------
    fps : float
    forget_frames : float
        An object not seen for longer is forgotten (the scene's ``forget_s`` in frames).
    """

    def __init__(self, fps: float, forget_frames: float) -> None:
        self.fps, self.forget_frames = float(fps), forget_frames
        self.objects: list[TrackedObject] = []
        self.history: deque[tuple[int, np.ndarray, np.ndarray, np.ndarray | None]] = deque()
        self.next_id = OBJECT_IDS

    def step(self, frame: int, ids: np.ndarray, boxes: np.ndarray,
             static: StaticFrame | None, labels: np.ndarray | None = None
             ) -> list[TrackedObject]:
        """Follow this frame's static objects (``labels``: the tracks' classes, when they were
        classified); returns the objects forgotten in it."""
        self.history.append((frame, ids, boxes, labels))
        while self.history and frame - self.history[0][0] > OWNER_S * self.fps:
            self.history.popleft()
        for o in self.objects:
            o.seen = o.still = False
        self._follow(frame, static)
        for o in self.objects:
            if o.origin is None and o.seen:
                self._find_origin(o, self.history if o.first_seen == frame
                                  else (self.history[-1],))
        gone = [o for o in self.objects if frame - o.last_seen > self.forget_frames]
        if gone:
            self.objects = [o for o in self.objects if frame - o.last_seen <= self.forget_frames]
        return gone

    def reset(self) -> None:
        """Forget every object and the tracks' history (object ids keep counting)."""
        self.objects = []
        self.history.clear()

    def object_id(self, o: TrackedObject, ids: np.ndarray, boxes: np.ndarray) -> int:
        """The object's event id, fixed the first time it is asked for: a track lying on the
        object (not its owner), else a new object id."""
        if o.oid is None:
            o.oid = o.origin
        if o.oid is None:
            k = _lying_on(o, ids, boxes)
            if k is not None:
                o.oid = int(ids[k])
            else:
                o.oid = self.next_id
                self.next_id += 1
        return o.oid

    def _follow(self, frame: int, static: StaticFrame | None) -> None:
        if static is None or not static.objects:
            return
        known = np.array([o.box for o in self.objects]).reshape(-1, 4)
        taken: set[int] = set()
        for so in sorted(static.objects, key=lambda s: -s.area):
            box = so.box.as_array()
            iou = box_iou(box, known)
            free = np.array([id(o) not in taken for o in self.objects], bool)
            iou = np.where(free, iou, 0.0) if len(iou) else iou
            if len(iou) and iou.max() >= SAME_IOU:
                o = self.objects[int(iou.argmax())]
            else:
                o = TrackedObject(box, frame, so.frames, *self._owner(box))
                self.objects.append(o)
                known = np.vstack([known, box[None]])
            o.box, o.last_seen, o.frames = box, frame, so.frames
            o.seen, o.still = True, so.change < STILL_LEVELS
            o.still_seen += o.still
            taken.add(id(o))

    def _find_origin(self, o: TrackedObject, frames) -> None:
        """The track ``o`` continues: the latest of ``frames`` (``(frame, ids, boxes, labels)``)
        with a track other than its owner lying on it, the one overlapping it most."""
        for _, ids, boxes, labels in reversed(frames):
            k = _lying_on(o, ids, boxes)
            if k is not None:
                o.origin = int(ids[k])
                o.origin_label = "" if labels is None else str(labels[k] or "")
                return

    def _owner(self, box: np.ndarray) -> tuple[int | None, float]:
        """The track that touched ``box`` most recently (largest overlap among those of that
        frame), at least ``1 / BAG_RATIO`` times as tall; ``(None, 0)`` when none did."""
        for _, ids, boxes, _ in reversed(self.history):
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
