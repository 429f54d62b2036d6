"""Heat map pictures: visit counts smoothed, colour-mapped and laid over a background frame, or
over a ground-plane grid with metre ticks.

The smoothing is a Gaussian (``cv2.GaussianBlur``); colour and opacity follow the square root
of the smoothed visits relative to the most visited place, so that places crossed only a few
times stay visible next to where people stood for long. Below :data:`FLOOR` of that maximum
nothing is drawn: the background shows through untouched.
"""

from __future__ import annotations

import math
from typing import Sequence

import cv2
import numpy as np

from .annotate import text_scale

__all__ = ["FLOOR", "COLORMAP", "smooth", "heat_overlay", "world_heat_map", "grid_step"]

#: places with less than this fraction of the most visited one are not coloured
FLOOR = 0.02
#: OpenCV colour map: blue (rarely) → red (most)
COLORMAP = cv2.COLORMAP_TURBO
#: opacity of the colour where the visits are highest
_ALPHA = 0.75


def smooth(counts: np.ndarray, sigma_px: float) -> np.ndarray:
    """``counts`` blurred by a Gaussian of ``sigma_px`` pixels (float32, same shape)."""
    c = np.asarray(counts, dtype=np.float32)
    if sigma_px <= 0 or not c.any():
        return c.copy()
    k = 2 * int(math.ceil(3.0 * sigma_px)) + 1
    return cv2.GaussianBlur(c, (k, k), sigmaX=sigma_px, sigmaY=sigma_px,
                            borderType=cv2.BORDER_CONSTANT)


def _paint(img: np.ndarray, density: np.ndarray) -> np.ndarray:
    """``density`` (H, W) colour-mapped over ``img`` (H, W, 3 uint8), a new image."""
    peak = float(density.max()) if density.size else 0.0
    if peak <= 0:
        return img.copy()
    level = np.sqrt(np.clip(density / peak, 0.0, 1.0))
    colors = cv2.applyColorMap(np.round(level * 255).astype(np.uint8), COLORMAP)
    alpha = np.where(level * level >= FLOOR, _ALPHA * level, 0.0)[:, :, None]
    out = img.astype(np.float32) * (1.0 - alpha) + colors.astype(np.float32) * alpha
    return np.clip(np.round(out), 0, 255).astype(np.uint8)


def _bgr(background: np.ndarray | None, width: int, height: int) -> np.ndarray:
    """The background as (height, width, 3) uint8 BGR: gray expanded, another size resized,
    none black."""
    if background is None:
        return np.zeros((height, width, 3), dtype=np.uint8)
    bg = np.asarray(background)
    if bg.dtype != np.uint8:
        bg = np.clip(bg, 0, 255).astype(np.uint8)
    if bg.ndim == 2:
        bg = cv2.cvtColor(bg, cv2.COLOR_GRAY2BGR)
    elif bg.shape[2] == 4:
        bg = cv2.cvtColor(bg, cv2.COLOR_BGRA2BGR)
    if bg.shape[:2] != (height, width):
        bg = cv2.resize(bg, (width, height), interpolation=cv2.INTER_LINEAR)
    return bg


def _polylines(img: np.ndarray, lines: Sequence[np.ndarray]) -> None:
    for pts in lines:
        q = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
        if len(q) >= 2 and np.all(np.isfinite(q)) and np.all(np.abs(q) < 1e6):
            cv2.polylines(img, [np.round(q).astype(np.int32)], False, (255, 255, 255), 1,
                          cv2.LINE_AA)


def heat_overlay(counts: np.ndarray, background: np.ndarray | None, sigma_px: float,
                 lines: Sequence[np.ndarray] = ()) -> np.ndarray:
    """Visits per pixel (H, W) smoothed and coloured over ``background`` (any size, gray or BGR,
    resized to W x H; ``None``: black), with ``lines`` ((M, 2) pixel polylines: the scene's
    lines and zone outlines) drawn thin and white. Returns (H, W, 3) uint8 BGR."""
    h, w = counts.shape
    out = _paint(_bgr(background, w, h), smooth(counts, sigma_px))
    _polylines(out, lines)
    return out


def grid_step(span_m: float, max_lines: int = 20) -> float:
    """The grid spacing (1, 2, 5, 10, 20, ... metres) giving at most ``max_lines`` lines over
    ``span_m`` metres."""
    step = 1.0
    while span_m / step > max_lines:
        for m in (2.0, 2.5, 2.0):   # 1 → 2 → 5 → 10 → 20 → 50 → ...
            step *= m
            if span_m / step <= max_lines:
                break
    return step


def world_heat_map(centres: np.ndarray, visits: np.ndarray,
                   extent: tuple[float, float, float, float], px_per_m: float,
                   sigma_m: float = 0.2, border: int = 40,
                   lines: Sequence[np.ndarray] = ()) -> np.ndarray:
    """The ground plane seen from above: ``X`` to the right, ``Y`` up, a grid line every
    :func:`grid_step` metres labelled on the left and bottom margins, and the visits coloured.

    Parameters
    ----------
    centres : (K, 2) float metres, the visited cells' centres; ``visits`` (K,) their counts.
    extent : ``(x0, x1, y0, y1)`` metres shown.
    px_per_m : pixels per metre.
    sigma_m : the smoothing in metres.
    border : pixels of margin around the plot for the tick labels.
    lines : (M, 2) arrays of ground points (metres) drawn as open polylines (scene geometry).

    Returns
    -------
    (border * 2 + (y1 - y0) * px_per_m, border * 2 + (x1 - x0) * px_per_m, 3) uint8 BGR.
    """
    x0, x1, y0, y1 = extent
    pw = int(round((x1 - x0) * px_per_m))
    ph = int(round((y1 - y0) * px_per_m))
    img = np.full((ph + 2 * border, pw + 2 * border, 3), 24, dtype=np.uint8)

    def to_px(xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        return np.column_stack([border + (xy[:, 0] - x0) * px_per_m,
                                border + (y1 - xy[:, 1]) * px_per_m])

    counts = np.zeros(img.shape[:2], dtype=np.float32)
    if len(centres):
        p = np.floor(to_px(centres)).astype(np.int64)
        ok = ((p[:, 0] >= 0) & (p[:, 0] < img.shape[1]) & (p[:, 1] >= 0)
              & (p[:, 1] < img.shape[0]))
        np.add.at(counts, (p[ok, 1], p[ok, 0]), np.asarray(visits, dtype=np.float32)[ok])
    plot = img[border:border + ph, border:border + pw]
    plot[:] = 40
    grid, label = (70, 70, 70), (200, 200, 200)
    scale, thick = text_scale(img.shape)
    scale *= 0.5
    step = grid_step(max(x1 - x0, y1 - y0))
    for gx in np.arange(math.ceil(x0 / step) * step, x1 + 1e-9, step):
        u = int(round(border + (gx - x0) * px_per_m))
        cv2.line(img, (u, border), (u, border + ph), grid, 1)
        text = f"{gx:g}"
        (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
        cv2.putText(img, text, (u - tw // 2, border + ph + th + 6), cv2.FONT_HERSHEY_SIMPLEX,
                    scale, label, thick, cv2.LINE_AA)
    for gy in np.arange(math.ceil(y0 / step) * step, y1 + 1e-9, step):
        v = int(round(border + (y1 - gy) * px_per_m))
        cv2.line(img, (border, v), (border + pw, v), grid, 1)
        text = f"{gy:g}"
        (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
        cv2.putText(img, text, (max(0, border - tw - 4), v + th // 2), cv2.FONT_HERSHEY_SIMPLEX,
                    scale, label, thick, cv2.LINE_AA)
    cv2.putText(img, "X (m)", (border + pw - 40, img.shape[0] - 4), cv2.FONT_HERSHEY_SIMPLEX,
                scale, label, thick, cv2.LINE_AA)
    cv2.putText(img, "Y (m)", (2, max(12, border - 10)), cv2.FONT_HERSHEY_SIMPLEX,
                scale, label, thick, cv2.LINE_AA)
    out = _paint(img, smooth(counts, sigma_m * px_per_m))
    _polylines(out, [to_px(pts) for pts in lines])
    return out
