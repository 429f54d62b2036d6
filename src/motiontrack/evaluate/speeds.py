"""Walking speeds of tracks against ground truth's world positions.

Each tracker track is paired with the ground-truth object it matches in most frames: in every
frame, tracker and ground-truth boxes (``consider`` rows only) are matched one to one at IoU
>= ``threshold``, maximising the total IoU (the frame-level matching of CLEAR-MOT without its
continuity rule). Over the frames where the pair is matched, both mean speeds are measured the
same way, the way ``summary.json`` and the scene rule ``[speed]`` measure a track's speed
(:func:`motiontrack.speed.mean_speed`): the mean over those frames of the straight distance from
the position ``window_s`` seconds earlier (the oldest within the window) to the current one over
their time apart (box jitter of a frame or two otherwise adds path that nobody walked). The
tracker's positions are its ``world`` column (``tracks.txt`` columns 8–9 with ``track
--camera``), the ground truth's its own (``gt_mot15.txt`` columns 8–9). Both speeds come from
the same frames at the same frame rate, so a frame rate other than the true one scales both
alike.
"""

from __future__ import annotations

from collections import Counter, defaultdict

import numpy as np

from ..assignment import linear_sum_assignment
from ..speed import SPEED_WINDOW_S, mean_speed
from ..types import Annotations
from .pairs import box_iou_xywh

__all__ = ["majority_matches", "speed_pairs"]


def majority_matches(gt: Annotations, pred: Annotations,
                     threshold: float = 0.5) -> dict[int, tuple[int, np.ndarray]]:
    """Tracker id → (its majority ground-truth id, the frames where the two are matched)."""
    gt = gt.select(gt.consider)
    g_rows, p_rows = gt.by_frame(), pred.by_frame()
    pairs: dict[int, list[tuple[int, int]]] = defaultdict(list)
    for f, pi in p_rows.items():
        gi = g_rows.get(f)
        if gi is None:
            continue
        ng, npr = len(gi), len(pi)
        iou = box_iou_xywh(np.repeat(gt.boxes[gi], npr, axis=0),
                           np.tile(pred.boxes[pi], (ng, 1))).reshape(ng, npr)
        r, c = linear_sum_assignment(np.where(iou >= threshold, iou, 0.0), maximize=True)
        for a, b in zip(r, c):
            if iou[a, b] >= threshold:
                pairs[int(pred.ids[pi[b]])].append((int(f), int(gt.ids[gi[a]])))
    out = {}
    for tid, rows in pairs.items():
        gid = Counter(g for _, g in rows).most_common(1)[0][0]
        out[tid] = (gid, np.array(sorted(f for f, g in rows if g == gid), dtype=np.int64))
    return out


def speed_pairs(gt: Annotations, pred: Annotations, fps: float, threshold: float = 0.5,
                min_frames: int = 10, window_s: float = SPEED_WINDOW_S) -> list[dict]:
    """Per tracker track matched in at least ``min_frames`` frames: ``track``, ``gt``,
    ``frames``, ``speed_mps`` (tracker), ``gt_speed_mps`` and ``diff_mps`` (tracker − ground
    truth), in track order; ``window_s`` (> 0) is the window of each speed."""
    g_index = {(int(f), int(i)): k for k, (f, i) in enumerate(zip(gt.frames, gt.ids))}
    p_index = {(int(f), int(i)): k for k, (f, i) in enumerate(zip(pred.frames, pred.ids))}
    rows = []
    for tid, (gid, frames) in sorted(majority_matches(gt, pred, threshold).items()):
        if len(frames) < max(2, min_frames):
            continue
        ours = pred.world[[p_index[(int(f), tid)] for f in frames], :2]
        theirs = gt.world[[g_index[(int(f), gid)] for f in frames], :2]
        ok = np.all(np.isfinite(ours), axis=1) & np.all(np.isfinite(theirs), axis=1)
        if np.count_nonzero(ok) < max(2, min_frames):
            continue
        v = mean_speed(frames[ok].tolist(), ours[ok].tolist(), fps, window_s)
        g = mean_speed(frames[ok].tolist(), theirs[ok].tolist(), fps, window_s)
        if v is None or g is None:   # matched over less than half a window
            continue
        rows.append({"track": tid, "gt": gid, "frames": int(np.count_nonzero(ok)),
                     "speed_mps": v, "gt_speed_mps": g, "diff_mps": v - g})
    return rows
