"""Drawing a scene's lines and zones with their running counts, and the frame's events.

The geometry comes as plain objects (lines with ``name, a, b``; zones with ``name, polygon``:
:class:`motiontrack.analytics.scene.LineSpec` and ``ZoneSpec`` fit) and the counts as a
:class:`~motiontrack.types.SceneFrame`, so drawing needs nothing from the analytics layer.
"""

from __future__ import annotations

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
        tint = img.copy()
        for z in zones:
            cv2.fillPoly(tint, [np.round(np.asarray(z.polygon)).astype(np.int32)], ZONE_COLOR)
        cv2.addWeighted(tint, _ZONE_ALPHA, img, 1.0 - _ZONE_ALPHA, 0.0, dst=img)
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
