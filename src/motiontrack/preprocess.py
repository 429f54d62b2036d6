"""Pure frame → frame preprocessing: processing scale, grayscale, blur, region of interest."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from .config import PreprocessConfig
from .errors import InputError

__all__ = ["preprocess", "load_roi", "scaled_size", "resolve_scale", "AUTO_PIXELS", "AUTO_MIN_SCALE"]

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


def preprocess(image: np.ndarray, cfg: PreprocessConfig) -> np.ndarray:
    """Resize to the processing scale, convert to gray, blur. Returns a new array.

    Parameters
    ----------
    image : (H, W, 3) or (H, W) uint8
    cfg : PreprocessConfig

    Returns
    -------
    (h, w) or (h, w, 3) uint8 at ``cfg.scale`` of the input size (see :func:`resolve_scale`
    for the automatic scale 0).
    """
    out = image
    scale = resolve_scale(cfg.scale, image.shape[1], image.shape[0])
    if scale != 1.0:
        w, h = scaled_size(image.shape[1], image.shape[0], scale)
        out = cv2.resize(out, (w, h), interpolation=cv2.INTER_AREA)
    if cfg.grayscale and out.ndim == 3:
        out = cv2.cvtColor(out, cv2.COLOR_BGR2GRAY)
    k = cfg.blur_kernel
    if cfg.blur == "gaussian" and k > 1:
        out = cv2.GaussianBlur(out, (k, k), 0)
    elif cfg.blur == "median" and k > 1:
        out = cv2.medianBlur(out, k)
    return out if out is not image else image.copy()


def load_roi(path: str | Path, width: int, height: int) -> np.ndarray:
    """Load a region-of-interest mask and resize it to ``(height, width)``: uint8 0/255."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"ROI mask not found: {p}")
    roi = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
    if roi is None:
        raise InputError(f"cannot read ROI mask image {p}")
    if roi.shape != (height, width):
        roi = cv2.resize(roi, (width, height), interpolation=cv2.INTER_NEAREST)
    return np.where(roi > 0, 255, 0).astype(np.uint8)
