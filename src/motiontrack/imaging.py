"""Image helpers every stage shares: the processing scale, box-to-pixel windows, gray images.

Pure functions of numbers and arrays, with no configuration: the foundation layer.
"""

from __future__ import annotations

import math
from typing import Sequence

import cv2
import numpy as np

__all__ = ["to_gray", "largest_difference", "pixel_window", "scaled_size", "resolve_scale", "AUTO_PIXELS",
           "AUTO_MIN_SCALE"]

#: automatic processing scale: about this many pixels are processed (384 x 288) ...
AUTO_PIXELS = 384 * 288
#: ... but frames are never reduced below half size (768 x 576 and larger frames get 0.5)
AUTO_MIN_SCALE = 0.5


def resolve_scale(scale: float, width: int, height: int) -> float:
    """The processing scale for frames of ``width`` x ``height``: ``scale`` itself, or when it is
    0 (automatic) ``min(1, max(0.5, sqrt(384*288 / (width*height))))`` — half size for PETS-sized
    and larger frames, up to full size for small ones (a 320x240 frame at half size leaves
    cars a few pixels wide)."""
    if scale > 0:
        return float(scale)
    area = max(1, int(width) * int(height))
    return float(min(1.0, max(AUTO_MIN_SCALE, (AUTO_PIXELS / area) ** 0.5)))


def scaled_size(width: int, height: int, scale: float) -> tuple[int, int]:
    """Processing size ``(w, h)`` for ``scale`` (at least 1 px each way)."""
    return max(1, int(round(width * scale))), max(1, int(round(height * scale)))


def pixel_window(box: Sequence[float] | np.ndarray, scale: float, shape: tuple[int, ...], margin: int = 0
                 ) -> tuple[int, int, int, int]:
    """The pixels ``(x1, y1, x2, y2)`` (end exclusive) that a box ``x, y, w, h`` in original-frame
    pixels covers in an image of ``shape`` (h, w, ...) at processing scale ``scale``: the scaled
    box widened to whole pixels, plus ``margin`` pixels on each side, cut to the image (empty
    when ``x2 <= x1`` or ``y2 <= y1``)."""
    # a list of floats first: NumPy scalars, or a generator, cost several times the arithmetic
    # (a window is taken per region and per box of every frame)
    x, y, bw, bh = box.tolist() if isinstance(box, np.ndarray) else [float(v) for v in box]
    x, y, bw, bh = x * scale, y * scale, bw * scale, bh * scale
    h, w = shape[:2]
    return (max(0, int(x) - margin), max(0, int(y) - margin),
            min(w, math.ceil(x + bw) + margin), min(h, math.ceil(y + bh) + margin))


def to_gray(image: np.ndarray) -> np.ndarray:
    """A BGR image in gray; a gray (2-D) image as it is (not copied)."""
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image


def largest_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The absolute difference of two uint8 images in their most different colour channel,
    (h, w) uint8 (a bag can have the brightness of the ground it lies on, not its colour)."""
    d = cv2.absdiff(a, b)
    if d.ndim == 3:
        c0, c1, c2 = cv2.split(d)
        d = cv2.max(cv2.max(c0, c1), c2)
    return d
