"""``[speed]``: tracks faster than a limit (``speeding``), in metres per second with a camera or
pixels per second without, measured on each track's smoothed trajectory
(:mod:`..smoothing`) over a window with its uncertainty (:class:`..movement.SpeedWindow`): an
alarm needs the speed to exceed the limit by :data:`..movement.SIGMAS` standard deviations for
``min_s``, and a track speeds again only after falling to :data:`..movement.REARM` of the limit.
"""

from __future__ import annotations

from ...types import Event
from ..movement import REARM, SIGMAS, SpeedWindow
from ..rule import RULES, BaseRule, EventType, FrameTable, RuleContext, TrackMemory, rounded
from ..specs import SpeedSpec

__all__ = ["Speed"]


@RULES.register
class Speed(BaseRule):
    """Tracks over a speed limit."""

    name = section = "speed"
    events = (EventType("speeding", (), ("speed_mps", "speed_px_s"),
                        meaning="the track's speed over `window_s` has exceeded the limit by two "
                                "standard deviations for `min_s`: exactly one of `speed_mps` "
                                "(with a camera) and `speed_px_s`"),)
    schema, exactly_one = SpeedSpec, (("limit_mps", "limit_px_s"),)

    @classmethod
    def camera_key(cls, spec: SpeedSpec) -> str | None:
        return "speed.limit_mps" if spec.limit_mps is not None else None

    def __init__(self, spec: SpeedSpec, context: RuleContext) -> None:
        super().__init__(spec, context)
        self.metres = spec.limit_mps is not None
        self.smooths = ("m",) if self.metres else ("px",)
        self.limit = spec.limit_mps if self.metres else spec.limit_px_s
        self.windows: dict[int, SpeedWindow] = {}

    def forget(self, frame: int, tid: int, state: TrackMemory) -> list[Event]:
        self.windows.pop(tid, None)
        return []

    def reset(self) -> None:
        self.windows.clear()

    def step(self, frame: FrameTable) -> list[Event]:
        spec, fps, limit = self.spec, self.context.fps, self.limit
        key = "speed_mps" if self.metres else "speed_px_s"
        smoothed = frame.smoothed[self.smooths[0]]
        updates = smoothed.updates.tolist()
        events = []
        for i, tid in enumerate(frame.ids.tolist()):
            w = self.windows.get(tid)
            if w is None:
                w = self.windows[tid] = SpeedWindow(spec.window_s, fps)
            elif updates[i] < w.updates:
                # its filter started again: the positions before belong to another stretch of
                # trajectory (an alarm raised stays raised until the track slows down)
                w.samples.clear()
                w.over_since = None
            w.updates = updates[i]
            if not updates[i]:
                continue
            measured = w.add(frame.frame, smoothed.position[i], smoothed.position_cov[i])
            if measured is None:
                continue
            v, sigma = measured
            if v - SIGMAS * sigma > limit:
                if w.over_since is None:
                    w.over_since = frame.frame
                if not w.speeding and frame.frame - w.over_since >= spec.min_s * fps - 1e-9:
                    w.speeding = True
                    events.append(frame.event("speeding", i, **{key: rounded(v, 2)}))
                continue
            w.over_since = None
            if v <= REARM * limit:
                w.speeding = False
        return events
