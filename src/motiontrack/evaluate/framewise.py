"""Framewise (pixel, object-area and count) metrics of the thesis §4.1 and ViPER-PE.

Every frame is judged on its own, ignoring identities. With ``T`` the target (ground-truth) boxes of
a frame, ``C`` the candidate (result) boxes, ``UT`` / ``UC`` their unions (areas of unions, so
overlapping boxes are not counted twice) and ``|.|`` the area in pixels:

* matched pixels ``|UT ∩ UC|``, missed pixels ``|UT| - matched``, false pixels ``|UC| - matched``
  (ViPER ``matchedpixels``, ``missedpixels``, ``falsepixels``);
* pixel precision ``matched / |UC|`` = ``1 - false / |UC|`` and pixel recall ``matched / |UT|``
  (thesis §4.1, eqs. for pixel-based precision/recall);
* object area recall, per target ``t``: ``|t ∩ UC| / |t|`` (ViPER ``arearecall``), averaged over
  targets;
* box area precision, per candidate ``c``: ``|c ∩ UT| / |c|`` (ViPER ``areaprecision``), averaged
  over candidates;
* fragmentation, per target overlapped by ``n >= 1`` candidate boxes: ``1 / (1 + log10 n)``
  (ViPER ``fragmentation``), averaged over those targets;
* localized object area recall / box area precision with threshold ``xi``: the fraction of targets
  (candidates) whose area recall (precision) is ``>= xi`` (ViPER ``[arearecall xi]``,
  ``[areaprecision xi]``);
* dice: ViPER's ``dice`` is a *distance*, ``1 - 2|a ∩ b| / (|a| + |b|)``, computed for every target
  against ``UC`` and every candidate against ``UT`` and averaged (ViPER prints it as "Dice
  coefficient"); we report it as ``dice_distance`` and ``dice = 1 - dice_distance``;
* detection accuracy ``2 min(nT, nC) / (nT + nC)``, object count recall ``min(nC / nT, 1)`` and
  precision ``min(nT / nC, 1)`` (ViPER's object counts, "Penn State" tracking measures).

Overall numbers are weighted exactly as ViPER-PE does: pixel counts are summed over frames; the
per-object lists (area recall, area precision, fragmentation, dice) are concatenated over all frames
and averaged over objects (so a frame with more objects weighs more); localized counts are pooled;
object counts are summed before the count ratios are taken. Frames with neither targets nor
candidates are skipped (ViPER does not report them). Undefined values are ``nan``.

Areas are computed analytically (coordinate compression of the box edges of each frame, half-open
boxes ``[x, x+w) x [y, y+h)``), so fractional boxes are exact too. When ``frame_size`` is known
(ViPER's H-FRAME-SIZE / V-FRAME-SIZE) every shape is clipped to ``[0, W) x [0, H)`` before areas are
measured, as ViPER-PE does; fragment counts use the unclipped boxes, as ViPER-PE does.

References
----------
Thesis §4.1 (framewise evaluation); D. Doermann, D. Mihalcik, "Tools and techniques for video
performance evaluation", ICPR 2000; V. Manohar et al., "Performance evaluation of object detection and
tracking in video", ACCV 2006 (the area/fragmentation/count measures implemented in ViPER-PE).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from ..types import Annotations

__all__ = ["evaluate_framewise", "frame_measures", "FrameMeasures", "METRIC_KEYS"]

#: keys of the overall dict (and of each per-frame dict, which adds "frame")
METRIC_KEYS = (
    "detection_accuracy",
    "object_count_recall",
    "object_count_precision",
    "dice",
    "dice_distance",
    "matched_pixels",
    "missed_pixels",
    "false_pixels",
    "pixel_precision",
    "pixel_recall",
    "fragmentation",
    "object_area_recall",
    "object_area_precision",
    "box_area_precision",
    "localized_object_recall",
    "localized_object_precision",
    "localized_object_area_recall",
    "localized_box_area_precision",
    "n_gt",
    "n_pred",
)


@dataclass(frozen=True)
class FrameMeasures:
    """Raw per-frame quantities from which every metric follows (no averaging yet).

    Attributes
    ----------
    n_gt, n_pred : int
        Number of target / candidate boxes in the frame.
    gt_area, pred_area, matched : float
        ``|UT|``, ``|UC|`` and ``|UT ∩ UC|`` in pixels (after clipping to the frame).
    area_recall : (n_gt,) float64
        ``|t ∩ UC| / |t|`` per target (ViPER edge cases: ``nan`` if both areas are 0, 1 if the
        target is empty, 0 if there is no candidate area).
    area_precision : (n_pred,) float64
        ``|c ∩ UT| / |c|`` per candidate (same edge cases, mirrored).
    fragmentation : (n_gt,) float64
        ``1 / (1 + log10 n)`` per target with ``n`` overlapping candidate boxes; ``nan`` if ``n = 0``.
    dice_distance : (n_gt + n_pred,) float64
        ``1 - 2|a ∩ b| / (|a| + |b|)``: each target against ``UC``, then each candidate against
        ``UT`` (0 if both areas are 0, 1 if exactly one is 0).
    """

    n_gt: int
    n_pred: int
    gt_area: float
    pred_area: float
    matched: float
    area_recall: np.ndarray
    area_precision: np.ndarray
    fragmentation: np.ndarray
    dice_distance: np.ndarray


def _clip(boxes: np.ndarray, frame_size: tuple[float, float] | None) -> np.ndarray:
    """``(N, 4)`` x, y, w, h → ``(N, 4)`` x1, y1, x2, y2, clipped to the frame (empty → x2 = x1)."""
    x1 = boxes[:, 0]
    y1 = boxes[:, 1]
    x2 = x1 + boxes[:, 2]
    y2 = y1 + boxes[:, 3]
    if frame_size is not None:
        W, H = frame_size
        x1, x2 = np.clip(x1, 0, W), np.clip(x2, 0, W)
        y1, y2 = np.clip(y1, 0, H), np.clip(y2, 0, H)
    x2 = np.maximum(x2, x1)
    y2 = np.maximum(y2, y1)
    return np.stack([x1, y1, x2, y2], axis=1)


def _cover(xyxy: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """``(N, gx, gy)`` bool: does box ``i`` cover the compressed cell ``(a, b)``?"""
    cx = (xs[:-1][None, :] >= xyxy[:, 0:1]) & (xs[1:][None, :] <= xyxy[:, 2:3])
    cy = (ys[:-1][None, :] >= xyxy[:, 1:2]) & (ys[1:][None, :] <= xyxy[:, 3:4])
    return cx[:, :, None] & cy[:, None, :]


def _ratio(num: np.ndarray, den: np.ndarray, other_total: float) -> np.ndarray:
    """ViPER's area recall/precision with its edge cases (see :class:`FrameMeasures`)."""
    out = np.empty(len(num), dtype=np.float64)
    pos = den > 0
    if other_total > 0:
        out[pos] = num[pos] / den[pos]
        out[~pos] = 1.0  # own area 0, other area > 0
    else:
        out[pos] = 0.0  # other area 0
        out[~pos] = np.nan  # both 0
    return out


def _dice_distance(shared: np.ndarray, a: np.ndarray, b: float) -> np.ndarray:
    out = np.empty(len(shared), dtype=np.float64)
    both = (a > 0) & (b > 0)
    out[both] = 1.0 - 2.0 * shared[both] / (a[both] + b)
    nb = ~both
    out[nb] = np.where(a[nb] == b, 0.0, 1.0)
    return out


def frame_measures(
    gt_boxes: np.ndarray,
    pred_boxes: np.ndarray,
    frame_size: tuple[float, float] | None = None,
) -> FrameMeasures:
    """Raw framewise quantities of one frame.

    Parameters
    ----------
    gt_boxes, pred_boxes : (N, 4), (M, 4) float64
        x, y, w, h in pixels (N or M may be 0).
    frame_size : (W, H) or None
        Clip shapes to ``[0, W) x [0, H)`` before measuring areas (ViPER-PE behaviour).
    """
    g = np.asarray(gt_boxes, dtype=np.float64).reshape(-1, 4)
    p = np.asarray(pred_boxes, dtype=np.float64).reshape(-1, 4)
    n, m = len(g), len(p)
    gc, pc = _clip(g, frame_size), _clip(p, frame_size)
    allb = np.concatenate([gc, pc])
    if n + m == 0:
        e = np.zeros(0)
        return FrameMeasures(0, 0, 0.0, 0.0, 0.0, e, e, e, e)
    # coordinate compression: every union/intersection of these boxes is a union of grid cells
    xs = np.unique(np.concatenate([allb[:, 0], allb[:, 2]]))
    ys = np.unique(np.concatenate([allb[:, 1], allb[:, 3]]))
    cell = np.diff(xs)[:, None] * np.diff(ys)[None, :]  # (gx, gy) pixel areas
    cov = _cover(allb, xs, ys)  # (n + m, gx, gy)
    gcov, pcov = cov[:n], cov[n:]
    ut = gcov.any(axis=0)
    uc = pcov.any(axis=0)
    gt_area = float((cell * ut).sum())
    pred_area = float((cell * uc).sum())
    matched = float((cell * (ut & uc)).sum())
    own_g = (gc[:, 2] - gc[:, 0]) * (gc[:, 3] - gc[:, 1])
    own_p = (pc[:, 2] - pc[:, 0]) * (pc[:, 3] - pc[:, 1])
    t_in_uc = np.einsum("ixy,xy->i", gcov & uc[None], cell) if n else np.zeros(0)
    c_in_ut = np.einsum("ixy,xy->i", pcov & ut[None], cell) if m else np.zeros(0)
    area_recall = _ratio(t_in_uc, own_g, pred_area)
    area_precision = _ratio(c_in_ut, own_p, gt_area)
    # fragments: candidate boxes (unclipped, as ViPER-PE) with positive-area overlap per target
    if n and m:
        g0 = _clip(g, None)
        p0 = _clip(p, None)
        iw = np.minimum(g0[:, None, 2], p0[None, :, 2]) - np.maximum(g0[:, None, 0], p0[None, :, 0])
        ih = np.minimum(g0[:, None, 3], p0[None, :, 3]) - np.maximum(g0[:, None, 1], p0[None, :, 1])
        count = ((iw > 0) & (ih > 0)).sum(axis=1)
    else:
        count = np.zeros(n, dtype=np.int64)
    frag = np.full(n, np.nan)
    ok = (count > 0) & (own_g > 0) & (pred_area > 0)
    frag[ok] = 1.0 / (1.0 + np.log10(count[ok]))
    dice = np.concatenate([
        _dice_distance(t_in_uc, own_g, pred_area),
        _dice_distance(c_in_ut, own_p, gt_area),
    ])
    return FrameMeasures(n, m, gt_area, pred_area, matched, area_recall, area_precision, frag, dice)


def _nanmean(parts: list[np.ndarray]) -> float:
    v = np.concatenate(parts) if parts else np.zeros(0)
    v = v[~np.isnan(v)]
    return float(v.sum() / len(v)) if len(v) else math.nan


def _localized(parts: list[np.ndarray], xi: float) -> float:
    v = np.concatenate(parts) if parts else np.zeros(0)
    v = v[~np.isnan(v)]
    return float((v >= xi).sum() / len(v)) if len(v) else math.nan


def _summarise(ms: list[FrameMeasures], xi: float) -> dict[str, float]:
    """Metrics of a list of frames, pooled the ViPER-PE way (one frame: its per-frame metrics)."""
    nt = sum(f.n_gt for f in ms)
    nc = sum(f.n_pred for f in ms)
    gt_area = sum(f.gt_area for f in ms)
    pred_area = sum(f.pred_area for f in ms)
    matched = sum(f.matched for f in ms)
    ar = [f.area_recall for f in ms]
    ap = [f.area_precision for f in ms]
    dd = _nanmean([f.dice_distance for f in ms])
    nan = math.nan
    out = {
        "detection_accuracy": 2.0 * min(nt, nc) / (nt + nc) if nt + nc else nan,
        "object_count_recall": (min(nc / nt, 1.0)) if nt else nan,
        "object_count_precision": (min(nt / nc, 1.0)) if nc else nan,
        "dice": 1.0 - dd,
        "dice_distance": dd,
        "matched_pixels": matched,
        "missed_pixels": gt_area - matched,
        "false_pixels": pred_area - matched,
        "pixel_precision": matched / pred_area if pred_area else nan,
        "pixel_recall": matched / gt_area if gt_area else nan,
        "fragmentation": _nanmean([f.fragmentation for f in ms]),
        "object_area_recall": _nanmean(ar),
        "object_area_precision": _nanmean(ap),
        "localized_object_recall": _localized(ar, xi),
        "localized_object_precision": _localized(ap, xi),
        "n_gt": float(nt),
        "n_pred": float(nc),
    }
    # ViPER-PE's names for the same numbers
    out["box_area_precision"] = out["object_area_precision"]
    out["localized_object_area_recall"] = out["localized_object_recall"]
    out["localized_box_area_precision"] = out["localized_object_precision"]
    return {k: out[k] for k in METRIC_KEYS}


def evaluate_framewise(
    gt: Annotations,
    pred: Annotations,
    xi: float = 0.75,
    *,
    frame_size: tuple[float, float] | None = None,
    frames: tuple[int, int] | None = None,
) -> tuple[dict[str, float], list[dict]]:
    """Framewise metrics of ``pred`` against ``gt`` (thesis §4.1, ViPER-PE framewise evaluation).

    Parameters
    ----------
    gt, pred : Annotations
        Ground truth (targets) and results (candidates). Ground-truth rows with ``consider == False``
        are dropped (ViPER don't-care regions are not modelled). Identities are not used.
    xi : float
        Localization threshold in [0, 1] for the localized object area recall / box area precision
        (thesis: 0.75; the ViPER sample's ``.epf`` uses 0.7).
    frame_size : (W, H) pixels, optional
        Clip shapes to the frame like ViPER-PE; default ``gt.meta["frame_size"]`` when present (the
        ViPER reader sets it), else no clipping.
    frames : (first, last), optional
        Evaluate only frames ``first..last`` (inclusive, 1-based).

    Returns
    -------
    overall : dict[str, float]
        Keys :data:`METRIC_KEYS` (pixel counts as floats; ``nan`` where undefined).
    per_frame : list of dict
        One dict per frame having a target or a candidate, sorted by frame, with ``"frame"`` (int)
        and the same keys.
    """
    if not (0.0 <= float(xi) <= 1.0) or math.isnan(float(xi)):
        raise ConfigError(f"xi must be in [0, 1], got xi={xi}")
    if frame_size is None and gt.meta:
        fs = gt.meta.get("frame_size")
        frame_size = tuple(fs) if fs is not None else None  # type: ignore[assignment]
    if frame_size is not None and (frame_size[0] <= 0 or frame_size[1] <= 0):
        raise ConfigError(f"frame_size must be positive, got {frame_size}")
    if len(gt):
        gt = gt.select(np.asarray(gt.consider, dtype=bool))
    if frames is not None:
        a, b = frames
        gt = gt.select((gt.frames >= a) & (gt.frames <= b))
        pred = pred.select((pred.frames >= a) & (pred.frames <= b))
    gidx = gt.by_frame()
    pidx = pred.by_frame()
    empty = np.zeros((0, 4))
    per_frame: list[dict] = []
    measures: list[FrameMeasures] = []
    for f in sorted(set(gidx) | set(pidx)):
        gb = gt.boxes[gidx[f]] if f in gidx else empty
        pb = pred.boxes[pidx[f]] if f in pidx else empty
        fm = frame_measures(gb, pb, frame_size)
        measures.append(fm)
        per_frame.append({"frame": int(f), **_summarise([fm], xi)})
    return _summarise(measures, xi), per_frame
