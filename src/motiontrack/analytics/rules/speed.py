"""``[speed]``: tracks faster than a limit over a window (``speeding``), in metres per second
with a camera or pixels per second without. The speed of one track is
:class:`motiontrack.speed.WindowSpeed` (the definition of the track speeds in
``summary.json`` too); a track speeds again only after falling to
:data:`..movement.REARM` of the limit.
"""

from __future__ import annotations

import numpy as np

from ...types import Event
from ..movement import REARM, SpeedWindow
from ..rule import RULES, BaseRule, EventType, FrameTable, RuleContext, TrackMemory, rounded
from ..specs import SpeedSpec

__all__ = ["Speed"]


@RULES.register
class Speed(BaseRule):
    """Tracks over a speed limit."""

    name = section = "speed"
    events = (EventType("speeding", (), ("speed_mps", "speed_px_s"),
                        meaning="the track's speed over `window_s` exceeds the limit: "
                                "exactly one of `speed_mps` (with a camera) and `speed_px_s`"),)
    schema, exactly_one = SpeedSpec, (("limit_mps", "limit_px_s"),)

    @classmethod
    def camera_key(cls, spec: SpeedSpec) -> str | None:
        return "speed.limit_mps" if spec.limit_mps is not None else None

    def __init__(self, spec: SpeedSpec, context: RuleContext) -> None:
        super().__init__(spec, context)
        self.windows: dict[int, SpeedWindow] = {}

    def forget(self, frame: int, tid: int, state: TrackMemory) -> list[Event]:
        self.windows.pop(tid, None)
        return []

    def reset(self) -> None:
        self.windows.clear()

    def step(self, frame: FrameTable) -> list[Event]:
        spec, fps = self.spec, self.context.fps
        metres = spec.limit_mps is not None
        pos = frame.world if metres else frame.points
        limit = spec.limit_mps if metres else spec.limit_px_s
        key = "speed_mps" if metres else "speed_px_s"
        finite = np.isfinite(pos).all(axis=1).tolist()
        events = []
        for i, tid in enumerate(frame.ids.tolist()):
            w = self.windows.get(tid)
            if w is None:
                w = self.windows[tid] = SpeedWindow(spec.window_s, fps)
            if not finite[i]:
                continue
            v = w.add(frame.frame, float(pos[i, 0]), float(pos[i, 1]))
            if v is None:
                continue
            if v > limit and not w.speeding:
                w.speeding = True
                events.append(frame.event("speeding", i, **{key: rounded(v, 2)}))
            elif v <= REARM * limit:
                w.speeding = False
        return events
