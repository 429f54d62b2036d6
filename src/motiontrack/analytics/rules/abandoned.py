"""``[abandoned]``: an object left static while its owner is away for ``after_s``
(``abandoned``). The rule over static objects and tracks is :class:`..abandoned.AbandonedRule`;
it needs the video's static foreground (``track --scene``).
"""

from __future__ import annotations

import logging

from ...types import Event
from ..abandoned import AbandonedRule
from ..rule import RULES, BaseRule, EventType, FrameTable, RuleContext, rounded
from ..specs import AbandonedSpec

log = logging.getLogger(__name__)

__all__ = ["Abandoned"]


@RULES.register
class Abandoned(BaseRule):
    """Objects left behind by the person who carried them."""

    name = section = "abandoned"
    events = (EventType("abandoned", ("duration_s",), ("owner",),
                        meaning="an object left static while its owner was away for "
                                "`after_s`; `duration_s` static so far, `owner` the track "
                                "that left it"),)
    schema, exactly_one = AbandonedSpec, (("distance_m", "distance_heights"),)
    uses_static = True

    @classmethod
    def camera_key(cls, spec: AbandonedSpec) -> str | None:
        return "abandoned.distance_m" if spec.distance_m is not None else None

    def __init__(self, spec: AbandonedSpec, context: RuleContext) -> None:
        super().__init__(spec, context)
        self.rule = AbandonedRule(spec, context.fps, context.objects, context.anchors,
                                  context.world)
        self._warned = False

    def step(self, frame: FrameTable) -> list[Event]:
        if frame.static is None and not self._warned:
            self._warned = True
            log.warning("abandoned objects are found in the video's static foreground "
                        "(track --scene); from tracks alone there are no abandoned events")
        return [self.context.box_event("abandoned", frame.frame, oid, box,
                                       duration_s=rounded(static_s, 3), owner=owner)
                for oid, owner, box, static_s in self.rule.step(frame.frame, frame.ids,
                                                                frame.boxes)]
