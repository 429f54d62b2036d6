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

That model describes the annotated boxes, not the motion regions the filter sees, and by
construction about a third of the people fall outside ``μ ± σ``: applied as a filter it drops most
of the people it was computed from. It is reported as the thesis model; what :func:`recommend_regions`
recommends instead are bounds that keep the ground truth's people (robust percentiles of the boxes
and of the groups they form, widened for segmentation noise).
"""

from __future__ import annotations

import math
from typing import Iterable

import numpy as np

from ..errors import ConfigError, InputError
from ..types import Annotations

__all__ = ["gt_statistics", "size_model", "parse_image_size", "recommend_regions", "touching_groups",
           "check_percentile"]


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


#: fraction of its bounding box a person's silhouette covers (limbs leave the corners empty); a
#: region's size is its mask's pixel count, not its box
SILHOUETTE_FILL = 0.5
#: a person whose colours match the background in places splits into pieces; the largest of two
#: holds at least half the pixels, and a top or bottom half has half the height-to-width ratio, a
#: left or right half twice it
FRAGMENT = 0.5
#: a region's pixel count stays below its box area (fill <= 1); twice the annotated box leaves room
#: for shadows, mask dilation and a neighbour whose annotated box does not quite touch
GROWTH = 2.0
#: default low percentile of the recommendation (the high one is 100 minus it)
DEFAULT_PERCENTILE = 5.0


def touching_groups(frames: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Union boxes of the groups of boxes that overlap or touch in the same frame.

    People whose boxes touch form one motion region until something splits them, so the region
    filter must keep the group's box as well as each person's.

    Parameters
    ----------
    frames : (N,) frame numbers.
    boxes : (N, 4) float, ``x, y, w, h`` in pixels.

    Returns
    -------
    (G, 5) float: ``x, y, w, h`` of each group of two or more boxes, then its number of boxes.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    frames = np.asarray(frames).reshape(-1)
    b = np.asarray(boxes, np.float64).reshape(-1, 4)
    n = len(b)
    if n == 0:
        return np.zeros((0, 5))
    x1, y1, x2, y2 = b[:, 0], b[:, 1], b[:, 0] + b[:, 2], b[:, 1] + b[:, 3]
    rows: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    order = np.argsort(frames, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(frames[order]) != 0, True])
    for s, e in zip(starts[:-1], starts[1:]):
        idx = order[s:e]
        for c in range(0, len(idx), 1024):     # blocks bound the memory of a crowded frame
            i = idx[c:c + 1024, None]
            touch = ((x1[i] <= x2[idx]) & (x1[idx] <= x2[i]) & (y1[i] <= y2[idx]) & (y1[idx] <= y2[i]))
            a, k = np.nonzero(touch)
            rows.append(idx[c:c + 1024][a])
            cols.append(idx[k])
    r, c = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(len(r), bool), (r, c)), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    size = np.bincount(label)
    gx1, gy1 = np.full(len(size), np.inf), np.full(len(size), np.inf)
    gx2, gy2 = np.full(len(size), -np.inf), np.full(len(size), -np.inf)
    np.minimum.at(gx1, label, x1)
    np.minimum.at(gy1, label, y1)
    np.maximum.at(gx2, label, x2)
    np.maximum.at(gy2, label, y2)
    keep = size >= 2
    return np.column_stack([gx1, gy1, gx2 - gx1, gy2 - gy1, size])[keep]


def check_percentile(q: float) -> None:
    """Refuse a low percentile outside [0, 50) (the high one, 100 - q, must lie above it)."""
    if not 0.0 <= q < 50.0:
        raise ConfigError(f"--percentile must be in [0, 50), got {q:g}")


def _percentile(v: np.ndarray, q: float) -> float:
    return float(np.percentile(v, q)) if len(v) else float("nan")


def recommend_regions(boxes: np.ndarray, groups: np.ndarray, image_size: tuple[int, int],
                      percentile: float = DEFAULT_PERCENTILE) -> dict[str, float | None]:
    """Region-filter limits that keep the ground truth's people.

    With ``q`` = ``percentile``, ``P_q`` its percentile over the people's boxes and ``G_q`` over
    the groups of touching boxes (:func:`touching_groups`):

    * ``regions.min_size = SILHOUETTE_FILL · FRAGMENT · P_q(area) / (W H)``: the largest piece of a
      small person split in two;
    * ``regions.max_size = GROWTH · max(P_100−q(area), G_100−q(area)) / (W H)``: a large person or
      group with its shadow (at most 1);
    * ``regions.min_hw_ratio = FRAGMENT · min(P_q(h/w), G_q(h/w))``: a wide group, or the top half
      of a person;
    * ``regions.max_hw_ratio = max(P_100−q(h/w), G_100−q(h/w)) / FRAGMENT``: a tall person's left
      or right half.

    Percentiles, not the extremes, so one mistaken annotation moves nothing. Groups are a
    population of their own because they are few: a percentile over everything would treat them
    as outliers and the filter would drop every group.

    Parameters
    ----------
    boxes : (N, 4) float, the considered ground-truth boxes ``x, y, w, h`` in pixels.
    groups : (G, 4+) float, the groups' union boxes (extra columns ignored).
    image_size : (W, H) in pixels.
    percentile : the low percentile ``q`` in [0, 50).

    Returns
    -------
    dict
        The percentiles used (``person_*``, ``group_*``; ``None`` without groups) and the four
        ``regions.*`` limits; all ``None`` when there are no boxes.
    """
    check_percentile(percentile)
    W, H = image_size
    b = np.asarray(boxes, np.float64).reshape(-1, 4)
    g = np.asarray(groups, np.float64).reshape(len(groups), -1)[:, :4] if len(groups) else \
        np.zeros((0, 4))
    lo_q, hi_q = percentile, 100.0 - percentile
    area, ratio = b[:, 2] * b[:, 3], b[:, 3] / b[:, 2]
    g_area, g_ratio = g[:, 2] * g[:, 3], g[:, 3] / g[:, 2]
    p = {"person_area_low_px2": _percentile(area, lo_q),
         "person_area_high_px2": _percentile(area, hi_q),
         "person_height_to_width_low": _percentile(ratio, lo_q),
         "person_height_to_width_high": _percentile(ratio, hi_q),
         "group_area_high_px2": _percentile(g_area, hi_q),
         "group_height_to_width_low": _percentile(g_ratio, lo_q),
         "group_height_to_width_high": _percentile(g_ratio, hi_q)}
    rec = {"regions.min_size": min(SILHOUETTE_FILL * FRAGMENT * p["person_area_low_px2"] / (W * H), 1.0),
           "regions.max_size": min(GROWTH * np.fmax(p["person_area_high_px2"],
                                                     p["group_area_high_px2"]) / (W * H), 1.0),
           "regions.min_hw_ratio": FRAGMENT * np.fmin(p["person_height_to_width_low"],
                                                      p["group_height_to_width_low"]),
           "regions.max_hw_ratio": np.fmax(p["person_height_to_width_high"],
                                           p["group_height_to_width_high"]) / FRAGMENT}
    return {k: None if math.isnan(v) else float(v) for k, v in {**p, **rec}.items()}


def gt_statistics(annotations: Iterable[Annotations], image_size: tuple[int, int],
                  ddof: int = 0, percentile: float = DEFAULT_PERCENTILE) -> dict[str, object]:
    """The statistical size model of the ground truth (thesis eqs. 4.27–4.30).

    Parameters
    ----------
    annotations : one or more ground-truth tables (pooled).
    image_size : (W, H) in pixels.
    ddof : 0 (population standard deviation, the thesis' form) or 1 (sample).
    percentile : the low percentile of :func:`recommend_regions`.

    Returns
    -------
    dict
        Keys say what each number is (areas in px² or as fractions of the image area ``W·H``).
        The thesis' limits are the ``thesis_model_*`` keys, with ``thesis_model_overrides`` to
        reproduce them; ``recommended_*`` are the limits of :func:`recommend_regions` and
        ``recommended_overrides`` their ``--set`` strings.
    """
    W, H = image_size
    if not (0 < W <= MAX_IMAGE_SIDE and 0 < H <= MAX_IMAGE_SIDE):
        raise ConfigError(f"image size must be between 1 and {MAX_IMAGE_SIDE} pixels each way, "
                          f"got {W}x{H}")
    if ddof not in (0, 1):
        raise ConfigError(f"ddof must be 0 or 1, got {ddof}")
    tables = list(annotations)
    keep = [np.asarray(a.consider, dtype=bool) for a in tables]
    boxes = [a.boxes[k] for a, k in zip(tables, keep)]
    b = np.concatenate(boxes) if boxes else np.zeros((0, 4))
    out = _thesis_model(b, (W, H), ddof)
    # groups form within one file's frames, never across files
    groups = [touching_groups(a.frames[k], a.boxes[k]) for a, k in zip(tables, keep)]
    g = np.concatenate(groups) if groups else np.zeros((0, 5))
    rec = recommend_regions(b, g, (W, H), percentile)
    out["n_groups"] = int(len(g))
    out["percentile_low"] = float(percentile)
    out["percentile_high"] = 100.0 - float(percentile)
    limits = {k: v for k, v in rec.items() if k.startswith("regions.")}
    out.update((k, v) for k, v in rec.items() if not k.startswith("regions."))
    out.update((f"recommended_{k}", v) for k, v in limits.items())
    out["recommended_overrides"] = [] if not len(b) else [
        f"{k}={v:.6g}" for k, v in limits.items()]
    return out


def _num(v: float) -> float | None:
    return None if math.isnan(v) else float(v)


def _thesis_model(b: np.ndarray, image_size: tuple[int, int], ddof: int) -> dict[str, object]:
    """The size statistics of the boxes ``b`` (N, 4) and the thesis' limits from them (eqs.
    4.27–4.30), keyed as :func:`gt_statistics` reports them."""
    W, H = image_size
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
    out: dict[str, object] = {
        "n_boxes": int(len(b)),
        "image_width_px": int(W),
        "image_height_px": int(H),
        "image_area_px2": int(W * H),
        "std_ddof": ddof,
        "area_mean_px2": _num(mu_px),
        "area_std_px2": _num(sd_px),
        "area_min_px2": _num(float(area_px.min())) if len(b) else None,
        "area_max_px2": _num(float(area_px.max())) if len(b) else None,
        "area_mean_fraction_of_image (mu, eq. 4.27)": _num(mu),
        "area_std_fraction_of_image (sigma, eq. 4.28)": _num(sd),
        "height_to_width_mean": _num(mu_r),
        "height_to_width_std": _num(sd_r),
        "height_to_width_observed_min": _num(float(ratio.min())) if len(b) else None,
        "height_to_width_observed_max": _num(float(ratio.max())) if len(b) else None,
        "thesis_model_MIN_REGION_SIZE_fraction_of_image (mu - sigma, eq. 4.29)": _num(lo),
        "thesis_model_MAX_REGION_SIZE_fraction_of_image (mu + sigma, eq. 4.30)": _num(hi),
        "thesis_model_MIN_REGION_SIZE_px2": _num(lo * W * H),
        "thesis_model_MAX_REGION_SIZE_px2": _num(hi * W * H),
        "thesis_model_MIN_HEIGHT_TO_WIDTH (mean - std)": _num(lo_r),
        "thesis_model_MAX_HEIGHT_TO_WIDTH (mean + std)": _num(hi_r),
    }
    out["thesis_model_overrides"] = [] if not len(b) else [
        f"regions.min_size={lo:.6g}", f"regions.max_size={hi:.6g}",
        f"regions.min_hw_ratio={lo_r:.6g}", f"regions.max_hw_ratio={hi_r:.6g}",
    ]
    return out
