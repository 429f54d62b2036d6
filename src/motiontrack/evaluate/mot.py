"""Tracking metrics: CLEAR-MOT, Identity and HOTA, identical to TrackEval.

Every number here reproduces TrackEval (Luiten et al., the reference implementation of the
MOTChallenge benchmark, ``trackeval==1.3.0``) to floating-point rounding; ``tests/golden/`` holds
values produced by TrackEval itself and ``tests/test_eval_mot.py`` compares every field to 1e-6.

Pipeline for one sequence (all pure functions, inputs never mutated)::

    gt, pred (Annotations) --preprocess--> SequenceData --clear/identity/hota--> dict of numbers

Preprocessing (TrackEval ``MotChallenge2DBox.get_preprocessed_seq_data``)
------------------------------------------------------------------------
When the ground truth carries MOTChallenge classes (MOT16/17/20 ``gt.txt``; any class >= 0):

1. In each frame, all gt rows (every class, also zero-marked ones) are matched to all tracker boxes
   with the Hungarian algorithm on IoU, pairs with IoU < 0.5 excluded.
2. Tracker boxes matched to a gt row of a *distractor* class (2 person on vehicle, 7 static person,
   8 distractor, 12 reflection; MOT20 adds 6 non-MOT vehicle) are removed.
3. Only gt rows of class 1 (pedestrian) with ``consider`` true (not zero-marked) are kept.

Note: TrackEval does *not* remove tracker boxes matched to zero-marked pedestrians; they count as
false positives, and so they do here.

When classes are unknown (all ``-1``, e.g. MOT15-style 10-column gt such as TUD-Campus) TrackEval's
MOT15 rule applies: no tracker box is removed and only gt rows with ``consider`` false are dropped.

Ids are then relabelled to ``0..n-1`` in sorted order; an id appearing twice in one frame is an
:class:`~motiontrack.errors.InputError`. Similarity is the IoU of ``x, y, w, h`` boxes, computed with
the same floating-point operations as TrackEval so that Hungarian ties break identically.

References
----------
* K. Bernardin, R. Stiefelhagen, "Evaluating Multiple Object Tracking Performance: The CLEAR MOT
  Metrics", EURASIP JIVP 2008 (MOTA, MOTP).
* Y. Li, C. Huang, R. Nevatia, "Learning to associate: HybridBoosted multi-target tracker", CVPR 2009
  (MT/PT/ML, Frag).
* E. Ristani et al., "Performance Measures and a Data Set for Multi-Target, Multi-Camera Tracking",
  ECCV-W 2016 (IDF1, IDP, IDR).
* J. Luiten et al., "HOTA: A Higher Order Metric for Evaluating Multi-Object Tracking", IJCV 2021.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Iterable, Mapping, Sequence

import numpy as np

from ..assignment import linear_sum_assignment
from ..errors import ConfigError, InputError
from ..types import Annotations
from .framewise import evaluate_framewise

__all__ = [
    "ALPHAS",
    "DISTRACTOR_CLASSES",
    "SequenceData",
    "PairTable",
    "pair_table",
    "restrict",
    "box_iou_xywh",
    "preprocess",
    "clear_metrics",
    "identity_metrics",
    "hota_metrics",
    "combine_clear",
    "combine_identity",
    "combine_hota",
    "evaluate_sequence",
    "combine_sequences",
    "flatten",
    "evaluate_tracking",
    "METRIC_FAMILIES",
]

log = logging.getLogger(__name__)

EPS = float(np.finfo(float).eps)
#: HOTA localisation thresholds alpha = 0.05, 0.10, ..., 0.95 (TrackEval ``np.arange(0.05, 0.99, 0.05)``).
ALPHAS = np.arange(0.05, 0.99, 0.05)
#: MOTChallenge distractor classes: person on vehicle, static person, distractor, reflection.
DISTRACTOR_CLASSES = (2, 7, 8, 12)
#: Metric families computed by :func:`evaluate_sequence`.
METRIC_FAMILIES = ("clear", "identity", "hota")
PEDESTRIAN = 1


# --------------------------------------------------------------------------------------------------
# similarity
# --------------------------------------------------------------------------------------------------
def box_iou_xywh(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Element-wise IoU of paired boxes, with TrackEval's exact operations.

    Parameters
    ----------
    a, b : (K, 4) float64
        Paired boxes ``x, y, w, h`` in pixels.

    Returns
    -------
    (K,) float64
        IoU in [0, 1]; 0 when either area or the union is <= machine epsilon.
    """
    a = np.asarray(a, dtype=np.float64).reshape(-1, 4)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 4)
    ax2, ay2 = a[:, 0] + a[:, 2], a[:, 1] + a[:, 3]
    bx2, by2 = b[:, 0] + b[:, 2], b[:, 1] + b[:, 3]
    iw = np.maximum(np.minimum(ax2, bx2) - np.maximum(a[:, 0], b[:, 0]), 0)
    ih = np.maximum(np.minimum(ay2, by2) - np.maximum(a[:, 1], b[:, 1]), 0)
    inter = iw * ih
    area_a = (ax2 - a[:, 0]) * (ay2 - a[:, 1])
    area_b = (bx2 - b[:, 0]) * (by2 - b[:, 1])
    union = area_a + area_b - inter
    bad = (area_a <= EPS) | (area_b <= EPS) | (union <= EPS)
    inter = np.where(bad, 0.0, inter)
    union = np.where(union <= EPS, 1.0, union)
    return inter / union


@dataclass(frozen=True, eq=False)
class PairTable:
    """IoU of every gt-tracker pair that overlaps (IoU > 0), frame by frame, in sparse form.

    Both inputs are sorted by frame, so each frame's rows are contiguous.

    Attributes
    ----------
    frames : (F,) int64
        Frames holding both gt and tracker rows.
    g0, ng, p0, np_ : (F,) int64
        First row and number of rows of gt / tracker in each of those frames.
    offsets : (F + 1,) int64
        Pairs of frame ``f`` are ``offsets[f]:offsets[f + 1]``.
    gi, pi : (K,) int64
        Gt and tracker row index of each overlapping pair (row-major within a frame).
    sim : (K,) float64
        Their IoU (> 0).
    """

    frames: np.ndarray
    g0: np.ndarray
    ng: np.ndarray
    p0: np.ndarray
    np_: np.ndarray
    offsets: np.ndarray
    gi: np.ndarray
    pi: np.ndarray
    sim: np.ndarray

    def dense(self, f: int) -> np.ndarray:
        """The full ``(ng, np)`` IoU matrix of frame index ``f`` (zeros where boxes do not overlap)."""
        m = np.zeros((int(self.ng[f]), int(self.np_[f])))
        a, b = self.offsets[f], self.offsets[f + 1]
        m[self.gi[a:b] - self.g0[f], self.pi[a:b] - self.p0[f]] = self.sim[a:b]
        return m

    def pair_frames(self) -> np.ndarray:
        """(K,) int64: the frame index (into ``frames``) of each pair."""
        return np.repeat(np.arange(len(self.frames)), np.diff(self.offsets))


_CHUNK = 1 << 17  # pairs per vectorised block: keeps temporaries in cache


def _frame_blocks(g_frames: np.ndarray, p_frames: np.ndarray) -> tuple[np.ndarray, ...]:
    """Frames holding both gt and tracker rows, and each side's first row and row count there."""
    gu, gs, gc = np.unique(g_frames, return_index=True, return_counts=True)
    pu, ps, pc = np.unique(p_frames, return_index=True, return_counts=True)
    common, gi_u, pi_u = np.intersect1d(gu, pu, assume_unique=True, return_indices=True)
    i64 = np.int64
    return (common.astype(i64), gs[gi_u].astype(i64), gc[gi_u].astype(i64),
            ps[pi_u].astype(i64), pc[pi_u].astype(i64))


def _ranges(starts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """``concatenate([arange(s, s + n) for s, n in zip(starts, lengths)])`` without the loop."""
    ends = np.cumsum(lengths)
    return np.arange(int(ends[-1]) if len(ends) else 0) + np.repeat(starts - (ends - lengths),
                                                                    lengths)


def _extents(boxes: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(left, right)`` and ``(top, bottom)`` of ``x, y, w, h`` boxes, as :func:`box_iou_xywh`
    computes them."""
    return [(boxes[:, k], boxes[:, k] + boxes[:, k + 2]) for k in (0, 1)]


def _overlaps(g_boxes: np.ndarray, p_boxes: np.ndarray, g_ext: list, p_ext: list,
              gi: np.ndarray, pi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pairs ``(gi, pi)`` whose IoU is > 0, with that IoU. Pairs apart in x or in y are
    dropped first with the very operations :func:`box_iou_xywh` does (the same floats, so the
    same pairs survive); the IoU is computed on the rest only."""
    for (g_lo, g_hi), (p_lo, p_hi) in zip(g_ext, p_ext):
        near = np.minimum(g_hi[gi], p_hi[pi]) - np.maximum(g_lo[gi], p_lo[pi]) > 0
        gi, pi = gi[near], pi[near]
    sim = box_iou_xywh(g_boxes[gi], p_boxes[pi])
    nz = sim > 0
    return gi[nz], pi[nz], sim[nz]


def _table(g_frames: np.ndarray, p_frames: np.ndarray, gi: np.ndarray, pi: np.ndarray,
           sim: np.ndarray) -> PairTable:
    """A :class:`PairTable` from its overlapping pairs (row-major within each frame)."""
    frames, g0, ng, p0, npp = _frame_blocks(g_frames, p_frames)
    counts = np.bincount(np.searchsorted(frames, g_frames[gi]), minlength=len(frames))
    return PairTable(frames=frames, g0=g0, ng=ng, p0=p0, np_=npp,
                     offsets=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
                     gi=gi.astype(np.int64), pi=pi.astype(np.int64),
                     sim=sim.astype(np.float64))


def pair_table(g_frames: np.ndarray, g_boxes: np.ndarray,
               p_frames: np.ndarray, p_boxes: np.ndarray) -> PairTable:
    """All overlapping (gt, tracker) pairs per frame with their IoU (:func:`box_iou_xywh`).

    Parameters
    ----------
    g_frames, p_frames : (G,), (P,) int64, each sorted ascending.
    g_boxes, p_boxes : (G, 4), (P, 4) float64 ``x, y, w, h``.
    """
    g_boxes = np.asarray(g_boxes, dtype=np.float64).reshape(-1, 4)
    p_boxes = np.asarray(p_boxes, dtype=np.float64).reshape(-1, 4)
    _, g0, ng, p0, npp = _frame_blocks(g_frames, p_frames)
    g_ext, p_ext = _extents(g_boxes), _extents(p_boxes)
    cum = np.concatenate([[0], np.cumsum(ng * npp)]).astype(np.int64)
    gis, pis, sims = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)], [np.zeros(0)]
    start = 0
    while start < len(g0):
        stop = int(np.searchsorted(cum, cum[start] + _CHUNK, side="right"))
        stop = max(stop - 1, start + 1)
        fr = slice(start, stop)
        rows = _ranges(g0[fr], ng[fr])  # every gt row of these frames ...
        width = np.repeat(npp[fr], ng[fr])  # ... meets every tracker row of its frame
        gi = np.repeat(rows, width)
        pi = _ranges(np.repeat(p0[fr], ng[fr]), width)
        for out, v in zip((gis, pis, sims), _overlaps(g_boxes, p_boxes, g_ext, p_ext, gi, pi)):
            out.append(v)
        start = stop
    return _table(g_frames, p_frames, np.concatenate(gis), np.concatenate(pis),
                  np.concatenate(sims))


def restrict(t: PairTable, g_frames: np.ndarray, p_frames: np.ndarray, g_keep: np.ndarray,
             p_keep: np.ndarray) -> PairTable:
    """The table of the kept rows only (``g_frames``, ``p_frames``: those of all rows), taken
    from ``t`` (the table of all rows) instead of computing the IoU again."""
    k = g_keep[t.gi] & p_keep[t.pi]
    g_new, p_new = np.cumsum(g_keep) - 1, np.cumsum(p_keep) - 1
    return _table(g_frames[g_keep], p_frames[p_keep], g_new[t.gi[k]], p_new[t.pi[k]], t.sim[k])


# --------------------------------------------------------------------------------------------------
# preprocessing
# --------------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class SequenceData:
    """One preprocessed sequence, ready for the metrics.

    Attributes
    ----------
    gt_frames, gt_ids : (G,) int64
        Frame number and contiguous id ``0..num_gt_ids-1`` of each kept gt row, sorted by frame
        (file order within a frame).
    pred_frames, pred_ids : (P,) int64
        The same for the kept tracker rows.
    pairs : PairTable
        IoU of the overlapping gt-tracker pairs, per frame.
    num_timesteps : int
        Sequence length in frames (only ``FP_per_frame`` uses it).
    gt_id_values, pred_id_values : (num_gt_ids,), (num_pred_ids,) int64
        The original ids of the contiguous ones.
    """

    gt_frames: np.ndarray
    gt_ids: np.ndarray
    pred_frames: np.ndarray
    pred_ids: np.ndarray
    pairs: PairTable
    num_timesteps: int
    gt_id_values: np.ndarray
    pred_id_values: np.ndarray

    def __post_init__(self) -> None:
        if len(self.gt_frames) != len(self.gt_ids) or len(self.pred_frames) != len(self.pred_ids):
            raise ValueError("frames and ids must have equal lengths")
        if self.num_timesteps < 0:
            raise ValueError(f"num_timesteps must be >= 0, got {self.num_timesteps}")

    @property
    def num_gt_dets(self) -> int:
        return len(self.gt_ids)

    @property
    def num_pred_dets(self) -> int:
        return len(self.pred_ids)

    @property
    def num_gt_ids(self) -> int:
        return len(self.gt_id_values)

    @property
    def num_pred_ids(self) -> int:
        return len(self.pred_id_values)

    def block(self, f: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Frame index ``f`` (into ``pairs.frames``): gt ids (ng,), tracker ids (np,), IoU (ng, np)."""
        t = self.pairs
        g = self.gt_ids[t.g0[f]:t.g0[f] + t.ng[f]]
        p = self.pred_ids[t.p0[f]:t.p0[f] + t.np_[f]]
        return g, p, t.dense(f)


def _check_unique(frames: np.ndarray, ids: np.ndarray, what: str) -> None:
    if len(ids) < 2:
        return
    order = np.lexsort((ids, frames))
    f, i = frames[order], ids[order]
    dup = np.flatnonzero((f[1:] == f[:-1]) & (i[1:] == i[:-1]))
    if len(dup):
        raise InputError(f"{what} has id {int(i[dup[0]])} more than once in frame {int(f[dup[0]])}")


def _sorted(ann: Annotations) -> Annotations:
    if len(ann) < 2 or bool(np.all(ann.frames[1:] >= ann.frames[:-1])):
        return ann
    return ann.select(np.argsort(ann.frames, kind="stable"))


def _shared_rows(t: PairTable, sel: np.ndarray, pair_frame: np.ndarray) -> np.ndarray:
    """(F,) bool: the frames in which two of the pairs ``sel`` (indices into ``t``, ascending)
    share a gt row or a tracker row.

    In every other frame those pairs form a matching; when they are the only positive entries of
    the frame's weight matrix, every maximum-weight assignment picks each of them and nothing
    else of positive weight, whatever the solver's tie-breaking. The metrics take such frames'
    matches directly and run the Hungarian algorithm on the others only."""
    out = np.zeros(len(t.frames), dtype=bool)
    gi = t.gi[sel]  # row-major: pairs of one gt row are adjacent
    out[pair_frame[sel[1:][gi[1:] == gi[:-1]]]] = True
    order = np.argsort(t.pi[sel], kind="stable")  # a tracker row lives in one frame only
    pi = t.pi[sel][order]
    out[pair_frame[sel[order][1:][pi[1:] == pi[:-1]]]] = True
    return out


def _distractor_removal(gt: Annotations, num_pred: int, t: PairTable,
                        distractors: Sequence[int], also: np.ndarray | None = None) -> np.ndarray:
    """Boolean keep-mask over the ``num_pred`` tracker rows (``t``: the pair table of all rows,
    both sides sorted by frame): steps 1-2 of the preprocessing.

    Tracker boxes matched (Hungarian, IoU >= 0.5) to gt rows of a distractor class are removed;
    ``also`` marks further gt rows treated the same way (ignore regions)."""
    keep = np.ones(num_pred, dtype=bool)
    is_dis = np.isin(gt.classes, np.asarray(distractors, dtype=np.int64))
    if also is not None:
        is_dis = is_dis | also
    if not is_dis.any() or num_pred == 0:
        return keep
    pf = t.pair_frames()
    cand = np.flatnonzero(t.sim >= 0.5 - EPS)  # the entries the matching may use
    hard = _shared_rows(t, cand, pf)
    on_dis = cand[is_dis[t.gi[cand]]]
    keep[t.pi[on_dis[~hard[pf[on_dis]]]]] = False
    for f in np.unique(pf[on_dis[hard[pf[on_dis]]]]):
        s = t.dense(f)
        s[s < 0.5 - EPS] = 0
        r, c = linear_sum_assignment(-s)
        ok = s[r, c] > 0 + EPS
        r, c = r[ok], c[ok]
        rows = t.g0[f] + r
        keep[(t.p0[f] + c)[is_dis[rows]]] = False
    return keep


def preprocess(
    gt: Annotations,
    pred: Annotations,
    num_timesteps: int | None = None,
    distractor_classes: Sequence[int] = DISTRACTOR_CLASSES,
    do_preproc: bool = True,
    ignore_zero_marked: bool = False,
) -> SequenceData:
    """MOTChallenge preprocessing and pairwise IoU (see the module docstring).

    Parameters
    ----------
    gt, pred : Annotations
        Ground truth and tracker output of one sequence (1-based frames).
    num_timesteps : int, optional
        Sequence length; default the last frame in ``gt`` or ``pred``.
    distractor_classes : sequence of int
        Classes whose matched tracker boxes are removed (MOT20: add 6).
    do_preproc : bool
        ``False`` skips distractor removal and class filtering (TrackEval ``DO_PREPROC``); gt rows with
        ``consider`` false are always dropped.
    ignore_zero_marked : bool
        ``True`` treats gt rows with ``consider`` false as *ignore regions*: tracker boxes matched
        to them are removed too, so they count neither as hits nor as false positives (the
        convention for PETS/MOT15 "consider = 0" rows and for occluded synthetic people).
        ``False`` (TrackEval's MOTChallenge behaviour) only drops those gt rows.

    Returns
    -------
    SequenceData

    Raises
    ------
    InputError
        An id appears twice in one frame.
    ConfigError
        ``num_timesteps`` is shorter than the data.
    """
    _check_unique(gt.frames, gt.ids, "ground truth")
    _check_unique(pred.frames, pred.ids, "tracker output")
    gt_s, pred_s = _sorted(gt), _sorted(pred)
    classes_known = len(gt_s) > 0 and bool((gt_s.classes >= 0).any())
    zero = ~gt_s.consider if ignore_zero_marked else None
    # one IoU table of all rows serves the distractor matching and, restricted, the metrics
    pairs = pair_table(gt_s.frames, gt_s.boxes, pred_s.frames, pred_s.boxes)
    pred_keep = np.ones(len(pred_s), dtype=bool)
    if (do_preproc and classes_known) or ignore_zero_marked:
        dis = distractor_classes if do_preproc and classes_known else ()
        pred_keep = _distractor_removal(gt_s, len(pred_s), pairs, dis, zero)
    if do_preproc and classes_known:
        gt_keep = gt_s.consider & (gt_s.classes == PEDESTRIAN)
    else:
        gt_keep = gt_s.consider
    if not (pred_keep.all() and gt_keep.all()):
        pairs = restrict(pairs, gt_s.frames, pred_s.frames, gt_keep, pred_keep)
        gt_s, pred_s = gt_s.select(gt_keep), pred_s.select(pred_keep)
    last = max([int(a.frames.max()) for a in (gt, pred) if len(a)] or [0])
    if num_timesteps is None:
        num_timesteps = last
    elif num_timesteps < last:
        raise ConfigError(f"num_timesteps={num_timesteps} is less than the last frame {last}")
    gvals, gids = np.unique(gt_s.ids, return_inverse=True)
    pvals, pids = np.unique(pred_s.ids, return_inverse=True)
    return SequenceData(
        gt_frames=gt_s.frames, gt_ids=gids.astype(np.int64).reshape(-1),
        pred_frames=pred_s.frames, pred_ids=pids.astype(np.int64).reshape(-1),
        pairs=pairs, num_timesteps=int(num_timesteps), gt_id_values=gvals, pred_id_values=pvals,
    )


# --------------------------------------------------------------------------------------------------
# CLEAR-MOT
# --------------------------------------------------------------------------------------------------
CLEAR_INT = ("CLR_TP", "CLR_FN", "CLR_FP", "IDSW", "MT", "PT", "ML", "Frag", "CLR_Frames")
CLEAR_FLOAT = ("MOTA", "MOTP", "MODA", "CLR_Re", "CLR_Pr", "MTR", "PTR", "MLR", "sMOTA",
               "CLR_F1", "FP_per_frame", "MOTAL", "MOTP_sum")


def _clear_final(res: dict) -> dict:
    """Ratios from counts (TrackEval ``CLEAR._compute_final_fields``); Bernardin & Stiefelhagen 2008."""
    n_ids = res["MT"] + res["ML"] + res["PT"]
    tp, fn, fp, idsw = res["CLR_TP"], res["CLR_FN"], res["CLR_FP"], res["IDSW"]
    res["MTR"] = res["MT"] / max(1.0, n_ids)
    res["MLR"] = res["ML"] / max(1.0, n_ids)
    res["PTR"] = res["PT"] / max(1.0, n_ids)
    res["CLR_Re"] = tp / max(1.0, tp + fn)
    res["CLR_Pr"] = tp / max(1.0, tp + fp)
    res["MODA"] = (tp - fp) / max(1.0, tp + fn)
    res["MOTA"] = (tp - fp - idsw) / max(1.0, tp + fn)  # MOTA = 1 - (FN + FP + IDSW) / GT
    res["MOTP"] = res["MOTP_sum"] / max(1.0, tp)
    res["sMOTA"] = (res["MOTP_sum"] - fp - idsw) / max(1.0, tp + fn)
    res["CLR_F1"] = tp / max(1.0, tp + 0.5 * fn + 0.5 * fp)
    res["FP_per_frame"] = fp / max(1.0, res["CLR_Frames"])
    safe_log = float(np.log10(idsw)) if idsw > 0 else idsw
    res["MOTAL"] = (tp - fp - safe_log) / max(1.0, tp + fn)
    return res


def clear_metrics(data: SequenceData, threshold: float = 0.5,
                  per_frame: list | None = None) -> dict:
    """CLEAR-MOT for one sequence (TrackEval ``CLEAR.eval_sequence``).

    Per frame, gt and tracker boxes are matched by the Hungarian algorithm maximising
    ``1000 * [tracker continues the gt's match of the previous frame] + IoU`` over pairs with
    IoU >= ``threshold``. IDSW counts a matched gt whose tracker id differs from its last matched
    id (any number of frames back); Frag counts re-starts of tracking after the first. MT/PT/ML:
    tracked > 80 % / >= 20 % / otherwise of the frames a gt is present. As in TrackEval, a frame
    without any gt or without any tracker box does not interrupt "tracked in the previous frame"
    (it only adds FP or FN).

    Parameters
    ----------
    data : SequenceData
    threshold : float
        Minimum IoU of a match.
    per_frame : list, optional
        When given, one dict per frame holding gt or tracker rows is appended to it:
        ``frame, gt, pred, TP, FP, FN, IDSW`` (ints).

    Returns
    -------
    dict
        Keys ``CLEAR_INT + CLEAR_FLOAT``; counts are ``int``, ratios ``float``.
    """
    res: dict = {k: 0 for k in CLEAR_INT}
    res.update({k: 0.0 for k in CLEAR_FLOAT})
    tp_f = np.zeros(len(data.pairs.frames), np.int64)
    sw_f = np.zeros(len(data.pairs.frames), np.int64)
    if data.num_pred_dets == 0:
        res["CLR_FN"] = data.num_gt_dets
        res["ML"] = data.num_gt_ids
        res["MLR"] = 1.0
    elif data.num_gt_dets == 0:
        res["CLR_FP"] = data.num_pred_dets
        res["MLR"] = 1.0
    else:
        res = _clear_loop(data, threshold, tp_f, sw_f)
    if per_frame is not None:
        gf, gc = np.unique(data.gt_frames, return_counts=True)
        pf, pc = np.unique(data.pred_frames, return_counts=True)
        allf = np.union1d(gf, pf)
        ng = np.zeros(len(allf), np.int64)
        npr = np.zeros(len(allf), np.int64)
        tp = np.zeros(len(allf), np.int64)
        sw = np.zeros(len(allf), np.int64)
        ng[np.searchsorted(allf, gf)] = gc
        npr[np.searchsorted(allf, pf)] = pc
        idx = np.searchsorted(allf, data.pairs.frames)
        tp[idx], sw[idx] = tp_f, sw_f
        for f, a, b, t, s in zip(allf.tolist(), ng.tolist(), npr.tolist(), tp.tolist(), sw.tolist()):
            per_frame.append({"frame": f, "gt": a, "pred": b, "TP": t, "FP": b - t, "FN": a - t,
                              "IDSW": s})
    return res


def _clear_matches(data: SequenceData, thr: float) -> tuple[np.ndarray, ...]:
    """CLEAR's matches of every frame: frame index, gt row, gt id, tracker id and IoU of each,
    ordered by gt row (so by frame, and within a frame in the order the solver returns them)."""
    t = data.pairs
    pf = t.pair_frames()
    cand = np.flatnonzero(t.sim >= thr)  # the entries the matching may use
    hard = _shared_rows(t, cand, pf)
    hard[pf[cand[t.sim[cand] <= EPS]]] = True
    if thr <= EPS:  # pairs that do not overlap could be matched too
        hard[:] = True
    easy = cand[~hard[pf[cand]]]
    rows = [t.gi[easy]]
    mp = [data.pred_ids[t.pi[easy]]]
    ms = [t.sim[easy]]
    easy_frames = pf[easy]
    prev_ts = np.full(data.num_gt_ids, np.nan)  # matched tracker id in the previous frame
    done: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # hard frame -> (gt ids, tracker ids)
    for f in np.flatnonzero(hard).tolist():
        if f - 1 in done:
            pg, pp = done[f - 1]
        else:
            a, b = np.searchsorted(easy_frames, [f - 1, f])
            pg, pp = data.gt_ids[rows[0][a:b]], mp[0][a:b]
        prev_ts[pg] = pp
        g, p, sim = data.block(f)
        # prefer continuing last frame's matches (+1000), then maximise IoU
        score = (p[None, :] == prev_ts[g][:, None]) * 1000.0 + sim
        prev_ts[pg] = np.nan
        score[sim < thr] = 0
        r, c = linear_sum_assignment(-score)
        ok = score[r, c] > EPS
        r, c = r[ok], c[ok]
        done[f] = g[r], p[c]
        rows.append(t.g0[f] + r)
        mp.append(p[c])
        ms.append(sim[r, c])
    row = np.concatenate(rows)
    order = np.argsort(row, kind="stable")
    row = row[order]
    return (np.searchsorted(t.g0, row, side="right") - 1, row, data.gt_ids[row],
            np.concatenate(mp)[order], np.concatenate(ms)[order])


def _frame_sums(values: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Per run of equal ``frames``, the sum of ``values`` added left to right (Python's
    ``sum()``, TrackEval's order; NumPy's pairwise sums round differently)."""
    if len(values) == 0:
        return np.zeros(0)
    starts = np.flatnonzero(np.concatenate([[True], frames[1:] != frames[:-1]]))
    lengths = np.diff(np.concatenate([starts, [len(values)]]))
    acc = np.zeros(len(starts))
    for j in range(int(lengths.max())):
        m = lengths > j
        acc[m] += values[starts[m] + j]
    return acc


def _clear_loop(data: SequenceData, threshold: float, tp_f: np.ndarray, sw_f: np.ndarray) -> dict:
    """The matching and counting of :func:`clear_metrics` (both sides non-empty)."""
    res: dict = {k: 0 for k in CLEAR_INT}
    res.update({k: 0.0 for k in CLEAR_FLOAT})
    n_ids, n_frames = data.num_gt_ids, len(data.pairs.frames)
    fr, _, mg, mp, ms = _clear_matches(data, threshold - EPS)
    tp_f[:] = np.bincount(fr, minlength=n_frames)
    # each gt's matches in frame order: IDSW = a tracker id other than its last match's,
    # however long ago; Frag = runs of consecutive matched frames after the first
    order = np.lexsort((fr, mg))
    g, f, p = mg[order], fr[order], mp[order]
    same = g[1:] == g[:-1]
    sw_f[:] = np.bincount(f[1:][same & (p[1:] != p[:-1])], minlength=n_frames)
    runs = np.count_nonzero(~same | (f[1:] != f[:-1] + 1)) + 1 if len(g) else 0
    tracked = np.count_nonzero(~same) + 1 if len(g) else 0
    motp_sum = 0.0
    for s in _frame_sums(ms, fr):  # frame by frame, in TrackEval's order
        motp_sum += s
    gt_id_count = np.bincount(data.gt_ids, minlength=n_ids).astype(np.float64)
    matched_count = np.bincount(mg, minlength=n_ids)
    tp = int(tp_f.sum())
    res["CLR_TP"] = tp
    res["CLR_FN"] = data.num_gt_dets - tp
    res["CLR_FP"] = data.num_pred_dets - tp
    res["IDSW"] = int(sw_f.sum())
    present = gt_id_count > 0
    ratio = matched_count[present] / gt_id_count[present]
    res["MT"] = int(np.sum(ratio > 0.8))
    res["PT"] = int(np.sum(ratio >= 0.2)) - res["MT"]
    res["ML"] = n_ids - res["MT"] - res["PT"]
    res["Frag"] = int(runs - tracked)
    res["MOTP_sum"] = float(motp_sum)
    res["CLR_Frames"] = data.num_timesteps
    return _clear_final(res)


def combine_clear(results: Iterable[Mapping]) -> dict:
    """Several sequences: sum the counts and ``MOTP_sum``, recompute the ratios."""
    results = list(results)
    res = {k: sum(r[k] for r in results) for k in CLEAR_INT + ("MOTP_sum",)}
    return _clear_final(res)


# --------------------------------------------------------------------------------------------------
# Identity
# --------------------------------------------------------------------------------------------------
IDENTITY_INT = ("IDTP", "IDFN", "IDFP")
IDENTITY_FLOAT = ("IDF1", "IDR", "IDP")


def _identity_final(res: dict) -> dict:
    """Ristani et al. 2016: IDR = IDTP/(IDTP+IDFN), IDP = IDTP/(IDTP+IDFP), IDF1 = 2 IDTP/(2 IDTP+IDFP+IDFN)."""
    tp, fn, fp = res["IDTP"], res["IDFN"], res["IDFP"]
    res["IDR"] = tp / max(1.0, tp + fn)
    res["IDP"] = tp / max(1.0, tp + fp)
    res["IDF1"] = tp / max(1.0, tp + 0.5 * fp + 0.5 * fn)
    return res


def identity_metrics(data: SequenceData, threshold: float = 0.5) -> dict:
    """Identity metrics for one sequence (TrackEval ``Identity.eval_sequence``).

    Each gt id is matched to at most one tracker id, globally, maximising the number of frames in
    which the pair overlaps with IoU >= ``threshold`` (IDTP). TrackEval solves this on a
    ``(G + T)^2`` cost matrix of IDFN + IDFP; since both equal a constant minus the matched overlap
    count, the plain ``G x T`` maximum-weight assignment gives the same (integer) optimum.
    """
    res: dict = {k: 0 for k in IDENTITY_INT}
    res.update({k: 0.0 for k in IDENTITY_FLOAT})
    if data.num_pred_dets == 0:
        res["IDFN"] = data.num_gt_dets
        return res
    if data.num_gt_dets == 0:
        res["IDFP"] = data.num_pred_dets
        return res
    t = data.pairs
    hit = t.sim >= threshold
    g = data.gt_ids[t.gi[hit]]
    p = data.pred_ids[t.pi[hit]]
    nt = data.num_pred_ids
    idtp = 0
    if len(g):
        key, cnt = np.unique(g * nt + p, return_counts=True)
        rows, rinv = np.unique(key // nt, return_inverse=True)
        cols, cinv = np.unique(key % nt, return_inverse=True)
        m = np.zeros((len(rows), len(cols)))
        m[rinv, cinv] = cnt
        r, c = linear_sum_assignment(m, maximize=True)
        idtp = int(round(m[r, c].sum()))
    res["IDTP"] = idtp
    res["IDFN"] = data.num_gt_dets - idtp
    res["IDFP"] = data.num_pred_dets - idtp
    return _identity_final(res)


def combine_identity(results: Iterable[Mapping]) -> dict:
    results = list(results)
    return _identity_final({k: sum(r[k] for r in results) for k in IDENTITY_INT})


# --------------------------------------------------------------------------------------------------
# HOTA
# --------------------------------------------------------------------------------------------------
HOTA_INT_ARRAYS = ("HOTA_TP", "HOTA_FN", "HOTA_FP")
HOTA_FLOAT_ARRAYS = ("HOTA", "DetA", "AssA", "DetRe", "DetPr", "AssRe", "AssPr", "LocA", "OWTA")
HOTA_FLOAT = ("HOTA(0)", "LocA(0)", "HOTALocA(0)")


def _hota_final(res: dict) -> dict:
    """Luiten et al. 2021: DetA = TP/(TP+FN+FP), HOTA = sqrt(DetA * AssA), per alpha."""
    tp, fn, fp = res["HOTA_TP"], res["HOTA_FN"], res["HOTA_FP"]
    res["DetRe"] = tp / np.maximum(1, tp + fn)
    res["DetPr"] = tp / np.maximum(1, tp + fp)
    res["DetA"] = tp / np.maximum(1, tp + fn + fp)
    res["HOTA"] = np.sqrt(res["DetA"] * res["AssA"])
    res["OWTA"] = np.sqrt(res["DetRe"] * res["AssA"])
    res["HOTA(0)"] = float(res["HOTA"][0])
    res["LocA(0)"] = float(res["LocA"][0])
    res["HOTALocA(0)"] = res["HOTA(0)"] * res["LocA(0)"]
    return res


def _hota_matches(data: SequenceData, score: np.ndarray) -> tuple[np.ndarray, ...]:
    """HOTA's matches (gt id, tracker id, IoU), ordered by gt row: per frame, the Hungarian
    matching maximising ``score`` (alignment x IoU, one entry per overlapping pair)."""
    t = data.pairs
    pf = t.pair_frames()
    hard = _shared_rows(t, np.arange(len(t.sim)), pf)
    hard[pf[score <= EPS]] = True
    easy = np.flatnonzero(~hard[pf])
    rows, cols, ms = [t.gi[easy]], [t.pi[easy]], [t.sim[easy]]
    for f in np.flatnonzero(hard).tolist():
        a, b = t.offsets[f], t.offsets[f + 1]
        g0, p0 = t.g0[f], t.p0[f]
        shape = (int(t.ng[f]), int(t.np_[f]))
        rr, cc = t.gi[a:b] - g0, t.pi[a:b] - p0
        s_mat = np.zeros(shape)
        s_mat[rr, cc] = score[a:b]
        r, c = linear_sum_assignment(-s_mat)
        sim_mat = np.zeros(shape)
        sim_mat[rr, cc] = t.sim[a:b]
        m_sim = sim_mat[r, c]
        hit = m_sim > 0  # IoU 0 is below every alpha
        rows.append(g0 + r[hit])
        cols.append(p0 + c[hit])
        ms.append(m_sim[hit])
    row = np.concatenate(rows)
    order = np.argsort(row, kind="stable")
    return (data.gt_ids[row[order]], data.pred_ids[np.concatenate(cols)[order]],
            np.concatenate(ms)[order])


def hota_metrics(data: SequenceData) -> dict:
    """HOTA for one sequence (TrackEval ``HOTA.eval_sequence``), all 19 alphas at once.

    1. Global alignment ``A(g, t) = M / (n_g + n_t - M)`` where ``M`` sums, over frames, each pair's
       IoU normalised by ``IoU / (row sum + column sum - IoU)`` of that frame's IoU matrix.
    2. Per frame: Hungarian matching maximising ``A(g, t) * IoU``, one matching for all alphas; a
       matched pair is a TP at alpha when IoU >= alpha.
    3. ``AssA = sum over TPs of A_c / TP`` with ``A_c = TPA / (TPA + FNA + FPA)`` from the counts of
       TPs per (g, t) pair; AssRe, AssPr likewise; LocA = mean IoU of TPs.

    Returns
    -------
    dict
        ``HOTA_INT_ARRAYS`` and ``HOTA_FLOAT_ARRAYS`` as ``(19,)`` float64 arrays over
        :data:`ALPHAS`, plus the scalars ``HOTA(0)``, ``LocA(0)``, ``HOTALocA(0)``.
    """
    na = len(ALPHAS)
    res: dict = {k: np.zeros(na) for k in HOTA_FLOAT_ARRAYS + HOTA_INT_ARRAYS}
    res.update({k: 0.0 for k in HOTA_FLOAT})
    if data.num_pred_dets == 0 or data.num_gt_dets == 0:
        res["HOTA_FN" if data.num_pred_dets == 0 else "HOTA_FP"] = np.full(
            na, float(data.num_gt_dets if data.num_pred_dets == 0 else data.num_pred_dets))
        res["LocA"] = np.ones(na)
        res["LocA(0)"] = 1.0
        return res
    ng_ids, nt_ids = data.num_gt_ids, data.num_pred_ids
    gt_count = np.bincount(data.gt_ids, minlength=ng_ids).astype(np.float64)
    tr_count = np.bincount(data.pred_ids, minlength=nt_ids).astype(np.float64)
    t = data.pairs
    sim, pg, pp = t.sim, t.gi, t.pi  # overlapping pairs only: the others add nothing below
    # 1. per-frame row/column sums of the IoU matrix (a gt row lives in one frame only)
    row_sum = np.bincount(pg, weights=sim, minlength=data.num_gt_dets)
    col_sum = np.bincount(pp, weights=sim, minlength=data.num_pred_dets)
    denom = row_sum[pg] + col_sum[pp] - sim
    ok = denom > EPS
    sim_iou = np.zeros_like(sim)
    sim_iou[ok] = sim[ok] / denom[ok]
    gid, tid = data.gt_ids[pg], data.pred_ids[pp]
    pair_key = gid * nt_ids + tid
    ukey, inv = np.unique(pair_key, return_inverse=True)
    pot = np.bincount(inv.reshape(-1), weights=sim_iou, minlength=len(ukey))
    align_u = pot / (gt_count[ukey // max(nt_ids, 1)] + tr_count[ukey % max(nt_ids, 1)] - pot)
    score = align_u[inv.reshape(-1)] * sim
    # 2. one Hungarian matching per frame, maximising alignment x IoU
    mg, mt, ms = _hota_matches(data, score)
    tp_mask = ms[None, :] >= (ALPHAS - EPS)[:, None]  # (19, K)
    tp = tp_mask.sum(axis=1).astype(np.float64)
    res["HOTA_TP"] = tp
    res["HOTA_FN"] = data.num_gt_dets - tp
    res["HOTA_FP"] = data.num_pred_dets - tp
    loc = (tp_mask * ms[None, :]).sum(axis=1)
    # 3. association per alpha
    mkey = mg * nt_ids + mt
    mu, minv = np.unique(mkey, return_inverse=True)
    minv = minv.reshape(-1)
    gc_u = gt_count[mu // nt_ids] if len(mu) else np.zeros(0)
    tc_u = tr_count[mu % nt_ids] if len(mu) else np.zeros(0)
    for ai in range(na):
        cnt = np.bincount(minv[tp_mask[ai]], minlength=len(mu)).astype(np.float64)
        denom_tp = max(1.0, tp[ai])
        res["AssA"][ai] = np.sum(cnt * (cnt / np.maximum(1, gc_u + tc_u - cnt))) / denom_tp
        res["AssRe"][ai] = np.sum(cnt * (cnt / np.maximum(1, gc_u))) / denom_tp
        res["AssPr"][ai] = np.sum(cnt * (cnt / np.maximum(1, tc_u))) / denom_tp
    res["LocA"] = np.maximum(1e-10, loc) / np.maximum(1e-10, tp)
    return _hota_final(res)


def combine_hota(results: Iterable[Mapping]) -> dict:
    """Several sequences (TrackEval ``HOTA.combine_sequences``): sum TP/FN/FP; AssA, AssRe, AssPr
    and LocA as TP-weighted means; recompute the rest."""
    results = list(results)
    na = len(ALPHAS)
    res: dict = {k: sum((np.asarray(r[k], float) for r in results), np.zeros(na))
                 for k in HOTA_INT_ARRAYS}
    w = np.maximum(1.0, res["HOTA_TP"])
    for k in ("AssRe", "AssPr", "AssA"):
        res[k] = sum((r[k] * r["HOTA_TP"] for r in results), np.zeros(na)) / w
    loc = sum((r["LocA"] * r["HOTA_TP"] for r in results), np.zeros(na))
    res["LocA"] = np.maximum(1e-10, loc) / np.maximum(1e-10, res["HOTA_TP"])
    return _hota_final(res)


# --------------------------------------------------------------------------------------------------
# front door
# --------------------------------------------------------------------------------------------------
def _check_metrics(metrics: Iterable[str]) -> tuple[str, ...]:
    ms = tuple(m.strip().lower() for m in metrics if m.strip())
    bad = [m for m in ms if m not in METRIC_FAMILIES]
    if bad:
        raise ConfigError(f"unknown metric {bad[0]!r}; valid: {', '.join(METRIC_FAMILIES)}")
    return ms


def evaluate_sequence(
    gt: Annotations,
    pred: Annotations,
    metrics: Iterable[str] = METRIC_FAMILIES,
    threshold: float = 0.5,
    num_timesteps: int | None = None,
    distractor_classes: Sequence[int] = DISTRACTOR_CLASSES,
    do_preproc: bool = True,
    ignore_zero_marked: bool = False,
) -> dict[str, dict]:
    """All requested metric families for one sequence: ``{"clear": {...}, "identity": ..., "hota": ...}``
    with TrackEval's field names."""
    ms = _check_metrics(metrics)
    if not 0.0 < threshold <= 1.0:
        raise ConfigError(f"threshold must be in (0, 1], got {threshold}")
    data = preprocess(gt, pred, num_timesteps, distractor_classes, do_preproc, ignore_zero_marked)
    out: dict[str, dict] = {}
    if "clear" in ms:
        out["clear"] = clear_metrics(data, threshold)
    if "identity" in ms:
        out["identity"] = identity_metrics(data, threshold)
    if "hota" in ms:
        out["hota"] = hota_metrics(data)
    return out


_COMBINERS = {"clear": combine_clear, "identity": combine_identity, "hota": combine_hota}


def combine_sequences(per_sequence: Iterable[Mapping[str, Mapping]]) -> dict[str, dict]:
    """Combine :func:`evaluate_sequence` results of several sequences as TrackEval does."""
    per_sequence = list(per_sequence)
    if not per_sequence:
        return {}
    fams = [k for k in METRIC_FAMILIES if all(k in r for r in per_sequence)]
    return {k: _COMBINERS[k]([r[k] for r in per_sequence]) for k in fams}


def flatten(results: Mapping[str, Mapping]) -> dict[str, float]:
    """A flat dict with the MOTChallenge summary names.

    HOTA, DetA, AssA, LocA, DetRe, DetPr, AssRe, AssPr are the means over the 19 alphas (as
    TrackEval reports them); TP/FP/FN are the CLEAR counts.
    """
    out: dict[str, float] = {}
    h = results.get("hota")
    if h is not None:
        for k in ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr"):
            out[k] = float(np.mean(h[k]))
        out["HOTA(0)"] = float(h["HOTA(0)"])
        out["LocA(0)"] = float(h["LocA(0)"])
    c = results.get("clear")
    if c is not None:
        for k in ("MOTA", "MOTP", "MODA", "sMOTA"):
            out[k] = float(c[k])
        out["recall"] = float(c["CLR_Re"])
        out["precision"] = float(c["CLR_Pr"])
        for k in ("IDSW", "Frag", "MT", "PT", "ML"):
            out[k] = int(c[k])
        out["TP"], out["FP"], out["FN"] = int(c["CLR_TP"]), int(c["CLR_FP"]), int(c["CLR_FN"])
    i = results.get("identity")
    if i is not None:
        for k in ("IDF1", "IDP", "IDR"):
            out[k] = float(i[k])
        for k in ("IDTP", "IDFP", "IDFN"):
            out[k] = int(i[k])
    return out


def evaluate_tracking(
    gt: Annotations,
    pred: Annotations,
    metrics: Iterable[str] = METRIC_FAMILIES,
    threshold: float = 0.5,
    num_timesteps: int | None = None,
    xi: float = 0.75,
    ignore_zero_marked: bool = False,
) -> dict[str, float]:
    """Score one run against ground truth: a flat dict (keys as :func:`flatten`).

    Used by the pipeline to score a run on the fly and by ``motiontrack evaluate``. ``metrics`` may
    also name ``"framewise"``: the ViPER framewise metrics
    (:func:`motiontrack.evaluate.framewise.evaluate_framewise` with localization threshold ``xi``)
    are then merged in under their own keys. ``ignore_zero_marked``: see :func:`preprocess`.
    """
    ms = [m.strip().lower() for m in metrics]
    out = flatten(evaluate_sequence(gt, pred, [m for m in ms if m != "framewise"], threshold,
                                    num_timesteps, ignore_zero_marked=ignore_zero_marked)
                  ) if any(m != "framewise" for m in ms) else {}
    if "framewise" in ms:
        out.update(evaluate_framewise(gt, pred, xi)[0])
    return out
