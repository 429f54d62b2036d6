"""Identity metrics (IDF1, IDP, IDR) for one sequence and for several combined, identical to
TrackEval ``Identity``.

After E. Ristani et al., "Performance Measures and a Data Set for Multi-Target, Multi-Camera
Tracking", ECCV-W 2016.
"""

from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np

from ..assignment import linear_sum_assignment
from .sequence import SequenceData

__all__ = ["IDENTITY_FLOAT", "IDENTITY_INT", "combine_identity", "identity_metrics"]

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

