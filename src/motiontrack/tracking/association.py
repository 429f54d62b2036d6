"""Association: cost matrices and gated Hungarian assignment (pure functions)."""

from __future__ import annotations

import numpy as np
from ..assignment import linear_sum_assignment

__all__ = ["iou_matrix", "intersections", "center_distance_matrix", "association_cost", "assign",
           "assign_in_stages"]

#: cost given to forbidden pairs (never chosen)
INF_COST = 1e6


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Intersection over union of boxes ``a`` (N, 4) and ``b`` (M, 4), ``x, y, w, h`` → (N, M)."""
    a = np.asarray(a, np.float64).reshape(-1, 4)
    b = np.asarray(b, np.float64).reshape(-1, 4)
    ax1, ay1 = a[:, 0:1], a[:, 1:2]
    bx1, by1 = b[:, 0], b[:, 1]
    iw = np.minimum(ax1 + a[:, 2:3], bx1 + b[:, 2]) - np.maximum(ax1, bx1)
    ih = np.minimum(ay1 + a[:, 3:4], by1 + b[:, 3]) - np.maximum(ay1, by1)
    np.maximum(iw, 0.0, out=iw)
    np.maximum(ih, 0.0, out=ih)
    inter = iw * ih
    union = a[:, 2:3] * a[:, 3:4] + b[:, 2] * b[:, 3] - inter
    out = np.zeros_like(inter)
    np.divide(inter, union, out=out, where=union > 0)
    return out


def intersections(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Intersection areas of boxes ``a`` (N, 4) and ``b`` (M, 4), ``x, y, w, h`` → (N, M)."""
    a = np.asarray(a, np.float64).reshape(-1, 4)
    b = np.asarray(b, np.float64).reshape(-1, 4)
    iw = (np.minimum(a[:, None, 0] + a[:, None, 2], b[None, :, 0] + b[None, :, 2])
          - np.maximum(a[:, None, 0], b[None, :, 0]))
    ih = (np.minimum(a[:, None, 1] + a[:, None, 3], b[None, :, 1] + b[None, :, 3])
          - np.maximum(a[:, None, 1], b[None, :, 1]))
    return np.clip(iw, 0, None) * np.clip(ih, 0, None)


def center_distance_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Centre distance between ``a`` (N, 4) and ``b`` (M, 4) divided by the diagonal of ``a``."""
    a = np.asarray(a, np.float64).reshape(-1, 4)
    b = np.asarray(b, np.float64).reshape(-1, 4)
    ca = a[:, :2] + a[:, 2:] / 2
    cb = b[:, :2] + b[:, 2:] / 2
    d = np.hypot(ca[:, 0:1] - cb[:, 0], ca[:, 1:2] - cb[:, 1])
    diag = np.hypot(a[:, 2], a[:, 3])[:, None]
    return d / np.maximum(diag, 1e-9)


def association_cost(pred: np.ndarray, det: np.ndarray, min_iou: float,
                     max_distance: float | np.ndarray, mode: str = "iou") -> np.ndarray:
    """Cost of matching predicted boxes (N, 4) to detections (M, 4).

    ``mode="iou"``: cost ``1 − IoU`` for pairs with IoU ≥ ``min_iou``; pairs below the IoU gate but
    with normalised centre distance < ``max_distance`` get ``1 + distance`` (always worse than an
    IoU match — this rescues small or fast objects whose boxes do not overlap the prediction);
    everything else is forbidden. ``mode="center"``: normalised centre distance, gated by
    ``max_distance``. ``max_distance`` may be a scalar or one value per prediction (N,).
    """
    n, m = len(pred), len(det)
    if n == 0 or m == 0:
        return np.zeros((n, m))
    # a scalar, or one value per prediction as a column (broadcasts against the (N, M) matrices)
    max_distance = np.reshape(max_distance, (-1, 1)) if np.ndim(max_distance) else max_distance
    if mode == "center":
        dist = center_distance_matrix(pred, det)
        return np.where(dist < max_distance, dist, INF_COST)
    iou = iou_matrix(pred, det)
    gated = iou < max(min_iou, 1e-12)
    cost = 1.0 - iou
    cost[gated] = INF_COST
    if gated.any():
        dist = center_distance_matrix(pred, det)
        fallback = gated & (dist < max_distance)
        cost[fallback] = 1.0 + dist[fallback]
    return cost


def assign(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Minimum-cost assignment ignoring forbidden pairs.

    Returns ``(matches (K, 2) [row, col], unmatched_rows, unmatched_cols)``.
    """
    n, m = cost.shape
    if n == 0 or m == 0:
        return np.zeros((0, 2), np.int64), np.arange(n), np.arange(m)
    rows, cols = linear_sum_assignment(cost)
    keep = cost[rows, cols] < INF_COST
    rows, cols = rows[keep], cols[keep]
    free_r = np.ones(n, bool)
    free_r[rows] = False
    free_c = np.ones(m, bool)
    free_c[cols] = False
    matches = np.empty((len(rows), 2), np.int64)
    matches[:, 0], matches[:, 1] = rows, cols
    return matches, np.flatnonzero(free_r), np.flatnonzero(free_c)


def assign_in_stages(cost: np.ndarray, first: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`assign` in two stages: the pairs marked ``first`` (e.g. boxes that overlap) are
    matched among themselves, then the rows and columns left over with all their allowed pairs.

    One minimum-cost assignment over every allowed pair maximises the *number* of matches before
    their cost (a forbidden pair costs more than any sum of allowed ones), so two poor pairs win
    over one good pair: a lost track takes a walker's box, and the walker's track a fragment
    nearby, because each is within the other's distance gate. Matching the first-stage pairs first
    keeps a good match from being traded for two poor ones.
    """
    n, m = cost.shape
    first = np.asarray(first, bool)
    if n == 0 or m == 0 or first.all() or not first.any():
        return assign(cost)
    m1, rows1, cols1 = assign(np.where(first, cost, INF_COST))
    if not len(rows1) or not len(cols1):
        return m1, rows1, cols1
    m2, r2, c2 = assign(cost[np.ix_(rows1, cols1)])
    matches = np.concatenate([m1, np.column_stack([rows1[m2[:, 0]], cols1[m2[:, 1]]])])
    return matches, rows1[r2], cols1[c2]
