"""Region-tracker semantics for merged blobs (the Reading People Tracker's region splitting).

When the predictions of two or more established tracks fall inside one measured region that is
clearly larger than each of them — people walking together or crossing — the single blob cannot be
matched to all of them. Following the Reading People Tracker, the predictions are treated as one
merged prediction that matches the blob, and the blob is split again into one *synthetic
measurement* per track: the track's predicted box moved (not resized) to lie inside the blob. Each
identity therefore survives the crossing with its own velocity. The tracker gives each share the
track's size held from before the merge (the larger of its last estimate and its reference size),
not the predicted one: a measurement equal to the prediction never corrects the prediction's size
velocity, so a track kept by shares of a blob would otherwise shrink (or grow) at its last rate
for as long as the blob lasts — down to a box one pixel wide.

When a better estimate of where each person is inside the blob exists this frame — the active
shape tracker's outline fitted to the person (``own`` boxes) — the synthetic measurement is that
box cut to the blob instead of the moved prediction: the prediction only knows where the person
was going, the outline was fitted to this frame's image.
"""

from __future__ import annotations

import numpy as np

from .association import intersections, iou_matrix

__all__ = ["split_merged", "anchor_partial", "fragment_matrix"]

#: reference height / width from which a track is taken for a person (upright) in the claim test
UPRIGHT = 1.5
#: IoU with a blob at which a track too large to claim a share of it is the blob's one object
SOLE_IOU = 0.5
#: a track's expected box is its reference size grown by this fraction on each side
FRAGMENT_MARGIN = 0.15
#: share of a detection's box inside a track's expected box that makes it a piece of it
FRAGMENT_INSIDE = 0.7
#: a piece is smaller than this share of the track's reference area (a whole object is not one)
FRAGMENT_AREA = 0.8


def fragment_matrix(pred: np.ndarray, established: np.ndarray, det: np.ndarray,
                    ref: np.ndarray, alone: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Which detections are pieces of which established tracks.

    A moving object's mask breaks into parts as it slows, turns or crosses a background of its
    own colour (a person's head, torso and legs). Each established track's *expected box* is its
    reference size centred on its prediction, grown by :data:`FRAGMENT_MARGIN` on each side. A
    detection is a piece of a track when at least :data:`FRAGMENT_INSIDE` of it lies in that
    track's expected box and it is smaller than :data:`FRAGMENT_AREA` of the track's reference
    area; with ``alone``, also only when it lies in no other established track's expected box
    and touches no other's prediction.

    Parameters
    ----------
    pred : (N, 4) float64
        Predicted track boxes ``x, y, w, h``.
    established : (N,) bool
        Tracks that may have pieces (confirmed or lost, not tentative).
    det : (M, 4) float64
        Measured boxes.
    ref : (N, 2) float64
        Each track's reference (unoccluded) size ``w, h``.

    Returns
    -------
    (N, M) bool, and (N, 2) the size of each track's expected box."""
    size = ref * (1 + 2 * FRAGMENT_MARGIN)
    cx, cy = _centre(pred)
    expected = np.column_stack([cx - size[:, 0] / 2, cy - size[:, 1] / 2, size])
    area = det[:, 2] * det[:, 3]
    share = intersections(expected, det) / np.maximum(area, 1e-9)[None, :]
    inside = (share >= FRAGMENT_INSIDE) & established[:, None]
    part = inside & (area[None, :] < FRAGMENT_AREA * (ref[:, 0] * ref[:, 1])[:, None])
    if alone:
        # a piece in two tracks' boxes, or touching another track's prediction, is not taken
        touches = (intersections(pred, det) > 0) & established[:, None]
        part &= (inside.sum(axis=0) == 1)[None, :] & ((touches & ~part).sum(axis=0) == 0)[None, :]
    return part, size


def split_merged(pred: np.ndarray, established: np.ndarray, det: np.ndarray,
                 max_share: float = 0.85, own: np.ndarray | None = None,
                 size: np.ndarray | None = None, ref: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split detections that contain several established tracks' predictions.

    Parameters
    ----------
    pred : (N, 4) float64
        Predicted track boxes ``x, y, w, h``.
    established : (N,) bool
        Tracks that may claim a share of a merged blob (confirmed or lost, not tentative).
    det : (M, 4) float64
        Measured boxes.
    max_share : float
        A prediction claims a blob only if its area is at most this fraction of the blob's.
    own : (N, 4) float64, optional
        This frame's own box estimate per track (NaN rows where there is none), e.g. fitted
        shapes. A track that claims a blob and has one gets that box cut to the blob as its
        synthetic measurement (when the cut is at least 2 px each way); the others get their
        prediction moved inside the blob. Which tracks claim which blob is decided by the
        predictions either way.
    size : (N, 2) float64, optional
        The size (w, h) of each track's synthetic measurement, centred on its prediction
        (default: the predicted size).
    ref : (N, 2) float64, optional
        Each track's reference (unmerged) size. An upright track (reference height at least
        :data:`UPRIGHT` times its width: a person) claims a blob when the smaller of its
        predicted and reference areas is at most ``max_share`` of the blob's; other tracks are
        judged by their predicted area.

    Returns
    -------
    boxes : (K, 4) float64
        Detections after splitting (unsplit ones first, in their original order, then the
        synthetic measurements).
    origin : (K,) int64
        Index into ``det`` each output box comes from.
    owner : (K,) int64
        For synthetic measurements the track index they were made for, else -1.
    """
    pred = np.asarray(pred, np.float64).reshape(-1, 4)
    det = np.asarray(det, np.float64).reshape(-1, 4)
    m = len(det)
    established = np.asarray(established, bool)
    if m == 0 or np.count_nonzero(established) < 2:  # a split needs two established tracks
        return _unsplit(det)
    inside = _centres_inside(pred, det) & established[:, None]
    if not (inside.sum(axis=0) >= 2).any():  # the common case: nothing to split
        return _unsplit(det)
    claim = _claims(pred, det, inside, max_share, ref)
    # a blob one established track explains on its own (its prediction, too large to claim a
    # share, covers it) is that object: the smaller tracks inside are pieces of it, not people
    # merged with it
    whole = inside & ~claim & (iou_matrix(pred, det) >= SOLE_IOU)
    claim[:, whole.any(axis=0)] = False
    return _split(pred, det, claim, size, own)


def _split(pred: np.ndarray, det: np.ndarray, claim: np.ndarray, size: np.ndarray | None,
           own: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Blobs claimed by two or more tracks replaced by one share per track, after the others."""
    split = claim.sum(axis=0) >= 2
    keep = np.flatnonzero(~split)
    boxes = [det[keep]]
    origin = [keep]
    owner = [np.full(len(keep), -1, np.int64)]
    for j in np.flatnonzero(split):
        tracks = np.flatnonzero(claim[:, j])
        boxes.append(_shares(pred[tracks], det[j], None if size is None else size[tracks],
                             None if own is None else own[tracks]))
        origin.append(np.full(len(tracks), j, np.int64))
        owner.append(tracks.astype(np.int64))
    return np.concatenate(boxes), np.concatenate(origin), np.concatenate(owner)


def _unsplit(det: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``split_merged``'s result when no detection is split."""
    m = len(det)
    return det.copy(), np.arange(m), np.full(m, -1, np.int64)


def _centre(boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return boxes[:, 0] + boxes[:, 2] / 2, boxes[:, 1] + boxes[:, 3] / 2


def _centres_inside(pred: np.ndarray, det: np.ndarray) -> np.ndarray:
    """(N, M) bool: the centre of prediction ``i`` lies in detection ``j`` (edges included)."""
    cx, cy = _centre(pred)
    return ((cx[:, None] >= det[None, :, 0]) & (cx[:, None] <= det[None, :, 0] + det[None, :, 2])
            & (cy[:, None] >= det[None, :, 1]) & (cy[:, None] <= det[None, :, 1] + det[None, :, 3]))


def _claims(pred: np.ndarray, det: np.ndarray, inside: np.ndarray, max_share: float,
            ref: np.ndarray | None) -> np.ndarray:
    """(N, M) bool: track ``i`` claims a share of blob ``j`` (see :func:`split_merged`).

    An upright track is judged by the smaller of its predicted and reference areas: a person's
    track that matched a blob holding a neighbour's body for a few frames before the blobs fused
    has grown to it, and would otherwise no longer claim its share. Other tracks are judged by
    their predicted area: a car approaching the camera grows faster than its reference follows,
    and its own blob would be split.
    """
    area = pred[:, 2] * pred[:, 3]
    if ref is not None:
        upright = ref[:, 1] >= UPRIGHT * ref[:, 0]
        area = np.where(upright, np.minimum(area, ref[:, 0] * ref[:, 1]), area)
    small = area[:, None] <= max_share * (det[:, 2] * det[:, 3])[None, :]
    claim = inside & small
    # a track claims at most one blob: the one whose centre is nearest its prediction
    if claim.any():
        cx, cy = _centre(pred)
        dcx, dcy = _centre(det)
        dist = np.hypot(cx[:, None] - dcx[None, :], cy[:, None] - dcy[None, :])
        dist[~claim] = np.inf
        best = np.argmin(dist, axis=1)
        claim = claim & (np.arange(len(det))[None, :] == best[:, None])
    return claim


def _shares(pred: np.ndarray, blob: np.ndarray, size: np.ndarray | None, own: np.ndarray | None
            ) -> np.ndarray:
    """Synthetic measurements of the tracks predicted at ``pred`` that claimed ``blob``.

    ``size`` replaces the predicted size when given: a share of a blob says nothing about the
    size of the object in it, and a measurement that repeats the prediction never corrects the
    prediction's size velocity, so the tracker passes sizes that do not follow it.
    """
    b = pred.copy()
    if size is not None:
        b[:, :2] += (b[:, 2:] - size) / 2
        b[:, 2:] = size
    # move each predicted box inside the blob (sizes kept unless larger than the blob)
    b[:, 2] = np.minimum(b[:, 2], blob[2])
    b[:, 3] = np.minimum(b[:, 3], blob[3])
    b[:, 0] = np.clip(b[:, 0], blob[0], blob[0] + blob[2] - b[:, 2])
    b[:, 1] = np.clip(b[:, 1], blob[1], blob[1] + blob[3] - b[:, 3])
    if own is not None:
        b = _cut_own(b, own, blob)
    return b


def _cut_own(moved: np.ndarray, own: np.ndarray, blob: np.ndarray) -> np.ndarray:
    """Rows of ``own`` (x, y, w, h; NaN = none) cut to ``blob`` replace rows of ``moved``."""
    x1 = np.maximum(own[:, 0], blob[0])
    y1 = np.maximum(own[:, 1], blob[1])
    x2 = np.minimum(own[:, 0] + own[:, 2], blob[0] + blob[2])
    y2 = np.minimum(own[:, 1] + own[:, 3], blob[1] + blob[3])
    ok = (x2 - x1 >= 2) & (y2 - y1 >= 2)  # False for NaN rows
    out = moved.copy()
    out[ok] = np.column_stack([x1, y1, x2 - x1, y2 - y1])[ok]
    return out


def anchor_partial(pred: np.ndarray, det: np.ndarray, ref_size: np.ndarray, min_ratio: float,
                   edge_tolerance: float = 0.2) -> tuple[np.ndarray, np.ndarray]:
    """Measurements of partly occluded objects, anchored on their visible edges.

    Each track remembers its reference size (a running average of its unoccluded sizes). When a
    matched measurement is much smaller than that (area below ``min_ratio``) *and* it is cut on one
    side only — on some axis one measured edge agrees with the predicted edge (within
    ``edge_tolerance`` of the reference size) while the other lies inside — the object is probably
    partly hidden (behind a column, at the image border). Using the box as is would shrink the
    track and drag its centre and velocity towards the occluder; instead the reference size is
    placed against the edges that agree.

    Parameters
    ----------
    pred, det : (K, 4) float64
        Predicted and measured boxes of matched pairs, ``x, y, w, h``.
    ref_size : (K, 2) float64
        Reference ``w, h`` of each track.
    min_ratio : float
        Measured/reference area below which a measurement may be partial (0 disables).
    edge_tolerance : float
        How closely (fraction of the reference size) the visible edge must agree.

    Returns
    -------
    boxes : (K, 4) float64 measurements to use.
    partial : (K,) bool, which were anchored.
    """
    pred = np.asarray(pred, np.float64).reshape(-1, 4)
    ref = np.asarray(ref_size, np.float64).reshape(-1, 2)
    out = np.asarray(det, np.float64).reshape(-1, 4).copy()
    partial = np.zeros(len(out), bool)
    if min_ratio <= 0 or len(out) == 0:
        return out, partial
    small = out[:, 2] * out[:, 3] < min_ratio * ref[:, 0] * ref[:, 1]
    for i in np.flatnonzero(small):
        anchored = _anchor(out[i], pred[i], ref[i], edge_tolerance)
        if anchored is not None:
            out[i] = anchored
            partial[i] = True
    return out, partial


def _anchor(d: np.ndarray, pred: np.ndarray, ref: np.ndarray, edge_tolerance: float
            ) -> np.ndarray | None:
    """Box ``d`` with the reference size placed against its edges that agree with ``pred``, or
    None when it is cut on one side only along neither axis (see :func:`anchor_partial`)."""
    anchored = d.copy()
    cut = False
    for a in (0, 1):  # x then y
        size = ref[a]
        centre = pred[a] + pred[a + 2] / 2
        p_lo, p_hi = centre - size / 2, centre + size / 2
        lo_err = abs(d[a] - p_lo)
        hi_err = abs(d[a] + d[a + 2] - p_hi)
        tol = edge_tolerance * size
        if d[a + 2] >= size - tol:      # not cut along this axis
            continue
        if lo_err <= tol < hi_err:       # far edge hidden: keep the near one
            anchored[a], anchored[a + 2] = d[a], size
            cut = True
        elif hi_err <= tol < lo_err:     # near edge hidden: keep the far one
            anchored[a], anchored[a + 2] = d[a] + d[a + 2] - size, size
            cut = True
    return anchored if cut else None
