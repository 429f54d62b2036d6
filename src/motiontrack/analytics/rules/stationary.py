"""``[stationary]``: tracks whose smoothed position (:mod:`..smoothing`) stays within a radius
for ``after_s`` (``stationary_start``) until it leaves ``release`` radii (``stationary_end``),
and, with the video's static foreground (``track --scene``), static objects that continue a
track the tracker lost once it stopped (:attr:`..objects.TrackedObject.origin`: under that
track's id and class). A static object that continues no track (a change of the background
nobody was seen to bring) raises no alarm.

A place is reported once: an object half covered by a stationary track is that track's stay
(a track becoming stationary on a reported object reports nothing), and a lost stationary
track whose place a static object of its size still holds hands its stay to the object.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ...types import Event
from ..movement import Stay
from ..objects import BAG_RATIO, TrackedObject
from ..rule import RULES, BaseRule, EventType, FrameTable, RuleContext, TrackMemory
from ..specs import StationarySpec, checked_classes

__all__ = ["Stationary", "STATIONARY_STILL"]

#: fraction of the frames since a static object was first seen in which it must have been seen
#: still before it can be stationary
STATIONARY_STILL = 0.4


def covers(outer: np.ndarray, inner: np.ndarray) -> bool:
    """Whether box ``outer`` covers at least half of box ``inner`` (``x, y, w, h``)."""
    ox = min(outer[0] + outer[2], inner[0] + inner[2]) - max(outer[0], inner[0])
    oy = min(outer[1] + outer[3], inner[1] + inner[3]) - max(outer[1], inner[1])
    return ox > 0 and oy > 0 and ox * oy >= 0.5 * inner[2] * inner[3]


@RULES.register
class Stationary(BaseRule):
    """Tracks and static objects that stay in one place."""

    name = section = "stationary"
    events = (
        EventType("stationary_start", meaning="the track (or static object) has stayed "
                                              "within the radius for `after_s`"),
        EventType("stationary_end", ("duration_s",),
                  meaning="the stay ended (or the track was forgotten), `duration_s` from its "
                          "first to its last frame"),
    )
    frame_order = ("stationary_end", "stationary_start")
    schema, exactly_one = StationarySpec, (("radius_px", "radius_m"),)
    uses_static = True

    @classmethod
    def camera_key(cls, spec: StationarySpec) -> str | None:
        return "stationary.radius_m" if spec.radius_m is not None else None

    @classmethod
    def idle_summary(cls) -> dict[str, Any]:
        return {"stationary_at_end": 0}

    @classmethod
    def build(cls, table: StationarySpec, camera: Any, where: str,
              earlier: tuple = ()) -> StationarySpec:
        return replace(table, classes=checked_classes(table.classes, where))

    def __init__(self, spec: StationarySpec, context: RuleContext) -> None:
        super().__init__(spec, context)
        self.smooths = ("m",) if spec.radius_m is not None else ("px",)
        self.objects = context.objects
        self.stays: dict[int, Stay] = {}   # every live track's stay, in the engine's order
        self.silent: set[int] = set()      # stationary tracks whose place an object reports

    def forget(self, frame: int, tid: int, state: TrackMemory) -> list[Event]:
        """A forgotten track ends its stay at its last position, unless a static object takes
        the stay over or already reports the place."""
        stay = self.stays.pop(tid, None)
        events = []
        if stay is not None and stay.stationary and not self._handed_over(tid, state, stay) and tid not in self.silent:
            events.append(self.context.last_event(
                "stationary_end", frame, tid, state,
                duration_s=self.context.seconds(stay.last - stay.first)))
        self.silent.discard(tid)
        return events

    def reset(self) -> None:
        """Every stay is dropped without ``stationary_end`` (the engine drops the static
        objects)."""
        self.stays.clear()
        self.silent.clear()

    def step(self, frame: FrameTable) -> list[Event]:
        events: list[Event] = []
        self._track_stays(frame, events)
        if self.objects is not None:
            self._object_stays(frame, events)
        return events

    def _track_stays(self, frame: FrameTable, events: list[Event]) -> None:
        spec, f = self.spec, frame.frame
        pos = frame.smoothed[self.smooths[0]].position
        radius = spec.radius_m if spec.radius_m is not None else spec.radius_px
        stays = [self.stays.setdefault(int(tid), Stay()) for tid in frame.ids.tolist()]
        # a track of a class the rule does not name never stays (``classes``)
        finite = (np.isfinite(pos).all(axis=1) & frame.of_classes(spec.classes)).tolist()
        for i, stay in enumerate(stays):
            if not finite[i]:
                continue
            what, lasted = stay.step((pos[i, 0], pos[i, 1]), f, radius,
                                     spec.after_s * self.context.fps, spec.release,
                                     spec.leave_s * self.context.fps)
            tid = int(frame.ids[i])
            if what == "start":
                if self._object_reports(frame.boxes[i]):
                    self.silent.add(tid)
                    continue
                events.append(frame.event("stationary_start", i))
            elif what == "end":
                if tid in self.silent:
                    self.silent.discard(tid)
                    continue
                events.append(frame.event("stationary_end", i,
                                          duration_s=self.context.seconds(lasted)))

    def _object_stays(self, frame: FrameTable, events: list[Event]) -> None:
        """``stationary`` of static objects that continue a track: ``stationary_start`` once an
        object has been static foreground for ``after_s``, if it is seen still in this frame,
        was followed for a second and seen still in 40 % of the frames since (a blob of static
        pixels that only just formed or a person swaying on the spot is not a still object),
        unless a stationary track covers it (that track reports the place); ``stationary_end``
        when a reported object is forgotten. Events carry the continued track's class."""
        ctx, f = self.context, frame.frame
        after = self.spec.after_s * ctx.fps
        classes = self.spec.classes
        for o in frame.gone:
            if o.stationary == "open":
                events.append(ctx.box_event("stationary_end", f, o.oid, o.box,
                                            duration_s=ctx.seconds(o.last_seen - o.stay_first),
                                            **_label(o)))
        for o in self.objects.objects:
            if o.stationary == "track":
                stay = self.stays.get(o.merged)
                if stay is not None and stay.stationary:
                    continue
                o.stationary = o.merged = None     # the track moved on: the object stays alone
            if (o.stationary is not None or o.origin is None or not (o.seen and o.still)
                    or f - o.since < after - 1e-9 or f - o.first_seen < ctx.fps - 1e-9
                    or o.still_seen < STATIONARY_STILL * (f - o.first_seen + 1)
                    or (classes is not None and (o.origin_label or "other") not in classes)):
                continue
            tid = self._reporting_track(o, frame)
            if tid is not None:
                o.stationary, o.merged = "track", tid
                continue
            o.stationary, o.stay_first = "open", o.since
            events.append(ctx.box_event("stationary_start", f, o.oid, o.box, **_label(o)))

    def _reporting_track(self, o: TrackedObject, frame: FrameTable) -> int | None:
        """The stationary track that reports the place of ``o``: one covering it, else the
        one lying on it (the object's event id); None when none does. Fixes the object's id."""
        tid = self._stationary_track_on(o.box)
        if tid is None:
            oid = self.objects.object_id(o, frame.ids, frame.boxes)
            stay = self.stays.get(oid)
            if stay is not None and stay.stationary and oid not in self.silent:
                tid = oid
        return tid

    def _stationary_track_on(self, box: np.ndarray) -> int | None:
        """A track reporting a stationary stay whose (last) box covers half of ``box``."""
        tracks = self.context.tracks
        for tid, stay in self.stays.items():
            if stay.stationary and tid not in self.silent and covers(tracks[tid].box, box):
                return tid
        return None

    def _object_reports(self, box: np.ndarray) -> bool:
        """Whether a reported stationary object lies at least half in ``box``."""
        return self.objects is not None and any(
            o.stationary == "open" and covers(box, o.box) for o in self.objects.objects)

    def _handed_over(self, tid: int, state: TrackMemory, stay: Stay) -> bool:
        """A forgotten stationary track whose place a static object of its size (not a bag it
        left) still holds: the object carries the stay on under the track's id (the tracker
        lost someone standing still)."""
        if self.objects is None:
            return False
        for o in self.objects.objects:
            if (o.stationary == "track" and o.merged == tid and o.seen
                    and o.box[3] > BAG_RATIO * state.box[3]):
                o.stationary, o.oid, o.stay_first, o.merged = "open", tid, stay.first, None
                return True
        return False

    def summary(self) -> dict[str, Any]:
        objects = self.objects.objects if self.objects is not None else ()
        return {"stationary_at_end": (
            sum(1 for t, s in self.stays.items() if s.stationary and t not in self.silent)
            + sum(1 for o in objects if o.stationary == "open"))}


def _label(o: TrackedObject) -> dict[str, str]:
    """The ``label`` field of an object's events: the class of the track it continues."""
    return {"label": o.origin_label} if o.origin_label else {}
