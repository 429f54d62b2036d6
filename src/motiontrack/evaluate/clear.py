"""CLEAR-MOT for one sequence and for several combined, identical to TrackEval ``CLEAR``.

MOTA, MOTP after K. Bernardin, R. Stiefelhagen, "Evaluating Multiple Object Tracking Performance:
The CLEAR MOT Metrics", EURASIP JIVP 2008; MT/PT/ML and Frag after Y. Li, C. Huang, R. Nevatia,
"Learning to associate: HybridBoosted multi-target tracker", CVPR 2009.
"""

from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np

from ..assignment import linear_sum_assignment
from .pairs import EPS, shared_rows
from .sequence import SequenceData

__all__ = ["CLEAR_FLOAT", "CLEAR_INT", "clear_metrics", "combine_clear"]

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
    hard = shared_rows(t, cand, pf)
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

