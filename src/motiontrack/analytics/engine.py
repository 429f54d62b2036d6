"""Scene analytics over tracks, one frame at a time: :class:`Analytics`.

Each frame's tracks (ids and boxes) go through the rules in a fixed order: tracks unseen for
``forget_s`` are forgotten (they leave their zones and stop being stationary), then line
crossings, zone membership (enter, exit, loiter), stationary stays and speeding. Events carry
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
from ..types import EVENT_TYPES, Event, SceneFrame
from .lines import LineState, cross_lines
from .movement import REARM, SpeedWindow, Stay
from .scene import Scene
from .zones import ZoneEdges

log = logging.getLogger(__name__)

__all__ = ["Analytics"]

#: the order of a frame's events for one track (then by line or zone order)
_ORDER = {k: i for i, k in enumerate(("line_cross", "zone_exit", "zone_enter", "loiter",
                                      "stationary_end", "stationary_start", "speeding"))}


class _TrackState:
    """What the rules remember of one track."""

    __slots__ = ("last_frame", "point", "world", "lines", "zone_in", "enter_frame", "loitered",
                 "stay", "speed")

    def __init__(self, n_lines: int, n_zones: int) -> None:
        self.last_frame = -1
        self.point = (0.0, 0.0)
        self.world: tuple[float, float] | None = None
        self.lines = LineState(n_lines)
        self.zone_in = np.zeros(n_zones, dtype=bool)
        self.enter_frame = np.zeros(n_zones, dtype=np.int64)
        self.loitered = np.zeros(n_zones, dtype=bool)
        self.stay = Stay()
        self.speed = SpeedWindow()


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
        if scene.abandoned is not None:
            log.warning("the scene's [abandoned] table is not analysed: no abandoned events")
        self.scene, self.fps, self.camera = scene, float(fps), camera
        self.a = np.array([ln.a for ln in scene.lines], dtype=np.float64).reshape(-1, 2)
        self.b = np.array([ln.b for ln in scene.lines], dtype=np.float64).reshape(-1, 2)
        self.edges = ZoneEdges(scene.zones)
        self.loiter_frames = np.array([np.inf if z.loiter_s is None else z.loiter_s * fps
                                       for z in scene.zones])
        self.forget_frames = scene.forget_s * fps
        self.tracks: dict[int, _TrackState] = {}
        self.crossings = np.zeros((len(scene.lines), 2), dtype=np.int64)  # in, out
        self.occupancy = np.zeros(len(scene.zones), dtype=np.int64)
        self.last_frame = 0
        # totals for the summary
        self.frames = 0
        self.by_type: Counter[str] = Counter()
        self.enters = np.zeros(len(scene.zones), dtype=np.int64)
        self.exits = np.zeros(len(scene.zones), dtype=np.int64)
        self.dwell_frames = np.zeros(len(scene.zones), dtype=np.int64)
        self.peak = np.zeros(len(scene.zones), dtype=np.int64)
        self.occupancy_sum = np.zeros(len(scene.zones), dtype=np.int64)

    # ------------------------------------------------------------------------------- frames
    def update(self, frame: int, tracks: Sequence[Any]) -> list[Event]:
        """The events of frame ``frame`` (1-based) with these tracks (each with ``.id`` and
        ``.box`` ``x, y, w, h``)."""
        return list(self.step(frame, [t.id for t in tracks],
                              [(t.box.x, t.box.y, t.box.w, t.box.h) for t in tracks]).events)

    def step(self, frame: int, ids: Any, boxes: Any) -> SceneFrame:
        """One frame from columns: ``ids`` (N,) int and ``boxes`` (N, 4) ``x, y, w, h``
        pixels. Frames must come in increasing order; a frame without tracks is a step too (it
        is how tracks are forgotten and occupancy averaged)."""
        frame = int(frame)
        if frame < 1 or frame <= self.last_frame:
            raise ValueError(f"analytics frames must be 1-based and increasing: frame {frame} "
                             f"after {self.last_frame}")
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        _, first = np.unique(ids, return_index=True)  # a repeated id: its first row counts
        first = np.sort(first)
        ids, boxes = ids[first], boxes[first]
        events: list[Event] = []
        self._forget(frame, set(ids.tolist()), events)
        points = self._anchors(boxes)
        world = self._world(boxes)
        states = []
        for tid in ids.tolist():
            st = self.tracks.get(tid)
            if st is None:
                st = self.tracks[tid] = _TrackState(len(self.a), self.edges.n)
            states.append(st)
        self._lines(frame, ids, states, points, world, events)
        self._zones(frame, ids, states, points, world, events)
        self._movement(frame, ids, states, points, world, events)
        for i, st in enumerate(states):
            st.last_frame = frame
            st.point = (float(points[i, 0]), float(points[i, 1]))
            st.world = None if world is None else (float(world[i, 0]), float(world[i, 1]))
        self.last_frame = frame
        self.frames += 1
        self.peak = np.maximum(self.peak, self.occupancy)
        self.occupancy_sum += self.occupancy
        events.sort(key=lambda e: (e.track, _ORDER[e.type], e.line or "", e.zone or ""))
        self.by_type.update(e.type for e in events)
        return SceneFrame(frame, tuple(events), self.counts_by_line(), self.occupancy_by_zone())

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
            "stationary_at_end": sum(1 for s in self.tracks.values() if s.stay.stationary),
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

    def _forget(self, frame: int, present: set[int], events: list[Event]) -> None:
        """Tracks unseen for more than ``forget_s`` have left: they exit their zones and end
        their stationary stay (at their last position). A track id seen again after that is a
        new track."""
        for tid in [t for t, st in self.tracks.items() if frame - st.last_frame > self.forget_frames]:
            st = self.tracks.pop(tid)
            for k in np.flatnonzero(st.zone_in):
                events.append(self._event("zone_exit", frame, tid, st.point, st.world,
                                          zone=self.scene.zones[k].name,
                                          dwell_s=self._seconds(st.last_frame - st.enter_frame[k])))
                self._exited(k, st.last_frame - st.enter_frame[k])
            if st.stay.stationary:
                events.append(self._event("stationary_end", frame, tid, st.point, st.world,
                                          duration_s=self._seconds(st.stay.last - st.stay.first)))

    def _exited(self, k: int, dwell: int) -> None:
        self.occupancy[k] -= 1
        self.exits[k] += 1
        self.dwell_frames[k] += dwell

    def _lines(self, frame, ids, states, points, world, events) -> None:
        if not len(self.a) or not len(ids):
            return
        has_prev = np.array([st.last_frame > 0 for st in states])
        prev = np.array([st.point for st in states], dtype=np.float64).reshape(-1, 2)
        crossed = cross_lines([st.lines for st in states], prev, has_prev, points, self.a,
                              self.b, self.scene.hysteresis_px)
        for i, j in zip(*np.nonzero(crossed)):
            direction = "in" if crossed[i, j] > 0 else "out"
            self.crossings[j, 0 if direction == "in" else 1] += 1
            events.append(self._event("line_cross", frame, ids[i], points[i], _row(world, i),
                                      line=self.scene.lines[j].name, direction=direction))

    def _zones(self, frame, ids, states, points, world, events) -> None:
        if not self.edges.n or not len(ids):
            return
        was_in = np.stack([st.zone_in for st in states])
        known = np.array([st.last_frame > 0 for st in states])
        now_in = self.edges.membership(was_in, known, points, self.scene.hysteresis_px)
        for i, k in zip(*np.nonzero(now_in != was_in)):
            st, name = states[i], self.scene.zones[k].name
            if now_in[i, k]:
                st.enter_frame[k], st.loitered[k] = frame, False
                self.occupancy[k] += 1
                self.enters[k] += 1
                events.append(self._event("zone_enter", frame, ids[i], points[i], _row(world, i),
                                          zone=name))
            else:
                dwell = frame - st.enter_frame[k]
                self._exited(k, dwell)
                events.append(self._event("zone_exit", frame, ids[i], points[i], _row(world, i),
                                          zone=name, dwell_s=self._seconds(dwell)))
            st.zone_in[k] = now_in[i, k]
        enter = np.stack([st.enter_frame for st in states])
        loitered = np.stack([st.loitered for st in states])
        due = now_in & ~loitered & (frame - enter >= self.loiter_frames[None, :] - 1e-9)
        for i, k in zip(*np.nonzero(due)):
            states[i].loitered[k] = True
            events.append(self._event("loiter", frame, ids[i], points[i], _row(world, i),
                                      zone=self.scene.zones[k].name,
                                      dwell_s=self._seconds(frame - enter[i, k])))

    def _movement(self, frame, ids, states, points, world, events) -> None:
        stat, speed = self.scene.stationary, self.scene.speed
        if stat is not None:
            pos = world if stat.radius_m is not None else points
            radius = stat.radius_m if stat.radius_m is not None else stat.radius_px
            for i, st in enumerate(states):
                if not np.all(np.isfinite(pos[i])):
                    continue
                what, lasted = st.stay.step((pos[i, 0], pos[i, 1]), frame, radius,
                                            stat.after_s * self.fps)
                if what == "start":
                    events.append(self._event("stationary_start", frame, ids[i], points[i],
                                              _row(world, i)))
                elif what == "end":
                    events.append(self._event("stationary_end", frame, ids[i], points[i],
                                              _row(world, i), duration_s=self._seconds(lasted)))
        if speed is not None:
            metres = speed.limit_mps is not None
            pos = world if metres else points
            limit = speed.limit_mps if metres else speed.limit_px_s
            for i, st in enumerate(states):
                if not np.all(np.isfinite(pos[i])):
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


def _row(world: np.ndarray | None, i: int) -> tuple[float, float] | None:
    return None if world is None else (float(world[i, 0]), float(world[i, 1]))
