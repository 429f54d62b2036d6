"""Drawing for the people modules: spline outlines, control points, heads, search normals.

Every function draws on a *copy* unless ``inplace=True`` and returns the image; coordinates are
original-frame pixels; colours are BGR. :func:`draw_people` takes the track colours of the
annotated frame (:class:`~motiontrack.render.colors.TrackColors`), so an outline has the colour of
its track's box.
"""

from __future__ import annotations

from typing import Iterable, Mapping

import cv2
import numpy as np

from ..types import PeopleFrame

__all__ = ["draw_outline", "draw_control_points", "draw_heads", "draw_normals", "draw_people"]

_SHIFT = 4  # sub-pixel bits for cv2 drawing
_ONE = 1 << _SHIFT


def _fixed(pts: np.ndarray) -> np.ndarray:
    return np.rint(np.asarray(pts, np.float64).reshape(-1, 2) * _ONE).astype(np.int32)


def _target(img: np.ndarray, inplace: bool) -> np.ndarray:
    out = img if inplace else img.copy()
    if out.ndim == 2:
        out = cv2.cvtColor(out, cv2.COLOR_GRAY2BGR)
    return out


def _color(track_id: int | None, colors: Mapping[int, tuple[int, int, int]] | None
           ) -> tuple[int, int, int]:
    """The track's colour in ``colors``; yellow for an outline of no track or unknown colour."""
    if colors is None or track_id is None or track_id not in colors:
        return (0, 255, 255)
    return tuple(int(c) for c in colors[track_id])


def draw_outline(img: np.ndarray, outline: np.ndarray, color=(0, 255, 255), thickness: int = 1,
                 inplace: bool = False) -> np.ndarray:
    """Closed polyline through the outline points ``(K, 2)``."""
    out = _target(img, inplace)
    if len(outline) >= 2:
        cv2.polylines(out, [_fixed(outline)], True, tuple(int(c) for c in color), thickness,
                      cv2.LINE_AA, _SHIFT)
    return out


def draw_control_points(img: np.ndarray, control: np.ndarray, color=(255, 0, 255), radius: int = 2,
                        inplace: bool = False) -> np.ndarray:
    """Small filled circles at the control points ``(N, 2)``."""
    out = _target(img, inplace)
    for p in _fixed(control):
        cv2.circle(out, (int(p[0]), int(p[1])), radius * _ONE, tuple(int(c) for c in color), -1,
                   cv2.LINE_AA, _SHIFT)
    return out


def draw_heads(img: np.ndarray, heads: Iterable, color=(0, 0, 255), inplace: bool = False) -> np.ndarray:
    """A circle as wide as each head interval and a cross at its centre."""
    out = _target(img, inplace)
    col = tuple(int(c) for c in color)
    for h in heads:
        c = _fixed([[h.x, h.y]])[0]
        r = max(2.0, h.width / 2.0)
        cv2.circle(out, (int(c[0]), int(c[1])), int(round(r * _ONE)), col, 1, cv2.LINE_AA, _SHIFT)
        cv2.drawMarker(out, (int(round(h.x)), int(round(h.y))), col, cv2.MARKER_CROSS, 5, 1)
    return out


def draw_normals(img: np.ndarray, points: np.ndarray, normals: np.ndarray, half: float,
                 color=(255, 255, 0), inplace: bool = False) -> np.ndarray:
    """The search segments ``p ± half · n`` at each outline point (debug view)."""
    out = _target(img, inplace)
    p = np.asarray(points, np.float64).reshape(-1, 2)
    n = np.asarray(normals, np.float64).reshape(-1, 2)
    a, b = _fixed(p - half * n), _fixed(p + half * n)
    col = tuple(int(c) for c in color)
    for u, v in zip(a, b):
        cv2.line(out, (int(u[0]), int(u[1])), (int(v[0]), int(v[1])), col, 1, cv2.LINE_AA, _SHIFT)
    return out


def draw_people(img: np.ndarray, people: PeopleFrame, *, outlines: bool = True,
                control_points: bool = False, heads: bool = True, normals: bool = False,
                hypotheses: bool = True, inplace: bool = False,
                colors: Mapping[int, tuple[int, int, int]] | None = None) -> np.ndarray:
    """Draw what the people stage found in a frame (:class:`~motiontrack.types.PeopleFrame`) on
    ``img``.

    Outlines use the track colour in ``colors`` (track id → BGR, as the boxes are drawn;
    yellow without it); hypotheses (boxes offered for lost people) are dashed-looking
    thin white boxes; search normals are the debug view.
    """
    out = _target(img, inplace)
    for s in people.shapes:
        col = _color(getattr(s, "track_id", None), colors)
        if normals and getattr(s, "normals", None) is not None:
            draw_normals(out, s.outline, s.normals, s.search, inplace=True)
        if outlines:
            draw_outline(out, s.outline, col, inplace=True)
        if control_points:
            draw_control_points(out, s.control, inplace=True)
    if heads:
        draw_heads(out, people.heads, inplace=True)
    if hypotheses:
        for r in people.hypotheses:
            b = r.box
            p1, p2 = _fixed([[b.x, b.y], [b.x2, b.y2]])
            cv2.rectangle(out, (int(p1[0]), int(p1[1])), (int(p2[0]), int(p2[1])), (255, 255, 255), 1,
                          cv2.LINE_4, _SHIFT)
    return out
