"""``[[zone]]``: polygons entered and left (``zone_enter``, ``zone_exit`` with the dwell) and
stayed in for ``loiter_s`` (``loiter``), with hysteresis along the edges.

The membership test over arrays of tracks is :class:`..zones.ZoneEdges`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import ConfigError
from ...schema import REQUIRED, param
from ...types import Event
from ..geometry import polygon_area, polygon_is_simple
from ..rule import RULES, BaseRule, Columns, EventType, FrameTable, RuleContext, TrackMemory, rounded
from ..specs import (COORD_LIMIT, MAX_POLYGON_POINTS, SceneSection, ZoneSpec, checked_classes,
                     classes_param, positive)
from ..validate import pixels, unique_name
from ..zones import ZoneEdges

__all__ = ["Zones", "ZoneTable"]

_POINT = dict(lo=-COORD_LIMIT, hi=COORD_LIMIT, max_items=MAX_POLYGON_POINTS)


@dataclass(frozen=True, kw_only=True)
class ZoneTable(SceneSection):
    """A ``[[zone]]`` table as written."""

    name: str = param(REQUIRED, nonblank=True, doc="unique among zones")
    polygon: tuple[tuple[float, float], ...] | None = param(
        None, **_POINT, doc="3 to 1,000 points in pixels, a simple polygon (no crossing edges, "
                            "no repeated point; exactly one of polygon and world)")
    world: tuple[tuple[float, float], ...] | None = param(
        None, **_POINT, doc="the polygon in ground-plane metres, projected through `--camera`")
    loiter_s: float | None = positive(None, "seconds in the zone before `loiter` (none: no "
                                            "loitering)")
    classes: tuple[str, ...] | None = classes_param()


@RULES.register
class Zones(BaseRule):
    """Zone entries, exits with their dwell, and loitering."""

    name = section = "zone"
    schema, many, exactly_one = ZoneTable, True, (("polygon", "world"),)
    events = (
        EventType("zone_enter", ("zone",), meaning="the track became inside the zone"),
        EventType("zone_exit", ("zone", "dwell_s"),
                  meaning="the track became outside the zone (or was forgotten), `dwell_s` "
                          "after entering"),
        EventType("loiter", ("zone", "dwell_s"),
                  meaning="the track has stayed `loiter_s` in the zone; once a visit"),
    )
    frame_order = ("zone_exit", "zone_enter", "loiter")

    @classmethod
    def build(cls, table: ZoneTable, camera: Any, where: str,
              earlier: tuple = ()) -> ZoneSpec:
        zone_name = unique_name(table.name, where, [z.name for z in earlier])
        used, pts = pixels(table, "polygon", where, camera)
        if len(pts) < 3:
            raise ConfigError(f"{where}.{used} must have at least 3 [x, y] points, "
                              f"got {len(pts)}")
        if not polygon_is_simple(pts):
            raise ConfigError(f"{where}.{used} must be a simple polygon: two of its edges cross "
                              "or a point repeats")
        if abs(polygon_area(pts)) < 1.0:
            raise ConfigError(f"{where}.{used} encloses no area (its points lie on a line)")
        return ZoneSpec(zone_name, tuple((float(x), float(y)) for x, y in pts), table.loiter_s,
                        checked_classes(table.classes, where))

    @classmethod
    def idle_summary(cls) -> dict[str, Any]:
        return {"zones": {}}

    def __init__(self, spec: tuple[ZoneSpec, ...], context: RuleContext) -> None:
        super().__init__(spec, context)
        self.edges = ZoneEdges(spec)
        n, fps = len(spec), context.fps
        self.state = Columns(n, inside=bool, enter_frame=np.int64, loitered=bool)
        self.loiter_frames = np.array([np.inf if z.loiter_s is None else z.loiter_s * fps
                                       for z in spec])
        self.loiters = bool(np.isfinite(self.loiter_frames).any())
        self.occupancy = np.zeros(n, dtype=np.int64)
        self.frames = 0
        self.enters = np.zeros(n, dtype=np.int64)
        self.exits = np.zeros(n, dtype=np.int64)
        self.dwell_frames = np.zeros(n, dtype=np.int64)
        self.peak = np.zeros(n, dtype=np.int64)
        self.occupancy_sum = np.zeros(n, dtype=np.int64)
        self._filtered = any(z.classes is not None for z in spec)

    def forget(self, frame: int, tid: int, state: TrackMemory) -> list[Event]:
        """A forgotten track exits its zones at its last position, dwell up to its last
        sighting."""
        if not self.edges.n:
            return []
        enter_frame = self.state.enter_frame[state.row]
        events = []
        for k in np.flatnonzero(self.state.inside[state.row]):
            dwell = state.last_frame - enter_frame[k]
            events.append(self.context.last_event("zone_exit", frame, tid, state,
                                                  zone=self.spec[k].name,
                                                  dwell_s=self.context.seconds(dwell)))
            self._exited(k, dwell)
        return events

    def reset(self) -> None:
        """The zones are empty: their occupants are dropped without ``zone_exit`` (entries,
        exits and dwell totals are kept)."""
        self.occupancy[:] = 0
        self.state.inside[:] = False

    def _exited(self, k: int, dwell: int) -> None:
        self.occupancy[k] -= 1
        self.exits[k] += 1
        self.dwell_frames[k] += dwell

    def step(self, frame: FrameTable) -> list[Event]:
        events: list[Event] = []
        if self.edges.n and len(frame):
            self.state.prepare(frame)
            self._membership(frame, events)
            if self.loiters:
                self._loiter(frame, events)
        # occupancy after this frame, for the means and peaks of the summary
        self.frames += 1
        np.maximum(self.peak, self.occupancy, out=self.peak)
        self.occupancy_sum += self.occupancy
        return events

    def _membership(self, frame: FrameTable, events: list[Event]) -> None:
        t, rows, f = self.state, frame.rows, frame.frame
        was_in = t.inside[rows]
        now_in = self.edges.membership(was_in, frame.known, frame.points,
                                       self.context.hysteresis_px)
        if self._filtered:
            # a zone with classes holds tracks of those classes only: another class is outside
            # (a track whose class changes to one of them enters where it is)
            now_in &= np.column_stack([frame.of_classes(z.classes) for z in self.spec])
        for i, k in zip(*np.nonzero(now_in != was_in)):
            r, zone = rows[i], self.spec[k].name
            if now_in[i, k]:
                t.enter_frame[r, k], t.loitered[r, k] = f, False
                self.occupancy[k] += 1
                self.enters[k] += 1
                events.append(frame.event("zone_enter", i, zone=zone))
            else:
                dwell = f - t.enter_frame[r, k]
                self._exited(k, dwell)
                events.append(frame.event("zone_exit", i, zone=zone,
                                          dwell_s=self.context.seconds(dwell)))
            t.inside[r, k] = now_in[i, k]

    def _loiter(self, frame: FrameTable, events: list[Event]) -> None:
        t, rows, f = self.state, frame.rows, frame.frame
        enter = t.enter_frame[rows]
        due = (t.inside[rows] & ~t.loitered[rows]
               & (f - enter >= self.loiter_frames[None, :] - 1e-9))
        for i, k in zip(*np.nonzero(due)):
            t.loitered[rows[i], k] = True
            events.append(frame.event("loiter", i, zone=self.spec[k].name,
                                      dwell_s=self.context.seconds(f - enter[i, k])))

    def occupancy_by_zone(self) -> dict[str, int]:
        """Zone name → tracks inside now."""
        return {z.name: int(n) for z, n in zip(self.spec, self.occupancy)}

    def counts(self) -> dict[str, Any]:
        return {"occupancy": self.occupancy_by_zone()}

    def summary(self) -> dict[str, Any]:
        zones = {}
        for k, z in enumerate(self.spec):
            zones[z.name] = {
                "enters": int(self.enters[k]), "exits": int(self.exits[k]),
                "inside_at_end": int(self.occupancy[k]), "peak": int(self.peak[k]),
                "mean_occupancy": rounded(self.occupancy_sum[k] / max(self.frames, 1), 4),
                "mean_dwell_s": (rounded(self.dwell_frames[k] / self.exits[k] / self.context.fps, 3)
                                 if self.exits[k] else None),
            }
        return {"zones": zones}
