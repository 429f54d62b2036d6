"""``[[line]]``: counting lines crossed ``in`` or ``out`` (``line_cross``), with hysteresis.

The crossing test over arrays of tracks is :class:`..lines.LineSet`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import ConfigError
from ...schema import REQUIRED, param
from ...types import Event
from ..lines import LineSet
from ..rule import RULES, BaseRule, Columns, EventType, FrameTable, RuleContext
from ..specs import COORD_LIMIT, LineSpec, SceneSection, checked_classes, classes_param
from ..validate import pixels, unique_name

__all__ = ["Lines", "LineTable"]

_POINT = dict(lo=-COORD_LIMIT, hi=COORD_LIMIT, max_items=2)


@dataclass(frozen=True, kw_only=True)
class LineTable(SceneSection):
    """A ``[[line]]`` table as written."""

    name: str = param(REQUIRED, nonblank=True, doc="unique among lines")
    points: tuple[tuple[float, float], ...] | None = param(
        None, **_POINT, doc="two points in pixels, at least 1 px apart (exactly one of points "
                            "and world)")
    world: tuple[tuple[float, float], ...] | None = param(
        None, **_POINT, doc="two points in ground-plane metres, projected through `--camera`")
    classes: tuple[str, ...] | None = classes_param()


@RULES.register
class Lines(BaseRule):
    """Crossings of counting lines, ``in`` or ``out``."""

    name = section = "line"
    schema, many, exactly_one = LineTable, True, (("points", "world"),)
    events = (EventType("line_cross", ("line", "direction"),
                        meaning="the anchor crossed the line's segment: `direction` `in` "
                                "(from s < 0 to s > 0) or `out`"),)

    @classmethod
    def build(cls, table: LineTable, camera: Any, where: str,
              earlier: tuple = ()) -> LineSpec:
        line_name = unique_name(table.name, where, [ln.name for ln in earlier])
        used, pts = pixels(table, "points", where, camera)
        if len(pts) != 2:
            raise ConfigError(f"{where}.{used} must be two [x, y] points, got {len(pts)}")
        if math.hypot(*(pts[1] - pts[0])) < 1.0:
            raise ConfigError(f"{where}.{used}: the two points are less than a pixel apart")
        return LineSpec(line_name, (float(pts[0, 0]), float(pts[0, 1])),
                        (float(pts[1, 0]), float(pts[1, 1])),
                        checked_classes(table.classes, where))

    @classmethod
    def idle_summary(cls) -> dict[str, Any]:
        return {"lines": {}}

    def __init__(self, spec: tuple[LineSpec, ...], context: RuleContext) -> None:
        super().__init__(spec, context)
        self.set = LineSet([ln.a for ln in spec], [ln.b for ln in spec])
        # side: the confirmed side; touched: a step met the segment since; s: s(p) last time
        self.state = Columns(self.set.n, side=np.int8, touched=bool, s=np.float64)
        self.crossings = np.zeros((len(spec), 2), dtype=np.int64)  # in, out
        #: crossings by line, then class of the track, then direction (classified tracks)
        self.by_class: list[dict[str, list[int]]] = [{} for _ in spec]
        self._filtered = any(ln.classes is not None for ln in spec)

    def step(self, frame: FrameTable) -> list[Event]:
        if not self.set.n or not len(frame):
            return []
        t, rows = self.state, frame.rows
        t.prepare(frame)
        crossed, t.side[rows], t.touched[rows], t.s[rows] = self.set.step(
            t.side[rows], t.touched[rows], t.s[rows], frame.previous, frame.known, frame.points,
            self.context.hysteresis_px)
        if self._filtered and crossed.any():
            # a line with classes counts its classes only (the sides follow every track)
            crossed = crossed * np.column_stack([frame.of_classes(ln.classes)
                                                 for ln in self.spec])
        if not crossed.any():
            return []
        events = []
        for i, j in zip(*np.nonzero(crossed)):
            direction = "in" if crossed[i, j] > 0 else "out"
            k = 0 if direction == "in" else 1
            self.crossings[j, k] += 1
            if frame.labels is not None:
                self.by_class[j].setdefault(str(frame.labels[i]), [0, 0])[k] += 1
            events.append(frame.event("line_cross", i, line=self.spec[j].name,
                                      direction=direction))
        return events

    def line_counts(self) -> dict[str, tuple[int, int]]:
        """Line name → (in, out) crossings so far."""
        return {ln.name: (int(c[0]), int(c[1])) for ln, c in zip(self.spec, self.crossings)}

    def counts(self) -> dict[str, Any]:
        return {"line_counts": self.line_counts()}

    def summary(self) -> dict[str, Any]:
        out: dict[str, Any] = {"lines": {k: {"in": i, "out": o}
                                         for k, (i, o) in self.line_counts().items()}}
        if any(self.by_class):   # classified tracks: each line's crossings by class
            out["lines_by_class"] = {
                ln.name: {c: {"in": i, "out": o} for c, (i, o) in sorted(by_class.items())}
                for ln, by_class in zip(self.spec, self.by_class)}
        return out
