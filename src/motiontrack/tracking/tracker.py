"""Multi-object tracker: constant-velocity Kalman filter + gated Hungarian assignment.

Lifecycle (parameters of :class:`~motiontrack.config.TrackerConfig`):

1. An unmatched detection starts a **tentative** track (no public id yet).
2. A tentative track with ``confirm_hits`` matched frames becomes **confirmed** and receives the
   next integer id (ids are therefore never wasted on noise and never reused).
   A tentative track that misses a frame is deleted.
3. A confirmed track that misses a frame becomes **lost** and coasts on its prediction; a match
   makes it confirmed again with the same id.
4. A lost track unseen for more than ``max_lost`` frames, or whose prediction has left the image,
   is **deleted**.

The per-frame step is vectorised over tracks (batched Kalman maths, one Hungarian solve).
"""

from __future__ import annotations

from collections import deque
from typing import Sequence

import numpy as np

from ..config import TrackerConfig
from ..registry import Registry
from ..types import Box, Region, Track, TrackState
from . import kalman
from .appearance import bhattacharyya, histograms
from .association import INF_COST, assign, association_cost, iou_matrix
from .merge import anchor_partial, split_merged

__all__ = ["TRACKERS", "MultiObjectTracker"]

TRACKERS: Registry["MultiObjectTracker"] = Registry("tracker")

#: consecutive partial views after which the measured (smaller) size is believed
MAX_PARTIAL_FRAMES = 8
#: running-average rate of a track's reference size
REF_RATE = 0.2
#: running-average rate of a track's appearance histogram
APPEARANCE_RATE = 0.1


class _TrackState:
    __slots__ = ("tid", "state", "hits", "age", "tsu", "history", "score", "partials", "ref",
                 "origin", "moved", "bridged", "hist")

    def __init__(self, history: int, size: np.ndarray) -> None:
        self.ref = np.asarray(size, np.float64).copy()  # reference (unoccluded) w, h
        self.tid = 0
        self.state = TrackState.TENTATIVE
        self.hits = 1
        self.age = 1
        self.tsu = 0
        self.history: deque = deque(maxlen=max(history, 1))
        self.score = 1.0
        self.partials = 0
        self.origin: np.ndarray | None = None   # centre where it was first matched
        self.moved = False                        # has travelled at least one body height
        self.bridged = False                      # last matched to a bridge measurement
        self.hist: np.ndarray | None = None       # appearance (colour histogram), running average


@TRACKERS.register("kalman")
class MultiObjectTracker:
    """SORT-style tracker with an explicit tentative → confirmed → lost → deleted lifecycle."""

    def __init__(self, cfg: TrackerConfig | None = None, image_size: tuple[int, int] | None = None) -> None:
        self.cfg = cfg or TrackerConfig()
        self.image_size = image_size
        self.x = np.zeros((0, 8))
        self.P = np.zeros((0, 8, 8))
        self.meta: list[_TrackState] = []
        self.next_id = 1
        self.frame_count = 0

    # ------------------------------------------------------------------------------- helpers
    def _boxes(self) -> np.ndarray:
        return kalman.z_to_box(self.x[:, :4]) if len(self.x) else np.zeros((0, 4))

    def _keep(self, keep: np.ndarray) -> None:
        self.x, self.P = self.x[keep], self.P[keep]
        self.meta = [m for m, k in zip(self.meta, keep) if k]

    def predict(self, dt: float = 1.0) -> np.ndarray:
        """Advance every track ``dt`` frames; returns the predicted boxes (N, 4)."""
        if len(self.x):
            c = self.cfg
            Q = kalman.process_noise(self.x, c.position_noise, c.velocity_noise) * dt
            self.x, self.P = kalman.predict(self.x, self.P, Q, dt)
            # keep sizes positive when a shrinking velocity overshoots
            self.x[:, 2:4] = np.maximum(self.x[:, 2:4], 1.0)
        return self._boxes()

    # ------------------------------------------------------------------------------- update
    def update(self, detections: Sequence[Region] | np.ndarray,
               scores: np.ndarray | None = None, dt: int = 1,
               owned: dict[int, np.ndarray] | None = None, image: np.ndarray | None = None,
               mask: np.ndarray | None = None, scale: float = 1.0) -> list[Track]:
        """One tracking step with this frame's detections (regions or an (M, 4) box array).

        ``dt`` is the number of frame periods since the previous update: more than 1 after a gap
        (dropped frames, a live source that reconnected), so predictions move on by the elapsed
        time and tracks age accordingly. ``owned`` maps a track index (in :attr:`meta`) to a
        measurement that can only belong to that track (e.g. from a single-object tracker
        bridging a detection miss, see :mod:`motiontrack.tracking.bridge`); it is used only when no
        detection matches the track. ``image`` and ``mask`` (processing scale ``scale``) feed the
        appearance model (:mod:`motiontrack.tracking.appearance`) when ``appearance_weight`` > 0.

        Returns the snapshots of the tracks to report this frame: confirmed tracks matched in this
        frame (plus coasting lost tracks when ``output_lost``).
        """
        dt = max(1, int(dt))
        c = self.cfg
        if isinstance(detections, np.ndarray):
            det = np.asarray(detections, np.float64).reshape(-1, 4)
            det_scores = np.ones(len(det)) if scores is None else np.asarray(scores, np.float64)
        else:
            det = np.array([r.box.as_array() for r in detections]).reshape(-1, 4)
            det_scores = np.array([r.score for r in detections], np.float64)
        self.frame_count += 1

        pred = self.predict(dt)
        if c.split_merged and len(det):
            established = np.array([m.state != TrackState.TENTATIVE for m in self.meta], bool)
            det, origin, owner = split_merged(pred, established, det)
            det_scores = det_scores[origin]
        else:
            owner = np.full(len(det), -1, np.int64)
        n_real = len(det)
        if owned:
            idx = np.fromiter(owned.keys(), np.int64, len(owned))
            det = np.concatenate([det, np.array([owned[i] for i in idx]).reshape(-1, 4)])
            det_scores = np.concatenate([det_scores, np.full(len(idx), 0.5)])
            owner = np.concatenate([owner, idx])
        # the search window around an unseen track's prediction grows with the time it is unseen
        tsu = np.array([m.tsu for m in self.meta], np.float64)
        cost = association_cost(pred, det, c.min_iou, c.max_distance * (1.0 + c.search_growth * tsu),
                                c.cost)
        det_hist = None
        if c.appearance_weight > 0 and image is not None and len(det) and len(self.meta):
            det_hist = histograms(image, det, mask, scale)
            have = [i for i, m in enumerate(self.meta) if m.hist is not None]
            if have:
                d_app = bhattacharyya(np.array([self.meta[i].hist for i in have]), det_hist)
                sub = cost[have]
                ok = sub < INF_COST
                sub[ok] += c.appearance_weight * d_app[ok]
                # re-identification of an unseen track needs a similar appearance
                lost = (tsu[have] > 0)[:, None]
                sub[lost & (d_app > c.appearance_gate)] = INF_COST
                cost[have] = sub
        # a synthetic measurement belongs to the track it was made for
        synth = np.flatnonzero(owner >= 0)
        if len(synth):
            cost[:, synth] = INF_COST
            # split measurements are certain (cost 0); a bridge is a fallback (cost 2, above any
            # detection match)
            cost[owner[synth], synth] = np.where(synth >= n_real, 2.0, 0.0)
        matches, un_tracks, un_dets = assign(cost)

        if len(matches):
            ti, di = matches[:, 0], matches[:, 1]
            if det_hist is not None:
                # learn appearance only from detections that overlap no other detection
                overlap = iou_matrix(det, det) > 0
                np.fill_diagonal(overlap, False)
                isolated = ~overlap.any(axis=1)
            ref = np.array([self.meta[t].ref for t in ti]).reshape(-1, 2)
            boxes, partial = anchor_partial(pred[ti], det[di], ref, c.partial_ratio)
            for k, t in enumerate(ti):
                m = self.meta[t]
                m.partials = m.partials + 1 if partial[k] else 0
                if m.partials > MAX_PARTIAL_FRAMES:
                    # a view that stays "partial" for long is the object's real size: accept it
                    boxes[k] = det[di[k]]
                    partial[k] = False
                if not partial[k] and owner[di[k]] < 0:
                    m.ref = m.ref + REF_RATE * (det[di[k], 2:4] - m.ref)
                    if det_hist is not None and det_hist[di[k]].any() and isolated[di[k]]:
                        m.hist = (det_hist[di[k]].copy() if m.hist is None
                                  else m.hist + APPEARANCE_RATE * (det_hist[di[k]] - m.hist))
            z = kalman.box_to_z(boxes)
            self.x[ti], self.P[ti] = kalman.update(self.x[ti], self.P[ti], z, c.measurement_noise)
            for t, d in zip(ti, di):
                m = self.meta[t]
                m.hits += 1
                m.tsu = 0
                m.bridged = bool(d >= n_real)
                if not m.moved:
                    centre = self.x[t, :2]
                    if m.origin is None:
                        m.origin = centre.copy()
                    elif np.hypot(*(centre - m.origin)) > m.ref[1]:
                        m.moved = True
                m.score = float(det_scores[d])
                if m.state == TrackState.TENTATIVE and m.hits >= c.confirm_hits:
                    m.state = TrackState.CONFIRMED
                    m.tid = self.next_id
                    self.next_id += 1
                elif m.state == TrackState.LOST:
                    m.state = TrackState.CONFIRMED

        keep = np.ones(len(self.meta), bool)
        boxes = self._boxes()
        for t in un_tracks:
            m = self.meta[t]
            m.tsu += dt
            if m.state == TrackState.TENTATIVE:
                keep[t] = False
            else:
                m.state = TrackState.LOST
                # coast on position only: the size keeps its reference value
                self.x[t, 2:4] = m.ref
                self.x[t, 6:8] = 0.0
                if m.tsu > c.max_lost or self._outside(boxes[t]):
                    keep[t] = False
        for m in self.meta:
            m.age += dt
        self._keep(keep)

        un_dets = un_dets[owner[un_dets] < 0]
        if len(un_dets):
            x0, P0 = kalman.initiate(det[un_dets], c.position_noise, c.velocity_noise)
            self.x = np.concatenate([self.x, x0])
            self.P = np.concatenate([self.P, P0])
            for d in un_dets:
                m = _TrackState(c.history, det[d, 2:4])
                m.score = float(det_scores[d])
                if det_hist is not None and det_hist[d].any():
                    m.hist = det_hist[d].copy()
                if c.confirm_hits <= 1:
                    m.state = TrackState.CONFIRMED
                    m.tid = self.next_id
                    self.next_id += 1
                self.meta.append(m)

        return self._snapshots()

    def _outside(self, box: np.ndarray) -> bool:
        if self.image_size is None:
            return False
        w, h = self.image_size
        x, y, bw, bh = box
        return x + bw <= 0 or y + bh <= 0 or x >= w or y >= h

    def _snapshots(self) -> list[Track]:
        out: list[Track] = []
        boxes = self._boxes()
        for i, m in enumerate(self.meta):
            b = boxes[i]
            m.history.append((float(b[0] + b[2] / 2), float(b[1] + b[3] / 2)))
            if m.state == TrackState.CONFIRMED and m.tsu == 0:
                pass
            elif m.state == TrackState.LOST and self.cfg.output_lost:
                pass
            else:
                continue
            out.append(Track(
                id=m.tid, box=Box(float(b[0]), float(b[1]), float(b[2]), float(b[3])), state=m.state,
                velocity=(float(self.x[i, 4]), float(self.x[i, 5])), hits=m.hits, age=m.age,
                time_since_update=m.tsu, history=tuple(m.history), score=m.score,
            ))
        return out

    def moving_boxes(self, margin: float = 0.1) -> np.ndarray:
        """Boxes (N, 4) where established tracks that have travelled at least one body height are
        expected next frame (current box moved by one step of velocity, grown by ``margin`` of its
        size on each side). Used to protect them from being learnt into the background."""
        keep = [i for i, m in enumerate(self.meta) if m.moved and m.state != TrackState.TENTATIVE
                and m.tsu <= 2]
        if not keep:
            return np.zeros((0, 4))
        x = self.x[keep]
        b = kalman.z_to_box(x[:, :4] + x[:, 4:8])
        grow = margin * b[:, 2:4]
        return np.column_stack([b[:, :2] - grow, b[:, 2:4] + 2 * grow])

    @property
    def active_count(self) -> int:
        """Tracks currently held (any state)."""
        return len(self.meta)
