"""Human feature (head) detector of the Reading People Tracker.

Siebel's thesis (section 4.3, "Human Feature Tracker") finds heads in a motion region from its
*vertical height profile*: scan each column from the top of the region for the first foreground
pixel; a head is an interval of columns with similar top heights that stands out above its
neighbours on both sides (the shoulders, or the gap to the next person). Steps, numbered as in
:func:`detect_heads`:

1. profile ``top[x]`` = row of the first foreground pixel in column ``x`` of the region (columns
   without foreground get the region's bottom), smoothed by a running median of 3 columns;
2. a column is a *peak column* when its top is within ``tolerance`` px of the highest top within
   ``min_width`` columns either side (a local maximum of the silhouette, plateau included);
3. consecutive peak columns form intervals; an interval narrower than ``min_width`` or wider than
   ``max_width`` is dropped;
4. the interval must stand out: on each side, the highest top within ``min_width`` columns
   beyond its edge lies at least ``min_drop`` px lower (off the region counts as infinitely low);
   tops are whole mask rows, so ``min_drop`` is rounded to whole mask pixels (at least 1): a head
   whose flank is 2 mask rows below its top then stands out the same way at scale 0.5 (2 rows =
   the 4 px default) and 0.6 (2.4 rows), instead of vanishing at scales where the drop falls
   between two rows;
5. the head is at ``x`` = interval centre and ``y`` = the interval's mean top + half the interval
   width (the head's centre, assuming a round head as wide as the interval).

Heads seed people: :func:`split_region_by_heads` cuts a merged region between adjacent heads.
Widths are given in original-frame pixels and converted with the mask ``scale``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from ..imaging import pixel_window
from ..types import Box, Region

__all__ = ["Head", "height_profile", "detect_heads", "detect_heads_many", "detect_heads_in_regions",
           "split_region_by_heads", "split_regions_by_heads"]


@dataclass(frozen=True)
class Head:
    """A detected head, original-frame pixels.

    Attributes
    ----------
    x, y : float
        Head centre.
    width : float
        Width of the head interval.
    top : float
        Mean top of the interval (row of the top of the head).
    """

    x: float
    y: float
    width: float
    top: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.x) and math.isfinite(self.y)) or self.width <= 0:
            raise ValueError(f"head needs a finite position and width > 0, got {self}")


def height_profile(mask: np.ndarray) -> np.ndarray:
    """Row of the first foreground pixel per column of a (cropped) mask.

    Parameters
    ----------
    mask : (h, w) array
        Non-zero = foreground.

    Returns
    -------
    (w,) float64
        ``top[x]`` in rows from the crop's top; ``h`` for empty columns.
    """
    m = np.asarray(mask) > 0
    if m.ndim != 2:
        raise ValueError(f"mask must be 2-D, got shape {m.shape}")
    h = m.shape[0]
    any_fg = m.any(axis=0)
    top = np.where(any_fg, np.argmax(m, axis=0), h).astype(np.float64)
    return top


def _running_max_top(top: np.ndarray, r: int) -> np.ndarray:
    """Highest (smallest) top within ``r`` columns either side: ``min(top[x-r:x+r+1])``."""
    if r <= 0 or len(top) == 0:
        return top.copy()
    # numpy's sliding windows, not scipy.ndimage's minimum_filter1d: the same minima without
    # the third of a second scipy.ndimage adds to every command's start
    padded = np.concatenate((np.full(r, np.inf), top, np.full(r, np.inf)))
    return sliding_window_view(padded, 2 * r + 1).min(axis=1)


def detect_heads(mask: np.ndarray, box: Box | None = None, scale: float = 1.0,
                 min_width: float = 6.0, max_width: float = 40.0, tolerance: float = 3.0,
                 min_drop: float = 4.0) -> list[Head]:
    """Heads in one motion region (thesis section 4.3; steps in the module docstring).

    Parameters
    ----------
    mask : (H, W) uint8
        Motion mask (non-zero = foreground) at processing resolution.
    box : Box, optional
        The region's box in original-frame pixels (default: the whole mask).
    scale : float
        Mask pixels per original pixel (the pipeline's ``preprocess.scale``).
    min_width, max_width : float
        Head interval width limits, original pixels.
    tolerance : float
        "Similar height": tops within this many original px of the local maximum.
    min_drop : float
        How much lower (original px) the neighbours must be.

    Returns
    -------
    list of Head
        Sorted by ``x``; original-frame pixels. Empty for an empty region.
    """
    m = np.asarray(mask)
    H, W = m.shape[:2]
    x1, y1, x2, y2 = (0, 0, W, H) if box is None else pixel_window(box.as_array(), scale, (H, W))
    if x2 <= x1 or y2 <= y1:
        return []
    crop = m[y1:y2, x1:x2]
    # 1. profile, smoothed across 3 columns (single-column mask noise).
    top = _median3(height_profile(crop))
    g = _mask_sizes(scale, min_width, max_width, tolerance, min_drop)
    # 2. peak columns: within tol of the highest top within one (smallest) head width.
    peak = (top <= _running_max_top(top, g.reach) + g.tol) & (top < crop.shape[0])
    # 3. runs of peak columns.
    heads: list[Head] = []
    for a, b in zip(*_runs(peak)):  # columns a .. b-1
        width = b - a
        if width < g.wmin or width > g.wmax:
            continue
        level = float(top[a:b].min())
        # 4. stand out on both sides (off the region = infinitely low).
        if not _stands_out(top, a, b, level, g):
            continue
        # 5. position: interval centre; y = mean top + half the width (round head).
        heads.append(_head(x1, y1, a, b, float(top[a:b].mean()), scale))
    return heads


@dataclass(frozen=True)
class _MaskSizes:
    """The detector's limits in mask pixels (steps 2-4 of the module docstring)."""

    wmin: float   # narrowest head interval
    wmax: float   # widest head interval
    tol: float    # "similar height" of a peak column
    drop: float   # how much lower the neighbours must be, whole rows
    reach: int    # columns either side searched for the highest top and for the neighbours


def _mask_sizes(scale: float, min_width: float, max_width: float, tolerance: float,
                min_drop: float) -> _MaskSizes:
    """The widths, tolerance and drop given in original pixels, in mask pixels."""
    wmin = max(1.0, min_width * scale)
    return _MaskSizes(wmin=wmin, wmax=max(wmin, max_width * scale), tol=tolerance * scale,
                      drop=_drop_px(min_drop, scale), reach=max(1, int(np.ceil(wmin))))


def _median3(top: np.ndarray) -> np.ndarray:
    """Running median of three columns, edges repeated: ``max(min(a, b), min(max(a, b), c))``."""
    if len(top) < 3:
        return top
    a = np.concatenate(([top[0]], top[:-1]))
    c = np.concatenate((top[1:], [top[-1]]))
    return np.maximum(np.minimum(a, top), np.minimum(np.maximum(a, top), c))


def _runs(peak: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and stops (exclusive) of the runs of True in ``peak``."""
    d = np.diff(np.concatenate(([0], peak.astype(np.int8), [0])))
    return np.flatnonzero(d == 1), np.flatnonzero(d == -1)


def _stands_out(top: np.ndarray, a: int, b: int, level: float, g: _MaskSizes) -> bool:
    """Step 4: the highest top within ``reach`` columns beyond each edge of columns ``a .. b-1``
    lies at least ``drop`` rows below ``level`` (no columns beyond an edge: it stands out)."""
    left = top[max(0, a - g.reach):a]
    right = top[b:b + g.reach]
    return not ((len(left) and left.min() < level + g.drop)
                or (len(right) and right.min() < level + g.drop))


def _head(x1: int, y1: int, a: int, b: int, mean_top: float, scale: float) -> Head:
    """Step 5: the head over columns ``a .. b-1`` of the crop at ``(x1, y1)``, original pixels."""
    width = b - a
    xc = (a + b - 1) / 2.0
    return Head(x=(x1 + xc + 0.5) / scale - 0.5, y=(y1 + mean_top + width / 2.0) / scale,
                width=width / scale, top=(y1 + mean_top) / scale)


def _drop_px(min_drop: float, scale: float) -> float:
    """``min_drop`` (original px) in whole mask rows (nearest, at least 1 when positive)."""
    if min_drop <= 0:
        return 0.0
    return float(max(1, int(np.floor(min_drop * scale + 0.5))))


def detect_heads_many(mask: np.ndarray, boxes, scale: float = 1.0, min_width: float = 6.0,
                      max_width: float = 40.0, tolerance: float = 3.0,
                      min_drop: float = 4.0) -> list[list[Head]]:
    """:func:`detect_heads` for many regions of one mask at once (same results, one list per
    box in order).

    The profiles of all regions are laid end to end with ``inf`` columns between them (off a
    region counts as infinitely low, exactly as at a region's edge), so the smoothing, the
    running maximum and the peak search run once per frame instead of once per region. The
    pipeline uses this; :func:`detect_heads` stays the step-by-step reference it is tested
    against (``tests/people/test_heads.py``).
    """
    m = np.asarray(mask)
    if m.ndim != 2:
        raise ValueError(f"mask must be 2-D, got shape {m.shape}")
    g = _mask_sizes(scale, min_width, max_width, tolerance, min_drop)
    top, heights, segs = _profiles(m, boxes, scale, g.reach)
    out: list[list[Head]] = [[] for _ in boxes]
    if not segs:
        return out
    peak = (top <= _running_max_top(top, g.reach) + g.tol) & (top < heights)
    starts, stops = _runs(peak)
    widths = stops - starts
    ok = (widths >= g.wmin) & (widths <= g.wmax)
    if not ok.any():
        return out
    starts, stops, widths = starts[ok], stops[ok], widths[ok]
    # per-run min and mean: reduceat over [a0, b0, a1, b1, ...] and every other entry (the
    # profile ends with an inf gap, so every stop is a valid index)
    bounds = np.column_stack([starts, stops]).ravel()
    levels = np.minimum.reduceat(top, bounds)[::2]
    means = np.add.reduceat(top, bounds)[::2] / widths
    seg_starts = np.array([s[1] for s in segs])
    for a, b, lv, mt in zip(starts.tolist(), stops.tolist(), levels.tolist(), means.tolist()):
        # stand out on both sides (the inf gap between regions is "infinitely low")
        if not _stands_out(top, a, b, lv, g):
            continue
        k, s0, _, x1, y1 = segs[int(np.searchsorted(seg_starts, a, side="right")) - 1]
        out[k].append(_head(x1, y1, a - s0, b - s0, mt, scale))
    return out


def _profiles(m: np.ndarray, boxes, scale: float, reach: int
              ) -> tuple[np.ndarray, np.ndarray, list[tuple[int, int, int, int, int]]]:
    """The smoothed profiles of the non-empty boxes laid end to end, each followed by
    ``reach + 1`` ``inf`` columns; the height of the region each column belongs to (0 in the
    gaps); and ``(box index, start, stop, x1, y1)`` per profile."""
    H, W = m.shape
    gap = np.full(reach + 1, np.inf)
    pieces: list[np.ndarray] = []
    heights: list[float] = []   # per profile and gap, laid out by one np.repeat
    lengths: list[int] = []
    segs: list[tuple[int, int, int, int, int]] = []
    pos = 0
    for k, box in enumerate(boxes):
        x1, y1, x2, y2 = pixel_window(box.as_array(), scale, (H, W))
        if x2 <= x1 or y2 <= y1:
            continue
        top = _median3(height_profile(m[y1:y2, x1:x2]))
        n = len(top)
        pieces += [top, gap]
        heights += [float(y2 - y1), 0.0]
        lengths += [n, len(gap)]
        segs.append((k, pos, pos + n, x1, y1))
        pos += n + len(gap)
    if not segs:
        return np.zeros(0), np.zeros(0), segs
    return np.concatenate(pieces), np.repeat(heights, lengths), segs


def detect_heads_in_regions(mask: np.ndarray, regions, scale: float = 1.0, **params) -> list[list[Head]]:
    """:func:`detect_heads` for each region; one list per region (same order)."""
    return detect_heads_many(mask, [r.box for r in regions], scale, **params)


def split_region_by_heads(region: Region, mask: np.ndarray, heads: list[Head] | None = None,
                          scale: float = 1.0, min_fraction: float = 0.1, **params) -> list[Region]:
    """Separate the people inside a merged region at the midpoints between adjacent heads.

    Parameters
    ----------
    region : Region
        Motion region, original-frame pixels.
    mask : (H, W) uint8
        Motion mask at processing resolution (``scale`` mask px per original px).
    heads : list of Head, optional
        Heads in this region (default: :func:`detect_heads` with ``params``).
    min_fraction : float
        A part with fewer than this fraction of the region's foreground pixels is dropped.

    Returns
    -------
    list of Region
        One region per head (tight box around the foreground of its vertical slice, centroid and
        area from those pixels, the parent's score); ``[region]`` unchanged with fewer than two
        heads or when the split leaves fewer than two usable parts.
    """
    if heads is None:
        heads = detect_heads(mask, region.box, scale, **params)
    heads = sorted((h for h in heads if region.box.x <= h.x <= region.box.x2), key=lambda h: h.x)
    if len(heads) < 2:
        return [region]
    m = np.asarray(mask)
    Hm, Wm = m.shape[:2]
    x1, y1, x2, y2 = pixel_window(region.box.as_array(), scale, (Hm, Wm))
    fg = m[y1:y2, x1:x2] > 0
    total = int(fg.sum())
    if total == 0:
        return [region]
    # Cut columns (mask px, relative to the crop) halfway between adjacent head centres.
    cuts = [int(round((a.x + b.x) / 2.0 * scale)) - x1 for a, b in zip(heads[:-1], heads[1:])]
    edges = [0] + [min(max(c, 0), fg.shape[1]) for c in cuts] + [fg.shape[1]]
    parts: list[Region] = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sub = fg[:, lo:hi]
        if hi <= lo or int(sub.sum()) < min_fraction * total:
            continue
        parts.append(_part(sub, x1 + lo, y1, scale, region.score))
    return parts if len(parts) >= 2 else [region]


def _part(fg: np.ndarray, ox: int, oy: int, scale: float, score: float) -> Region:
    """The region of the foreground ``fg`` of a mask slice at ``(ox, oy)``, original pixels: its
    tight box, centroid and area."""
    ys, xs = np.nonzero(fg)
    bx1, bx2 = (ox + xs.min()) / scale, (ox + xs.max() + 1) / scale
    by1, by2 = (oy + ys.min()) / scale, (oy + ys.max() + 1) / scale
    cx = (ox + xs.mean() + 0.5) / scale
    cy = (oy + ys.mean() + 0.5) / scale
    return Region(box=Box.from_xyxy(bx1, by1, bx2, by2), centroid=(cx, cy),
                  area=int(fg.sum()) / (scale * scale), score=score)


def split_regions_by_heads(mask: np.ndarray, regions: Sequence[Region], scale: float = 1.0,
                           search: Sequence[bool] | None = None, split: bool = True, **params
                           ) -> tuple[list[Region], list[Head]]:
    """Heads in the regions of one mask (:func:`detect_heads_many`) and each region split between
    its heads (:func:`split_region_by_heads`), in order.

    ``search`` (one flag per region, default all) picks the regions searched for heads; the others
    pass unchanged. With ``split`` false the heads are found but no region is split. Returns
    ``(regions, heads)``.
    """
    picked = range(len(regions)) if search is None else [k for k, s in enumerate(search) if s]
    found = detect_heads_many(mask, [regions[k].box for k in picked], scale, **params)
    heads = dict(zip(picked, found))
    out: list[Region] = []
    for k, r in enumerate(regions):
        hs = heads.get(k)
        out.extend(split_region_by_heads(r, mask, hs, scale) if split and hs else [r])
    return out, [h for hs in found for h in hs]
