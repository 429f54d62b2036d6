"""Scene analytics over tracks, one frame at a time: :class:`Analytics`.

Each frame's tracks (ids and boxes) go through the rules in a fixed order: tracks unseen for
``forget_s`` are forgotten (they leave their zones and stop being stationary), then line
crossings, zone membership (enter, exit, loiter), stationary stays, speeding, and the rules on
the frame's static objects (:mod:`.objects`): stationary objects and abandoned objects
(:mod:`.abandoned`). Events carry
the frame, its time ``(frame - 1) / fps``, the track's anchor in pixels and, with a camera,
its foot point on the ground plane in metres.
"""

from __future__ import annotations

import logging
from collections import Counter
from typing import Any, Sequence

import numpy as np

from ..calibrate.measure import world_positions
from ..errors import ConfigError
from ..types import EVENT_TYPES, Event, SceneFrame, StaticFrame
from .abandoned import AbandonedRule
from .lines import LineSet
from .movement import REARM, SpeedWindow, Stay
from .objects import BAG_RATIO, StaticObjects, TrackedObject
from .scene import Scene
from .zones import ZoneEdges

log = logging.getLogger(__name__)

__all__ = ["Analytics"]

#: the order of a frame's events for one track (then by line or zone order)
_ORDER = {k: i for i, k in enumerate(("line_cross", "zone_exit", "zone_enter", "loiter",
                                      "stationary_end", "stationary_start", "abandoned",
                                      "speeding"))}


class _TrackState:
    """What the rules remember of one track; its line and zone state is row ``row`` of the
    engine's :class:`_Table`."""

    __slots__ = ("row", "last_frame", "point", "world", "box", "stay", "speed")

    def __init__(self, row: int) -> None:
        self.row = row
        self.last_frame = -1
        self.point = (0.0, 0.0)
        self.box = np.zeros(4)
        self.world: tuple[float, float] | None = None
        self.stay = Stay()
        self.speed = SpeedWindow()


class _Table:
    """The line and zone state of every track, one row per track: a frame's tracks are read
    and written with one fancy index per column instead of a loop over track objects."""

    _COLUMNS = ("side", "touched", "s", "point", "zone_in", "enter_frame", "loitered")

    def __init__(self, n_lines: int, n_zones: int, capacity: int = 16) -> None:
        self.side = np.zeros((capacity, n_lines), dtype=np.int8)
        self.touched = np.zeros((capacity, n_lines), dtype=bool)
        self.s = np.zeros((capacity, n_lines))          # s(p) of each line at the last anchor
        self.point = np.zeros((capacity, 2))            # the last anchor
        self.zone_in = np.zeros((capacity, n_zones), dtype=bool)
        self.enter_frame = np.zeros((capacity, n_zones), dtype=np.int64)
        self.loitered = np.zeros((capacity, n_zones), dtype=bool)
        self.free = list(range(capacity - 1, -1, -1))

    def take(self) -> int:
        """A cleared row for a new track."""
        if not self.free:
            n = len(self.side)
            for name in self._COLUMNS:
                col = getattr(self, name)
                setattr(self, name, np.concatenate([col, np.zeros_like(col)]))
            self.free = list(range(2 * n - 1, n - 1, -1))
        row = self.free.pop()
        for name in self._COLUMNS:
            getattr(self, name)[row] = 0
        return row


#: fraction of the frames since a static object was first seen in which it must have been seen
#: still before it can be stationary
STATIONARY_STILL = 0.4


def _r(v: float, digits: int) -> float:
    return round(float(v), digits)


class Analytics:
    """The rules of a :class:`~.scene.Scene` applied to tracks frame by frame.

    Parameters
    ----------
    scene : Scene
    fps : float
        Frames per second: event times are ``(frame - 1) / fps``.
    camera : optional
        A calibrated camera fitted to the video: events get ground-plane ``X, Y`` (metres) and
        the rules in metres (``radius_m``, ``limit_mps``) work.
    """

    def __init__(self, scene: Scene, fps: float, camera: Any = None) -> None:
        if not (isinstance(fps, (int, float)) and np.isfinite(fps) and fps > 0):
            raise ConfigError(f"analytics needs a frame rate > 0, got fps={fps!r}")
        if scene.needs_camera and camera is None:
            raise ConfigError("the scene measures in metres and needs a camera calibration "
                              "(--camera)")
        self.scene, self.fps, self.camera = scene, float(fps), camera
        self.objects = self.abandoned = None
        if scene.abandoned is not None or scene.stationary is not None:
            self.objects = StaticObjects(self.fps, scene.forget_s * self.fps)
        if scene.abandoned is not None:
            self.abandoned = AbandonedRule(scene.abandoned, self.fps, self.objects,
                                           self._anchors, self._world)
        self._silent: set[int] = set()   # stationary tracks whose place an object reports
        self._warned_static = False
        self.lines = LineSet([ln.a for ln in scene.lines], [ln.b for ln in scene.lines])
        self.edges = ZoneEdges(scene.zones)
        self.table = _Table(self.lines.n, self.edges.n)
        self.loiter_frames = np.array([np.inf if z.loiter_s is None else z.loiter_s * fps
                                       for z in scene.zones])
        self.loiters = bool(np.isfinite(self.loiter_frames).any())
        self.forget_frames = scene.forget_s * fps
        self.tracks: dict[int, _TrackState] = {}
        self.crossings = np.zeros((len(scene.lines), 2), dtype=np.int64)  # in, out
        self.occupancy = np.zeros(len(scene.zones), dtype=np.int64)
        self.last_frame = 0
        self._counts: tuple[dict, dict] | None = None
        # totals for the summary
        self.frames = 0
        self.by_type: Counter[str] = Counter()
        self.enters = np.zeros(len(scene.zones), dtype=np.int64)
        self.exits = np.zeros(len(scene.zones), dtype=np.int64)
        self.dwell_frames = np.zeros(len(scene.zones), dtype=np.int64)
        self.peak = np.zeros(len(scene.zones), dtype=np.int64)
        self.occupancy_sum = np.zeros(len(scene.zones), dtype=np.int64)

    @property
    def wants_static(self) -> bool:
        """Whether the rules need each frame's static objects (``[abandoned]``,
        ``[stationary]``): the pipeline then keeps its dual background
        (:class:`~motiontrack.motion.static.DualBackground`)."""
        return self.objects is not None

    # ------------------------------------------------------------------------------- frames
    def update(self, frame: int, tracks: Sequence[Any],
               static: StaticFrame | None = None) -> list[Event]:
        """The events of frame ``frame`` (1-based) with these tracks (each with ``.id`` and
        ``.box`` ``x, y, w, h``) and the frame's static objects."""
        return list(self.step(frame, [t.id for t in tracks],
                              [(t.box.x, t.box.y, t.box.w, t.box.h) for t in tracks],
                              static).events)

    def step(self, frame: int, ids: Any, boxes: Any,
             static: StaticFrame | None = None) -> SceneFrame:
        """One frame from columns: ``ids`` (N,) int and ``boxes`` (N, 4) ``x, y, w, h``
        pixels, and the frame's static objects (``FrameResult.static``; the ``abandoned`` rule
        needs them). Frames must come in increasing order; a frame without tracks is a step too
        (it is how tracks are forgotten and occupancy averaged)."""
        frame = int(frame)
        if frame < 1 or frame <= self.last_frame:
            raise ValueError(f"analytics frames must be 1-based and increasing: frame {frame} "
                             f"after {self.last_frame}")
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        id_list = ids.tolist()
        if len(set(id_list)) != len(id_list):
            _, first = np.unique(ids, return_index=True)  # a repeated id: its first row counts
            first = np.sort(first)
            ids, boxes = ids[first], boxes[first]
            id_list = ids.tolist()
        events: list[Event] = []
        gone = [] if self.objects is None else self.objects.step(frame, ids, boxes, static)
        self._forget(frame, events)
        points = self._anchors(boxes)
        world = self._world(boxes)
        states = []
        for tid in id_list:
            st = self.tracks.get(tid)
            if st is None:
                st = self.tracks[tid] = _TrackState(self.table.take())
            states.append(st)
        rows = np.fromiter((st.row for st in states), dtype=np.int64, count=len(states))
        known = np.fromiter((st.last_frame > 0 for st in states), dtype=bool, count=len(states))
        self._lines(frame, ids, rows, known, points, world, events)
        self._zones(frame, ids, states, rows, known, points, world, events)
        self._movement(frame, ids, states, boxes, points, world, events)
        if self.scene.stationary is not None and self.objects is not None:
            self._object_stays(frame, ids, boxes, gone, events)
        if self.abandoned is not None:
            self._abandoned(frame, ids, boxes, static, events)
        self.table.point[rows] = points
        for i, st in enumerate(states):
            st.last_frame = frame
            st.point = (float(points[i, 0]), float(points[i, 1]))
            st.box = boxes[i]
            st.world = None if world is None else (float(world[i, 0]), float(world[i, 1]))
        self.last_frame = frame
        self.frames += 1
        np.maximum(self.peak, self.occupancy, out=self.peak)
        self.occupancy_sum += self.occupancy
        if events:
            events.sort(key=lambda e: (e.track, _ORDER[e.type], e.line or "", e.zone or ""))
            self.by_type.update(e.type for e in events)
            self._counts = None
        if self._counts is None:   # the totals change only with events
            self._counts = (self.counts_by_line(), self.occupancy_by_zone())
        return SceneFrame(frame, tuple(events), dict(self._counts[0]), dict(self._counts[1]))

    def finish(self, last_frame: int | None = None) -> list[Event]:
        """Events at the end of the input: none. A track still in a zone or stationary has not
        left; :meth:`summary` reports it as open."""
        return []

    # ------------------------------------------------------------------------------- counts
    def counts_by_line(self) -> dict[str, tuple[int, int]]:
        """Line name → (in, out) crossings so far."""
        return {ln.name: (int(c[0]), int(c[1])) for ln, c in zip(self.scene.lines, self.crossings)}

    def occupancy_by_zone(self) -> dict[str, int]:
        """Zone name → tracks inside now."""
        return {z.name: int(n) for z, n in zip(self.scene.zones, self.occupancy)}

    @property
    def counts(self) -> dict[str, dict]:
        """``{"lines": {name: {"in", "out"}}, "zones": {name: occupancy}}`` now."""
        return {"lines": {k: {"in": i, "out": o} for k, (i, o) in self.counts_by_line().items()},
                "zones": self.occupancy_by_zone()}

    def summary(self) -> dict[str, Any]:
        """Totals for ``summary.json``."""
        zones = {}
        for k, z in enumerate(self.scene.zones):
            zones[z.name] = {
                "enters": int(self.enters[k]), "exits": int(self.exits[k]),
                "inside_at_end": int(self.occupancy[k]), "peak": int(self.peak[k]),
                "mean_occupancy": _r(self.occupancy_sum[k] / max(self.frames, 1), 4),
                "mean_dwell_s": (_r(self.dwell_frames[k] / self.exits[k] / self.fps, 3)
                                 if self.exits[k] else None),
            }
        return {
            "scene": self.scene.source, "fps": self.fps, "frames": self.frames,
            "events": {t: int(self.by_type.get(t, 0)) for t in EVENT_TYPES},
            "lines": self.counts["lines"], "zones": zones,
            "stationary_at_end": (
                sum(1 for t, s in self.tracks.items() if s.stay.stationary and t not in self._silent)
                + sum(1 for o in (self.objects.objects if self.objects else ()) if o.stationary == "open")),
        }

    # -------------------------------------------------------------------------------- rules
    def _anchors(self, boxes: np.ndarray) -> np.ndarray:
        x, y, w, h = boxes.T
        bottom = y + h if self.scene.anchor == "bottom_center" else y + h / 2.0
        return np.column_stack([x + w / 2.0, bottom])

    def _world(self, boxes: np.ndarray) -> np.ndarray | None:
        return None if self.camera is None else world_positions(boxes, self.camera)

    def _event(self, kind: str, frame: int, tid: int, p: tuple[float, float],
               w: tuple[float, float] | None, **fields: Any) -> Event:
        XY = {}
        if w is not None and np.isfinite(w[0]) and np.isfinite(w[1]):
            XY = {"X": _r(w[0], 3), "Y": _r(w[1], 3)}
        return Event(kind, frame, _r((frame - 1) / self.fps, 6), int(tid), _r(p[0], 2),
                     _r(p[1], 2), **XY, **fields)

    def _seconds(self, frames: float) -> float:
        return _r(frames / self.fps, 3)

    def _forget(self, frame: int, events: list[Event]) -> None:
        """Tracks unseen for more than ``forget_s`` have left: they exit their zones and end
        their stationary stay (at their last position). A track id seen again after that is a
        new track."""
        for tid in [t for t, st in self.tracks.items() if frame - st.last_frame > self.forget_frames]:
            st = self.tracks.pop(tid)
            self.table.free.append(st.row)
            enter_frame = self.table.enter_frame[st.row]
            for k in np.flatnonzero(self.table.zone_in[st.row]):
                events.append(self._event("zone_exit", frame, tid, st.point, st.world,
                                          zone=self.scene.zones[k].name,
                                          dwell_s=self._seconds(st.last_frame - enter_frame[k])))
                self._exited(k, st.last_frame - enter_frame[k])
            if st.stay.stationary and not self._handed_over(tid, st) and tid not in self._silent:
                events.append(self._event("stationary_end", frame, tid, st.point, st.world,
                                          duration_s=self._seconds(st.stay.last - st.stay.first)))
            self._silent.discard(tid)

    def _exited(self, k: int, dwell: int) -> None:
        self.occupancy[k] -= 1
        self.exits[k] += 1
        self.dwell_frames[k] += dwell

    def _lines(self, frame, ids, rows, known, points, world, events) -> None:
        if not self.lines.n or not len(ids):
            return
        t = self.table
        crossed, t.side[rows], t.touched[rows], t.s[rows] = self.lines.step(
            t.side[rows], t.touched[rows], t.s[rows], t.point[rows], known, points,
            self.scene.hysteresis_px)
        if not crossed.any():
            return
        for i, j in zip(*np.nonzero(crossed)):
            direction = "in" if crossed[i, j] > 0 else "out"
            self.crossings[j, 0 if direction == "in" else 1] += 1
            events.append(self._event("line_cross", frame, ids[i], points[i], _row(world, i),
                                      line=self.scene.lines[j].name, direction=direction))

    def _zones(self, frame, ids, states, rows, known, points, world, events) -> None:
        if not self.edges.n or not len(ids):
            return
        t = self.table
        was_in = t.zone_in[rows]
        now_in = self.edges.membership(was_in, known, points, self.scene.hysteresis_px)
        for i, k in zip(*np.nonzero(now_in != was_in)):
            r, name = rows[i], self.scene.zones[k].name
            if now_in[i, k]:
                t.enter_frame[r, k], t.loitered[r, k] = frame, False
                self.occupancy[k] += 1
                self.enters[k] += 1
                events.append(self._event("zone_enter", frame, ids[i], points[i], _row(world, i),
                                          zone=name))
            else:
                dwell = frame - t.enter_frame[r, k]
                self._exited(k, dwell)
                events.append(self._event("zone_exit", frame, ids[i], points[i], _row(world, i),
                                          zone=name, dwell_s=self._seconds(dwell)))
            t.zone_in[r, k] = now_in[i, k]
        if not self.loiters:
            return
        enter = t.enter_frame[rows]
        due = now_in & ~t.loitered[rows] & (frame - enter >= self.loiter_frames[None, :] - 1e-9)
        for i, k in zip(*np.nonzero(due)):
            t.loitered[rows[i], k] = True
            events.append(self._event("loiter", frame, ids[i], points[i], _row(world, i),
                                      zone=self.scene.zones[k].name,
                                      dwell_s=self._seconds(frame - enter[i, k])))

    def _movement(self, frame, ids, states, boxes, points, world, events) -> None:
        stat, speed = self.scene.stationary, self.scene.speed
        if stat is not None:
            pos = world if stat.radius_m is not None else points
            radius = stat.radius_m if stat.radius_m is not None else stat.radius_px
            finite = np.isfinite(pos).all(axis=1).tolist()
            for i, st in enumerate(states):
                if not finite[i]:
                    continue
                what, lasted = st.stay.step((pos[i, 0], pos[i, 1]), frame, radius,
                                            stat.after_s * self.fps)
                if what == "start":
                    if self._object_reports(boxes[i]):
                        self._silent.add(int(ids[i]))
                        continue
                    events.append(self._event("stationary_start", frame, ids[i], points[i],
                                              _row(world, i)))
                elif what == "end":
                    if int(ids[i]) in self._silent:
                        self._silent.discard(int(ids[i]))
                        continue
                    events.append(self._event("stationary_end", frame, ids[i], points[i],
                                              _row(world, i), duration_s=self._seconds(lasted)))
        if speed is not None:
            metres = speed.limit_mps is not None
            pos = world if metres else points
            limit = speed.limit_mps if metres else speed.limit_px_s
            finite = np.isfinite(pos).all(axis=1).tolist()
            for i, st in enumerate(states):
                if not finite[i]:
                    continue
                v = st.speed.speed(frame, (pos[i, 0], pos[i, 1]), speed.window_s * self.fps, self.fps)
                if v is None:
                    continue
                if v > limit and not st.speed.speeding:
                    st.speed.speeding = True
                    key = "speed_mps" if metres else "speed_px_s"
                    events.append(self._event("speeding", frame, ids[i], points[i],
                                              _row(world, i), **{key: _r(v, 2)}))
                elif v <= REARM * limit:
                    st.speed.speeding = False


    # ----------------------------------------------------------------- stationary objects
    def _object_stays(self, frame, ids, boxes, gone, events) -> None:
        """``stationary`` of static objects: ``stationary_start`` once an object has been static
        foreground for ``after_s``, if it is seen still in this frame, was followed for a second
        and seen still in 40 % of the frames since (a blob of static pixels that only just formed
        or a person swaying on the spot is not a still object), unless a stationary track covers
        it (that track reports the place); ``stationary_end`` when a reported object is
        forgotten."""
        after = self.scene.stationary.after_s * self.fps
        for o in gone:
            if o.stationary == "open":
                self._object_event(events, "stationary_end", frame, o, duration_s=self._seconds(
                    o.last_seen - o.stay_first))
        for o in self.objects.objects:
            if o.stationary == "track":
                st = self.tracks.get(o.merged)
                if st is not None and st.stay.stationary:
                    continue
                o.stationary = o.merged = None     # the track moved on: the object stays alone
            if (o.stationary is not None or not (o.seen and o.still)
                    or frame - o.since < after - 1e-9 or frame - o.first_seen < self.fps - 1e-9
                    or o.still_seen < STATIONARY_STILL * (frame - o.first_seen + 1)):
                continue
            tid = self._stationary_track_on(o.box)
            if tid is None:
                oid = self.objects.object_id(o, ids, boxes)
                st = self.tracks.get(oid)
                if st is not None and st.stay.stationary and oid not in self._silent:
                    tid = oid
            if tid is not None:
                o.stationary, o.merged = "track", tid
                continue
            o.stationary, o.stay_first = "open", o.since
            self._object_event(events, "stationary_start", frame, o)

    def _object_event(self, events, kind: str, frame: int, o: TrackedObject, **fields: Any) -> None:
        b = o.box[None]
        events.append(self._event(kind, frame, o.oid, self._anchors(b)[0],
                                  _row(self._world(b), 0), **fields))

    def _stationary_track_on(self, box: np.ndarray) -> int | None:
        """A track reporting a stationary stay whose (last) box covers half of ``box``."""
        for tid, st in self.tracks.items():
            if st.stay.stationary and tid not in self._silent and _covers(st.box, box):
                return tid
        return None

    def _object_reports(self, box: np.ndarray) -> bool:
        """Whether a reported stationary object lies at least half in ``box``."""
        return self.objects is not None and any(
            o.stationary == "open" and _covers(box, o.box) for o in self.objects.objects)

    def _handed_over(self, tid: int, st: _TrackState) -> bool:
        """A forgotten stationary track whose place a static object of its size (not a bag it
        left) still holds: the object carries the stay on under the track's id (the tracker
        lost someone standing still)."""
        if self.objects is None or self.scene.stationary is None:
            return False
        for o in self.objects.objects:
            if (o.stationary == "track" and o.merged == tid and o.seen
                    and o.box[3] > BAG_RATIO * st.box[3]):
                o.stationary, o.oid, o.stay_first, o.merged = "open", tid, st.stay.first, None
                return True
        return False

    def _abandoned(self, frame, ids, boxes, static, events) -> None:
        if static is None and not self._warned_static:
            self._warned_static = True
            log.warning("abandoned objects are found in the video's static foreground "
                        "(track --scene); from tracks alone there are no abandoned events")
        for oid, owner, box, static_s in self.abandoned.step(frame, ids, boxes):
            b = box[None]
            w = self._world(b)
            events.append(self._event("abandoned", frame, oid, self._anchors(b)[0],
                                      _row(w, 0), duration_s=_r(static_s, 3), owner=owner))


def _covers(outer: np.ndarray, inner: np.ndarray) -> bool:
    """Whether box ``outer`` covers at least half of box ``inner`` (``x, y, w, h``)."""
    ox = min(outer[0] + outer[2], inner[0] + inner[2]) - max(outer[0], inner[0])
    oy = min(outer[1] + outer[3], inner[1] + inner[3]) - max(outer[1], inner[1])
    return ox > 0 and oy > 0 and ox * oy >= 0.5 * inner[2] * inner[3]


def _row(world: np.ndarray | None, i: int) -> tuple[float, float] | None:
    return None if world is None else (float(world[i, 0]), float(world[i, 1]))
