"""Similarity of ground-truth and tracker boxes, as TrackEval computes it.

The IoU of ``x, y, w, h`` boxes with TrackEval's very floating-point operations (so that Hungarian
ties break identically), the sparse table of every overlapping gt-tracker pair per frame that
preprocessing and every metric family read (:class:`PairTable`), and the test that lets the
metrics take a frame's matches without the solver (:func:`shared_rows`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["EPS", "PairTable", "box_iou_xywh", "pair_table", "restrict", "shared_rows"]

#: Machine epsilon, TrackEval's tolerance in every comparison of IoU and scores.
EPS = float(np.finfo(float).eps)


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



def shared_rows(t: PairTable, sel: np.ndarray, pair_frame: np.ndarray) -> np.ndarray:
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

