"""HOTA and its sub-metrics for one sequence and for several combined, identical to TrackEval
``HOTA``, at all 19 localisation thresholds at once.

After J. Luiten et al., "HOTA: A Higher Order Metric for Evaluating Multi-Object Tracking", IJCV
2021.
"""

from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np

from ..assignment import linear_sum_assignment
from .pairs import EPS, shared_rows
from .sequence import SequenceData

__all__ = ["ALPHAS", "HOTA_FLOAT", "HOTA_FLOAT_ARRAYS", "HOTA_INT_ARRAYS", "combine_hota",
           "hota_metrics"]

#: HOTA localisation thresholds alpha = 0.05, 0.10, ..., 0.95 (TrackEval ``np.arange(0.05, 0.99, 0.05)``).
ALPHAS = np.arange(0.05, 0.99, 0.05)
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
    hard = shared_rows(t, np.arange(len(t.sim)), pf)
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

