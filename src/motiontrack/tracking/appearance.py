"""Appearance model: colour histograms of what moves inside a box (pure functions).

Each box is described by a hue–saturation histogram (16 × 4 bins, HSV) of its foreground pixels —
the motion mask inside the box, so the background around a person does not dilute it — or, for
gray input, a 32-bin intensity histogram. Histograms are L1-normalised; two are compared with the
Bhattacharyya distance ``sqrt(1 − Σ sqrt(p q))`` in [0, 1] (Comaniciu, Ramesh & Meer 2003).
"""

from __future__ import annotations

import cv2
import numpy as np

from ..imaging import pixel_window

__all__ = ["histograms", "bhattacharyya", "BINS"]

HUE_BINS, SAT_BINS, GRAY_BINS = 16, 4, 32
BINS = HUE_BINS * SAT_BINS


def histograms(image: np.ndarray, boxes: np.ndarray, mask: np.ndarray | None = None,
               scale: float = 1.0, min_pixels: int = 20) -> np.ndarray:
    """Histograms of ``boxes`` (N, 4, original pixels) in ``image`` (processing scale ``scale``).

    Returns
    -------
    (N, BINS) float64, rows summing to 1; a row of zeros where the box holds fewer than
    ``min_pixels`` foreground pixels (no reliable appearance).
    """
    boxes = np.asarray(boxes, np.float64).reshape(-1, 4)
    out = np.zeros((len(boxes), BINS))
    if len(boxes) == 0:
        return out
    colour = image.ndim == 3
    for i, box in enumerate(boxes):
        x1, y1, x2, y2 = pixel_window(box, scale, image.shape)
        if x2 - x1 < 2 or y2 - y1 < 2:
            continue
        m = None if mask is None else mask[y1:y2, x1:x2]
        if m is not None and cv2.countNonZero(m) < min_pixels:
            continue
        crop = image[y1:y2, x1:x2]
        if colour:
            # converting only the boxes costs less than the whole frame when they cover little of it
            crop = cv2.cvtColor(crop, cv2.COLOR_BGR2HSV)
            hist = cv2.calcHist([crop], [0, 1], m, [HUE_BINS, SAT_BINS], [0, 180, 0, 256]).ravel()
        else:
            hist = np.zeros(BINS, np.float32)
            hist[:GRAY_BINS] = cv2.calcHist([crop], [0], m, [GRAY_BINS], [0, 256]).ravel()
        total = hist.sum()
        if total >= min_pixels:
            out[i] = hist / total
    return out


def bhattacharyya(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Bhattacharyya distance between rows of ``a`` (N, B) and ``b`` (M, B) → (N, M) in [0, 1].

    Pairs where either histogram is empty (all zeros) get distance 0 (no evidence either way)."""
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    bc = np.sqrt(a) @ np.sqrt(b).T
    d = np.sqrt(np.clip(1.0 - bc, 0.0, 1.0))
    empty = (a.sum(axis=1) == 0)[:, None] | (b.sum(axis=1) == 0)[None, :]
    d[empty] = 0.0
    return d
