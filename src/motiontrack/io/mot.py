"""MOTChallenge CSV: ground truth, tracker results and detections; ``seqinfo.ini``.

Layouts (columns, 1-based):

* MOT15 / results / detections (10 columns):
  ``frame, id, left, top, width, height, conf|consider, world_x, world_y, world_z``
* MOT16/17/20 ground truth (9 columns): ``frame, id, left, top, width, height, consider, class,
  visibility``
* motiontrack tracks with classes (11 columns): the 10 of results, then ``class`` (1 person,
  3 vehicle, 0 other: :mod:`motiontrack.classify`). Readers of the 10-column layout (and
  TrackEval's) read the first ten and ignore it.

In ground truth, column 7 is the *consider* flag (0 = ignore); in results and detections it is the
confidence. Frames are 1-based.
"""

from __future__ import annotations

import io
import math
import re
import warnings
from pathlib import Path
from typing import Iterable

import numpy as np

from ..errors import InputError, excerpt, finite_number, location, require_file
from ..types import INT_LIMIT, Annotations
from .atomic import atomic_open

__all__ = ["read_mot", "parse_mot", "write_mot", "format_mot_rows", "read_seqinfo"]


def read_mot(path: str | Path, kind: str = "auto") -> Annotations:
    """Read a MOTChallenge CSV file.

    Parameters
    ----------
    path : path of the ``.txt``/``.csv`` file.
    kind : ``"gt"`` (column 7 = consider flag), ``"results"``/``"det"`` (column 7 = confidence), or
        ``"auto"``: ``gt`` when the file is named ``gt*`` and otherwise ``results``.
    """
    p = require_file(path, "annotation file")
    if kind == "auto":
        kind = "gt" if p.name.lower().startswith("gt") else "results"
    try:
        text = p.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{location(p)}: not a text file ({exc.reason} at byte {exc.start})") \
            from None
    ann = parse_mot(text, kind=kind, name=str(p))
    return Annotations(**{k: getattr(ann, k) for k in (
        "frames", "ids", "boxes", "scores", "consider", "classes", "visibility", "world")},
        meta={"format": "mot", "kind": kind, "path": str(p)})


def _fast_rows(text: str) -> tuple[np.ndarray, int] | None:
    """Well-formed comma-separated text parsed in one vectorised pass (``np.loadtxt``), or None
    when anything is unusual — then the line-by-line parser runs and names the bad line."""
    if "," not in text or "#" in text:
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            a = np.loadtxt(io.StringIO(text), delimiter=",", dtype=np.float64, ndmin=2)
    except (ValueError, UserWarning):
        return None
    if a.size == 0 or a.shape[1] < 6:
        return None
    ncols = a.shape[1]
    a = a[:, :11]
    frame, ident = a[:, 0], a[:, 1]
    klass = a[:, 7] if a.shape[1] > 7 else np.zeros(len(a))
    if a.shape[1] > 10:
        klass = np.column_stack([klass, a[:, 10]])
    ok = (np.isfinite(a).all() and (frame >= 1).all() and (frame == np.floor(frame)).all()
          and (a[:, 4] > 0).all() and (a[:, 5] > 0).all()
          and (np.abs(np.column_stack([frame, ident, klass])) < INT_LIMIT).all())
    if not ok:
        return None
    if a.shape[1] < 11:
        a = np.hstack([a, np.full((len(a), 11 - a.shape[1]), -1.0)])
    return a, ncols


def parse_mot(text: str, kind: str = "results", name: str = "<string>") -> Annotations:
    """Parse MOTChallenge CSV text; a malformed line raises :class:`InputError` naming it."""
    if kind not in ("gt", "results", "det"):
        raise ValueError(f"kind must be 'gt', 'results' or 'det', got {kind!r}")
    fast = _fast_rows(text)
    if fast is not None:
        return _annotations(*fast, kind)
    rows: list[list[float]] = []
    ncols: int | None = None
    for lineno, raw in enumerate(io.StringIO(text), start=1):
        line = raw.rstrip("\r\n")
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = _split_fields(line)
        if len(fields) < 6:
            raise InputError(f"{location(name, lineno)}: expected at least 6 comma-separated "
                             f"values (frame,id,left,top,width,height), got {len(fields)}")
        vals = [finite_number(tok, location(name, lineno, col), _field(k))
                for k, (col, tok) in enumerate(fields[:11])]
        # frame, id, (9-column gt) class and (11-column) class become int64: refuse values
        # that cannot be one
        for k in (0, 1, 7, 10):
            if k < len(vals) and abs(vals[k]) >= INT_LIMIT:
                col, tok = fields[k]
                raise InputError(f"{location(name, lineno, col)}: {_field(k)} out of range "
                                 f"(|value| < 2**62), got {excerpt(tok)}")
        if vals[0] < 1 or not float(vals[0]).is_integer():
            raise InputError(f"{location(name, lineno, fields[0][0])}: frame must be an integer "
                             f">= 1, got {excerpt(fields[0][1])}")
        for k in (4, 5):
            if vals[k] <= 0:
                col, tok = fields[k]
                raise InputError(f"{location(name, lineno, col)}: box width and height must be "
                                 f"> 0, got {_field(k)} {excerpt(tok)}")
        ncols = len(fields) if ncols is None else ncols
        rows.append(vals + [-1.0] * (11 - len(vals)))
    if not rows:
        return Annotations.empty()
    return _annotations(np.asarray(rows, dtype=np.float64), ncols, kind)


_FIELDS = ("frame", "id", "left", "top", "width", "height")


def _field(k: int) -> str:
    """The name of (0-based) field ``k`` for messages: ``field 3 (left)``."""
    return f"field {k + 1}" + (f" ({_FIELDS[k]})" if k < len(_FIELDS) else "")


def _split_fields(line: str) -> list[tuple[int, str]]:
    """The fields of a row (comma-separated, or whitespace-separated when it has no comma), each
    with the 1-based character column where it starts."""
    if "," not in line:
        return [(m.start() + 1, m.group()) for m in re.finditer(r"\S+", line)]
    out, start = [], 0
    for part in line.split(","):
        lead = len(part) - len(part.lstrip())
        out.append((start + lead + 1, part.strip()))
        start += len(part) + 1
    return out


def _annotations(a: np.ndarray, ncols: int | None, kind: str) -> Annotations:
    """Rows padded to 11 columns → :class:`Annotations` for the given ``kind``."""
    n = len(a)
    if kind == "gt":
        consider = a[:, 6] != 0
        scores = np.ones(n)
    else:
        consider = np.ones(n, dtype=bool)
        scores = a[:, 6]
    if ncols == 9 and kind == "gt":
        # MOT16/17/20 ground truth: class and visibility
        classes, visibility = a[:, 7].astype(np.int64), a[:, 8]
        world = np.full((n, 3), -1.0)
    else:
        classes, visibility = np.full(n, -1, dtype=np.int64), np.full(n, -1.0)
        world = a[:, 7:10]
        if ncols is not None and ncols >= 11 and kind != "gt":
            classes = a[:, 10].astype(np.int64)
    return Annotations.from_columns(
        frames=a[:, 0].astype(np.int64), ids=a[:, 1].astype(np.int64), boxes=a[:, 2:6],
        scores=scores, consider=consider, classes=classes, visibility=visibility, world=world,
    )


def _fmt(v: float) -> str:
    return f"{v:.6g}" if not float(v).is_integer() else str(int(v))


def format_mot_rows(frames: Iterable[int], ids: Iterable[int], boxes: np.ndarray,
                    scores: Iterable[float] | None = None, world: np.ndarray | None = None,
                    classes: Iterable[int] | None = None) -> str:
    """Rows of a MOTChallenge *results* file (10 columns), newline-terminated; with
    ``classes``, each row's class number in an 11th column."""
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    n = len(boxes)
    scores = np.ones(n) if scores is None else np.asarray(list(scores), dtype=np.float64)
    world = np.full((n, 3), -1.0) if world is None else np.asarray(world, dtype=np.float64)
    out = []
    for f, i, b, s, w in zip(frames, ids, boxes, scores, world):
        out.append(
            f"{int(f)},{int(i)},{b[0]:.2f},{b[1]:.2f},{b[2]:.2f},{b[3]:.2f},{_fmt(s)},"
            f"{_fmt(w[0])},{_fmt(w[1])},{_fmt(w[2])}\n"
        )
    if classes is not None:
        out = [f"{row[:-1]},{int(k)}\n" for row, k in zip(out, classes)]
    return "".join(out)


def write_mot(ann: Annotations, path: str | Path, kind: str = "results") -> None:
    """Write annotations as MOTChallenge CSV (atomically). ``kind="gt"`` writes the consider flag
    in column 7 and, when classes are known, the 9-column MOT17 layout."""
    a = ann.sorted()
    with atomic_open(path) as fh:
        if kind == "gt" and len(a) and (a.classes >= 0).any():
            for f, i, b, c, k, v in zip(a.frames, a.ids, a.boxes, a.consider, a.classes, a.visibility):
                fh.write(f"{f},{i},{b[0]:.2f},{b[1]:.2f},{b[2]:.2f},{b[3]:.2f},{int(c)},{k},{_fmt(v)}\n")
        else:
            col7 = a.consider.astype(np.float64) if kind == "gt" else a.scores
            # results with classes (a track file of a run that classified its tracks)
            classes = a.classes if kind != "gt" and len(a) and (a.classes >= 0).all() else None
            fh.write(format_mot_rows(a.frames, a.ids, a.boxes, col7, a.world, classes))


def read_seqinfo(path: str | Path) -> dict[str, object]:
    """Read ``seqinfo.ini``: name, imDir, frameRate, seqLength, imWidth, imHeight, imExt."""
    import configparser   # here: every command reads MOT files, few read seqinfo.ini

    p = Path(path)
    if p.is_dir():
        p = p / "seqinfo.ini"
    if not p.is_file():
        raise InputError(f"seqinfo.ini not found: {location(p)}")
    cp = configparser.ConfigParser(interpolation=None)
    try:
        cp.read_string(p.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:
        raise InputError(f"{location(p)}: not UTF-8 text (byte at offset {exc.start})") from None
    except configparser.Error as exc:
        # configparser's messages quote the offending line: name only where it is
        line = getattr(exc, "lineno", None) or next(iter(getattr(exc, "errors", [])), (None,))[0]
        raise InputError(f"{location(p, line)}: malformed seqinfo.ini "
                         f"({type(exc).__name__})") from None
    if "Sequence" not in cp:
        raise InputError(f"{location(p)}: no [Sequence] section")
    out: dict[str, object] = {}
    for key, value in cp["Sequence"].items():
        try:
            number = int(value) if value.strip().lstrip("-").isdigit() else float(value)
        except ValueError:
            out[key] = value
            continue
        if not math.isfinite(number) or abs(number) >= INT_LIMIT:
            raise InputError(f"{location(p)}: {excerpt(key)}: expected a finite number "
                             f"below 2**62, got {excerpt(value.strip())}")
        out[key] = number
    return out
