"""The scene file: named lines and zones of one camera view and the rules' thresholds.

A scene is TOML (``docs/analytics.md``)::

    anchor = "bottom_center"          # or "center": the point of a track that counts
    hysteresis_px = 5                 # a side changes only this far past a line or zone edge
    forget_s = 2                      # a track unseen this long has left
    [[line]]
    name = "gate"
    points = [[120, 410], [640, 430]] # pixels; or world = [[X, Y], [X, Y]] metres
    [[zone]]
    name = "plaza"
    polygon = [[0, 300], [400, 300], [400, 576], [0, 576]]  # or world = [...]
    loiter_s = 20
    [stationary]
    after_s = 10
    radius_px = 15                    # or radius_m
    [abandoned]
    after_s = 15
    distance_m = 3                    # or distance_heights
    [speed]
    limit_mps = 3.0                   # or limit_px_s
    window_s = 1.0

:func:`parse_scene` turns the parsed table into a frozen :class:`Scene` in source pixels,
projecting ``world`` geometry through a camera; every problem is one :class:`ConfigError`
naming the key as written (tables of an array counted from 1: ``line[2].points``). The top-level
keys are :class:`SceneTop`; each table belongs to a rule (:data:`.rule.RULES`), whose schema
checks it (:meth:`.rule.Rule.parse`): the scene's keys are these three and the sections of the
registered rules. :func:`scene_json_schema` exports the whole file as JSON Schema.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from ..errors import ConfigError
from ..io.tomlfile import read_toml
from ..schema import from_dict, json_schema, keys_shown, param, shown
from .evidence import EvidenceOverride, EvidencePlan, EvidenceSpec, split_evidence
from .rules import RULES
from .specs import (COORD_LIMIT, MAX_TABLES, AbandonedSpec, LineSpec, SceneSection, SpeedSpec,
                    StationarySpec, ZoneSpec)

__all__ = [
    "ANCHORS",
    "SceneTop",
    "LineSpec",
    "ZoneSpec",
    "StationarySpec",
    "AbandonedSpec",
    "SpeedSpec",
    "Scene",
    "parse_scene",
    "load_scene",
    "scene_json_schema",
]

ANCHORS = ("bottom_center", "center")


@dataclass(frozen=True, kw_only=True)
class SceneTop(SceneSection):
    """The keys of the scene's top level that all rules share."""

    anchor: str = param("bottom_center", choices=ANCHORS, doc="the point of a box the rules use")
    hysteresis_px: float = param(5.0, lo=0.0, hi=COORD_LIMIT,
                                 doc="band around lines and zone edges in which a side does not "
                                     "change")
    forget_s: float = param(2.0, lo=0.0, lo_open=True, hi=COORD_LIMIT,
                            doc="a track unseen longer has left (zone exit, stationary end); "
                                "its id seen again is a new track")
    evidence: EvidenceSpec = field(default_factory=EvidenceSpec)


#: the scene's fields of the built-in rules' sections
_FIELDS = {"line": "lines", "zone": "zones", "stationary": "stationary",
           "abandoned": "abandoned", "speed": "speed"}


@dataclass(frozen=True)
class Scene:
    """Everything analytics needs to know about one camera view, in source pixels.

    The built-in rules' sections are fields of their own; ``sections`` holds those of plug-in
    rules (:data:`.rule.RULES`), section → parsed spec. :meth:`spec` reads either.
    """

    anchor: str = "bottom_center"
    hysteresis_px: float = 5.0
    forget_s: float = 2.0
    lines: tuple[LineSpec, ...] = ()
    zones: tuple[ZoneSpec, ...] = ()
    stationary: StationarySpec | None = None
    abandoned: AbandonedSpec | None = None
    speed: SpeedSpec | None = None
    source: str = ""
    sections: tuple[tuple[str, Any], ...] = ()
    evidence: EvidencePlan = field(default_factory=EvidencePlan)

    def spec(self, section: str) -> Any:
        """The parsed table of ``section`` (None when the scene has none)."""
        if section in _FIELDS:
            return getattr(self, _FIELDS[section])
        return dict(self.sections).get(section)

    @property
    def camera_key(self) -> str | None:
        """The first key in metres, in the order the rules check them; None if none is."""
        for rule in _camera_order():
            spec = self.spec(rule.section)
            if spec is not None and rule.camera_key(spec) is not None:
                return rule.camera_key(spec)
        return None

    @property
    def needs_camera(self) -> bool:
        """Whether a rule measures in metres (positions of events then carry ``X, Y`` too)."""
        return self.camera_key is not None


def _camera_order() -> list:
    # a scene with several keys in metres and no camera names stationary's, then speed's, then
    # abandoned's (then the plug-in rules', in their order)
    order = {"stationary": 0, "speed": 1, "abandoned": 2}
    return sorted(RULES.ordered(), key=lambda r: order.get(r.section, len(order)))


def parse_scene(data: Any, camera: Any = None, source: str = "") -> Scene:
    """The :class:`Scene` a parsed scene TOML table describes.

    Parameters
    ----------
    data : dict
        The parsed TOML.
    camera : optional
        A camera from :func:`motiontrack.calibrate.load_camera`, fitted to the video; needed by
        ``world`` geometry and by ``radius_m``, ``limit_mps`` and ``distance_m``.
    source : str
        The file's name, kept for outputs.

    Raises
    ------
    ConfigError
        One line naming the key path as written.
    """
    rules = RULES.ordered()
    if not isinstance(data, dict):
        raise ConfigError(f"the scene must be a table, got {shown(data)}")
    top = [f.name for f in fields(SceneTop)]
    valid = top + [r.section for r in rules]
    unknown = sorted(str(k) for k in data if k not in valid)
    if unknown:
        raise ConfigError(f"unknown scene key(s) {keys_shown(unknown)}; valid keys: "
                          f"{', '.join(valid)}")
    head = from_dict(SceneTop, {k: v for k, v in data.items() if k in top})
    data, overrides = split_evidence(data, {r.section: r.many for r in rules})
    specs = {r.section: r.parse(data.get(r.section), camera, r.section) for r in rules}
    builtin = {name: specs.pop(section) for section, name in _FIELDS.items() if section in specs}
    plan = EvidencePlan(head.evidence, overrides,
                        {e.name: r.section for r in rules for e in r.events})
    scene = Scene(head.anchor, head.hysteresis_px, head.forget_s, **builtin, source=source,
                  sections=tuple((k, v) for k, v in specs.items() if v is not None),
                  evidence=plan)
    key = scene.camera_key
    if key is not None and camera is None:
        raise ConfigError(f"{key} is in metres and needs a camera calibration (--camera); "
                          "give it in pixels (radius_px, limit_px_s, distance_heights) instead")
    return scene


def load_scene(path: str | Path, camera: Any = None) -> Scene:
    """Read and validate a scene TOML file (see :func:`parse_scene`); a missing or malformed
    file is an :class:`~motiontrack.errors.InputError`, bad content a :class:`ConfigError`
    that names the file."""
    data = read_toml(path, "scene file")
    try:
        return parse_scene(data, camera, source=str(path))
    except ConfigError as exc:
        raise ConfigError(f"scene file {Path(path).name}: {exc}") from None


#: a rule table's own ``snapshot`` and ``clip_s`` (:mod:`.evidence`), as JSON Schema
_OVERRIDE_PROPERTIES = json_schema(EvidenceOverride)["properties"]


def scene_json_schema() -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of the scene file with the tables of every registered rule,
    for editors: a rule's keys of which exactly one must be given are a ``oneOf``; a rule that
    parses its table by hand takes any table."""
    out = json_schema(SceneTop, title="motiontrack scene file")
    for rule in RULES.ordered():
        if rule.schema is None:
            table: dict[str, Any] = {"type": "object"}
        else:
            table = json_schema(rule.schema)
            del table["$schema"]
            table["properties"].update(_OVERRIDE_PROPERTIES)   # split off before the rule reads
            if rule.exactly_one:
                table["allOf"] = [{"oneOf": [{"required": [k]} for k in keys]}
                                  for keys in rule.exactly_one]
        out["properties"][rule.section] = (
            {"type": "array", "items": table, "maxItems": MAX_TABLES,
             "description": f"[[{rule.section}]] tables"}
            if rule.many else table)
    return out
