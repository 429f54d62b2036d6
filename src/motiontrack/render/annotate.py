"""Drawing on a copy of the frame: boxes, ids, centroids, coloured trails, the mask inset and a
legend of the kinds of boxes drawn.

Sizes follow the frame: text, lines and markers are proportional to the frame's smaller side
(:func:`text_scale`, :func:`line_width`), so labels read the same at 320×240 and at 1920×1080.
Track colours come from :class:`~motiontrack.render.colors.TrackColors`: no two tracks visible in
a frame share one.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Mapping, Sequence

import cv2
import numpy as np

from ..types import Region, Track, frame_number
from .colors import TrackColors, palette_color

__all__ = ["frame_caption", "INSETS", "LEGEND_STYLES", "text_scale", "line_width", "draw_tracks",
           "draw_regions", "draw_mask_inset", "draw_legend", "annotate_frame", "draw_label",
           "track_caption"]

#: where the mask inset goes (``output.inset``)
INSETS = ("none", "top-left", "top-right", "bottom-left", "bottom-right")
#: grey of region outlines
REGION_COLOR = (200, 200, 200)
#: the frame's smaller side (px) at which text is drawn at OpenCV font scale 1
_TEXT_SIDE = 720.0
_FONT = cv2.FONT_HERSHEY_SIMPLEX
BGR = tuple[int, int, int]


def text_scale(shape: Sequence[int]) -> tuple[float, int]:
    """OpenCV font scale and stroke thickness for text on an image of ``shape`` (h, w[, c]):
    proportional to the smaller side (scale 1, about 22 px tall, at 720 px)."""
    side = max(1, min(int(shape[0]), int(shape[1])))
    scale = side / _TEXT_SIDE
    return scale, max(1, int(round(scale * 1.5)))


def frame_caption(index: int) -> str:
    """The frame label every annotated picture carries: ``"frame N"`` with N the number
    ``tracks.txt`` and ``events.jsonl`` give that frame (:func:`~motiontrack.types.frame_number`;
    ``index`` is the 0-based index in the source)."""
    return f"frame {frame_number(index)}"


def line_width(shape: Sequence[int], seen: bool = True) -> int:
    """Box and trail line width (px) on an image of ``shape``: 2 up to about 600 px, then
    proportional; a box not seen in this frame (a prediction) is drawn at half that."""
    w = max(2, int(round(min(int(shape[0]), int(shape[1])) / 270.0)))
    return w if seen else max(1, w // 2)


def draw_label(img: np.ndarray, text: str, org: tuple[int, int], color: tuple[int, int, int],
               scale: float | None = 0.5, thickness: int = 1) -> None:
    """Text on a filled background box so it stays readable on any frame (draws in place);
    ``scale`` None takes the frame's size into account (:func:`text_scale`)."""
    if scale is None:
        scale, thickness = text_scale(img.shape)
    (tw, th), base = cv2.getTextSize(text, _FONT, scale, thickness)
    x, y = org
    y = max(y, th + base)
    cv2.rectangle(img, (x, y - th - base), (x + tw + 2, y), color, -1)
    luminance = 0.114 * color[0] + 0.587 * color[1] + 0.299 * color[2]
    cv2.putText(img, text, (x + 1, y - base), _FONT, scale,
                (0, 0, 0) if luminance > 128 else (255, 255, 255), thickness, cv2.LINE_AA)


def track_caption(t: Track) -> str:
    """A track's label on the picture: its id, and its class once it has one other than
    ``other`` (``7 person``)."""
    return f"{t.id} {t.label}" if t.label and t.label != "other" else str(t.id)


def _colors_of(tracks: Sequence[Track], colors: Mapping[int, BGR] | None) -> Mapping[int, BGR]:
    # without a video's TrackColors, the tracks of this one frame still get distinct colours
    return colors if colors is not None else TrackColors().assign(t.id for t in tracks)


def draw_tracks(img: np.ndarray, tracks: Sequence[Track], trail: int = 32,
                colors: Mapping[int, BGR] | None = None) -> None:
    """Boxes, ids, centroids and trails of ``tracks`` (draws in place on ``img``); ``colors``
    maps each track id to its BGR colour (:meth:`TrackColors.assign`)."""
    colors = _colors_of(tracks, colors)
    scale, thick = text_scale(img.shape)
    radius = max(3, int(round(min(img.shape[:2]) / 160.0)))
    seen_width, predicted_width = line_width(img.shape), line_width(img.shape, seen=False)
    for t in tracks:
        color = colors[t.id]
        b = t.box
        p1 = (int(round(b.x)), int(round(b.y)))
        p2 = (int(round(b.x2)), int(round(b.y2)))
        width = seen_width if t.time_since_update == 0 else predicted_width
        cv2.rectangle(img, p1, p2, color, width)
        cx, cy = b.center
        cv2.circle(img, (int(round(cx)), int(round(cy))), radius, color, -1)
        if trail > 1 and len(t.history) > 1:
            pts = np.round(np.array(t.history[-trail:])).astype(np.int32).reshape(-1, 1, 2)
            cv2.polylines(img, [pts], False, color, seen_width, cv2.LINE_AA)
        draw_label(img, track_caption(t), (p1[0], p1[1] - 2), color, scale, thick)


def draw_regions(img: np.ndarray, regions: Sequence[Region], color: BGR = REGION_COLOR) -> None:
    """Thin outlines of the detected regions (draws in place)."""
    width = line_width(img.shape, seen=False)
    for r in regions:
        b = r.box
        cv2.rectangle(img, (int(b.x), int(b.y)), (int(b.x2), int(b.y2)), color, width)


def draw_mask_inset(img: np.ndarray, mask: np.ndarray, fraction: float = 0.2,
                    corner: str = "top-right") -> tuple[int, int, int, int]:
    """The motion mask, shrunk to ``fraction`` of the frame width, in ``corner`` (one of
    :data:`INSETS` but ``none``); returns the inset's ``(x, y, w, h)``."""
    if corner not in INSETS[1:]:
        raise ValueError(f"inset corner must be one of {list(INSETS[1:])}, got {corner!r}")
    h, w = img.shape[:2]
    iw = min(w, max(1, int(w * fraction)))
    ih = min(h, max(1, int(iw * mask.shape[0] / mask.shape[1])))
    small = cv2.resize(mask, (iw, ih), interpolation=cv2.INTER_NEAREST)
    inset = cv2.cvtColor(small, cv2.COLOR_GRAY2BGR) if img.ndim == 3 else small
    x = 0 if corner.endswith("left") else w - iw
    y = 0 if corner.startswith("top") else h - ih
    img[y:y + ih, x:x + iw] = inset
    cv2.rectangle(img, (x, y), (x + iw - 1, y + ih - 1), (255, 255, 255), 1)
    return x, y, iw, ih


#: legend entries: style → how it is drawn (see :func:`draw_legend`)
LEGEND_STYLES = ("track", "predicted", "region", "hypothesis", "head", "points")


def _swatch(img: np.ndarray, style: str, x: int, y: int, size: int,
            frame_shape: Sequence[int]) -> None:
    """One legend symbol in the square ``(x, y)``–``(x + size, y + size)``, its lines as wide
    as on a frame of ``frame_shape``."""
    p1, p2 = (x, y), (x + size, y + size)
    c = (x + size // 2, y + size // 2)
    if style == "track":
        cv2.rectangle(img, p1, p2, palette_color(0), line_width(frame_shape))
    elif style == "predicted":
        cv2.rectangle(img, p1, p2, palette_color(0), line_width(frame_shape, seen=False))
    elif style == "region":
        cv2.rectangle(img, p1, p2, REGION_COLOR, line_width(frame_shape, seen=False))
    elif style == "hypothesis":
        cv2.rectangle(img, p1, p2, (255, 255, 255), 1)
    elif style == "head":
        cv2.circle(img, c, size // 2, (0, 0, 255), 1, cv2.LINE_AA)
        cv2.drawMarker(img, c, (0, 0, 255), cv2.MARKER_CROSS, max(3, size // 2), 1)
    elif style == "points":
        for dx in (-size // 3, 0, size // 3):
            cv2.circle(img, (c[0] + dx, c[1] + dx // 2), max(1, size // 8), palette_color(0), -1)
    else:
        raise ValueError(f"legend style must be one of {list(LEGEND_STYLES)}, got {style!r}")


def draw_legend(img: np.ndarray, entries: Sequence[tuple[str, str]], origin: tuple[int, int],
                right: bool = False) -> int:
    """A legend of ``(style, label)`` entries (styles in :data:`LEGEND_STYLES`) on a translucent
    dark panel whose bottom-left (bottom-right with ``right``) corner is ``origin`` (in place);
    returns the panel's height in pixels. A panel that would leave the frame is moved inside.

    The panel is drawn once per frame size (:func:`_legend_layer`); each frame only darkens
    the scene under it and lays the drawn panel over it.
    """
    if not entries:
        return 0
    shape = (int(img.shape[0]), int(img.shape[1]), 3)
    (y0, y1, x0, x1), ph, keep, paint = _legend_layer(shape, tuple(map(tuple, entries)),
                                                      (int(origin[0]), int(origin[1])), right)
    roi = img[y0:y1, x0:x1]
    if img.ndim == 2:   # the coverage is the same in every channel
        keep, paint = keep[..., 0], cv2.cvtColor(paint, cv2.COLOR_BGR2GRAY)
    roi[...] = cv2.add(cv2.multiply(roi, keep, dtype=cv2.CV_32F), paint, dtype=cv2.CV_8U)
    return ph


@lru_cache(maxsize=32)
def _legend_layer(shape: tuple[int, int, int], entries: tuple[tuple[str, str], ...],
                  origin: tuple[int, int], right: bool
                  ) -> tuple[tuple[int, int, int, int], int, np.ndarray, np.ndarray]:
    """The legend panel of a frame of ``shape``: its rectangle ``(y0, y1, x0, x1)``, its
    height, and per pixel the share of the scene kept (``keep``, float32: 0.4 under the panel,
    less under anti-aliased edges, 0 under symbols) and the colour laid over it (``paint``,
    float32). Drawn over black and over white: where the two agree the legend covers the pixel,
    where they differ, by how much the difference tells."""
    scale, thick = text_scale(shape)
    scale *= 0.8   # a key, read once: smaller than the ids it explains
    (_, th), base = cv2.getTextSize("Ag", _FONT, scale, thick)
    row = th + base + max(2, th // 3)
    size = th + base // 2
    pad = max(3, th // 3)
    width = max(cv2.getTextSize(label, _FONT, scale, thick)[0][0] for _, label in entries)
    pw, ph = pad * 3 + size + width, pad * 2 + row * len(entries) - (row - size)
    h, w = shape[:2]
    x0 = min(max(0, origin[0] - pw if right else origin[0]), max(0, w - pw))
    y0 = min(max(0, origin[1] - ph), max(0, h - ph))
    x1, y1 = min(w, x0 + pw), min(h, y0 + ph)
    drawn = []
    for background in (0, 255):
        canvas = np.full((y1 - y0, x1 - x0, 3), background, np.uint8)
        for i, (style, label) in enumerate(entries):
            y = pad + i * row
            # swatches sized by the whole frame's shape, as on the frame itself
            _swatch(canvas, style, pad, y, size, shape)
            cv2.putText(canvas, label, (2 * pad + size, y + size - base // 2), _FONT, scale,
                        (255, 255, 255), thick, cv2.LINE_AA)
        drawn.append(canvas.astype(np.float32))
    over_black, over_white = drawn
    # translucent, so the scene under the legend stays visible: 2/5 of it is kept
    keep = (over_white - over_black) / 255.0 * 0.4
    return (y0, y1, x0, x1), ph, keep, over_black


def annotate_frame(frame: np.ndarray, tracks: Sequence[Track], regions: Sequence[Region] = (),
                   mask: np.ndarray | None = None, trail: int = 32, inset: str = "none", *,
                   inset_scale: float = 0.2, text: str | None = None,
                   colors: Mapping[int, BGR] | None = None,
                   legend: Sequence[tuple[str, str]] = ()) -> np.ndarray:
    """A new annotated BGR image (the input frame is not modified).

    ``inset`` places the motion mask, ``inset_scale`` of the frame width wide, in a corner
    (:data:`INSETS`); ``text`` (the frame number) and the ``legend`` go to the bottom-left, or
    to the bottom-right when the inset is there. ``colors`` maps track ids to colours (one
    :class:`~motiontrack.render.colors.TrackColors` per video keeps them stable); without it the
    tracks of this frame get distinct colours of their own.
    """
    img = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR) if frame.ndim == 2 else frame.copy()
    draw_regions(img, regions)
    draw_tracks(img, tracks, trail, colors)
    if mask is not None and inset != "none":
        draw_mask_inset(img, mask, inset_scale, inset)
    h, w = img.shape[:2]
    margin = max(4, h // 120)
    y = h - margin
    right = inset == "bottom-left"
    if text:
        scale, thick = text_scale(img.shape)
        (tw, th), base = cv2.getTextSize(text, _FONT, scale, thick)
        draw_label(img, text, (w - margin - tw - 2 if right else margin, y), (40, 40, 40), scale,
                   thick)
        y -= th + base + margin
    if legend:
        draw_legend(img, legend, (w - margin if right else margin, y), right)
    return img
