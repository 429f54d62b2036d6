"""Exact scene-analytics events of a synthetic scene, from its ground-truth trajectories.

The rules are those of the scene file (``docs/analytics.md``), written out independently of
:mod:`motiontrack.analytics` (which sits above this layer) and applied to each ground-truth
object's anchor point (``bottom_center`` = ``(x + w / 2, y + h)`` of its box, ``center`` =
``(x + w / 2, y + h / 2)``) in every frame where it has a row; ``h`` below is the scene file's
``hysteresis_px`` (default :data:`HYSTERESIS_PX`):

* ``line_cross``: for a line from A to B, ``s(p) = (Bx - Ax)(py - Ay) - (By - Ay)(px - Ax)``.
  A side is confirmed where the anchor is more than ``h`` from the (infinite) line; when the
  confirmed side flips and a step since the last confirmed position met the segment AB, the
  object crossed: ``in`` from ``s < 0`` to ``s > 0``, ``out`` the other way, at the frame where
  the new side is confirmed.
* ``zone_enter`` / ``zone_exit``: the object is inside a polygon (even-odd rule) from the
  frame its anchor is inside and more than ``h`` from every edge, outside again once it is
  outside and as far; its first row decides by the plain even-odd rule. ``dwell_s`` on exit is
  the time since entering.
* ``loiter``: the first frame at which the dwell reaches the zone's ``loiter_s``; once a visit.
* ``stationary_start`` / ``stationary_end``: a *stay* begins at a position; a later anchor
  within ``radius_px`` of the mean of the stay's anchors extends it, the first one farther ends
  it (and begins the next). ``stationary_start`` when a stay has lasted ``after_s``,
  ``stationary_end`` when such a stay ends (``duration_s`` from its first to its last frame).
* ``abandoned``: a bag (an object with an owner) whose owner is out of view or farther than
  ``distance_heights`` times the owner's box height for ``after_s`` without a break;
  ``duration_s`` is how long the bag has lain still (since its first frame), ``owner`` the
  person who left it.

Times are ``(frame - 1) / fps``; a duration reaches ``d`` seconds at the first frame ``f`` with
``(f - f0) / fps >= d``. Positions are rounded to 0.01 px, durations to 1 ms. Ground-truth
objects have a row in every frame from their first to their last, so no object is forgotten
and found again (the scene file's ``forget_s`` never applies). Scenes place their lines and
zones a quarter pixel off the whole and half pixels anchors take, so no anchor lies exactly on
a line or an edge.
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

from ..types import Annotations, Event

__all__ = ["HYSTERESIS_PX", "ground_truth_events", "scene_toml"]

#: distance from a line or zone edge beyond which a side counts (the scene file's default)
HYSTERESIS_PX = 5.0

_TYPE_ORDER = {"zone_exit": 0, "line_cross": 1, "zone_enter": 2, "loiter": 3,
               "stationary_start": 4, "stationary_end": 5, "abandoned": 6}
_EPS = 1e-9  # seconds: (f - f0) / fps that should equal d exactly may round just below it


def _anchors(boxes: np.ndarray, anchor: str) -> np.ndarray:
    """``(N, 2)`` anchor points of ``(N, 4)`` boxes."""
    x = boxes[:, 0] + boxes[:, 2] / 2
    y = boxes[:, 1] + (boxes[:, 3] if anchor == "bottom_center" else boxes[:, 3] / 2)
    return np.stack([x, y], axis=1)


def _side(a: Sequence[float], b: Sequence[float], p: Sequence[float]) -> float:
    return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])


def _segments_cross(p: Sequence[float], q: Sequence[float], a: Sequence[float],
                    b: Sequence[float]) -> bool:
    """Does segment pq meet segment ab (touching counts)?"""
    d1, d2 = _side(a, b, p), _side(a, b, q)
    d3, d4 = _side(p, q, a), _side(p, q, b)
    return d1 * d2 <= 0 and d3 * d4 <= 0


def _edge_distance(poly: Sequence[Sequence[float]], p: Sequence[float]) -> float:
    """Distance from ``p`` to the nearest edge of the polygon."""
    best = math.inf
    n = len(poly)
    for k in range(n):
        (x1, y1), (x2, y2) = poly[k], poly[(k + 1) % n]
        ex, ey = x2 - x1, y2 - y1
        t = min(1.0, max(0.0, ((p[0] - x1) * ex + (p[1] - y1) * ey) / max(ex * ex + ey * ey, 1e-12)))
        best = min(best, math.hypot(p[0] - (x1 + t * ex), p[1] - (y1 + t * ey)))
    return best


def _inside(poly: Sequence[Sequence[float]], p: Sequence[float]) -> bool:
    """Even-odd rule: a ray to the right of ``p`` crosses the polygon's edges an odd number of
    times."""
    x, y = p
    inside = False
    n = len(poly)
    for k in range(n):
        (x1, y1), (x2, y2) = poly[k], poly[(k + 1) % n]
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def _reached(f: int, f0: int, fps: float, d: float) -> bool:
    return (f - f0) / fps >= d - _EPS


class _Emitter:
    """Builds :class:`Event` objects of one object's trajectory."""

    def __init__(self, fps: float, track: int) -> None:
        self.fps, self.track, self.events = fps, track, []

    def __call__(self, kind: str, frame: int, p: Sequence[float], **fields: Any) -> None:
        fields = {k: (round(float(v), 3) if isinstance(v, float) else v) for k, v in fields.items()}
        self.events.append(Event(type=kind, frame=int(frame), t=round(float(frame - 1) / self.fps, 6),
                                 track=self.track, x=round(float(p[0]), 2),
                                 y=round(float(p[1]), 2), **fields))


def _lines(emit: _Emitter, frames: np.ndarray, pts: np.ndarray, lines: list[dict],
           hysteresis: float) -> None:
    for line in lines:
        a, b = line["points"]
        norm = math.hypot(b[0] - a[0], b[1] - a[1])
        side, touched, prev = 0.0, False, None
        for f, p in zip(frames, pts):
            touched = touched or (prev is not None and _segments_cross(prev, p, a, b))
            prev = p
            s = _side(a, b, p)
            if abs(s) / norm <= hysteresis:
                continue
            new = math.copysign(1.0, s)
            if side and new != side and touched:
                emit("line_cross", f, p, line=line["name"], direction="in" if new > 0 else "out")
            side, touched = new, False


def _zones(emit: _Emitter, frames: np.ndarray, pts: np.ndarray, zones: list[dict],
           fps: float, hysteresis: float) -> None:
    for zone in zones:
        entered, loitered = None, False
        for k, (f, p) in enumerate(zip(frames, pts)):
            inside = _inside(zone["polygon"], p)
            if k and _edge_distance(zone["polygon"], p) <= hysteresis:
                inside = entered is not None  # in the band along the edges: no change
            if inside and entered is None:
                entered, loitered = int(f), False
                emit("zone_enter", f, p, zone=zone["name"])
            elif not inside and entered is not None:
                emit("zone_exit", f, p, zone=zone["name"], dwell_s=(f - entered) / fps)
                entered = None
            if inside and not loitered and "loiter_s" in zone \
                    and _reached(f, entered, fps, zone["loiter_s"]):
                emit("loiter", f, p, zone=zone["name"], dwell_s=(f - entered) / fps)
                loitered = True


def _stationary(emit: _Emitter, frames: np.ndarray, pts: np.ndarray, rule: Mapping,
                fps: float) -> None:
    first = last = int(frames[0])
    total, n, started = np.array(pts[0], dtype=np.float64), 1, False
    for f, p in zip(frames[1:], pts[1:]):
        mean = total / n
        if math.hypot(p[0] - mean[0], p[1] - mean[1]) > rule["radius_px"]:
            if started:
                emit("stationary_end", f, p, duration_s=(last - first) / fps)
            first = last = int(f)
            total, n, started = np.array(p, dtype=np.float64), 1, False
            continue
        total, n, last = total + p, n + 1, int(f)
        if not started and _reached(f, first, fps, rule["after_s"]):
            emit("stationary_start", f, p)
            started = True


def _abandoned(emit: _Emitter, frames: np.ndarray, pts: np.ndarray, owner: int,
               owner_rows: Mapping[int, tuple[np.ndarray, float]], rule: Mapping,
               fps: float) -> None:
    away = None
    for f, p in zip(frames, pts):
        o = owner_rows.get(int(f))
        near = o is not None and math.hypot(o[0][0] - p[0], o[0][1] - p[1]) \
            <= rule["distance_heights"] * o[1]
        if near:
            away = None
            continue
        away = int(f) if away is None else away
        if _reached(f, away, fps, rule["after_s"]):
            emit("abandoned", f, p, duration_s=(f - int(frames[0])) / fps, owner=int(owner))
            return


def _applying(tables: Sequence[Mapping[str, Any]], cls: str | None) -> list:
    """The tables whose ``classes`` (if any) include ``cls`` (all of them when ``cls`` is None)."""
    return [t for t in tables
            if cls is None or t.get("classes") is None or cls in t["classes"]]


def ground_truth_events(scene_file: Mapping[str, Any], gt: Annotations, fps: float,
                        owners: Mapping[int, int] | None = None,
                        classes: Mapping[int, str] | None = None) -> list[Event]:
    """Every event the rules of ``scene_file`` give on the trajectories of ``gt``.

    Parameters
    ----------
    scene_file : mapping
        The scene file's tables: ``anchor``, ``line`` (``name``, ``points`` in pixels), ``zone``
        (``name``, ``polygon`` in pixels, optional ``loiter_s``), optional ``stationary``
        (``after_s``, ``radius_px``) and ``abandoned`` (``after_s``, ``distance_heights``).
    gt : Annotations
        Ground truth: one row per object and frame, 1-based frames.
    fps : float
        Frames per second (event times and durations).
    owners : mapping, optional
        ``{object id: owner id}`` for objects that can be abandoned (bags).
    classes : mapping, optional
        ``{object id: class}``: a line or zone with ``classes`` applies to the objects of
        those classes only (every object when None).

    Returns
    -------
    list of Event
        Sorted by frame, then track, then type.
    """
    anchor = scene_file.get("anchor", "bottom_center")
    hysteresis = float(scene_file.get("hysteresis_px", HYSTERESIS_PX))
    pts_all = _anchors(gt.boxes, anchor)
    by_id = {int(k): np.flatnonzero(gt.ids == k) for k in np.unique(gt.ids)}
    out: list[Event] = []
    for oid, rows in by_id.items():
        rows = rows[np.argsort(gt.frames[rows], kind="stable")]
        frames, pts = gt.frames[rows], pts_all[rows]
        emit = _Emitter(fps, oid)
        cls = None if classes is None else classes.get(oid, "other")
        _lines(emit, frames, pts, _applying(scene_file.get("line", ()), cls), hysteresis)
        _zones(emit, frames, pts, _applying(scene_file.get("zone", ()), cls), fps, hysteresis)
        if "stationary" in scene_file:
            _stationary(emit, frames, pts, scene_file["stationary"], fps)
        owner = (owners or {}).get(oid)
        if owner is not None and "abandoned" in scene_file and owner in by_id:
            orows = by_id[owner]
            owner_rows = {int(gt.frames[r]): (pts_all[r], float(gt.boxes[r, 3])) for r in orows}
            _abandoned(emit, frames, pts, owner, owner_rows, scene_file["abandoned"], fps)
        out += emit.events
    out.sort(key=lambda e: (e.frame, e.track, _TYPE_ORDER[e.type], e.line or e.zone or ""))
    return out


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(float(v)) if isinstance(v, float) else str(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return "[" + ", ".join(_toml_value(x) for x in v) + "]"


def scene_toml(scene_file: Mapping[str, Any], comment: str = "") -> str:
    """The scene file as TOML text (top-level keys, then ``[[line]]``, ``[[zone]]`` and the
    rule tables), for ``track --scene`` and ``analyze --scene``."""
    lines = [f"# {c}" for c in comment.splitlines()]
    tables = {k: v for k, v in scene_file.items() if isinstance(v, (dict, list))}
    for k, v in scene_file.items():
        if k not in tables:
            lines.append(f"{k} = {_toml_value(v)}")
    for k, v in tables.items():
        for item in (v if isinstance(v, list) else [v]):
            lines += ["", f"[[{k}]]" if isinstance(v, list) else f"[{k}]"]
            lines += [f"{kk} = {_toml_value(vv)}" for kk, vv in item.items()]
    return "\n".join(lines) + "\n"
