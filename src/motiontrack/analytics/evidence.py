"""What evidence each event keeps: a snapshot, and a clip of some seconds around it.

The scene's ``[evidence]`` table sets it for every rule; any rule's table (a ``[[line]]``, a
``[[zone]]``, ``[stationary]``, ``[abandoned]``, ``[speed]``, a plug-in rule's) may set
``snapshot`` and ``clip_s`` for its own events::

    [evidence]
    snapshot = true           # the annotated frame and a crop of the object, as JPEG
    clip_s = [5, 10]          # seconds before and after the event; [0, 0]: no clip
    clip_fps = 10             # most frames a second of a clip
    clip_width = 480          # most pixels across a clip's frames
    [[zone]]
    name = "bench"
    polygon = [[0, 300], [400, 300], [400, 576], [0, 576]]
    clip_s = [10, 20]         # this zone's events keep longer clips

The keys are taken out of the rule tables here (:func:`split_evidence`), before each rule checks
its own keys, so every rule has them without declaring them. ``clip_fps`` and ``clip_width`` are
the scene's only: one stream of clip frames serves every rule.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Mapping

from ..schema import from_dict, param
from .specs import SceneSection

__all__ = ["EvidenceSpec", "EvidenceOverride", "EVIDENCE_KEYS", "split_evidence",
           "EvidencePlan"]

#: longest clip side (seconds): the pre-roll is held in memory
MAX_CLIP_S = 60.0


@dataclass(frozen=True, kw_only=True)
class EvidenceSpec(SceneSection):
    """The ``[evidence]`` table: what every event keeps unless its rule says otherwise."""

    snapshot: bool = param(True, doc="keep a JPEG of the annotated frame and one of the object "
                                     "for each event")
    clip_s: tuple[float, float] = param(
        (5.0, 10.0), lo=0.0, hi=MAX_CLIP_S,
        doc="seconds of video kept before and after each event (MJPEG AVI); [0, 0]: none")

    clip_fps: float = param(10.0, lo=0.0, lo_open=True, hi=120.0,
                            doc="most frames a second of a clip (frames of a faster source are "
                                "skipped: every frame is JPEG-encoded for the pre-roll)")
    clip_width: int = param(480, lo=16, hi=8192,
                            doc="most pixels across a clip's frames (a wider source is scaled "
                                "down; snapshots keep the source's size)")

    @property
    def clip(self) -> bool:
        return self.clip_s[0] > 0 or self.clip_s[1] > 0


@dataclass(frozen=True, kw_only=True)
class EvidenceOverride(SceneSection):
    """``snapshot`` and ``clip_s`` in a rule's table: its own events' evidence."""

    snapshot: bool | None = param(None, doc="as [evidence] snapshot, for this rule's events")
    clip_s: tuple[float, float] | None = param(None, lo=0.0, hi=MAX_CLIP_S,
                                               doc="as [evidence] clip_s, for this rule's events")

    def over(self, base: EvidenceSpec) -> EvidenceSpec:
        return replace(base, **{k: v for k, v in (("snapshot", self.snapshot),
                                                  ("clip_s", self.clip_s)) if v is not None})


EVIDENCE_KEYS = ("snapshot", "clip_s")


def split_evidence(data: Mapping[str, Any], sections: Mapping[str, bool]
                   ) -> tuple[dict[str, Any], tuple[tuple[str, str | None, EvidenceOverride], ...]]:
    """``data`` (a parsed scene) without the evidence keys of its rule tables, and those keys:
    ``(section, table name or None, override)``. ``sections``: each rule's section → whether it
    is an array of named tables."""
    out: dict[str, Any] = dict(data)
    found: list[tuple[str, str | None, EvidenceOverride]] = []
    for section, many in sections.items():
        value = data.get(section)
        tables = value if many and isinstance(value, list) else [value] if not many else []
        kept = []
        for k, table in enumerate(tables):
            if not isinstance(table, dict):
                kept.append(table)
                continue
            own = {key: table[key] for key in EVIDENCE_KEYS if key in table}
            if own:
                where = f"{section}[{k + 1}]" if many else section
                name = table.get("name") if many else None
                found.append((section, name if isinstance(name, str) else None,
                              from_dict(EvidenceOverride, own, where)))
            kept.append({key: v for key, v in table.items() if key not in EVIDENCE_KEYS})
        if value is not None and (many and isinstance(value, list) or not many):
            out[section] = kept if many else kept[0]
    return out, tuple(found)


@dataclass(frozen=True)
class EvidencePlan:
    """The evidence of each event: the scene's ``[evidence]`` and its rules' overrides.

    ``sections``: event type → the section of the rule that emits it; ``names``: the event key
    that names a rule's table (``line``, ``zone``) for the sections of named tables."""

    default: EvidenceSpec = field(default_factory=EvidenceSpec)
    overrides: tuple[tuple[str, str | None, EvidenceOverride], ...] = ()
    sections: Mapping[str, str] = field(default_factory=dict)

    def of(self, event: Mapping[str, Any]) -> EvidenceSpec:
        """What ``event`` (an ``events.jsonl`` object) keeps."""
        section = self.sections.get(str(event.get("type")))
        name = event.get(section) if section is not None else None
        for s, n, override in self.overrides:
            if s == section and (n is None or n == name):
                return override.over(self.default)
        return self.default

    @property
    def longest_before_s(self) -> float:
        """The longest pre-roll any event needs (what the frame buffer must hold)."""
        return max([self.default.clip_s[0]] + [o.clip_s[0] for _, _, o in self.overrides
                                               if o.clip_s is not None])
