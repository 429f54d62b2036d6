"""The detection-driven tracker: a detector's scored boxes in, tracks out.

A detector's box is one object with a confidence, unlike a motion blob, so this tracker
(``tracker.method = detections``, chosen by ``--detections`` through the ``detections`` preset)
associates in three stages, each a gated Hungarian solve (settings: ``tracker.detections.*``,
:class:`~motiontrack.config.DetectionsParams`):

1. **High-score detections** (score ≥ ``high_score``) against every track's Kalman prediction:
   the benefit of a pair is its IoU plus OC-SORT's *observation-centric momentum* (OCM; Cao et
   al., CVPR 2023, eq. 9): ``inertia × score × (π/2 − θ) / π``, where θ is the angle between the
   track's direction (its observations ``delta_t`` frames apart) and the direction from its
   observation ``delta_t`` frames back to the detection. A detection behind a walking person
   loses to one ahead of them. Pairs with IoU below ``min_iou`` never match.
2. **Low-score detections** (``low_score`` ≤ score < ``high_score``) against the tracks left
   over, by IoU alone, gated by ``low_iou`` (ByteTrack's second association; Zhang et al., ECCV
   2022): a partly occluded person's weak box continues their track instead of being dropped.
3. **Observation-centric recovery** (OCR, ``recover``): the tracks still unmatched against the
   high-score detections still unmatched, by the IoU with the track's *last observation*
   instead of its prediction: a track that stopped while occluded is found where it was last
   seen.

A track seen again after a gap re-runs its filter over the line from its last observation to the
new one (*observation-centric re-update*, ORU, ``reupdate``): the prediction that drifted while
it coasted is replaced by what the two observations say.

Life cycle: only an unmatched detection of score ≥ ``new_score`` starts a track (tentative); it
is confirmed after ``tracker.confirm_hits`` matched frames in a row, and a tentative track that
misses a frame is deleted. A confirmed track unmatched in a frame is lost: it is not reported,
and it is deleted after ``tracker.max_lost_s`` unseen. Reported boxes are the Kalman filter's
estimate after the frame's correction (``tracker.position_noise``, ``velocity_noise``,
``measurement_noise``: :mod:`motiontrack.tracking.kalman`). With pictures (a video beside the
detections) and ``appearance_weight`` > 0, stage 1 also weighs the colour-histogram distance
(:mod:`motiontrack.tracking.appearance`).
"""

from __future__ import annotations

import math
from collections import deque
from typing import Any, Mapping, Sequence

import numpy as np

from ..config import DetectionsParams, TrackerConfig
from ..types import Box, Region, Track, TrackState
from . import kalman
from .appearance import bhattacharyya, histograms
from ..assignment import linear_sum_assignment
from .association import INF_COST, iou_matrix
from .tracker import APPEARANCE_RATE, TRACKERS, TrackView, tentative_tracks

__all__ = ["DetectionTracker", "direction_cost", "unit_directions"]

#: running-average rate of a track's appearance histogram (the motion-blob tracker's)
_HIST_RATE = APPEARANCE_RATE


def unit_directions(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Unit vectors from centres ``src`` (N, 2) to ``dst`` (N, 2) (or (N, M, 2) with ``src``
    broadcast as (N, 1, 2)); a zero vector where the two centres coincide."""
    d = np.asarray(dst, np.float64) - np.asarray(src, np.float64)
    norm = np.sqrt((d * d).sum(axis=-1, keepdims=True))
    return np.divide(d, norm, out=np.zeros_like(d), where=norm > 1e-6)


def direction_cost(direction: np.ndarray, anchor: np.ndarray, centres: np.ndarray,
                   valid: np.ndarray) -> np.ndarray:
    """OC-SORT's direction-consistency benefit (OCM) of each (track, detection) pair, (N, M).

    ``direction`` (N, 2) is each track's unit direction, ``anchor`` (N, 2) the centre of its
    observation ``delta_t`` frames back, ``centres`` (M, 2) the detections' centres, ``valid``
    (N,) whether a track has a direction yet. The benefit is ``(π/2 − θ) / π`` with θ the angle
    between the track's direction and the direction from its anchor to the detection: +0.5 for
    a detection straight ahead, 0 at a right angle, −0.5 straight behind; 0 for invalid tracks.
    """
    n, m = len(direction), len(centres)
    if n == 0 or m == 0:
        return np.zeros((n, m))
    to_det = unit_directions(anchor[:, None, :], centres[None, :, :])
    cos = np.clip((to_det * direction[:, None, :]).sum(axis=-1), -1.0, 1.0)
    benefit = (math.pi / 2 - np.arccos(cos)) / math.pi
    benefit[~valid] = 0.0
    return benefit


class _Meta:
    """What the tracker keeps of one track besides its arrays (Kalman state, last observed box,
    state after that observation, direction)."""

    __slots__ = ("tid", "state", "hits", "age", "tsu", "score", "seen", "obs", "history", "hist",
                 "tentative", "reported")

    def __init__(self, box: list[float], score: float, frame: int, history: int,
                 delta_t: int) -> None:
        self.tid = 0
        self.state = TrackState.TENTATIVE
        self.hits = 1
        self.age = 1
        self.tsu = 0
        self.score = score
        self.seen = frame                  # the update count of the last observation
        self.obs: deque = deque(maxlen=delta_t + 1)   # (update count, cx, cy) of recent ones
        self.obs.append((frame, box[0] + box[2] / 2, box[1] + box[3] / 2))
        self.history: deque = deque(maxlen=max(history, 1))
        self.hist: np.ndarray | None = None
        self.tentative: list[tuple] = []
        self.reported: int | None = None

    def anchor(self, now: int, delta_t: int) -> tuple[float, float]:
        """Centre of the observation ``delta_t`` update counts before ``now`` (the closest later
        one when that frame was missed, OC-SORT's ``k_previous_obs``), else the last one."""
        for f, cx, cy in self.obs:
            if now - delta_t <= f < now:
                return cx, cy
        return self.obs[-1][1], self.obs[-1][2]


@TRACKERS.register("detections")
class DetectionTracker:
    """Detector boxes by score: ByteTrack's two stages with OC-SORT's ORU, OCM and OCR.

    Per track, in arrays of one row per track: the Kalman state ``x`` (N, 8) and covariance
    blocks ``P`` (N, 3, 4) (:mod:`~motiontrack.tracking.kalman`), the last observed box ``last``
    (N, 4), the filter right after that observation ``fx``, ``fP`` (for the re-update) and the
    unit direction of motion ``dirs`` (N, 2; zero until the track has moved)."""

    def __init__(self, cfg: TrackerConfig | None = None, image_size: tuple[int, int] | None = None,
                 fps: float | None = None) -> None:
        self.cfg = cfg or TrackerConfig()
        self.p: DetectionsParams = self.cfg.detections
        self.image_size = image_size
        #: frames a lost track is kept for re-association (``max_lost_s`` at ``fps``; 25 unknown)
        self.max_lost = int(round(self.cfg.max_lost_s * (fps or 25.0)))
        self.next_id = 1
        self.frame_count = 0
        self.keep_tentative = False
        self.reset()

    def reset(self) -> None:
        """End every track at once; ids keep counting."""
        self.x = np.zeros((0, 8))
        self.P = np.zeros((0, 3, 4))
        self.fx = np.zeros((0, 8))
        self.fP = np.zeros((0, 3, 4))
        self.last = np.zeros((0, 4))
        self.dirs = np.zeros((0, 2))
        self.meta: list[_Meta] = []
        self.confirmed_earlier: list[tuple[int, Track]] = []

    # --------------------------------------------------------------------------------- update
    def update(self, detections: Sequence[Region] | np.ndarray, scores: np.ndarray | None = None,
               dt: int = 1, owned: Mapping[int, np.ndarray] | None = None,
               image: np.ndarray | None = None, mask: np.ndarray | None = None,
               scale: float = 1.0, frame: int | None = None, **_: Any) -> list[Track]:
        """One step with this frame's detections (regions, or an (M, 4) box array with
        ``scores``). ``dt`` is the frame periods since the previous update; ``image`` (at
        processing scale ``scale``) feeds the appearance term. Owned measurements and the
        people stage's boxes (the motion tracker's) are not used. Returns the confirmed tracks
        matched in this frame."""
        dt = max(1, int(dt))
        det, det_scores = _as_arrays(detections, scores)
        self.frame_count += dt
        self.confirmed_earlier = []
        p = self.p
        if len(det_scores) and det_scores.min() < p.low_score:
            keep = det_scores >= p.low_score
            det, det_scores = det[keep], det_scores[keep]
        pred = self._predict(dt)
        hist = (histograms(image, det, mask, scale)
                if p.appearance_weight > 0 and image is not None and image.size and len(det)
                else None)
        matches, left_t, left_d = self._associate(pred, det, det_scores, hist)
        self._correct(matches, det, det_scores, hist)
        self._miss(left_t, dt)
        self._spawn([d for d in left_d if det_scores[d] >= p.new_score], det, det_scores, hist)
        return self._snapshots(self.frame_count - 1 if frame is None else frame)

    def _predict(self, dt: int) -> np.ndarray:
        """Every track moved on ``dt`` frames; the predicted boxes (N, 4)."""
        if not self.meta:
            return np.zeros((0, 4))
        for m in self.meta:
            m.age += dt
        c = self.cfg
        Q = kalman.process_noise(self.x, c.position_noise, c.velocity_noise) * dt
        self.x, self.P = kalman.predict(self.x, self.P, Q, dt)
        np.maximum(self.x[:, 2:4], 1.0, out=self.x[:, 2:4])
        return kalman.z_to_box(self.x)

    def _associate(self, pred: np.ndarray, det: np.ndarray, scores: np.ndarray,
                   hist: np.ndarray | None) -> tuple[list, list[int], list[int]]:
        """The three stages of the module docstring: the matches as (track, detection) pairs,
        the tracks and the detections left unmatched."""
        p = self.p
        is_high = scores >= p.high_score
        high = np.flatnonzero(is_high)
        tracks = list(range(len(pred)))
        if not len(pred) or not len(det):
            return [], tracks, high.tolist()
        iou = iou_matrix(pred, det[high])
        benefit = self._first_benefit(iou, det[high], scores[high], hist, high)
        matches, t_left, d_left = _stage(tracks, high.tolist(), benefit, iou, p.min_iou)
        if t_left and not is_high.all():
            low = np.flatnonzero(~is_high)
            iou = iou_matrix(pred[t_left], det[low])
            found, t_left, _ = _stage(t_left, low.tolist(), iou, iou, p.low_iou)
            matches += found
        if p.recover and t_left and d_left:
            iou = iou_matrix(self.last[t_left], det[d_left])
            found, t_left, d_left = _stage(t_left, d_left, iou, iou, p.min_iou)
            matches += found
        return matches, t_left, d_left

    def _first_benefit(self, iou: np.ndarray, det: np.ndarray, scores: np.ndarray,
                       hist: np.ndarray | None, high: np.ndarray) -> np.ndarray:
        """Stage 1's benefit of every (track, high-score detection) pair: IoU, plus the
        direction term (OCM) times the detection's score, minus the appearance distance."""
        p = self.p
        if not iou.size:
            return iou
        benefit = iou
        valid = self.dirs.any(axis=1)
        if p.inertia > 0 and valid.any():
            now = self.frame_count
            anchors = np.array([m.anchor(now, p.delta_t) for m in self.meta])
            centres = det[:, :2] + det[:, 2:] / 2
            benefit = iou + (p.inertia * scores)[None, :] * direction_cost(
                self.dirs, anchors, centres, valid)
        if hist is not None:
            have = [i for i, m in enumerate(self.meta) if m.hist is not None]
            if have:
                dist = bhattacharyya(np.array([self.meta[i].hist for i in have]), hist[high])
                benefit = benefit.copy()
                benefit[have] -= p.appearance_weight * dist
        return benefit

    def _correct(self, matches: list, det: np.ndarray, scores: np.ndarray,
                 hist: np.ndarray | None) -> None:
        """Kalman correction of the matched tracks (a re-update over the gap first for the
        tracks seen again, ``reupdate``), their observations, directions and life cycle."""
        if not matches:
            return
        c, p = self.cfg, self.p
        ti = [t for t, _ in matches]
        di = [d for _, d in matches]
        if p.reupdate:
            for t, d in matches:
                if self.meta[t].tsu > 0:
                    self._reupdate(t, det[d])
        boxes = det[di]
        self.x[ti], self.P[ti] = kalman.update(self.x[ti], self.P[ti], kalman.box_to_z(boxes),
                                               c.measurement_noise)
        self.fx[ti], self.fP[ti], self.last[ti] = self.x[ti], self.P[ti], boxes
        now = self.frame_count
        dirs = self.dirs
        for (t, d), (x, y, w, h), sc in zip(matches, boxes.tolist(), scores[di].tolist()):
            m = self.meta[t]
            cx, cy = x + w / 2, y + h / 2
            ax, ay = m.anchor(now, p.delta_t)
            norm = math.hypot(cx - ax, cy - ay)
            if norm > 1e-6:
                dirs[t] = ((cx - ax) / norm, (cy - ay) / norm)
            m.obs.append((now, cx, cy))
            m.seen, m.score = now, sc
            m.hits += 1
            m.tsu = 0
            if hist is not None and hist[d].any():
                m.hist = hist[d].copy() if m.hist is None else m.hist + _HIST_RATE * (hist[d] - m.hist)
            if m.state == TrackState.TENTATIVE and m.hits >= c.confirm_hits:
                m.state = TrackState.CONFIRMED
                m.tid, self.next_id = self.next_id, self.next_id + 1
            elif m.state == TrackState.LOST:
                m.state = TrackState.CONFIRMED

    def _reupdate(self, t: int, box: np.ndarray) -> None:
        """OC-SORT's ORU for track ``t``, unseen since its last observation and now matched to
        ``box``: from the filter's state right after that observation, one prediction and one
        correction per frame of the gap with a virtual observation on the line between the two
        boxes; the last prediction is left for the real correction that follows."""
        m = self.meta[t]
        gap = self.frame_count - m.seen
        x, P = self.fx[t:t + 1].copy(), self.fP[t:t + 1].copy()
        last = self.last[t]
        for k in range(1, gap):
            x, P = self._step(x, P)
            virtual = last + (box - last) * (k / gap)
            x, P = kalman.update(x, P, kalman.box_to_z(virtual[None]), self.cfg.measurement_noise)
        x, P = self._step(x, P)
        self.x[t], self.P[t] = x[0], P[0]

    def _step(self, x: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c = self.cfg
        x, P = kalman.predict(x, P, kalman.process_noise(x, c.position_noise, c.velocity_noise))
        x[:, 2:4] = np.maximum(x[:, 2:4], 1.0)
        return x, P

    def _miss(self, tracks: list[int], dt: int) -> None:
        """Unmatched tracks: a tentative one is deleted, a confirmed one is lost, a track lost
        for longer than ``max_lost`` frames, or predicted outside the image, is deleted."""
        if not tracks:
            return
        outside = self._outside(kalman.z_to_box(self.x[tracks])).tolist()
        drop = []
        for t, out in zip(tracks, outside):
            m = self.meta[t]
            m.tsu += dt
            if m.state == TrackState.TENTATIVE or m.tsu > self.max_lost or out:
                drop.append(t)
            else:
                m.state = TrackState.LOST
        if drop:
            keep = np.ones(len(self.meta), bool)
            keep[drop] = False
            for name in ("x", "P", "fx", "fP", "last", "dirs"):
                setattr(self, name, getattr(self, name)[keep])
            self.meta = [m for m, k in zip(self.meta, keep.tolist()) if k]

    def _spawn(self, rows: list[int], det: np.ndarray, scores: np.ndarray,
               hist: np.ndarray | None) -> None:
        """New tentative tracks (confirmed at once when ``confirm_hits`` is 1)."""
        if not rows:
            return
        c = self.cfg
        boxes = det[rows]
        x0, P0 = kalman.initiate(boxes, c.position_noise, c.velocity_noise)
        self.x = np.concatenate([self.x, x0])
        self.P = np.concatenate([self.P, P0])
        self.fx = np.concatenate([self.fx, x0])
        self.fP = np.concatenate([self.fP, P0])
        self.last = np.concatenate([self.last, boxes])
        self.dirs = np.concatenate([self.dirs, np.zeros((len(rows), 2))])
        for d, box in zip(rows, boxes.tolist()):
            m = _Meta(box, float(scores[d]), self.frame_count, c.history, self.p.delta_t)
            if hist is not None and hist[d].any():
                m.hist = hist[d].copy()
            if c.confirm_hits <= 1:
                m.state = TrackState.CONFIRMED
                m.tid, self.next_id = self.next_id, self.next_id + 1
            self.meta.append(m)

    def _outside(self, boxes: np.ndarray) -> np.ndarray:
        """Which boxes (N, 4) lie wholly outside the image (none when its size is unknown)."""
        if self.image_size is None:
            return np.zeros(len(boxes), bool)
        w, h = self.image_size
        return ((boxes[:, 0] + boxes[:, 2] <= 0) | (boxes[:, 1] + boxes[:, 3] <= 0)
                | (boxes[:, 0] >= w) | (boxes[:, 1] >= h))

    def _snapshots(self, frame: int) -> list[Track]:
        """The confirmed tracks matched in this update, and the tentative frames of those
        confirmed in it (:attr:`confirmed_earlier`, with :attr:`keep_tentative`)."""
        out: list[Track] = []
        if not self.meta:
            return out
        boxes = kalman.z_to_box(self.x).tolist()
        vel = self.x[:, 4:6].tolist()
        for m, (x, y, w, h), (vx, vy) in zip(self.meta, boxes, vel):
            if m.tsu:
                continue
            m.history.append((x + w / 2, y + h / 2))
            if m.state == TrackState.TENTATIVE:
                if self.keep_tentative:
                    m.tentative.append((frame, Box(x, y, w, h), (vx, vy), m.hits, m.age,
                                        tuple(m.history), m.score))
                continue
            if m.tentative:
                self.confirmed_earlier.extend(tentative_tracks(m.tid, m.tentative))
                m.tentative = []
            m.reported = frame
            out.append(Track(id=m.tid, box=Box(x, y, w, h), state=m.state, velocity=(vx, vy),
                             hits=m.hits, age=m.age, time_since_update=0,
                             history=tuple(m.history), score=m.score))
        return out

    # ------------------------------------------------------------------- what other stages see
    def views(self) -> list[TrackView]:
        """Every named track (ids > 0), as :meth:`MultiObjectTracker.views` shows them."""
        return [TrackView(m.tid, m.state, m.tsu, True, False) for m in self.meta if m.tid > 0]

    def moving_boxes(self, margin: float = 0.1, unseen: int = 2,
                     slower: float | None = None) -> np.ndarray:
        """No motion mask to protect with detections: an empty (0, 4) array."""
        return np.zeros((0, 4))

    @property
    def active_count(self) -> int:
        """Tracks currently held (any state)."""
        return len(self.meta)


def _stage(rows: list[int], cols: list[int], benefit: np.ndarray, iou: np.ndarray,
           gate: float) -> tuple[list, list[int], list[int]]:
    """One gated Hungarian solve maximising ``benefit`` over the pairs of ``rows`` (tracks) and
    ``cols`` (detections) whose ``iou`` reaches ``gate``: the matches as (track, detection)
    pairs, the rows and the columns left over."""
    if not rows or not cols:
        return [], rows, cols
    allowed = iou >= max(gate, 1e-9)
    if not allowed.any():
        return [], rows, cols
    r, c = linear_sum_assignment(np.where(allowed, -benefit, INF_COST))
    ok = allowed[r, c].tolist()
    matched_r = {i for i, k in zip(r.tolist(), ok) if k}
    matched_c = {j for j, k in zip(c.tolist(), ok) if k}
    matches = [(rows[i], cols[j]) for i, j, k in zip(r.tolist(), c.tolist(), ok) if k]
    return (matches, [t for i, t in enumerate(rows) if i not in matched_r],
            [d for j, d in enumerate(cols) if j not in matched_c])


def _as_arrays(detections: Sequence[Region] | np.ndarray,
               scores: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Boxes (M, 4) and scores (M,) of regions or of a box array (scores default 1)."""
    if isinstance(detections, np.ndarray):
        det = np.asarray(detections, np.float64).reshape(-1, 4)
        return det, (np.ones(len(det)) if scores is None else np.asarray(scores, np.float64))
    det = np.array([r.box.as_array() for r in detections], np.float64).reshape(-1, 4)
    return det, np.array([r.score for r in detections], np.float64)
