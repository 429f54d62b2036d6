"""Bridging motion-detection misses with single-object trackers.

When a confirmed track is not matched — the person stopped and faded into the background model,
or the mask broke up — a single-object tracker (:mod:`motiontrack.tracking.single`, e.g. KCF) is
started on the track's last reported box in the previous frame. While motion detection does not
find the track, the single-object tracker's box is offered to the multi-object tracker as a
measurement that belongs to that track. The bridge ends when motion detection finds the track
again, when the single-object tracker reports a failure, when its box reaches the image border
(the object is leaving the view), or after ``max_frames`` frames. Only
tracks that have travelled at least one body height are bridged, so a ghost (a static blob that
never moved) is not kept alive.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..types import Box, TrackState
from .single import SINGLE_TRACKERS, SingleTracker, clip_box
from .tracker import TrackView

__all__ = ["Bridge"]


@dataclass
class _Carried:
    sot: SingleTracker
    frames: int = 0


def _at_border(box: Box, w: int, h: int, margin: float = 2.0) -> bool:
    """Whether ``box`` reaches the image border: an object there is leaving the view, and a
    single-object tracker would stay on the background it leaves behind."""
    return (box.x <= margin or box.y <= margin or box.x2 >= w - margin
            or box.y2 >= h - margin)


class Bridge:
    """One single-object tracker per confirmed track that motion detection lost.

    Parameters
    ----------
    method : name in :data:`SINGLE_TRACKERS` (``"kcf"``, ``"csrt"``, ...).
    max_frames : frames a track may be carried by its single-object tracker.
    """

    def __init__(self, method: str, max_frames: int) -> None:
        SINGLE_TRACKERS.get(method)  # an unknown name fails before any frame
        self.method = method
        self.max_frames = max_frames
        self._carried: dict[int, _Carried] = {}        # track id -> its single-object tracker
        # track id -> (frame, box) where motion detection last reported it
        self._last_seen: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._spent: set[int] = set()   # bridged once; not again until detection finds them

    def measurements(self, tracks: Sequence[TrackView], image: np.ndarray) -> dict[int, np.ndarray]:
        """Boxes ``(x, y, w, h)`` for this frame keyed by the id of the track they belong to;
        ``tracks`` are the tracker's :meth:`~motiontrack.tracking.tracker.MultiObjectTracker.views`
        before this frame's update."""
        h, w = image.shape[:2]
        out: dict[int, np.ndarray] = {}
        alive: set[int] = set()
        for m in tracks:
            alive.add(m.id)
            carried = self._carried.get(m.id)
            if m.time_since_update == 0 and not m.bridged:             # motion detection has it
                self._carried.pop(m.id, None)
                self._spent.discard(m.id)
                continue
            if carried is None:
                if m.state != TrackState.LOST or not m.moved or m.id in self._spent:
                    continue
                seen = self._last_seen.get(m.id)
                start = None if seen is None else clip_box(Box(*map(float, seen[1])), w, h)
                if start is None or start.w < 4 or start.h < 4 or _at_border(start, w, h):
                    continue
                carried = _Carried(SINGLE_TRACKERS.create(self.method))
                carried.sot.init(seen[0], start)
                self._carried[m.id] = carried
            ok, box, _score = carried.sot.update(image)
            carried.frames += 1
            if (not ok or box is None or carried.frames > self.max_frames
                    or _at_border(box, w, h)):
                del self._carried[m.id]
                self._spent.add(m.id)
                continue
            out[m.id] = box.as_array()
        for store in (self._carried, self._last_seen):
            for tid in [t for t in store if t not in alive]:
                del store[tid]
        self._spent &= alive
        return out

    def remember(self, image: np.ndarray, tracks) -> None:
        """Note where motion detection reported each track in this frame (a bridge starts from
        the frame and box where its track was last seen)."""
        for t in tracks:
            if t.time_since_update == 0 and t.id not in self._carried:
                self._last_seen[t.id] = (image, t.box.as_array())
