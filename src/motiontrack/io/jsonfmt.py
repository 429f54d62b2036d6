"""motiontrack JSON: a lossless, documented annotation format.

Schema (version 1)::

    {
      "format": "motiontrack",          required, exactly this string
      "version": 1,                     required, integer; readers refuse newer versions
      "meta": {...},                    optional, free JSON object (kept in Annotations.meta["json_meta"])
      "tracks": [                       required, list (may be empty)
        {
          "id": 7,                      required, integer (-1 = anonymous detections)
          "boxes": [                    required, list of observations of this id
            {
              "frame": 1,               required, integer >= 1 (MOTChallenge numbering)
              "box": [x, y, w, h],      required, 4 finite numbers, pixels, w > 0 and h > 0
              "score": 0.9,             optional, finite number, default 1
              "consider": true,         optional, boolean, default true
              "class": 1,               optional, integer, default -1
              "visibility": 0.8,        optional, finite number, default -1
              "world": [X, Y, Z]        optional, 3 finite numbers, default [-1, -1, -1]
            }
          ]
        }
      ]
    }

Unknown keys are errors (they are usually typos), as are ``NaN``/``Infinity``. The writer groups
rows by id (ids ascending, boxes by frame), writes optional fields only when they differ from the
default, and writes floats with ``repr`` precision, so ``read_json(write_json(a)) == a`` exactly
(up to row order).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import EXCERPT_CHARS, InputError, excerpt, location, printable
from ..types import INT_LIMIT, Annotations
from .atomic import atomic_open

__all__ = ["read_json", "parse_json", "write_json", "format_json", "FORMAT_NAME", "VERSION"]

FORMAT_NAME = "motiontrack"
VERSION = 1
_TOP_KEYS = {"format", "version", "meta", "tracks"}
_TRACK_KEYS = {"id", "boxes"}
_BOX_KEYS = {"frame", "box", "score", "consider", "class", "visibility", "world"}
#: deepest "meta" object kept (and written back by format_json, whose encoder recurses)
MAX_META_DEPTH = 64


def read_json(path: str | Path) -> Annotations:
    """Read a motiontrack JSON file (schema in the module docstring)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"annotation file not found: {p}")
    data = p.read_bytes()
    ann = parse_json(data, name=str(p))
    return Annotations(**{k: getattr(ann, k) for k in (
        "frames", "ids", "boxes", "scores", "consider", "classes", "visibility", "world")},
        meta={**ann.meta, "path": str(p)})


def _shown(v: Any) -> str:
    """A JSON value for a message: lists and objects by kind, anything else as a short excerpt
    (the file may be anything a user passed by mistake)."""
    if isinstance(v, dict):
        return "an object"
    if isinstance(v, list):
        return "a list"
    text = json.dumps(v)
    if isinstance(v, (int, float)) and not isinstance(v, bool) and len(text) <= EXCERPT_CHARS:
        return text
    return excerpt(text)


def _depth(obj: Any) -> int:
    """How deeply lists and objects nest in ``obj`` (a scalar is 0), without recursion."""
    deepest, stack = 0, [(obj, 1)]
    while stack:
        node, d = stack.pop()
        children = node.values() if isinstance(node, dict) else node if isinstance(node, list) \
            else None
        if children is None:
            continue
        deepest = max(deepest, d)
        stack.extend((c, d + 1) for c in children)
    return deepest


def _reject_constant(token: str) -> Any:
    raise ValueError(f"non-finite number {token} is not allowed")


def _int(v: Any, where: str, lo: int = -INT_LIMIT) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise InputError(f"{where}: expected an integer, got {_shown(v)}")
    if not lo <= v < INT_LIMIT:
        raise InputError(f"{where}: {_shown(v)} out of range [{lo}, 2**62)")
    return v


def _float(v: Any, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise InputError(f"{where}: expected a number, got {_shown(v)}")
    try:
        f = float(v)
    except OverflowError:
        raise InputError(f"{where}: number too large") from None
    if not math.isfinite(f):
        raise InputError(f"{where}: expected a finite number, got {_shown(v)}")
    return f


def _vec(v: Any, n: int, where: str) -> list[float]:
    if not isinstance(v, list) or len(v) != n:
        raise InputError(f"{where}: expected a list of {n} numbers, got {_shown(v)}")
    return [_float(x, f"{where}[{i}]") for i, x in enumerate(v)]


def _keys(obj: Any, allowed: set[str], required: tuple[str, ...], where: str) -> dict:
    if not isinstance(obj, dict):
        raise InputError(f"{where}: expected an object, got {type(obj).__name__}")
    unknown = sorted(set(obj) - allowed)
    if unknown:
        shown = ", ".join(excerpt(k) for k in unknown[:5])
        shown += f" and {len(unknown) - 5} more" if len(unknown) > 5 else ""
        raise InputError(f"{where}: unknown key(s) {shown}; allowed: "
                         f"{', '.join(sorted(allowed))}")
    for k in required:
        if k not in obj:
            raise InputError(f"{where}: missing required key {k!r}")
    return obj


def parse_json(data: bytes | str, name: str = "<json>") -> Annotations:
    """Parse motiontrack JSON into :class:`Annotations`; errors name the JSON path
    (``tracks[3].boxes[7].box``) or the line and column of a syntax error."""
    name = location(name)
    doc = _load(data, name)
    doc = _keys(doc, _TOP_KEYS, ("format", "version", "tracks"), f"{name}: top level")
    if doc["format"] != FORMAT_NAME:
        raise InputError(f"{name}: \"format\" must be {FORMAT_NAME!r}, got "
                         f"{_shown(doc['format'])}")
    version = _int(doc["version"], f"{name}: version")
    if version != VERSION:
        raise InputError(f"{name}: unsupported version {version} (this reader knows {VERSION})")
    meta_in = doc.get("meta", {})
    if not isinstance(meta_in, dict):
        raise InputError(f"{name}: meta: expected an object")
    if _depth(meta_in) > MAX_META_DEPTH:
        raise InputError(f"{name}: meta: nested deeper than {MAX_META_DEPTH} levels")
    tracks = doc["tracks"]
    if not isinstance(tracks, list):
        raise InputError(f"{name}: tracks: expected a list")
    rows = _Rows()
    for ti, tr in enumerate(tracks):
        where_t = f"{name}: tracks[{ti}]"
        tr = _keys(tr, _TRACK_KEYS, ("id", "boxes"), where_t)
        tid = _int(tr["id"], f"{where_t}.id")
        if not isinstance(tr["boxes"], list):
            raise InputError(f"{where_t}.boxes: expected a list")
        for bi, b in enumerate(tr["boxes"]):
            rows.add_box(b, tid, f"{where_t}.boxes[{bi}]")
    meta = {"format": "json"}
    if meta_in:
        meta["json_meta"] = meta_in
    return rows.annotations(meta)


def _load(data: bytes | str, name: str) -> Any:
    """The JSON document; syntax errors give the line and column."""
    try:
        return json.loads(data, parse_constant=_reject_constant)
    except json.JSONDecodeError as exc:
        # the decoder's messages ("Expecting ',' delimiter") quote nothing of the file
        raise InputError(f"{location(name, exc.lineno, exc.colno)}: malformed JSON: {exc.msg}") \
            from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{name}: not UTF-8 JSON (undecodable byte at offset {exc.start})") \
            from None
    except RecursionError:
        raise InputError(f"{name}: JSON nested too deeply") from None
    except ValueError as exc:  # _reject_constant, huge integer literals (no content quoted)
        raise InputError(f"{name}: malformed JSON: {printable(exc)}") from None


class _Rows:
    """Columns of the boxes read so far."""

    def __init__(self) -> None:
        self.frames: list[int] = []
        self.ids: list[int] = []
        self.boxes: list[list[float]] = []
        self.scores: list[float] = []
        self.consider: list[bool] = []
        self.classes: list[int] = []
        self.vis: list[float] = []
        self.world: list[list[float]] = []

    def add_box(self, b: Any, tid: int, w: str) -> None:
        """One observation of track ``tid``, checked field by field; ``w`` is its JSON path."""
        b = _keys(b, _BOX_KEYS, ("frame", "box"), w)
        self.frames.append(_int(b["frame"], f"{w}.frame", lo=1))
        box = _vec(b["box"], 4, f"{w}.box")
        if box[2] <= 0 or box[3] <= 0:
            raise InputError(f"{w}.box: width and height must be > 0, got w={box[2]}, "
                             f"h={box[3]}")
        self.boxes.append(box)
        self.ids.append(tid)
        self.scores.append(_float(b.get("score", 1.0), f"{w}.score"))
        c = b.get("consider", True)
        if not isinstance(c, bool):
            raise InputError(f"{w}.consider: expected true or false, got {_shown(c)}")
        self.consider.append(c)
        self.classes.append(_int(b.get("class", -1), f"{w}.class"))
        self.vis.append(_float(b.get("visibility", -1.0), f"{w}.visibility"))
        self.world.append(_vec(b.get("world", [-1.0, -1.0, -1.0]), 3, f"{w}.world"))

    def annotations(self, meta: dict) -> Annotations:
        if not self.frames:
            return Annotations.empty(meta)
        return Annotations.from_columns(self.frames, self.ids,
                                        np.asarray(self.boxes, dtype=np.float64),
                                        scores=self.scores, consider=self.consider,
                                        classes=self.classes, visibility=self.vis,
                                        world=np.asarray(self.world, dtype=np.float64), meta=meta)


def format_json(ann: Annotations, meta: dict | None = None) -> str:
    """JSON text for ``ann`` (schema in the module docstring). ``meta`` defaults to the
    ``"meta"`` of the file ``ann`` was read from (``ann.meta["json_meta"]``), if any."""
    if meta is None and isinstance(ann.meta.get("json_meta"), dict):
        meta = dict(ann.meta["json_meta"])
    tracks = []
    if len(ann):
        order = np.lexsort((ann.frames, ann.ids))
        ids = ann.ids[order]
        cuts = np.flatnonzero(np.diff(ids)) + 1
        for seg in np.split(order, cuts):
            rows = []
            for r in seg:
                row: dict[str, Any] = {"frame": int(ann.frames[r]),
                                       "box": [float(v) for v in ann.boxes[r]]}
                if ann.scores[r] != 1.0:
                    row["score"] = float(ann.scores[r])
                if not ann.consider[r]:
                    row["consider"] = False
                if ann.classes[r] != -1:
                    row["class"] = int(ann.classes[r])
                if ann.visibility[r] != -1.0:
                    row["visibility"] = float(ann.visibility[r])
                if np.any(ann.world[r] != -1.0):
                    row["world"] = [float(v) for v in ann.world[r]]
                rows.append(row)
            tracks.append({"id": int(ann.ids[seg[0]]), "boxes": rows})
    doc: dict[str, Any] = {"format": FORMAT_NAME, "version": VERSION}
    if meta:
        doc["meta"] = meta
    doc["tracks"] = tracks
    try:
        return json.dumps(doc, indent=1, allow_nan=False) + "\n"
    except ValueError as exc:
        raise InputError(f"cannot write JSON: {exc} (non-finite value in the annotations)") \
            from None


def write_json(ann: Annotations, path: str | Path, meta: dict | None = None) -> None:
    """Write ``ann`` as motiontrack JSON (atomically). ``meta`` (a JSON-able dict) is stored in
    the file's ``"meta"`` field."""
    text = format_json(ann, meta)
    with atomic_open(path) as fh:
        fh.write(text)
