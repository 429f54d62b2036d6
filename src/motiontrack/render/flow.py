"""Optical flow as pictures: dense flow in colour (hue = direction, value = magnitude), and the
trails of sparse-flow feature points.

Colour convention: direction is the angle of ``(dx, dy)`` in *image* coordinates (x right, y down),
``θ = atan2(dy, dx)`` in [0°, 360°), so 0° = moving right, 90° = moving down, 180° = left,
270° = up; OpenCV hue is ``θ / 2`` (0..179): right = red (0), down = yellow-green (45),
left = cyan (90), up = blue-violet (135). Saturation is 255; value is ``255 · min(1, |flow| / m)``
with ``m`` = ``max_magnitude`` (px/frame) or, when it is ``None``, the frame's largest magnitude
(as in the OpenCV optical-flow tutorial).
"""

from __future__ import annotations

import cv2
import numpy as np

from ..errors import ConfigError
from .annotate import color_for

__all__ = ["flow_to_hsv", "flow_to_bgr", "hue_to_angle", "draw_feature_trails"]


def flow_to_hsv(flow: np.ndarray, max_magnitude: float | None = None) -> np.ndarray:
    """HSV image of a flow field.

    Parameters
    ----------
    flow : (H, W, 2) float, ``(dx, dy)`` in pixels per frame.
    max_magnitude : magnitude (px/frame) shown at full brightness; ``None`` = this field's maximum.

    Returns
    -------
    (H, W, 3) uint8 OpenCV HSV: hue = direction / 2 (0..179), saturation 255, value ∝ magnitude.
    """
    flow = np.asarray(flow, np.float32)
    if flow.ndim != 3 or flow.shape[2] != 2:
        raise ConfigError(f"flow must have shape (H, W, 2), got {flow.shape}")
    if max_magnitude is not None and not max_magnitude > 0:
        raise ConfigError(f"max_magnitude must be > 0, got {max_magnitude}")
    hsv = np.zeros(flow.shape[:2] + (3,), np.uint8)
    if flow.size == 0:
        return hsv
    mag, ang = cv2.cartToPolar(flow[..., 0], flow[..., 1], angleInDegrees=True)
    top = float(max_magnitude) if max_magnitude is not None else float(mag.max())
    hsv[..., 0] = np.round(ang / 2.0).astype(np.int32) % 180
    hsv[..., 1] = 255
    if top > 0:
        hsv[..., 2] = np.round(np.clip(mag / top, 0.0, 1.0) * 255.0).astype(np.uint8)
    return hsv


def flow_to_bgr(flow: np.ndarray, max_magnitude: float | None = None) -> np.ndarray:
    """BGR picture of a flow field (see :func:`flow_to_hsv`), (H, W, 3) uint8."""
    return cv2.cvtColor(flow_to_hsv(flow, max_magnitude), cv2.COLOR_HSV2BGR)


def hue_to_angle(hue: np.ndarray | float) -> np.ndarray:
    """OpenCV hue (0..179) back to the flow direction in degrees [0, 360)."""
    return (np.asarray(hue, np.float64) * 2.0) % 360.0


def draw_feature_trails(img: np.ndarray, trails: list[tuple[int, np.ndarray]]) -> None:
    """Draw each feature point's trail and current position in its object's colour (in place)."""
    for oid, tr in trails:
        color = color_for(oid)
        if len(tr) > 1:
            cv2.polylines(img, [np.round(tr).astype(np.int32).reshape(-1, 1, 2)], False, color, 1,
                          cv2.LINE_AA)
        if len(tr):
            x, y = tr[-1]
            cv2.circle(img, (int(round(x)), int(round(y))), 2, color, -1)
