"""``[abandoned]``: an object left static while its owner is away for ``after_s``
(``abandoned``). The rule over static objects and tracks is :class:`..abandoned.AbandonedRule`;
it needs the video's static foreground (``track --scene``).
"""

from __future__ import annotations

import logging
from dataclasses import replace
from typing import Any

from ...types import Event
from ..abandoned import AbandonedRule
from ..rule import RULES, BaseRule, EventType, FrameTable, RuleContext, TrackMemory, rounded
from ..specs import AbandonedSpec, checked_classes

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

    @classmethod
    def build(cls, table: AbandonedSpec, camera: Any, where: str,
              earlier: tuple = ()) -> AbandonedSpec:
        return replace(table, classes=checked_classes(table.classes, where))

    def __init__(self, spec: AbandonedSpec, context: RuleContext) -> None:
        super().__init__(spec, context)
        self.rule = AbandonedRule(spec, context.fps, context.objects, context.anchors,
                                  context.world)
        self._warned = False
        #: each live track's latest class (``classes``: an object's owner may be out of view)
        self.labels: dict[int, str] = {}

    def forget(self, frame: int, tid: int, state: TrackMemory) -> list[Event]:
        # an owner long gone still names the class of what it left; others are dropped
        if not any(o.owner == tid for o in self.rule.objects.objects):
            self.labels.pop(tid, None)
        return []

    def reset(self) -> None:
        self.labels.clear()

    def step(self, frame: FrameTable) -> list[Event]:
        if frame.static is None and not self._warned:
            self._warned = True
            log.warning("abandoned objects are found in the video's static foreground "
                        "(track --scene); from tracks alone there are no abandoned events")
        if frame.labels is not None:
            self.labels.update(zip(frame.ids.tolist(), frame.labels.tolist()))
        found = self.rule.step(frame.frame, frame.ids, frame.boxes)
        if self.spec.classes is not None:   # objects left by tracks of those classes only
            found = [x for x in found if self.labels.get(x[1]) in self.spec.classes]
        return [self.context.box_event("abandoned", frame.frame, oid, box,
                                       duration_s=rounded(static_s, 3), owner=owner)
                for oid, owner, box, static_s in found]
