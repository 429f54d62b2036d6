"""Scene analytics over tracks, one frame at a time: :class:`Analytics`.

The engine keeps what every rule shares and runs the rules (:data:`.rule.RULES`) whose table
the scene has, in the order they were registered. Each frame: the static objects are followed
(when a rule uses them, :mod:`.objects`), tracks unseen for ``forget_s`` are forgotten (each
rule's :meth:`~.rule.Rule.forget`: they leave their zones and stop being stationary), the
frame's table is built (anchors, ground positions, each track's row and its previous anchor:
:class:`~.rule.FrameTable`), every rule steps on it, and the frame's events are ordered by
track, then by rule and type (:meth:`.rule.RuleRegistry.event_order`), then by line or zone.
The built-in rules: line crossings, zone membership (enter, exit, loiter), stationary stays,
abandoned objects, speeding (:mod:`.rules`). A frame marked with a
:class:`~motiontrack.types.Discontinuity` (the source looped, reconnected or was positioned at
a start frame) first drops every track's state (:meth:`Analytics.reset`: stays, zone occupants,
static objects; totals and counts stay), without events, and its ``SceneFrame`` carries the
mark for the event stream. Events carry the frame, its time
``(frame - 1) / fps``, the track's anchor in pixels and, with a camera, its foot point on the
ground plane in metres.
"""

from __future__ import annotations

from collections import Counter
from typing import Any, Sequence

import numpy as np

from ..calibrate.measure import world_positions
from ..errors import ConfigError
from ..types import Discontinuity, Event, SceneFrame, StaticFrame
from .objects import StaticObjects
from .rule import FrameTable, Rule, RuleContext, TrackMemory
from .rules import RULES
from .scene import Scene
from .smoothing import Smoother, jacobians

__all__ = ["Analytics"]


class _Rows:
    """Each track's row in the rules' per-track columns, and the anchor it was last seen at:
    a frame's tracks are read and written with one fancy index per column."""

    def __init__(self, capacity: int = 16) -> None:
        self.point = np.zeros((capacity, 2))   # the last anchor
        self.free = list(range(capacity - 1, -1, -1))

    def take(self) -> int:
        """A cleared row for a new track."""
        if not self.free:
            n = len(self.point)
            self.point = np.concatenate([self.point, np.zeros_like(self.point)])
            self.free = list(range(2 * n - 1, n - 1, -1))
        row = self.free.pop()
        self.point[row] = 0
        return row


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
        active = [(r, scene.spec(r.section)) for r in RULES.ordered()]
        active = [(r, spec) for r, spec in active if spec is not None]
        self.objects = None
        if any(r.uses_static for r, _ in active):
            self.objects = StaticObjects(self.fps, scene.forget_s * self.fps)
        self.tracks: dict[int, TrackMemory] = {}
        self.context = RuleContext(
            self.fps, scene.anchor, scene.hysteresis_px, scene.forget_s * self.fps, camera,
            self.objects, self.tracks,
            None if camera is None else (lambda boxes: world_positions(boxes, camera)))
        self.rules: dict[str, Rule] = {r.name: RULES.create(r.name, spec=spec, context=self.context)
                                       for r, spec in active}
        #: the smoothed trajectories the rules measure, by unit ("px", "m"): see .smoothing
        self.smoothers = {unit: Smoother(self.fps) for unit in sorted(
            {u for rule in self.rules.values() for u in rule.smooths})}
        self._order = RULES.event_order()
        self._types = tuple(e.name for e in RULES.event_types())
        self._rows = _Rows()
        self.forget_frames = scene.forget_s * self.fps
        self.last_frame = 0
        self._counts: dict[str, Any] | None = None
        self.frames = 0
        self.by_type: Counter[str] = Counter()
        #: discontinuities seen, by reason (``summary.json``)
        self.resets: Counter[str] = Counter()

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
        labels = [getattr(t, "label", "") for t in tracks]
        return list(self.step(frame, [t.id for t in tracks],
                              [(t.box.x, t.box.y, t.box.w, t.box.h) for t in tracks],
                              static, labels=labels if any(labels) else None).events)

    def step(self, frame: int, ids: Any, boxes: Any, static: StaticFrame | None = None,
             discontinuity: Discontinuity | None = None, labels: Any = None) -> SceneFrame:
        """One frame from columns: ``ids`` (N,) int and ``boxes`` (N, 4) ``x, y, w, h``
        pixels, and the frame's static objects (``FrameResult.static``; the ``abandoned`` rule
        needs them); ``labels`` (N,) the tracks' classes, when they were classified (events
        carry them; rule items with ``classes`` apply to those classes only). Frames must come in increasing order; a frame without tracks is a step too
        (it is how tracks are forgotten and occupancy averaged). A ``discontinuity`` resets
        (:meth:`reset`) before the frame."""
        frame = int(frame)
        if frame < 1 or frame <= self.last_frame:
            raise ValueError(f"analytics frames must be 1-based and increasing: frame {frame} "
                             f"after {self.last_frame}")
        if discontinuity is not None:
            self.reset(discontinuity)
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        first = _first_of_each(ids)
        ids, boxes = ids[first], np.asarray(boxes, dtype=np.float64).reshape(-1, 4)[first]
        if labels is not None:
            labels = np.asarray(labels, dtype=object).reshape(-1)[first]
        gone = [] if self.objects is None else self.objects.step(frame, ids, boxes, static,
                                                                  labels)
        events = self._forget(frame)
        table, states = self._table(frame, ids, boxes, static, gone, labels)
        for rule in self.rules.values():
            events += rule.step(table)
        self._remember(table, states)
        if events:
            events.sort(key=lambda e: (e.track, self._order[e.type], e.line or "", e.zone or ""))
            self.by_type.update(e.type for e in events)
            self._counts = None
        if self._counts is None:   # the totals change only with events
            self._counts = {"line_counts": {}, "occupancy": {}}
            for rule in self.rules.values():
                self._counts.update(rule.counts())
        return SceneFrame(frame, tuple(events), dict(self._counts["line_counts"]),
                          dict(self._counts["occupancy"]), discontinuity)

    def reset(self, discontinuity: Discontinuity) -> None:
        """Forget every track and static object, and each rule's per-track state (stays, zone
        occupants, speed windows), without events: after a discontinuity the tracks of the
        frames before it are gone, not ended in place. Line and zone totals are kept; track
        and object ids keep counting."""
        self.resets[discontinuity.reason] += 1
        self.tracks.clear()
        self._rows.free = list(range(len(self._rows.point) - 1, -1, -1))
        if self.objects is not None:
            self.objects.reset()
        for rule in self.rules.values():
            rule.reset()
        self._counts = None

    def finish(self, last_frame: int | None = None) -> list[Event]:
        """Events at the end of the input: none. A track still in a zone or stationary has not
        left; :meth:`summary` reports it as open."""
        return []

    def _forget(self, frame: int) -> list[Event]:
        """Tracks unseen for more than ``forget_s`` have left: each rule ends what they had
        open (at their last position). A track id seen again after that is a new track."""
        events: list[Event] = []
        for tid in [t for t, st in self.tracks.items() if frame - st.last_frame > self.forget_frames]:
            st = self.tracks.pop(tid)
            self._rows.free.append(st.row)
            for rule in self.rules.values():
                events += rule.forget(frame, tid, st)
        return events

    def _table(self, frame: int, ids: np.ndarray, boxes: np.ndarray,
               static: StaticFrame | None, gone: list, labels: np.ndarray | None = None
               ) -> tuple[FrameTable, list[TrackMemory]]:
        """The frame's :class:`FrameTable`, new tracks given a row."""
        states, fresh = [], []
        for tid in ids.tolist():
            st = self.tracks.get(tid)
            if st is None:
                st = self.tracks[tid] = TrackMemory(self._rows.take())
                fresh.append(st.row)
            states.append(st)
        rows = np.fromiter((st.row for st in states), dtype=np.int64, count=len(states))
        known = np.fromiter((st.last_frame > 0 for st in states), dtype=bool, count=len(states))
        fresh_rows = np.asarray(fresh, dtype=np.int64)
        points, world = self.context.anchors(boxes), self.context.world(boxes)
        table = FrameTable(frame, ids, boxes, points, world, rows, known,
                           self._rows.point[rows], fresh_rows, self.context, static, gone,
                           labels, self._smoothed(frame, rows, fresh_rows, points, world, boxes))
        return table, states

    def _smoothed(self, frame: int, rows: np.ndarray, fresh: np.ndarray, points: np.ndarray,
                  world: np.ndarray | None, boxes: np.ndarray) -> dict[str, Any]:
        """Each smoother stepped with the frame's anchors (pixels) or foot points (metres)."""
        out = {}
        for unit, smoother in self.smoothers.items():
            smoother.clear(fresh)
            if unit == "m" and world is not None:
                out[unit] = smoother.step(frame, rows, world, boxes[:, 3],
                                          jacobians(self.context.world_of, boxes, world))
            else:
                out[unit] = smoother.step(frame, rows, points, boxes[:, 3])
        return out

    def _remember(self, table: FrameTable, states: list[TrackMemory]) -> None:
        """The tracks' last sighting, for the next frame's rules and for forgetting."""
        points, world, frame = table.points, table.world, table.frame
        labels = table.labels
        self._rows.point[table.rows] = points
        for i, st in enumerate(states):
            st.last_frame = frame
            st.point = (float(points[i, 0]), float(points[i, 1]))
            st.box = table.boxes[i]
            st.world = None if world is None else (float(world[i, 0]), float(world[i, 1]))
            if labels is not None:
                st.label = str(labels[i] or "")
        self.last_frame = frame
        self.frames += 1

    # ------------------------------------------------------------------------------- counts
    def counts_by_line(self) -> dict[str, tuple[int, int]]:
        """Line name → (in, out) crossings so far."""
        rule = self.rules.get("line")
        return rule.line_counts() if rule is not None else {}

    def occupancy_by_zone(self) -> dict[str, int]:
        """Zone name → tracks inside now."""
        rule = self.rules.get("zone")
        return rule.occupancy_by_zone() if rule is not None else {}

    @property
    def counts(self) -> dict[str, dict]:
        """``{"lines": {name: {"in", "out"}}, "zones": {name: occupancy}}`` now."""
        return {"lines": {k: {"in": i, "out": o} for k, (i, o) in self.counts_by_line().items()},
                "zones": self.occupancy_by_zone()}

    def summary(self) -> dict[str, Any]:
        """Totals for ``summary.json``: the scene, frame rate, frames and events per type, then
        each rule's entries in registry order (a rule the scene does not use gives its idle
        entries)."""
        out: dict[str, Any] = {
            "scene": self.scene.source, "fps": self.fps, "frames": self.frames,
            "events": {t: int(self.by_type.get(t, 0)) for t in self._types},
            "discontinuities": dict(self.resets),
        }
        for r in RULES.ordered():
            rule = self.rules.get(r.name)
            out.update(rule.summary() if rule is not None else r.idle_summary())
        return out


def _first_of_each(ids: np.ndarray) -> np.ndarray | slice:
    """The rows of a frame with a repeated track id left out but the first (an index)."""
    id_list = ids.tolist()
    if len(set(id_list)) == len(id_list):
        return slice(None)
    _, first = np.unique(ids, return_index=True)
    return np.sort(first)
