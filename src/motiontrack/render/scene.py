"""Drawing a scene's lines and zones with their running counts, and the frame's events.

The geometry comes as plain objects (lines with ``name, a, b``; zones with ``name, polygon``:
:class:`motiontrack.analytics.scene.LineSpec` and ``ZoneSpec`` fit) and the counts as a
:class:`~motiontrack.types.SceneFrame`, so drawing needs nothing from the analytics layer.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, Sequence

import cv2
import numpy as np

from ..types import SceneFrame
from .annotate import draw_label, line_width, text_scale

__all__ = ["LINE_COLOR", "ZONE_COLOR", "EVENT_COLOR", "draw_scene"]

LINE_COLOR = (0, 215, 255)    # amber
ZONE_COLOR = (255, 160, 40)   # blue
EVENT_COLOR = (60, 60, 255)   # red
#: opacity of a zone's fill
_ZONE_ALPHA = 0.15


def _pt(p: Sequence[float]) -> tuple[int, int]:
    return int(round(p[0])), int(round(p[1]))


@lru_cache(maxsize=16)
def _zone_layer(shape: tuple[int, ...], polygons: tuple[tuple[tuple[int, int], ...], ...]
                ) -> tuple[tuple[int, int, int, int], np.ndarray, np.ndarray] | None:
    """The zones' fill, drawn once per frame size: the rectangle ``(y0, y1, x0, x1)`` around
    the zones, which of its pixels they cover (uint8 mask, 255 inside) and the zone colour at its
    size."""
    mask = np.zeros(shape[:2], np.uint8)
    cv2.fillPoly(mask, [np.array(p, np.int32).reshape(-1, 2) for p in polygons], 255)
    x, y, w, h = cv2.boundingRect(mask)
    if w == 0 or h == 0:
        return None
    inside = np.ascontiguousarray(mask[y:y + h, x:x + w])
    color = np.empty((h, w, 3), np.uint8)
    color[:] = ZONE_COLOR
    return (y, y + h, x, x + w), inside, color


def _tint_zones(img: np.ndarray, polygons: tuple[tuple[tuple[int, int], ...], ...]) -> None:
    """Blend the zone colour into the zones, in place, touching only the rectangle around them
    (the fill does not change from frame to frame)."""
    layer = _zone_layer(img.shape, polygons)
    if layer is None:
        return
    (y0, y1, x0, x1), inside, color = layer
    roi = img[y0:y1, x0:x1]
    # the same arithmetic as blending a tinted copy of the whole frame, on the zones only
    cv2.copyTo(cv2.addWeighted(color, _ZONE_ALPHA, roi, 1.0 - _ZONE_ALPHA, 0.0), inside, roi)


def draw_scene(img: np.ndarray, lines: Sequence[Any], zones: Sequence[Any],
               frame: SceneFrame | None) -> np.ndarray:
    """Draw zones (tinted, outlined, ``name: occupancy``), lines (with an arrow towards the
    ``in`` side, ``name in N out M``) and a ring at each of the frame's events, in place.

    Returns ``img``.
    """
    lw = line_width(img.shape)
    scale, thick = text_scale(img.shape)
    scale *= 0.6
    occupancy = frame.occupancy if frame is not None else {}
    counts = frame.line_counts if frame is not None else {}
    if zones:
        polygons = tuple(tuple(map(tuple, np.round(np.asarray(z.polygon)).astype(int).tolist()))
                         for z in zones)
        _tint_zones(img, polygons)
    for z in zones:
        poly = np.round(np.asarray(z.polygon)).astype(np.int32)
        cv2.polylines(img, [poly], True, ZONE_COLOR, lw, cv2.LINE_AA)
        top = poly[np.argmin(poly[:, 1])]
        draw_label(img, f"{z.name}: {occupancy.get(z.name, 0)}", (int(top[0]), int(top[1])),
                   ZONE_COLOR, scale, thick)
    for ln in lines:
        a, b = np.asarray(ln.a, dtype=float), np.asarray(ln.b, dtype=float)
        cv2.line(img, _pt(a), _pt(b), LINE_COLOR, lw, cv2.LINE_AA)
        # the "in" side is s > 0: the normal (-(By - Ay), Bx - Ax) points there (y down)
        mid, d = (a + b) / 2.0, b - a
        normal = np.array([-d[1], d[0]]) / max(np.hypot(*d), 1e-9)
        size = max(12.0, 6.0 * lw)
        cv2.arrowedLine(img, _pt(mid), _pt(mid + normal * size), LINE_COLOR, lw, cv2.LINE_AA,
                        tipLength=0.4)
        n_in, n_out = counts.get(ln.name, (0, 0))
        draw_label(img, f"{ln.name} in {n_in} out {n_out}", _pt(a), LINE_COLOR, scale, thick)
    if frame is not None:
        for e in frame.events:
            cv2.circle(img, _pt((e.x, e.y)), 3 * lw, EVENT_COLOR, lw, cv2.LINE_AA)
    return img
