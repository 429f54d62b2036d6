"""Drawing on a copy of the frame: boxes, ids, centroids, coloured trails, mask inset."""

from __future__ import annotations

from typing import Sequence

import cv2
import numpy as np

from ..types import Region, Track

__all__ = ["color_for", "draw_tracks", "draw_regions", "draw_mask_inset", "annotate_frame",
           "draw_label"]


def color_for(track_id: int) -> tuple[int, int, int]:
    """A stable, well-separated BGR colour per id (golden-ratio hue steps)."""
    hue = int((track_id * 0.618033988749895 % 1.0) * 179)
    hsv = np.uint8([[[hue, 220, 255]]])
    b, g, r = cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0]
    return int(b), int(g), int(r)


def draw_label(img: np.ndarray, text: str, org: tuple[int, int], color: tuple[int, int, int],
               scale: float = 0.5) -> None:
    """Text on a filled background box so it stays readable on any frame (draws in place)."""
    (tw, th), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
    x, y = org
    y = max(y, th + base)
    cv2.rectangle(img, (x, y - th - base), (x + tw + 2, y), color, -1)
    luminance = 0.114 * color[0] + 0.587 * color[1] + 0.299 * color[2]
    cv2.putText(img, text, (x + 1, y - base), cv2.FONT_HERSHEY_SIMPLEX, scale,
                (0, 0, 0) if luminance > 128 else (255, 255, 255), 1, cv2.LINE_AA)


def draw_tracks(img: np.ndarray, tracks: Sequence[Track], trail: int = 32) -> None:
    """Boxes, ids, centroids and trails of ``tracks`` (draws in place on ``img``)."""
    for t in tracks:
        color = color_for(t.id)
        b = t.box
        p1 = (int(round(b.x)), int(round(b.y)))
        p2 = (int(round(b.x2)), int(round(b.y2)))
        thickness = 2 if t.time_since_update == 0 else 1
        cv2.rectangle(img, p1, p2, color, thickness)
        cx, cy = b.center
        cv2.circle(img, (int(round(cx)), int(round(cy))), 3, color, -1)
        if trail > 1 and len(t.history) > 1:
            pts = np.round(np.array(t.history[-trail:])).astype(np.int32).reshape(-1, 1, 2)
            cv2.polylines(img, [pts], False, color, 2, cv2.LINE_AA)
        draw_label(img, str(t.id), (p1[0], p1[1] - 2), color)


def draw_regions(img: np.ndarray, regions: Sequence[Region], color=(200, 200, 200)) -> None:
    """Thin outlines of the detected regions (draws in place)."""
    for r in regions:
        b = r.box
        cv2.rectangle(img, (int(b.x), int(b.y)), (int(b.x2), int(b.y2)), color, 1)


def draw_mask_inset(img: np.ndarray, mask: np.ndarray, fraction: float = 0.25) -> None:
    """The motion mask, shrunk to ``fraction`` of the frame width, in the top-right corner."""
    h, w = img.shape[:2]
    iw = max(1, int(w * fraction))
    ih = max(1, int(iw * mask.shape[0] / mask.shape[1]))
    small = cv2.resize(mask, (iw, ih), interpolation=cv2.INTER_NEAREST)
    inset = cv2.cvtColor(small, cv2.COLOR_GRAY2BGR) if img.ndim == 3 else small
    img[0:ih, w - iw:w] = inset
    cv2.rectangle(img, (w - iw, 0), (w - 1, ih - 1), (255, 255, 255), 1)


def annotate_frame(frame: np.ndarray, tracks: Sequence[Track], regions: Sequence[Region] = (),
                   mask: np.ndarray | None = None, trail: int = 32, mask_inset: bool = True,
                   text: str | None = None) -> np.ndarray:
    """A new annotated BGR image (the input frame is not modified)."""
    img = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR) if frame.ndim == 2 else frame.copy()
    draw_regions(img, regions)
    draw_tracks(img, tracks, trail)
    if mask is not None and mask_inset:
        draw_mask_inset(img, mask)
    if text:
        draw_label(img, text, (4, img.shape[0] - 4), (40, 40, 40))
    return img
