"""Ground-truth statistics: the thesis' statistical model of object size (eqs. 4.27–4.30).

The thesis (its ``bbstatistics`` script) chooses the region-size filter of the motion detector from
the ground truth instead of by hand. With ``N`` considered ground-truth boxes of width ``w_i`` and
height ``h_i`` in an image of ``W × H`` pixels, and the relative areas ``a_i = w_i h_i / (W H)``:

* eq. 4.27, mean relative area       ``μ = (1/N) Σ a_i``
* eq. 4.28, its standard deviation   ``σ = sqrt((1/N) Σ (a_i − μ)²)``  (population form, ``ddof=0``)
* eq. 4.29, ``MIN_REGION_SIZE = μ − σ`` (clamped at 0)
* eq. 4.30, ``MAX_REGION_SIZE = μ + σ`` (clamped at 1)

both as fractions of the image area — the units of ``regions.min_size`` / ``regions.max_size``. The
same model applied to the height-to-width ratios ``r_i = h_i / w_i`` gives the limits
``μ_r − σ_r`` and ``μ_r + σ_r`` for ``regions.min_hw_ratio`` / ``regions.max_hw_ratio``. Boxes with
``consider == False`` (MOT ground-truth "ignore" rows) are left out.
"""

from __future__ import annotations

import math
from typing import Iterable

import numpy as np

from ..errors import ConfigError, InputError
from ..types import Annotations

__all__ = ["gt_statistics", "size_model", "parse_image_size"]


def parse_image_size(text: str) -> tuple[int, int]:
    """``"768x576"`` → ``(768, 576)``."""
    parts = text.lower().replace("×", "x").split("x")
    try:
        w, h = (int(p) for p in parts)
    except ValueError:
        raise ConfigError(f"--image-size expects WxH in pixels, e.g. 768x576, got {text!r}") from None
    if not (0 < w <= MAX_IMAGE_SIDE and 0 < h <= MAX_IMAGE_SIDE):
        raise ConfigError(f"--image-size must be between 1 and {MAX_IMAGE_SIDE} pixels each way, "
                          f"got {text!r}")
    return w, h


#: largest image width or height (pixels) for the statistics
MAX_IMAGE_SIDE = 1_000_000


def size_model(values: np.ndarray, ddof: int = 0) -> tuple[float, float]:
    """Mean and standard deviation of ``values`` (``nan, nan`` when there are none)."""
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    if len(v) == 0 or len(v) <= ddof:
        return float("nan"), float("nan")
    return float(v.mean()), float(v.std(ddof=ddof))


def _clip01(v: float, hi: float | None = 1.0) -> float:
    if math.isnan(v):
        return v
    v = max(v, 0.0)
    return min(v, hi) if hi is not None else v


def gt_statistics(annotations: Iterable[Annotations], image_size: tuple[int, int],
                  ddof: int = 0) -> dict[str, object]:
    """The statistical size model of the ground truth (thesis eqs. 4.27–4.30).

    Parameters
    ----------
    annotations : one or more ground-truth tables (pooled).
    image_size : (W, H) in pixels.
    ddof : 0 (population standard deviation, the thesis' form) or 1 (sample).

    Returns
    -------
    dict
        Keys say what each number is (areas in px² or as fractions of the image area ``W·H``);
        ``recommended_overrides`` lists the ``--set`` strings for the region filter.
    """
    W, H = image_size
    if not (0 < W <= MAX_IMAGE_SIDE and 0 < H <= MAX_IMAGE_SIDE):
        raise ConfigError(f"image size must be between 1 and {MAX_IMAGE_SIDE} pixels each way, "
                          f"got {W}x{H}")
    if ddof not in (0, 1):
        raise ConfigError(f"ddof must be 0 or 1, got {ddof}")
    boxes = [a.boxes[np.asarray(a.consider, dtype=bool)] for a in annotations]
    b = np.concatenate(boxes) if boxes else np.zeros((0, 4))
    w, h = b[:, 2], b[:, 3]
    with np.errstate(over="ignore"):
        area_px = w * h
    if not np.isfinite(area_px).all():
        k = int(np.flatnonzero(~np.isfinite(area_px))[0])
        raise InputError(f"ground-truth box {w[k]:g} x {h[k]:g} px: its area is not a finite "
                         "number")
    rel = area_px / float(W * H)
    ratio = h / w if len(w) else np.zeros(0)
    mu, sd = size_model(rel, ddof)              # eqs. 4.27, 4.28
    mu_px, sd_px = size_model(area_px, ddof)
    mu_r, sd_r = size_model(ratio, ddof)
    lo, hi = _clip01(mu - sd), _clip01(mu + sd)  # eqs. 4.29, 4.30
    lo_r, hi_r = _clip01(mu_r - sd_r, None), _clip01(mu_r + sd_r, None)

    def num(v: float) -> float | None:
        return None if math.isnan(v) else float(v)

    out: dict[str, object] = {
        "n_boxes": int(len(b)),
        "image_width_px": int(W),
        "image_height_px": int(H),
        "image_area_px2": int(W * H),
        "std_ddof": ddof,
        "area_mean_px2": num(mu_px),
        "area_std_px2": num(sd_px),
        "area_min_px2": num(float(area_px.min())) if len(b) else None,
        "area_max_px2": num(float(area_px.max())) if len(b) else None,
        "area_mean_fraction_of_image (mu, eq. 4.27)": num(mu),
        "area_std_fraction_of_image (sigma, eq. 4.28)": num(sd),
        "MIN_REGION_SIZE_fraction_of_image (mu - sigma, eq. 4.29)": num(lo),
        "MAX_REGION_SIZE_fraction_of_image (mu + sigma, eq. 4.30)": num(hi),
        "MIN_REGION_SIZE_px2": num(lo * W * H),
        "MAX_REGION_SIZE_px2": num(hi * W * H),
        "height_to_width_mean": num(mu_r),
        "height_to_width_std": num(sd_r),
        "height_to_width_observed_min": num(float(ratio.min())) if len(b) else None,
        "height_to_width_observed_max": num(float(ratio.max())) if len(b) else None,
        "MIN_HEIGHT_TO_WIDTH (mean - std)": num(lo_r),
        "MAX_HEIGHT_TO_WIDTH (mean + std)": num(hi_r),
    }
    out["recommended_overrides"] = [] if not len(b) else [
        f"regions.min_size={lo:.6g}", f"regions.max_size={hi:.6g}",
        f"regions.min_hw_ratio={lo_r:.6g}", f"regions.max_hw_ratio={hi_r:.6g}",
    ]
    return out
