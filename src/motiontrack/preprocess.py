"""Pure frame → frame preprocessing: processing scale, grayscale, blur, region of interest."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from .config import PreprocessConfig
from .errors import InputError
from .imaging import resolve_scale, scaled_size
from .io.imagesize import DEFAULT_MAX_PIXELS, check_image

__all__ = ["preprocess", "load_roi"]


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


def load_roi(path: str | Path, width: int, height: int,
             max_pixels: int = DEFAULT_MAX_PIXELS) -> np.ndarray:
    """Load a region-of-interest mask and resize it to ``(height, width)``: uint8 0/255; a file
    whose header claims more than ``max_pixels`` (``source.max_pixels``) is refused undecoded."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"ROI mask not found: {p}")
    check_image(p, max_pixels)
    roi = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
    if roi is None:
        raise InputError(f"cannot read ROI mask image {p}")
    if roi.shape != (height, width):
        roi = cv2.resize(roi, (width, height), interpolation=cv2.INTER_NEAREST)
    return np.where(roi > 0, 255, 0).astype(np.uint8)
