"""Analytics rules as plug-ins: the :class:`Rule` protocol and the :data:`RULES` registry.

A rule owns one table of the scene file (:attr:`Rule.section`): how it is written and checked
is its :attr:`Rule.schema` (a :class:`~.specs.SceneSection` of ``param`` fields with type, range,
default and meaning; :func:`motiontrack.schema.from_dict` checks each key), what the schema
cannot say is :meth:`Rule.build` (geometry, projection through the camera); the same schema
gives the docs' table of scene keys and the scene file's JSON Schema. A rule also owns the event
types it emits with their fields (:attr:`Rule.events`, registered with
:func:`motiontrack.types.register_event_type`), what it does with each frame (:meth:`Rule.step`,
on the :class:`FrameTable` the engine builds) and its entries of ``summary.json``
(:meth:`Rule.summary`). :class:`~.engine.Analytics` keeps what all rules share (track anchors,
forgetting old tracks, the frame table, the order of a frame's events) and runs every rule whose
table the scene has, in the order they were registered.

A new rule is one module::

    @dataclass(frozen=True)
    class AppearedTable(SceneSection):
        min_frames: int = param(1, lo=1, hi=1000, doc="frames seen before `appeared`")

    @RULES.register
    class Appeared(BaseRule):
        name = section = "appeared"
        schema = AppearedTable          # parse() then gives an AppearedTable, or None
        events = (EventType("appeared", meaning="a track is seen for the first time"),)

        def step(self, frame):
            return [frame.event("appeared", i) for i in np.flatnonzero(~frame.known)]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, ClassVar, Mapping, Protocol, Sequence, runtime_checkable

import numpy as np

from ..registry import Registry
from ..schema import from_dict
from ..types import EVENT_TYPES, Event, StaticFrame, register_event_type, unregister_event_type
from .validate import array_of_tables, one_of

__all__ = ["EventType", "SceneKey", "TrackMemory", "RuleContext", "FrameTable", "Rule",
           "BaseRule", "Columns", "RuleRegistry", "RULES", "rounded", "row_of"]


@dataclass(frozen=True)
class EventType:
    """One event type a rule emits: its fields beyond ``type, frame, t, track, x, y`` (``X, Y``
    with a camera) and what it means, for the docs."""

    name: str
    required: tuple[str, ...] = ()
    optional: tuple[str, ...] = ()
    meaning: str = ""


@dataclass(frozen=True)
class SceneKey:
    """One key of the scene file as the docs' table lists it (of a rule that parses its table
    without a :attr:`Rule.schema`; a schema's keys are listed from its fields)."""

    key: str
    type: str
    default: str
    meaning: str


def rounded(v: float, digits: int) -> float:
    """``v`` as a float rounded to ``digits`` (the precision events and summaries carry)."""
    return round(float(v), digits)


def row_of(world: np.ndarray | None, i: int) -> tuple[float, float] | None:
    """Row ``i`` of ground-plane positions (None without a camera)."""
    return None if world is None else (float(world[i, 0]), float(world[i, 1]))


class TrackMemory:
    """What the engine remembers of one track between frames: its row in every rule's
    per-track columns, the frame it was last seen in and its last box, anchor, ground
    position and class (updated after the rules of a frame ran, so they see the previous
    sighting)."""

    __slots__ = ("row", "last_frame", "point", "world", "box", "label")

    def __init__(self, row: int) -> None:
        self.row = row
        self.last_frame = -1
        self.point = (0.0, 0.0)
        self.box = np.zeros(4)
        self.world: tuple[float, float] | None = None
        self.label = ""


@dataclass(frozen=True)
class RuleContext:
    """What every rule of one :class:`~.engine.Analytics` shares: the frame rate, the scene's
    anchor, hysteresis and forgetting, the camera and the static objects (when a rule needs
    them).

    Attributes
    ----------
    tracks : mapping of track id → TrackMemory
        The engine's live tracks (read only for rules).
    objects : StaticObjects or None
        Static objects followed from frame to frame (:mod:`.objects`), stepped by the engine
        before the rules; present when a rule of the scene has ``uses_static``.
    """

    fps: float
    anchor: str
    hysteresis_px: float
    forget_frames: float
    camera: Any = None
    objects: Any = None
    tracks: Mapping[int, TrackMemory] = field(default_factory=dict)
    world_of: Callable[[np.ndarray], np.ndarray] | None = None

    def anchors(self, boxes: np.ndarray) -> np.ndarray:
        """(N, 2) anchor points of (N, 4) boxes ``x, y, w, h``."""
        x, y, w, h = boxes.T
        bottom = y + h if self.anchor == "bottom_center" else y + h / 2.0
        return np.column_stack([x + w / 2.0, bottom])

    def world(self, boxes: np.ndarray) -> np.ndarray | None:
        """(N, 2) ground-plane metres of the boxes' foot points (None without a camera)."""
        return None if self.world_of is None else self.world_of(boxes)

    def seconds(self, frames: float) -> float:
        """Frames as seconds, rounded to the millisecond."""
        return rounded(frames / self.fps, 3)

    def event(self, kind: str, frame: int, tid: int, p: Sequence[float],
              w: Sequence[float] | None, **fields: Any) -> Event:
        """An event at anchor ``p`` (pixels) and ground position ``w`` (metres, or None)."""
        xy = {}
        if w is not None and np.isfinite(w[0]) and np.isfinite(w[1]):
            xy = {"X": rounded(w[0], 3), "Y": rounded(w[1], 3)}
        return Event(kind, frame, rounded((frame - 1) / self.fps, 6), int(tid),
                     rounded(p[0], 2), rounded(p[1], 2), **xy, **fields)

    def last_event(self, kind: str, frame: int, tid: int, state: TrackMemory,
                   **fields: Any) -> Event:
        """An event of a track at its last sighting ``state`` (a track forgotten in ``frame``),
        with the class it had then."""
        if state.label:
            fields.setdefault("label", state.label)
        return self.event(kind, frame, tid, state.point, state.world, **fields)

    def box_event(self, kind: str, frame: int, tid: int, box: np.ndarray, **fields: Any) -> Event:
        """An event at the anchor of ``box`` (4,) (a static object rather than a track)."""
        b = box[None]
        return self.event(kind, frame, tid, self.anchors(b)[0], row_of(self.world(b), 0), **fields)


@dataclass(frozen=True)
class FrameTable:
    """One frame's tracks as every rule reads them: columns of ``N`` rows, one per track.

    Attributes
    ----------
    frame : int
        1-based frame number.
    ids : (N,) int64
    boxes : (N, 4) float64
        ``x, y, w, h`` source pixels.
    points : (N, 2) float64
        Anchors (the scene's ``anchor``).
    world : (N, 2) float64 or None
        Ground-plane metres of the foot points (with a camera).
    rows : (N,) int64
        Each track's row in the rules' per-track columns; rows of new tracks are in ``fresh``.
    known : (N,) bool
        Whether the track was seen in an earlier frame (and not forgotten since).
    previous : (N, 2) float64
        The track's anchor when last seen (0 for new tracks).
    fresh : (M,) int64
        Rows first used by a track in this frame: a rule clears its columns there.
    static : StaticFrame or None
        The frame's static objects (``track --scene`` with a rule that uses them).
    gone : list
        Static objects forgotten in this frame (:meth:`.objects.StaticObjects.step`).
    labels : (N,) object array of str, or None
        Each track's class (``person``, ``vehicle``, ``other``) when the tracks were
        classified; events carry it and rules with ``classes`` count only those classes.
    smoothed : mapping of unit → :class:`~.smoothing.Smoothed`
        The tracks' smoothed trajectories in the units the rules asked for
        (:attr:`BaseRule.smooths`: ``"px"`` anchors, ``"m"`` foot points on the ground).
    """

    frame: int
    ids: np.ndarray
    boxes: np.ndarray
    points: np.ndarray
    world: np.ndarray | None
    rows: np.ndarray
    known: np.ndarray
    previous: np.ndarray
    fresh: np.ndarray
    context: RuleContext
    static: StaticFrame | None = None
    gone: Sequence[Any] = ()
    labels: np.ndarray | None = None
    smoothed: Mapping[str, Any] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.ids)

    def event(self, kind: str, i: int, **fields: Any) -> Event:
        """An event of this frame about track row ``i`` at its anchor (with its class)."""
        if self.labels is not None and self.labels[i]:
            fields.setdefault("label", str(self.labels[i]))
        return self.context.event(kind, self.frame, self.ids[i], self.points[i],
                                  row_of(self.world, i), **fields)

    def of_classes(self, classes: Sequence[str] | None) -> np.ndarray:
        """(N,) bool: the tracks a rule item with ``classes`` applies to (every track when
        ``classes`` is None; none of an unclassified frame otherwise)."""
        if classes is None:
            return np.ones(len(self.ids), dtype=bool)
        if self.labels is None:
            return np.zeros(len(self.ids), dtype=bool)
        return np.isin(self.labels, list(classes))


@runtime_checkable
class Rule(Protocol):
    """An analytics rule: one table of the scene file in, events and summary entries out."""

    #: the name the registry creates it by, and the scene file's key of its table
    name: ClassVar[str]
    section: ClassVar[str]
    #: the event types it emits (the docs' order) and their order in a frame for one track
    events: ClassVar[tuple[EventType, ...]]
    frame_order: ClassVar[tuple[str, ...]]
    #: the schema of its table (a ``SceneSection``), or None for a rule that parses by hand
    schema: ClassVar[type | None]
    #: whether the scene writes its table as an array of tables (``[[line]]``)
    many: ClassVar[bool]
    #: groups of keys of which a table gives exactly one (``("radius_px", "radius_m")``)
    exactly_one: ClassVar[tuple[tuple[str, ...], ...]]
    #: the scene keys of its table for the docs, of a rule without a schema
    keys: ClassVar[tuple[SceneKey, ...]]
    #: whether it needs each frame's static objects (``track --scene`` keeps a dual background)
    uses_static: ClassVar[bool]
    #: the units of the smoothed trajectories it measures (``"px"``, ``"m"``)
    smooths: tuple[str, ...]

    @classmethod
    def parse(cls, data: Any, camera: Any, where: str) -> Any:
        """The rule's spec from its table of the scene file (``data`` None: the table is
        absent); None when the rule does not run. Raises ``ConfigError`` naming the key."""

    @classmethod
    def build(cls, table: Any, camera: Any, where: str, earlier: tuple = ()) -> Any:
        """The spec of one table checked by the schema (``earlier``: the specs of the tables
        before it in an array), after the checks the schema cannot make."""

    @classmethod
    def camera_key(cls, spec: Any) -> str | None:
        """The key of ``spec`` in metres (the scene then needs a camera), or None."""

    @classmethod
    def idle_summary(cls) -> dict[str, Any]:
        """Its ``summary.json`` entries when the scene does not use it."""

    def step(self, frame: FrameTable) -> list[Event]:
        """The events of one frame."""

    def forget(self, frame: int, tid: int, state: TrackMemory) -> list[Event]:
        """The events of a track forgotten in ``frame`` (unseen for ``forget_s``)."""

    def reset(self) -> None:
        """Drop every track's state after a discontinuity of the source (no events: the tracks
        neither left nor ended; the engine forgets them all), keeping the totals."""

    def counts(self) -> dict[str, Any]:
        """``SceneFrame`` entries (``line_counts``, ``occupancy``) now."""

    def summary(self) -> dict[str, Any]:
        """Its entries of ``summary.json``."""


class BaseRule:
    """Defaults of the :class:`Rule` protocol: no camera key, no summary, nothing on
    forgetting. Subclasses set the class attributes and :meth:`step`."""

    name: ClassVar[str] = ""
    section: ClassVar[str] = ""
    events: ClassVar[tuple[EventType, ...]] = ()
    frame_order: ClassVar[tuple[str, ...]] = ()
    schema: ClassVar[type | None] = None
    many: ClassVar[bool] = False
    exactly_one: ClassVar[tuple[tuple[str, ...], ...]] = ()
    keys: ClassVar[tuple[SceneKey, ...]] = ()
    uses_static: ClassVar[bool] = False
    #: the units of the smoothed trajectories the rule measures (``"px"``, ``"m"``): the
    #: engine keeps them (:mod:`.smoothing`) and hands them in :attr:`FrameTable.smoothed`
    smooths: tuple[str, ...] = ()

    def __init__(self, spec: Any, context: RuleContext) -> None:
        self.spec, self.context = spec, context

    @classmethod
    def parse(cls, data: Any, camera: Any, where: str) -> Any:
        """Each table through :attr:`schema` (every key checked), :attr:`exactly_one` and
        :meth:`build`: a tuple of specs for an array of tables, else one spec or None; without
        a schema, the table as it is."""
        if cls.schema is None:
            return data
        if not cls.many:
            return None if data is None else cls._one(data, camera, where, ())
        specs: list[Any] = []
        for i, t in enumerate(array_of_tables(data, where), 1):
            specs.append(cls._one(t, camera, f"{where}[{i}]", tuple(specs)))
        return tuple(specs)

    @classmethod
    def _one(cls, data: Any, camera: Any, where: str, earlier: tuple) -> Any:
        table = from_dict(cls.schema, data, where)
        for keys in cls.exactly_one:
            one_of(table, keys, where)
        return cls.build(table, camera, where, earlier)

    @classmethod
    def build(cls, table: Any, camera: Any, where: str, earlier: tuple = ()) -> Any:
        return table

    @classmethod
    def camera_key(cls, spec: Any) -> str | None:
        return None

    @classmethod
    def idle_summary(cls) -> dict[str, Any]:
        return {}

    def step(self, frame: FrameTable) -> list[Event]:
        raise NotImplementedError

    def forget(self, frame: int, tid: int, state: TrackMemory) -> list[Event]:
        return []

    def reset(self) -> None:
        """Nothing kept by track id: the engine's new rows clear the :class:`Columns`."""

    def counts(self) -> dict[str, Any]:
        return {}

    def summary(self) -> dict[str, Any]:
        return {}


class Columns:
    """A rule's per-track state: arrays with one row per track row of the engine
    (:attr:`FrameTable.rows`), grown as the engine takes more rows, cleared where a new track
    takes a row (:attr:`FrameTable.fresh`); one fancy index reads or writes a frame's tracks.

    Parameters
    ----------
    width : int
        Columns per row (lines or zones of the scene).
    **dtypes
        Array name → dtype, each array ``(rows, width)``.
    """

    def __init__(self, width: int, **dtypes: Any) -> None:
        self._names = tuple(dtypes)
        for name, dtype in dtypes.items():
            setattr(self, name, np.zeros((16, width), dtype=dtype))

    def prepare(self, frame: FrameTable) -> None:
        """Room for every row of ``frame``, and its fresh rows cleared."""
        need = int(frame.rows.max()) + 1 if len(frame.rows) else 0
        for name in self._names:
            col = getattr(self, name)
            n = len(col)
            while n < need:
                n *= 2
            if n > len(col):
                grown = np.zeros((n,) + col.shape[1:], dtype=col.dtype)
                grown[:len(col)] = col
                setattr(self, name, grown)
            if len(frame.fresh):
                getattr(self, name)[frame.fresh] = 0


class RuleRegistry(Registry[Rule]):
    """The rules by name, in the order they were registered: the order of the scene file's
    keys, of running them each frame and of their ``summary.json`` entries. Registering a
    rule registers its event types."""

    def __init__(self) -> None:
        super().__init__("analytics rule")
        self._order: list[type] = []

    def register(self, rule: type) -> type:  # type: ignore[override]
        """Class decorator: ``@RULES.register``; the rule's :attr:`Rule.name` is its name."""
        if not rule.name or not rule.section:
            raise ValueError(f"rule {rule.__name__} needs a name and a section")
        if any(r.section == rule.section for r in self._order):
            raise ValueError(f"scene section {rule.section!r} already belongs to a rule")
        emitted = [e.name for r in self._order for e in r.events]
        for e in rule.events:
            if e.name in emitted:
                raise ValueError(f"event type {e.name!r} already belongs to a rule")
        super().register(rule.name)(rule)
        for e in rule.events:
            register_event_type(e.name, e.required, e.optional)
        self._order.append(rule)
        return rule

    def unregister(self, name: str) -> None:
        """Remove a rule and its plug-in event types (tests register rules of their own)."""
        rule = self.get(name)
        del self._items[name], self._docs[name]
        self._order.remove(rule)
        for e in rule.events:
            if e.name not in EVENT_TYPES:
                unregister_event_type(e.name)

    def ordered(self) -> tuple[type, ...]:
        """Every rule class in registration order."""
        return tuple(self._order)

    def event_order(self) -> dict[str, int]:
        """Event type → its rank among a frame's events of one track: rules in registration
        order, each in its :attr:`Rule.frame_order` (default: the order of its events)."""
        names = [n for r in self._order for n in (r.frame_order or [e.name for e in r.events])]
        return {n: i for i, n in enumerate(names)}

    def event_types(self) -> tuple[EventType, ...]:
        """Every rule's event types, in registration order."""
        return tuple(e for r in self._order for e in r.events)


#: the analytics rules; :mod:`.rules` registers the built-in ones
RULES = RuleRegistry()
