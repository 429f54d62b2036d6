"""Overlay ground truth and several runs on the video (the thesis' ``overlaybbs`` script).

Each annotation set gets one colour (ground truth green, runs from a fixed palette of well separated
colours) and a legend in the top-left corner names them, so that several parameter settings can be
compared on the same frames. The overlay job (:func:`motiontrack.run.overlay_job`) writes it as a
video and PNG stills of chosen frames.
"""

from __future__ import annotations

import logging
from typing import Sequence

import cv2
import numpy as np

from ..types import Annotations
from .annotate import draw_label, line_width, text_scale

log = logging.getLogger(__name__)

__all__ = ["GT_COLOR", "PALETTE", "draw_overlay", "overlay_layers", "layers_at"]

#: BGR
GT_COLOR = (80, 220, 80)
PALETTE = ((60, 60, 255), (255, 150, 40), (0, 215, 255), (255, 60, 220), (255, 255, 80),
           (40, 140, 255), (180, 120, 255), (200, 200, 200))


def _colors(n: int) -> list[tuple[int, int, int]]:
    return [PALETTE[i % len(PALETTE)] for i in range(n)]


def draw_overlay(image: np.ndarray, layers: Sequence[tuple[str, tuple[int, int, int], np.ndarray, np.ndarray]],
                 frame_label: str | None = None, legend: bool = True) -> np.ndarray:
    """Draw boxes of several annotation layers on a copy of ``image``.

    Parameters
    ----------
    image : (h, w, 3) or (h, w) uint8 frame (not modified).
    layers : (name, BGR colour, boxes (N, 4) x,y,w,h px, ids (N,)) per layer; the first layer is
        drawn thicker (ground truth).
    frame_label : text drawn at the bottom-left (e.g. the frame number).
    legend : draw a legend naming the layers in their colours.

    Returns
    -------
    (h, w, 3) uint8
    """
    img = image.copy() if image.ndim == 3 else cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    # text and lines grow with the frame, as in the annotated video
    scale, thickness = text_scale(img.shape)
    width = line_width(img.shape)
    for li, (name, color, boxes, ids) in enumerate(layers):
        thick = width if li == 0 else max(1, width // 2)
        for b, i in zip(np.asarray(boxes).reshape(-1, 4), np.asarray(ids).reshape(-1)):
            p1 = (int(round(b[0])), int(round(b[1])))
            p2 = (int(round(b[0] + b[2])), int(round(b[1] + b[3])))
            cv2.rectangle(img, p1, p2, color, thick)
            cv2.putText(img, str(int(i)), (p1[0] + 2, p2[1] - 3), cv2.FONT_HERSHEY_SIMPLEX,
                        0.7 * scale, color, thickness, cv2.LINE_AA)
    if legend:
        y = 4
        for name, color, _, _ in layers:
            (tw, th), base = cv2.getTextSize(name, cv2.FONT_HERSHEY_SIMPLEX, scale, thickness)
            y += th + base + 4
            draw_label(img, name, (6, y), color, scale=None)
    if frame_label:
        draw_label(img, frame_label, (6, img.shape[0] - 6), (30, 30, 30), scale=None)
    return img


#: one layer of an overlay: legend name, BGR colour, the annotations and their rows by frame
Layer = tuple[str, tuple[int, int, int], Annotations, dict[int, np.ndarray]]


def overlay_layers(runs: Sequence[tuple[str, Annotations]],
                   gt: Annotations | None = None) -> list[Layer]:
    """The layers of an overlay: the ground truth first (green; rows with ``consider == False``
    left out), then each run in its palette colour."""
    named: list[tuple[str, tuple[int, int, int], Annotations]] = []
    if gt is not None:
        named.append(("ground truth", GT_COLOR, gt.select(np.asarray(gt.consider, dtype=bool))))
    named += [(name, color, ann) for (name, ann), color in zip(runs, _colors(len(runs)))]
    return [(n, c, a, a.by_frame()) for n, c, a in named]


def layers_at(layers: Sequence[Layer], frame: int
              ) -> list[tuple[str, tuple[int, int, int], np.ndarray, np.ndarray]]:
    """Each layer's boxes and ids at a 1-based ``frame``, as :func:`draw_overlay` takes them."""
    out = []
    for name, color, ann, by_frame in layers:
        rows = by_frame.get(frame)
        if rows is None:
            out.append((name, color, np.zeros((0, 4)), np.zeros(0)))
        else:
            out.append((name, color, ann.boxes[rows], ann.ids[rows]))
    return out
