"""Optical flow as pictures: dense flow in colour (hue = direction, value = magnitude), and the
trails of sparse-flow feature points.

Colour convention: direction is the angle of ``(dx, dy)`` in *image* coordinates (x right, y down),
``θ = atan2(dy, dx)`` in [0°, 360°), so 0° = moving right, 90° = moving down, 180° = left,
270° = up; OpenCV hue is ``θ / 2`` (0..179): right = red (0), down = yellow-green (45),
left = cyan (90), up = blue-violet (135). Saturation is 255; value is ``255 · min(1, |flow| / m)``
with ``m`` = ``max_magnitude`` (px/frame) or, when it is ``None``, the frame's largest magnitude
(as in the OpenCV optical-flow tutorial).

The flow video carries its key (:func:`draw_flow_legend`): a colour wheel drawn with the same
colours, where the point at offset ``(dx, dy)`` from the centre has the colour of a flow
``(dx, dy)`` (the colour right of the centre is "moving right") and its rim is ``m``.
"""

from __future__ import annotations

from typing import Mapping

import cv2
import numpy as np

from ..errors import ConfigError
from .annotate import text_scale

__all__ = ["flow_to_hsv", "flow_to_bgr", "hue_to_angle", "flow_wheel", "draw_flow_legend",
           "draw_feature_trails"]


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


def flow_wheel(diameter: int) -> tuple[np.ndarray, np.ndarray]:
    """The key of :func:`flow_to_bgr`: a ``(d, d, 3) uint8`` BGR picture in which the pixel at
    offset ``(dx, dy)`` from the centre has the colour of the flow ``(dx, dy)`` scaled so that
    the rim is the full-brightness magnitude, and the ``(d, d) bool`` disc it fills."""
    d = max(3, int(diameter))
    r = (d - 1) / 2.0
    v, u = np.mgrid[0:d, 0:d].astype(np.float32) - np.float32(r)
    wheel = flow_to_bgr(np.dstack([u, v]), max_magnitude=r)
    return wheel, u * u + v * v <= r * r


def draw_flow_legend(img: np.ndarray, max_magnitude: float) -> None:
    """The colour wheel of :func:`flow_wheel`, a fifth of the frame's smaller side across, on a
    translucent dark panel in the top-right corner of ``img`` (in place), with the magnitude of
    its rim in px/frame (``max_magnitude``: fixed, or the frame's largest)."""
    h, w = img.shape[:2]
    scale, thick = text_scale(img.shape)
    d = max(16, min(h, w) // 5)
    pad = max(3, d // 12)
    text = f"rim {max_magnitude:.3g} px/frame"
    (tw, th), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
    pw, ph = min(w, max(d, tw) + 2 * pad), min(h, d + th + base + 3 * pad)
    panel = img[0:ph, w - pw:w]
    panel[:] = (panel.astype(np.uint16) * 2 // 5).astype(np.uint8)
    wheel, disc = flow_wheel(d)
    wx = (pw - d) // 2
    region = panel[pad:pad + d, wx:wx + d]
    dh, dw = region.shape[:2]
    region[disc[:dh, :dw]] = wheel[:dh, :dw][disc[:dh, :dw]]
    cv2.putText(panel, text, ((pw - tw) // 2, pad * 2 + d + th), cv2.FONT_HERSHEY_SIMPLEX, scale,
                (255, 255, 255), thick, cv2.LINE_AA)


def draw_feature_trails(img: np.ndarray, trails: list[tuple[int, np.ndarray]],
                        colors: Mapping[int, tuple[int, int, int]]) -> None:
    """Draw each feature point's trail and current position in its object's colour (``colors``:
    object id → BGR, as its box is drawn) (in place)."""
    for oid, tr in trails:
        color = colors[oid]
        if len(tr) > 1:
            cv2.polylines(img, [np.round(tr).astype(np.int32).reshape(-1, 1, 2)], False, color, 1,
                          cv2.LINE_AA)
        if len(tr):
            x, y = tr[-1]
            cv2.circle(img, (int(round(x)), int(round(y))), 2, color, -1)
