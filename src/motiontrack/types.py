"""The data model: small frozen dataclasses that validate themselves.

Conventions
-----------
* Boxes are ``(x, y, w, h)`` in pixels of the *original* frame: ``x, y`` is the top-left corner,
  ``w, h`` the width and height (MOTChallenge convention).
* Frame numbers in :class:`Annotations` are 1-based (MOTChallenge); :class:`Frame.index` and
  :class:`FrameResult.index` are 0-based video frame indices, and :func:`frame_number` turns
  one into the other: every frame a run shows or writes (the annotated picture's label, stills,
  tracks, events, masks) carries ``frame_number(index)``.
* Stacked arrays are ``float64`` of shape ``(N, 4)``; every function handles ``N = 0``.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

#: the number of a source's first frame wherever a frame is shown or written (MOTChallenge)
FIRST_FRAME = 1


def frame_number(index: int) -> int:
    """The number frame ``index`` (0-based in its source) is shown and written with: the label
    of the annotated picture, stills, ``tracks.txt``, ``events.jsonl``, mask images (counting
    from :data:`FIRST_FRAME`, as MOTChallenge files do)."""
    return int(index) + FIRST_FRAME

__all__ = [
    "FIRST_FRAME",
    "frame_number",
    "Box",
    "Region",
    "TrackState",
    "Track",
    "Frame",
    "Discontinuity",
    "DISCONTINUITY_REASONS",
    "FrameResult",
    "PeopleFrame",
    "Annotations",
    "INT_LIMIT",
    "Event",
    "EVENT_TYPES",
    "event_types",
    "register_event_type",
    "unregister_event_type",
    "EVENTS_SCHEMA",
    "EVENTS_SCHEMA_VERSION",
    "events_header",
    "SceneFrame",
    "StaticObject",
    "StaticFrame",
]


@dataclass(frozen=True)
class Box:
    """Axis-aligned box ``(x, y, w, h)`` in pixels; ``x, y`` is the top-left corner."""

    x: float
    y: float
    w: float
    h: float

    def __post_init__(self) -> None:
        # one cheap test on the common path (boxes are made for every region and track of every
        # frame); the message is worked out only for a bad box
        if self.w > 0 and self.h > 0 and math.isfinite(self.x + self.y + self.w + self.h):
            return
        for name, v in (("x", self.x), ("y", self.y), ("w", self.w), ("h", self.h)):
            if not math.isfinite(v):
                raise ValueError(f"box {name} must be finite, got {name}={v!r}")
        if not (self.w > 0 and self.h > 0):
            raise ValueError(f"box must have w > 0 and h > 0, got w={self.w}, h={self.h}")
        raise ValueError(f"box coordinates too large: {self}")

    @property
    def x2(self) -> float:
        return self.x + self.w

    @property
    def y2(self) -> float:
        return self.y + self.h

    @property
    def center(self) -> tuple[float, float]:
        return (self.x + self.w / 2.0, self.y + self.h / 2.0)

    @property
    def bottom_center(self) -> tuple[float, float]:
        """The foot point: where a standing person touches the ground plane."""
        return (self.x + self.w / 2.0, self.y + self.h)

    @property
    def area(self) -> float:
        return self.w * self.h

    def as_array(self) -> np.ndarray:
        return np.array([self.x, self.y, self.w, self.h], dtype=np.float64)

    @classmethod
    def from_xyxy(cls, x1: float, y1: float, x2: float, y2: float) -> "Box":
        return cls(float(x1), float(y1), float(x2 - x1), float(y2 - y1))

    @classmethod
    def from_center(cls, xc: float, yc: float, w: float, h: float) -> "Box":
        return cls(float(xc - w / 2.0), float(yc - h / 2.0), float(w), float(h))


@dataclass(frozen=True)
class Region:
    """A connected foreground region (blob) found in a motion mask.

    Attributes
    ----------
    box : Box
        Bounding box in original-frame pixels.
    centroid : tuple of float
        Centre of mass ``(cx, cy)`` from image moments, original-frame pixels.
    area : float
        Number of foreground pixels, in original-frame pixels² (scaled back when the detector ran on
        a smaller image).
    score : float
        Detection confidence; 1.0 for motion regions, the detector score for external detections.
    """

    box: Box
    centroid: tuple[float, float]
    area: float
    score: float = 1.0

    def __post_init__(self) -> None:
        if self.area < 0:
            raise ValueError(f"region area must be >= 0, got area={self.area}")


class TrackState(str, enum.Enum):
    """Track lifecycle: tentative → confirmed → lost → deleted."""

    TENTATIVE = "tentative"
    CONFIRMED = "confirmed"
    LOST = "lost"
    DELETED = "deleted"


@dataclass(frozen=True)
class Track:
    """A snapshot of one track after a frame's update.

    Attributes
    ----------
    id : int
        Stable integer identity (1-based, never reused within a run).
    box : Box
        Current box (the filtered estimate, original pixels).
    state : TrackState
    velocity : tuple of float
        Centre velocity ``(vx, vy)`` in pixels per frame.
    hits : int
        Frames with an associated measurement.
    age : int
        Frames since the track was born.
    time_since_update : int
        Frames since the last associated measurement (0 = measured this frame).
    history : tuple
        Recent centre points ``((x, y), ...)`` for trails; bounded length.
    label : str
        The track's class (``person``, ``vehicle``, ``other``; :mod:`motiontrack.classify`),
        ``""`` when no classifier ran.
    label_score : float
        The confidence of ``label`` in [0, 1]: its share of the track's votes so far.
    """

    id: int
    box: Box
    state: TrackState
    velocity: tuple[float, float] = (0.0, 0.0)
    hits: int = 1
    age: int = 1
    time_since_update: int = 0
    history: tuple[tuple[float, float], ...] = ()
    score: float = 1.0
    label: str = ""
    label_score: float = 0.0

    def __post_init__(self) -> None:
        if self.id < 1:
            raise ValueError(f"track id must be >= 1, got id={self.id}")


#: why a source's frames jump: ``loop`` (a file played again from its start), ``reconnect`` (a
#: live source back after a gap), ``seek`` (the source was positioned at a start frame)
DISCONTINUITY_REASONS = ("loop", "reconnect", "seek")


@dataclass(frozen=True)
class Discontinuity:
    """The mark of the first frame after a jump in a source's picture or time: what the
    stages learnt from the frames before it (background models, tracks, the analytics' stays
    and zone occupants) no longer applies (:meth:`motiontrack.pipeline.Pipeline.reset`).

    Attributes
    ----------
    reason : str
        One of :data:`DISCONTINUITY_REASONS`.
    """

    reason: str

    def __post_init__(self) -> None:
        if self.reason not in DISCONTINUITY_REASONS:
            raise ValueError(f"discontinuity reason must be one of "
                             f"{', '.join(DISCONTINUITY_REASONS)}, got {self.reason!r}")

    def to_json(self, frame: int) -> dict:
        """The record of ``events.jsonl`` and of serve's event stream, at 1-based ``frame``."""
        return {"type": "discontinuity", "reason": self.reason, "frame": int(frame)}


@dataclass(frozen=True)
class Frame:
    """One decoded frame.

    Attributes
    ----------
    index : int
        0-based frame index in the source.
    image : np.ndarray
        ``(H, W, 3) uint8`` BGR (or ``(H, W) uint8`` gray).
    timestamp : float
        Seconds: the source's position for files, wall-clock time for live sources.
    discontinuity : Discontinuity or None
        Set on the first frame after a jump (a loop, a reconnection, a seek).
    """

    index: int
    image: np.ndarray = field(repr=False)
    timestamp: float = 0.0
    discontinuity: Discontinuity | None = None

    def __post_init__(self) -> None:
        if self.index < 0:
            raise ValueError(f"frame index must be >= 0, got index={self.index}")
        if not isinstance(self.image, np.ndarray) or self.image.ndim not in (2, 3):
            raise ValueError("frame image must be a 2-D or 3-D numpy array")


@dataclass(frozen=True)
class PeopleFrame:
    """What the people stage found in one frame (:class:`motiontrack.people.PeopleStage`).

    Attributes
    ----------
    heads : tuple of :class:`motiontrack.people.heads.Head`
        Heads found in the motion regions (also those of ``people.auto_split``).
    shapes : tuple of :class:`motiontrack.people.shape_tracker.FittedShape`
        Active shapes fitted this frame, one per tracked person.
    hog : tuple of Region
        HOG people detections.
    hypotheses : tuple of Region
        Fitted boxes offered to lost people (``people.hypotheses``), for drawing.
    hypotheses_by_track : mapping of track id → Region
        The fitted box of every tracked person no region covers: the tracker may apply it to
        that one lost track, never start a track from it.
    located_by_track : mapping of track id → (4,) float64 box
        Where each tracked person's outline was fitted this frame (``people.shape_split``): its
        share of a merged region.
    """

    heads: tuple = ()
    shapes: tuple = ()
    hog: tuple[Region, ...] = ()
    hypotheses: tuple[Region, ...] = ()
    hypotheses_by_track: Mapping[int, Region] = field(default_factory=dict)
    located_by_track: Mapping[int, np.ndarray] = field(default_factory=dict)


@dataclass(frozen=True)
class FrameResult:
    """What the pipeline yields for each frame.

    ``mask`` is the cleaned motion mask (``uint8``, 0/255) at processing resolution as the
    regions' silhouettes (``regions.silhouettes``: specks out, holes filled; the tracker
    had the mask before that), or ``None`` when detections came from elsewhere; ``raw_mask`` the
    detector's mask before clean-up.
    ``people`` is what the people stage (or ``people.auto_split``'s head search) found, when it
    ran; ``static`` the recently stopped objects of the dual background, when the run asked
    for them (a scene with ``[abandoned]``). ``earlier`` holds the tracks confirmed in this frame at the earlier frames where they
    were still tentative, as ``(frame index, Track)`` pairs (empty unless ``tracker.backfill``
    applies to the run). ``discontinuity`` is the frame's :attr:`Frame.discontinuity`: the
    stages were reset before it. Every value is an attribute or a property (:attr:`reported`),
    never a method to call.
    """

    index: int
    timestamp: float
    frame: np.ndarray = field(repr=False)
    mask: np.ndarray | None = field(repr=False)
    regions: tuple[Region, ...]
    tracks: tuple[Track, ...]
    raw_mask: np.ndarray | None = field(default=None, repr=False)
    people: PeopleFrame | None = field(default=None, repr=False)
    earlier: tuple[tuple[int, Track], ...] = field(default=(), repr=False)
    scene: SceneFrame | None = field(default=None, repr=False)
    static: StaticFrame | None = field(default=None, repr=False)
    discontinuity: Discontinuity | None = None

    @property
    def reported(self) -> tuple[tuple[int, Track], ...]:
        """``(frame index, track)`` rows this frame adds to a tracks file: its tracks, then the
        tracks confirmed in it at their earlier, tentative frames (:attr:`earlier`)."""
        return (*((self.index, t) for t in self.tracks), *self.earlier)


#: frame numbers, ids and classes are int64 columns: readers refuse values at or beyond this
INT_LIMIT = 2**62

_ANN_COLUMNS = ("frames", "ids", "boxes", "scores", "consider", "classes", "visibility", "world")


@dataclass(frozen=True, eq=False)
class Annotations:
    """A table of boxes over frames: ground truth, tracker output or detections.

    All columns are numpy arrays of equal length N (N may be 0).

    Attributes
    ----------
    frames : (N,) int64
        1-based frame numbers (MOTChallenge).
    ids : (N,) int64
        Object / track ids (-1 for anonymous detections).
    boxes : (N, 4) float64
        ``x, y, w, h`` in pixels.
    scores : (N,) float64
        Confidence (ground truth: 1).
    consider : (N,) bool
        MOTChallenge "consider" flag: ``False`` marks ignore regions / distractors.
    classes : (N,) int64
        MOTChallenge class id (1 = pedestrian; -1 unknown).
    visibility : (N,) float64
        Visible fraction in [0, 1] (-1 unknown).
    world : (N, 3) float64
        World coordinates (metres for ours; -1 unknown).
    """

    frames: np.ndarray
    ids: np.ndarray
    boxes: np.ndarray
    scores: np.ndarray
    consider: np.ndarray
    classes: np.ndarray
    visibility: np.ndarray
    world: np.ndarray
    meta: Mapping[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = len(self.frames)
        for name in _ANN_COLUMNS:
            col = getattr(self, name)
            if not isinstance(col, np.ndarray) or len(col) != n:
                raise ValueError(
                    f"annotation column {name!r} must be an array of length {n}, "
                    f"got {type(col).__name__} of length {len(col)}"
                )
        if self.boxes.shape != (n, 4):
            raise ValueError(f"boxes must have shape ({n}, 4), got {self.boxes.shape}")
        if self.world.shape != (n, 3):
            raise ValueError(f"world must have shape ({n}, 3), got {self.world.shape}")

    @classmethod
    def from_columns(
        cls,
        frames,
        ids,
        boxes,
        scores=None,
        consider=None,
        classes=None,
        visibility=None,
        world=None,
        meta: Mapping[str, object] | None = None,
    ) -> "Annotations":
        """Build from array-likes, filling missing columns with their defaults."""
        frames = np.asarray(frames, dtype=np.int64).reshape(-1)
        n = len(frames)
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        boxes = np.asarray(boxes, dtype=np.float64).reshape(n, 4)

        def col(v, default, dtype):
            if v is None:
                return np.full(n, default, dtype=dtype)
            return np.asarray(v, dtype=dtype).reshape(-1)

        return cls(
            frames=frames,
            ids=ids,
            boxes=boxes,
            scores=col(scores, 1.0, np.float64),
            consider=col(consider, True, bool),
            classes=col(classes, -1, np.int64),
            visibility=col(visibility, -1.0, np.float64),
            world=(
                np.full((n, 3), -1.0, dtype=np.float64)
                if world is None
                else np.asarray(world, dtype=np.float64).reshape(n, 3)
            ),
            meta=dict(meta or {}),
        )

    @classmethod
    def empty(cls, meta: Mapping[str, object] | None = None) -> "Annotations":
        return cls.from_columns(np.zeros(0), np.zeros(0), np.zeros((0, 4)), meta=meta)

    def __len__(self) -> int:
        return len(self.frames)

    def select(self, mask: np.ndarray) -> "Annotations":
        """Rows where the boolean ``mask`` is true (a new object; inputs are never mutated)."""
        return Annotations(**{c: getattr(self, c)[mask] for c in _ANN_COLUMNS}, meta=self.meta)

    def sorted(self) -> "Annotations":
        """The rows sorted by frame, then id (stable: equal pairs keep their order)."""
        return self.select(np.lexsort((self.ids, self.frames)))

    def frame_numbers(self) -> np.ndarray:
        """Sorted unique frame numbers present."""
        return np.unique(self.frames)

    def at(self, frame: int) -> "Annotations":
        return self.select(self.frames == frame)

    def by_frame(self) -> dict[int, np.ndarray]:
        """Map frame number → row indices (sorted by frame); one pass, O(N log N)."""
        if len(self) == 0:
            return {}
        order = np.argsort(self.frames, kind="stable")
        f = self.frames[order]
        cuts = np.flatnonzero(np.diff(f)) + 1
        return {int(g[0]): idx for g, idx in zip(np.split(f, cuts), np.split(order, cuts))}

    def concat(self, other: "Annotations") -> "Annotations":
        return Annotations(
            **{c: np.concatenate([getattr(self, c), getattr(other, c)]) for c in _ANN_COLUMNS},
            meta={**self.meta, **other.meta},
        )


# ------------------------------------------------------------------------------------- events
#: every event type scene analytics emits, in the order documentation lists them
EVENT_TYPES = (
    "line_cross",
    "zone_enter",
    "zone_exit",
    "loiter",
    "stationary_start",
    "stationary_end",
    "abandoned",
    "speeding",
)

#: the ``schema`` of an events file's header line, and its version (raised on any change a reader
#: of the previous version would misread)
EVENTS_SCHEMA = "motiontrack.events"
EVENTS_SCHEMA_VERSION = 1

#: the fields each type needs beyond ``type, frame, t, track, x, y`` (``speeding`` needs exactly
#: one of its two speeds), and the optional ones it may carry
_EVENT_REQUIRED = {
    "line_cross": ("line", "direction"),
    "zone_enter": ("zone",),
    "zone_exit": ("zone", "dwell_s"),
    "loiter": ("zone", "dwell_s"),
    "stationary_start": (),
    "stationary_end": ("duration_s",),
    "abandoned": ("duration_s",),
    "speeding": (),
}
_EVENT_OPTIONAL = {"abandoned": ("owner",), "speeding": ("speed_mps", "speed_px_s")}
#: every type an :class:`Event` may have: the built-in ones, then those analytics rules register
_EVENT_ORDER = list(EVENT_TYPES)
#: the JSON key order of every event (absent keys are left out)
_EVENT_KEYS = (
    "type", "frame", "t", "track", "x", "y", "X", "Y", "line", "direction", "zone", "dwell_s",
    "speed_mps", "speed_px_s", "duration_s", "owner", "label",
)  # fmt: skip
_EVENT_EXTRA = ("line", "direction", "zone", "dwell_s", "speed_mps", "speed_px_s", "duration_s", "owner")
_EVENT_STR = ("line", "direction", "zone", "label")
_EVENT_INT = ("frame", "track", "owner")


def event_types() -> tuple[str, ...]:
    """Every event type known now: :data:`EVENT_TYPES`, then the types of plug-in analytics
    rules (:func:`register_event_type`) in the order they were registered."""
    return tuple(_EVENT_ORDER)


def register_event_type(name: str, required: tuple[str, ...] = (),
                        optional: tuple[str, ...] = ()) -> None:
    """Make ``name`` a valid :class:`Event` type carrying the fields ``required`` and maybe
    ``optional`` (beyond ``type, frame, t, track, x, y``; each one of the event's fields).

    An analytics rule registers the types it emits (:mod:`motiontrack.analytics.rule`);
    registering a type again with the same fields does nothing, with other fields it is an
    error (a built-in type's fields are fixed here, where events files are read without the
    rules).
    """
    required, optional = tuple(required), tuple(optional)
    bad = [f for f in required + optional if f not in _EVENT_EXTRA]
    if bad:
        raise ValueError(f"event type {name!r}: unknown field {bad[0]!r}; an event's fields "
                         f"are {', '.join(_EVENT_EXTRA)}")
    if name in _EVENT_REQUIRED:
        if (_EVENT_REQUIRED[name], _EVENT_OPTIONAL.get(name, ())) != (required, optional):
            raise ValueError(f"event type {name!r} is already registered with other fields")
        return
    if not (isinstance(name, str) and name.isidentifier()):
        raise ValueError(f"an event type must be a name of letters, digits and _, got {name!r}")
    _EVENT_REQUIRED[name] = required
    if optional:
        _EVENT_OPTIONAL[name] = optional
    _EVENT_ORDER.append(name)


def unregister_event_type(name: str) -> None:
    """Forget a type :func:`register_event_type` added (the built-in types stay)."""
    if name in EVENT_TYPES or name not in _EVENT_REQUIRED:
        raise ValueError(f"event type {name!r} is not a registered plug-in type")
    del _EVENT_REQUIRED[name]
    _EVENT_OPTIONAL.pop(name, None)
    _EVENT_ORDER.remove(name)


@dataclass(frozen=True)
class Event:
    """One scene-analytics event: what happened, when, to which track and where.

    Attributes
    ----------
    type : str
        One of :func:`event_types`: :data:`EVENT_TYPES` and those of plug-in rules.
    frame : int
        1-based frame number (MOTChallenge numbering).
    t : float
        Seconds since the first frame, ``(frame - 1) / fps``.
    track : int
        The track the event is about.
    x, y : float
        The track's anchor point in source-frame pixels.
    X, Y : float or None
        The anchor on the ground plane in metres (only with a camera calibration; both or none).
    line, direction : str or None
        ``line_cross``: the line's name and ``"in"`` or ``"out"``.
    zone : str or None
        ``zone_enter``, ``zone_exit``, ``loiter``: the zone's name.
    dwell_s : float or None
        ``zone_exit``, ``loiter``: seconds in the zone so far.
    speed_mps, speed_px_s : float or None
        ``speeding``: metres per second (with a camera) or pixels per second (without); exactly one.
    duration_s : float or None
        ``stationary_end``, ``abandoned``: seconds the object has been static.
    owner : int or None
        ``abandoned``: the track that left the object, when known.
    label : str or None
        The track's class at the event (``person``, ``vehicle``, ``other``), when the tracks
        were classified (``classes.enabled``); any type may carry it.
    """

    type: str
    frame: int
    t: float
    track: int
    x: float
    y: float
    X: float | None = None
    Y: float | None = None
    line: str | None = None
    direction: str | None = None
    zone: str | None = None
    dwell_s: float | None = None
    speed_mps: float | None = None
    speed_px_s: float | None = None
    duration_s: float | None = None
    owner: int | None = None
    label: str | None = None

    def __post_init__(self) -> None:
        if self.type not in _EVENT_REQUIRED:
            raise ValueError(f"event type must be one of {', '.join(_EVENT_ORDER)}, got {self.type!r}")
        for name in _EVENT_KEYS[1:]:
            v = getattr(self, name)
            if v is None:
                continue
            if name in _EVENT_STR:
                ok = isinstance(v, str) and v != ""
                expected = "a non-empty string"
            elif name in _EVENT_INT:
                ok = isinstance(v, (int, np.integer)) and not isinstance(v, bool)
                expected = "an integer"
            else:
                ok = isinstance(v, (int, float, np.number)) and not isinstance(v, bool)
                ok = ok and math.isfinite(v)
                expected = "a finite number"
            if not ok:
                raise ValueError(f"{self.type} event {name} must be {expected}, got {v!r}")
        for name in ("frame", "t", "track", "x", "y"):
            if getattr(self, name) is None:
                raise ValueError(f"{self.type} event needs {name}")
        if self.frame < 1:
            raise ValueError(f"event frame must be >= 1 (1-based), got frame={self.frame}")
        if self.t < 0:
            raise ValueError(f"event t must be >= 0 seconds, got t={self.t}")
        if (self.X is None) != (self.Y is None):
            raise ValueError(f"{self.type} event needs both X and Y or neither")
        required = _EVENT_REQUIRED[self.type]
        allowed = required + _EVENT_OPTIONAL.get(self.type, ())
        for name in _EVENT_EXTRA:
            present = getattr(self, name) is not None
            if name in required and not present:
                raise ValueError(f"{self.type} event needs {name}")
            if present and name not in allowed:
                raise ValueError(f"{self.type} event cannot have {name}")
        if self.direction is not None and self.direction not in ("in", "out"):
            raise ValueError(f"line_cross direction must be 'in' or 'out', got {self.direction!r}")
        if self.type == "speeding" and (self.speed_mps is None) == (self.speed_px_s is None):
            raise ValueError("speeding event needs exactly one of speed_mps and speed_px_s")
        for name in ("dwell_s", "duration_s", "speed_mps", "speed_px_s"):
            v = getattr(self, name)
            if v is not None and v < 0:
                raise ValueError(f"{self.type} event {name} must be >= 0, got {v}")

    def to_json(self) -> dict:
        """The event as one JSON object: keys in schema order, absent ones left out."""
        out = {}
        for name in _EVENT_KEYS:
            v = getattr(self, name)
            if v is None:
                continue
            if name in _EVENT_INT:
                v = int(v)
            elif name not in _EVENT_STR and name != "type":
                v = float(v)
            out[name] = v
        return out

    @classmethod
    def from_json(cls, obj: Mapping) -> "Event":
        """The event an object of an events file describes (:meth:`to_json`'s inverse).

        Raises ``ValueError`` naming the problem for anything that is not an event of this
        schema version: not an object, an unknown type or key, a missing or mistyped field.
        """
        if not isinstance(obj, Mapping):
            raise ValueError(f"an event must be a JSON object, got {type(obj).__name__}")
        kind = obj.get("type")
        if kind not in _EVENT_REQUIRED:
            shown = repr(kind)[:40]
            raise ValueError(f"event type must be one of {', '.join(_EVENT_ORDER)}, got {shown}")
        unknown = [str(k) for k in obj if k not in _EVENT_KEYS]
        if unknown:
            raise ValueError(f"{kind} event has unknown key {unknown[0][:40]!r}")
        for name in ("frame", "t", "track", "x", "y"):
            if name not in obj:
                raise ValueError(f"{kind} event needs {name}")
        values = dict(obj)
        for name in _EVENT_KEYS[1:]:
            v = values.get(name)
            # JSON has one number type: 3.0 is a fine frame, 3.5 is not; ints are fine floats
            if name in _EVENT_INT and isinstance(v, float) and v.is_integer():
                values[name] = int(v)
            elif name not in _EVENT_INT and name not in _EVENT_STR:
                if isinstance(v, int) and not isinstance(v, bool):
                    values[name] = float(v)
        return cls(**values)


def events_header(fps: float, source: str = "", scene: str = "") -> dict:
    """The first line of an events file: schema name and version, frame rate, what was analysed."""
    return {
        "schema": EVENTS_SCHEMA,
        "version": EVENTS_SCHEMA_VERSION,
        "fps": float(fps),
        "source": str(source),
        "scene": str(scene),
    }


@dataclass(frozen=True)
class SceneFrame:
    """What scene analytics made of one frame's tracks (:class:`motiontrack.analytics.Analytics`).

    Attributes
    ----------
    frame : int
        1-based frame number.
    events : tuple of Event
        The events of this frame, in a fixed order (by track, then rule).
    line_counts : mapping of line name → (in, out)
        Crossings of each line so far.
    occupancy : mapping of zone name → int
        Tracks inside each zone after this frame.
    discontinuity : Discontinuity or None
        Set when the analytics' per-track state was reset before this frame.
    """

    frame: int
    events: tuple[Event, ...] = ()
    line_counts: Mapping[str, tuple[int, int]] = field(default_factory=dict)
    occupancy: Mapping[str, int] = field(default_factory=dict)
    discontinuity: Discontinuity | None = None


@dataclass(frozen=True)
class StaticObject:
    """A recently stopped object: a blob of static foreground (foreground in a slowly learning
    background model, background in a fast one; :class:`motiontrack.motion.static.DualBackground`).

    Attributes
    ----------
    box : Box
        Bounding box in source-frame pixels.
    area : float
        Static pixels, in source-frame pixels².
    frames : int
        Frames its longest-static pixel has been static foreground.
    change : float
        Mean difference (largest colour channel, levels) of the frame from the short-term
        background over the object's pixels: about the sensor noise for a still object in view,
        more for one that moves a little (a standing person) or is hidden behind a passer-by.
    """

    box: Box
    area: float
    frames: int
    change: float = 0.0


@dataclass(frozen=True)
class StaticFrame:
    """The static foreground of one frame: its objects and the mask they came from
    (``(h, w) uint8`` 0/255 at processing scale; None before the models have settled)."""

    objects: tuple[StaticObject, ...] = ()
    mask: np.ndarray | None = field(default=None, repr=False)
