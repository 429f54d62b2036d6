"""Mask clean-up: median filter, erosion (removes specks), dilation (closes gaps)."""

from __future__ import annotations

import cv2
import numpy as np

from ..config import CleanupConfig

_KERNELS: dict[int, np.ndarray] = {}


def _kernel(k: int) -> np.ndarray:
    if k not in _KERNELS:
        _KERNELS[k] = cv2.getStructuringElement(cv2.MORPH_RECT, (k, k))
    return _KERNELS[k]


def clean_mask(mask: np.ndarray, cfg: CleanupConfig, scale: float = 1.0) -> np.ndarray:
    """Apply the clean-up steps of ``cfg`` in order; returns a new uint8 0/255 mask.

    Kernel sizes are in processing pixels (``scale`` is accepted for callers that want to keep
    them in original pixels, but the defaults are tuned for the default processing scale).
    """
    out = mask
    if cfg.median_kernel > 1:
        out = cv2.medianBlur(out, cfg.median_kernel)
    if cfg.erode_kernel > 0 and cfg.erode_iterations > 0:
        out = cv2.erode(out, _kernel(cfg.erode_kernel), iterations=cfg.erode_iterations)
    if cfg.dilate_kernel > 0 and cfg.dilate_iterations > 0:
        out = cv2.dilate(out, _kernel(cfg.dilate_kernel), iterations=cfg.dilate_iterations)
    return out if out is not mask else mask.copy()
