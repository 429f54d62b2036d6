"""MOTChallenge preprocessing of one sequence into :class:`SequenceData`, as TrackEval does it.

TrackEval ``MotChallenge2DBox.get_preprocessed_seq_data``
--------------------------------------------------------
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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..assignment import linear_sum_assignment
from ..errors import ConfigError, InputError
from ..types import Annotations
from .pairs import EPS, PairTable, pair_table, restrict, shared_rows

__all__ = ["DISTRACTOR_CLASSES", "SequenceData", "preprocess"]

#: MOTChallenge distractor classes: person on vehicle, static person, distractor, reflection.
DISTRACTOR_CLASSES = (2, 7, 8, 12)
PEDESTRIAN = 1


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
    hard = shared_rows(t, cand, pf)
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

