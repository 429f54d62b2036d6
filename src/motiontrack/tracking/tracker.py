"""Multi-object tracker: constant-velocity Kalman filter + gated Hungarian assignment.

Lifecycle (parameters of :class:`~motiontrack.config.TrackerConfig`):

1. An unmatched detection starts a **tentative** track (no public id yet).
2. A tentative track with ``confirm_hits`` matched frames becomes **confirmed** and receives the
   next integer id (ids are therefore never wasted on noise and never reused) — or, when a lost
   track fits it (appearance, search window, height), that track's id: the same person
   reappearing, taken over first by a tentative track (re-identification at confirmation; the
   lost track is dropped). A tentative track that misses a frame is deleted.
3. A confirmed track that misses a frame becomes **lost** and coasts on its prediction, at the
   median pace of its last ``coast_frames`` steps rather than its last Kalman velocity; a match
   makes it confirmed again with the same id.
4. A lost track unseen for more than ``max_lost_s`` seconds (at the source's frame rate), or
   whose prediction has left the image, is **deleted**.

Region-tracker semantics of the Reading People Tracker (see :mod:`.merge`): a blob holding
several tracks' predictions is split into one synthetic measurement per track, and a partly
occluded view is anchored on its visible edges with the track's reference size. One object,
one track (``absorb_pieces``): a piece of an established track's expected box starts no track,
a track lying inside a larger one for :data:`NEST_S` seconds ends (the older id lives on), and a
blob one established track explains is not split between smaller ones. Optional: an
appearance model in the cost (:mod:`.appearance`) and measurements *owned* by one track (a
single-object tracker's bridge, a shape hypothesis) that can never start a track.

The per-frame step is vectorised over tracks (batched Kalman maths, one Hungarian solve).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from ..config import TrackerConfig
from ..registry import Registry
from ..types import Box, Region, Track, TrackState
from . import kalman
from .appearance import bhattacharyya, histograms
from .association import (INF_COST, assign_in_stages, association_cost, center_distance_matrix,
                          intersections, iou_matrix)
from .merge import anchor_partial, fragment_matrix, split_merged

__all__ = ["TRACKERS", "MultiObjectTracker", "TrackView"]

TRACKERS: Registry["MultiObjectTracker"] = Registry("tracker")

#: consecutive partial views after which the measured (smaller) size is believed
MAX_PARTIAL_FRAMES = 8
#: running-average rate of a track's reference size
REF_RATE = 0.2
#: running-average rate of a track's appearance histogram
APPEARANCE_RATE = 0.1
#: a track with this share of its box inside a track at least 1 / NEST_AREA times larger, both
#: seen, for NEST_S seconds in a row is a piece of the larger one (:meth:`_drop_nested`)
NEST_INSIDE, NEST_AREA, NEST_S = 0.8, 0.6, 0.5
#: a track has moved once its centre is this many of its heights from where it was first seen:
#: only what has moved is held when it slows down (a flickering light or a ghost never moved)
MOVED = 0.5


def _recent_velocity(history: deque, k: int) -> np.ndarray | None:
    """Median per-frame displacement of the centre over the last ``k`` steps of ``history``
    (None with fewer than two steps)."""
    n = min(len(history), k + 1)
    if n < 3:
        return None
    pts = np.array([history[i] for i in range(len(history) - n, len(history))], np.float64)
    return np.median(np.diff(pts, axis=0), axis=0)


def tentative_tracks(tid: int, kept: Sequence[tuple]) -> list[tuple[int, Track]]:
    """The frames a track was tentative in (``(frame, box, velocity, hits, age, history,
    score)`` as kept), as ``(frame, Track)`` under the id ``tid`` it has once confirmed."""
    return [(f, Track(id=tid, box=b, state=TrackState.TENTATIVE, velocity=v, hits=n, age=a,
                      history=hist, score=sc)) for f, b, v, n, a, hist, sc in kept]


@dataclass(frozen=True)
class TrackView:
    """A named track as :meth:`MultiObjectTracker.views` shows it to other stages."""

    id: int
    state: TrackState
    time_since_update: int
    moved: bool
    bridged: bool


class _TrackState:
    __slots__ = ("tid", "state", "hits", "age", "tsu", "history", "score", "partials", "ref",
                 "origin", "moved", "bridged", "hist", "tentative", "reported", "nested")

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
        self.origin: tuple[float, float] | None = None   # centre where it was first matched
        self.moved = False                        # has travelled MOVED of its height
        self.bridged = False                      # last matched to a bridge measurement
        self.hist: np.ndarray | None = None       # appearance (colour histogram), running average
        self.tentative: list[tuple] = []  # (frame, Track fields) of each frame while tentative
        self.reported: int | None = None          # the last frame it was reported in
        self.nested = 0                           # frames in a row inside a larger track


@TRACKERS.register("kalman")
class MultiObjectTracker:
    """SORT-style tracker with an explicit tentative → confirmed → lost → deleted lifecycle."""

    def __init__(self, cfg: TrackerConfig | None = None, image_size: tuple[int, int] | None = None,
                 fps: float | None = None) -> None:
        self.cfg = cfg or TrackerConfig()
        self.image_size = image_size
        #: frames a lost track may coast (``max_lost_s`` at ``fps``; 25 fps when unknown)
        self.fps = fps or 25.0
        self.max_lost = int(round(self.cfg.max_lost_s * self.fps))
        self.x = np.zeros((0, 8))
        self.P = np.zeros((0, 3, 4))  # covariance as 2x2 blocks (see kalman)
        self.meta: list[_TrackState] = []
        self.next_id = 1
        self.frame_count = 0
        #: keep the snapshots of tentative tracks, to report them in :attr:`confirmed_earlier`
        #: once the track is confirmed (off: nothing is kept)
        self.keep_tentative = False
        #: ``(frame, snapshot)`` of the tracks confirmed in the last update, at each earlier frame
        #: where they were tentative (empty unless :attr:`keep_tentative`)
        self.confirmed_earlier: list[tuple[int, Track]] = []
        #: the pieces of a tracked object are absorbed (``absorb_pieces``), unless the pipeline
        #: says the scene's tracks are mostly vehicles: a car's silhouette does not break apart,
        #: and cars one behind the other in a lane would be taken for one car's pieces
        self.vehicles = False

    def reset(self) -> None:
        """End every track at once (after a discontinuity of the source): none is reported
        again; new tracks get new ids (:attr:`next_id` keeps counting)."""
        self.x = np.zeros((0, 8))
        self.P = np.zeros((0, 3, 4))
        self.meta = []
        self.confirmed_earlier = []

    # ------------------------------------------------------------------------------- helpers
    def _search_window(self, tsu: np.ndarray) -> np.ndarray:
        """Largest centre distance (in diagonals of the prediction) at which a track unseen for
        ``tsu`` frames may match: ``max_distance``, grown by ``search_growth`` per unseen frame."""
        return self.cfg.max_distance * (1.0 + self.cfg.search_growth * tsu)

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
               owned: Mapping[int, np.ndarray] | None = None, image: np.ndarray | None = None,
               mask: np.ndarray | None = None, scale: float = 1.0,
               located: Mapping[int, np.ndarray] | None = None,
               frame: int | None = None,
               hypotheses: Mapping[int, np.ndarray] | None = None) -> list[Track]:
        """One tracking step with this frame's detections (regions or an (M, 4) box array).

        ``dt`` is the number of frame periods since the previous update: more than 1 after a gap
        (dropped frames, a live source that reconnected), so predictions move on by the elapsed
        time and tracks age accordingly. ``owned`` maps a track id to a measurement that can only
        belong to that track (e.g. from a single-object tracker bridging a detection miss, see
        :mod:`motiontrack.tracking.bridge`); it is used only when no detection matches the track.
        ``hypotheses`` maps a track id to a box offered for it only while it is lost and owns no
        other measurement (the active shape tracker's fitted box of a person the motion detector
        lost, thesis §4.5); like owned measurements, it never starts a track. ``image`` and ``mask`` (processing scale ``scale``) feed the
        appearance model (:mod:`motiontrack.tracking.appearance`) when ``appearance_weight`` > 0.
        ``located`` maps a track id to its box found in this frame by other means (the active
        shape tracker's fitted outline): when a merged blob is split, such a track's share is
        that box cut to the blob rather than its moved prediction (see
        :func:`~motiontrack.tracking.merge.split_merged`). ``frame`` labels this update in
        :attr:`confirmed_earlier` (default: the number of earlier updates, so 0-based like the
        pipeline's frame index).

        Returns the snapshots of the tracks to report this frame: confirmed tracks matched in this
        frame (plus coasting lost tracks when ``output_lost``).
        """
        dt = max(1, int(dt))
        if isinstance(detections, np.ndarray):
            det = np.asarray(detections, np.float64).reshape(-1, 4)
            det_scores = np.ones(len(det)) if scores is None else np.asarray(scores, np.float64)
        else:
            det = np.array([r.box.as_array() for r in detections]).reshape(-1, 4)
            det_scores = np.array([r.score for r in detections], np.float64)
        self.frame_count += 1
        self.confirmed_earlier = []

        owned, located = self._by_index(owned, located, hypotheses)
        held = self.x[:, 2:4].copy()   # sizes before this step's size velocity (merged blobs)
        pred = self.predict(dt)
        before = self._fragment_hosts(pred)
        det, det_scores, owner, n_real = self._measurements(pred, det, det_scores, owned, located,
                                                            held)
        det_hist = (histograms(image, det, mask, scale)
                    if self.cfg.appearance_weight > 0 and image is not None and len(det) else None)
        matches, un_tracks, un_dets = assign_in_stages(*self._cost(pred, det, owner, n_real, det_hist))
        self._correct(matches, pred, det, det_scores, owner, n_real, det_hist)
        self._miss(un_tracks, dt)
        if self.absorbs_pieces:
            self._drop_nested()
        self._name_confirmed()
        for m in self.meta:
            m.age += dt
        # synthetic (split) and owned (bridge, hypothesis) measurements never start tracks, nor
        # does a piece of a tracked object
        new = un_dets[owner[un_dets] < 0]
        if self.absorbs_pieces and len(new) and before is not None:
            hosts, established, ref = before
            pieces = fragment_matrix(hosts, established, det[new], ref, alone=False)[0]
            new = new[~pieces.any(axis=0)]
        self._spawn(new, det, det_scores, det_hist)
        return self._snapshots(self.frame_count - 1 if frame is None else frame)

    @property
    def absorbs_pieces(self) -> bool:
        """Whether the pieces of tracked objects are absorbed this frame (see
        :attr:`vehicles`): they start no track, and a track inside a larger one ends."""
        return self.cfg.absorb_pieces and not self.vehicles

    def _fragment_hosts(self, pred: np.ndarray):
        """``(pred, established, ref)`` of the tracks whose pieces are no new track
        (:func:`~.merge.fragment_matrix`), or None when there is none."""
        if not self.absorbs_pieces or not len(self.meta):
            return None
        established = np.array([m.state != TrackState.TENTATIVE for m in self.meta], bool)
        if not established.any():
            return None
        return pred.copy(), established, np.array([m.ref for m in self.meta], np.float64)

    # ------------------------------------------------------------------------ update steps
    def _by_index(self, owned: Mapping[int, np.ndarray] | None,
                  located: Mapping[int, np.ndarray] | None,
                  hypotheses: Mapping[int, np.ndarray] | None
                  ) -> tuple[dict[int, np.ndarray] | None, dict[int, np.ndarray] | None]:
        """The owned (plus the applicable hypotheses) and located boxes keyed by track index
        instead of track id; ids of no current track are dropped."""
        if not (owned or located or hypotheses):
            return None, None
        index = {m.tid: i for i, m in enumerate(self.meta) if m.tid > 0}
        by_index = {index[tid]: box for tid, box in (owned or {}).items() if tid in index}
        for tid, box in (hypotheses or {}).items():
            i = index.get(tid)
            if i is not None and self.meta[i].tsu > 0 and i not in by_index:
                by_index[i] = box
        where = {index[tid]: box for tid, box in (located or {}).items() if tid in index}
        return by_index or None, where or None

    def _measurements(self, pred: np.ndarray, det: np.ndarray, det_scores: np.ndarray,
                      owned: dict[int, np.ndarray] | None,
                      located: dict[int, np.ndarray] | None = None,
                      held: np.ndarray | None = None):
        """This frame's measurements: merged blobs split per track, then the owned ones.

        A track's share of a merged blob gets the larger of its size before this frame's
        prediction (``held``, (N, 2)) and its reference size: a share is no measurement of size.

        Returns ``(boxes, scores, owner, n_real)``: ``owner`` is the track index a synthetic
        measurement belongs to (-1 for a detection); rows from ``n_real`` on are owned ones."""
        if self.cfg.split_merged and len(det):
            established = np.array([m.state != TrackState.TENTATIVE for m in self.meta], bool)
            ref = np.array([m.ref for m in self.meta], np.float64).reshape(-1, 2)
            own = None
            if located:
                own = np.full((len(pred), 4), np.nan)
                for t, box in located.items():
                    own[t] = box
            size = ref if held is None else np.maximum(ref, held)
            det, origin, owner = split_merged(pred, established, det, own=own, size=size, ref=ref)
            det_scores = det_scores[origin]
        else:
            owner = np.full(len(det), -1, np.int64)
        n_real = len(det)
        if owned:
            idx = np.fromiter(owned.keys(), np.int64, len(owned))
            det = np.concatenate([det, np.array([owned[i] for i in idx]).reshape(-1, 4)])
            det_scores = np.concatenate([det_scores, np.full(len(idx), 0.5)])
            owner = np.concatenate([owner, idx])
        return det, det_scores, owner, n_real

    def _cost(self, pred: np.ndarray, det: np.ndarray, owner: np.ndarray, n_real: int,
              det_hist: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """The association cost matrix, and which pairs are matched in the first stage: boxes
        that overlap (IoU cost) and split measurements, before the distance rescues and the
        owned (bridge) measurements."""
        c = self.cfg
        tsu = np.array([m.tsu for m in self.meta], np.float64)
        cost = association_cost(pred, det, c.min_iou, self._search_window(tsu), c.cost)
        # IoU costs are below 1, the centre-distance rescue of non-overlapping boxes 1 + distance
        first = cost < 1.0 if c.cost == "iou" else np.ones(cost.shape, bool)
        if det_hist is not None and len(self.meta):
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
        # a synthetic measurement belongs to the track it was made for: split measurements are
        # certain (cost 0), owned ones a fallback (cost 2, above any detection match)
        synth = np.flatnonzero(owner >= 0)
        if len(synth):
            cost[:, synth] = INF_COST
            cost[owner[synth], synth] = np.where(synth >= n_real, 2.0, 0.0)
            first[:, synth] = synth < n_real
        return cost, first

    def _correct(self, matches: np.ndarray, pred: np.ndarray, det: np.ndarray,
                 det_scores: np.ndarray, owner: np.ndarray, n_real: int,
                 det_hist: np.ndarray | None) -> None:
        """Kalman correction of the matched tracks and their bookkeeping."""
        if not len(matches):
            return
        c = self.cfg
        ti, di = matches[:, 0], matches[:, 1]
        if det_hist is not None:
            # learn appearance only from detections that overlap no other detection
            overlap = iou_matrix(det, det) > 0
            np.fill_diagonal(overlap, False)
            isolated = ~overlap.any(axis=1)
        ref = np.array([self.meta[t].ref for t in ti]).reshape(-1, 2)
        boxes, partial = anchor_partial(pred[ti], det[di], ref, c.partial_ratio)
        new_ref = ref + REF_RATE * (det[di, 2:4] - ref)
        tl, dl = ti.tolist(), di.tolist()
        part = partial.tolist()
        for k, (t, d) in enumerate(zip(tl, dl)):
            m = self.meta[t]
            m.partials = m.partials + 1 if part[k] else 0
            if m.partials > MAX_PARTIAL_FRAMES:
                # a view that stays "partial" for long is the object's real size: accept it
                boxes[k] = det[d]
                part[k] = False
            if not part[k] and owner[d] < 0:
                m.ref = new_ref[k]
                if det_hist is not None and det_hist[d].any() and isolated[d]:
                    m.hist = (det_hist[d].copy() if m.hist is None
                              else m.hist + APPEARANCE_RATE * (det_hist[d] - m.hist))
        self.x[ti], self.P[ti] = kalman.update(self.x[ti], self.P[ti], kalman.box_to_z(boxes),
                                               c.measurement_noise)
        centres = self.x[ti, :2].tolist()
        scores = det_scores[di].tolist()
        for k, (t, d) in enumerate(zip(tl, dl)):
            m = self.meta[t]
            m.hits += 1
            m.tsu = 0
            m.bridged = d >= n_real
            if not m.moved:
                cx, cy = centres[k]
                if m.origin is None:
                    m.origin = (cx, cy)
                elif math.hypot(cx - m.origin[0], cy - m.origin[1]) > MOVED * m.ref[1]:
                    m.moved = True
            m.score = scores[k]
            if m.state == TrackState.TENTATIVE and m.hits >= c.confirm_hits:
                m.state = TrackState.CONFIRMED   # named by _name_confirmed, after _miss
            elif m.state == TrackState.LOST:
                m.state = TrackState.CONFIRMED

    def _miss(self, un_tracks: np.ndarray, dt: int) -> None:
        """Unmatched tracks: tentative ones are dropped, confirmed ones coast, old ones go."""
        if not len(un_tracks):
            return
        c = self.cfg
        keep = np.ones(len(self.meta), bool)
        boxes = self._boxes()
        for t in un_tracks:
            m = self.meta[t]
            m.tsu += dt
            if m.state == TrackState.TENTATIVE:
                keep[t] = False
                continue
            if m.state == TrackState.CONFIRMED and c.coast_frames:
                # just lost: coast at the pace of its recent matches, not at the last
                # Kalman velocity (a fragment matched in the last frames before an occluder
                # tilts it, and a long coast amplifies the tilt)
                v = _recent_velocity(m.history, c.coast_frames)
                if v is not None:
                    self.x[t, 4:6] = v
            m.state = TrackState.LOST
            # coast on position only: the size keeps its reference value
            self.x[t, 2:4] = m.ref
            self.x[t, 6:8] = 0.0
            if m.tsu > self.max_lost or self._outside(boxes[t]):
                keep[t] = False
        if not keep.all():
            self._keep(keep)

    def _drop_nested(self) -> None:
        """A named track that has lain inside a larger one, seen in the same frames, for
        :data:`NEST_S` seconds is a piece of it (a person's torso tracked on its own while the
        mask broke apart): it ends, and the larger one carries on, under the older id of the
        two."""
        named = [i for i, m in enumerate(self.meta) if m.tid > 0]
        if len(named) < 2:
            for m in self.meta:
                m.nested = 0
            return
        boxes = self._boxes()[named]
        seen = np.array([self.meta[i].tsu == 0 for i in named], bool)
        area = boxes[:, 2] * boxes[:, 3]
        inter = intersections(boxes, boxes)
        np.fill_diagonal(inter, 0.0)
        host = ((inter >= NEST_INSIDE * area[:, None]) & (area[:, None] < NEST_AREA * area[None, :])
                & seen[:, None] & seen[None, :])
        limit = max(1, int(round(NEST_S * self.fps)))
        for k, i in enumerate(named):
            m = self.meta[i]
            m.nested = m.nested + 1 if host[k].any() else 0
        drop: list[int] = []
        # the smallest pieces first; a track that ends is no host of another
        for k in np.argsort(area, kind="stable").tolist():
            i = named[k]
            m = self.meta[i]
            hosts = host[k] & ~np.isin(named, drop)
            if m.nested < limit or not hosts.any():
                continue
            j = named[int(np.argmax(np.where(hosts, area, -1)))]
            if m.tid < self.meta[j].tid:        # the piece is the older track: its id lives on
                self.meta[j].tid, m.tid = m.tid, self.meta[j].tid
            drop.append(i)
        if drop:
            keep = np.ones(len(self.meta), bool)
            keep[drop] = False
            self._keep(keep)

    def _name_confirmed(self) -> None:
        """Ids for the tracks confirmed in this update: a lost track's id when one fits (the
        same person reappearing, whom a tentative track took over first), else a new one.

        A lost track fits a newly confirmed one when its appearance is within
        ``appearance_gate`` of the new track's, the new track's centre lies within the lost
        track's search window (``max_distance`` of its diagonal, grown by ``search_growth``
        per unseen frame) around its prediction, and the new track's height agrees with the
        lost one's reference height within a third (the new track's own reference still
        remembers the sliver it was born from). The closest in appearance wins; the lost track
        is then dropped and the new one continues under its id, with its trajectory and
        appearance."""
        new = [i for i, m in enumerate(self.meta) if m.state == TrackState.CONFIRMED and m.tid == 0]
        if not new:
            return
        c = self.cfg
        lost = [j for j, m in enumerate(self.meta) if m.state == TrackState.LOST]
        drop: list[int] = []
        if lost and c.appearance_weight > 0:
            boxes = self._boxes()
            # (lost, new) centre distances in diagonals of the lost tracks' predictions
            near = (center_distance_matrix(boxes[lost], boxes[new])
                    < self._search_window(np.array([self.meta[j].tsu for j in lost],
                                                   np.float64))[:, None])
            for b, i in enumerate(new):
                m = self.meta[i]
                best, best_d = -1, c.appearance_gate
                for a, j in enumerate(lost):
                    o = self.meta[j]
                    if j in drop or m.hist is None or o.hist is None or not near[a, b]:
                        continue
                    if not 0.75 <= boxes[i, 3] / max(o.ref[1], 1e-9) <= 1.33:
                        continue
                    d = float(bhattacharyya(o.hist[None], m.hist[None])[0, 0])
                    if d < best_d:
                        best, best_d = j, d
                if best >= 0:
                    o = self.meta[best]
                    m.tid = o.tid
                    # the lost track's trajectory, then the new one's (the newest kept)
                    m.history = deque([*o.history, *m.history], maxlen=m.history.maxlen)
                    m.hist, m.moved, m.origin = o.hist, o.moved or m.moved, o.origin
                    if o.reported is not None:
                        # the id is already in the frames the lost track was reported in: its
                        # successor's tentative frames are reported only after them
                        m.tentative = [e for e in m.tentative if e[0] > o.reported]
                    drop.append(best)
        for i in new:
            if self.meta[i].tid == 0:
                self.meta[i].tid = self._new_id()
        if drop:
            keep = np.ones(len(self.meta), bool)
            keep[drop] = False
            self._keep(keep)

    def _spawn(self, rows: np.ndarray, det: np.ndarray, det_scores: np.ndarray,
               det_hist: np.ndarray | None) -> None:
        """New tentative tracks (confirmed at once when ``confirm_hits`` is 1)."""
        if not len(rows):
            return
        c = self.cfg
        x0, P0 = kalman.initiate(det[rows], c.position_noise, c.velocity_noise)
        self.x = np.concatenate([self.x, x0])
        self.P = np.concatenate([self.P, P0])
        for d in rows:
            m = _TrackState(c.history, det[d, 2:4])
            m.score = float(det_scores[d])
            if det_hist is not None and det_hist[d].any():
                m.hist = det_hist[d].copy()
            if c.confirm_hits <= 1:
                m.state = TrackState.CONFIRMED
                m.tid = self._new_id()
            self.meta.append(m)

    def _new_id(self) -> int:
        tid, self.next_id = self.next_id, self.next_id + 1
        return tid
    def _outside(self, box: np.ndarray) -> bool:
        if self.image_size is None:
            return False
        w, h = self.image_size
        x, y, bw, bh = box
        return x + bw <= 0 or y + bh <= 0 or x >= w or y >= h

    def _snapshots(self, frame: int) -> list[Track]:
        out: list[Track] = []
        boxes = self._boxes().tolist()
        vel = self.x[:, 4:6].tolist()
        output_lost = self.cfg.output_lost
        for m, (x, y, w, h), (vx, vy) in zip(self.meta, boxes, vel):
            m.history.append((x + w / 2, y + h / 2))
            if m.state == TrackState.TENTATIVE:
                if self.keep_tentative:
                    # a tentative track is matched in every frame it lives (a miss deletes it)
                    m.tentative.append((frame, Box(x, y, w, h), (vx, vy), m.hits, m.age,
                                        tuple(m.history), m.score))
                continue
            if not ((m.state == TrackState.CONFIRMED and m.tsu == 0)
                    or (m.state == TrackState.LOST and output_lost)):
                continue
            if m.tentative:
                # confirmed in this frame: its tentative frames, under the id it now has
                self.confirmed_earlier.extend(tentative_tracks(m.tid, m.tentative))
                m.tentative = []
            m.reported = frame
            out.append(Track(
                id=m.tid, box=Box(x, y, w, h), state=m.state, velocity=(vx, vy), hits=m.hits,
                age=m.age, time_since_update=m.tsu, history=tuple(m.history), score=m.score,
            ))
        return out

    def views(self) -> list[TrackView]:
        """What other stages may know of every named track (ids > 0), before this frame's
        update: state, frames since its last measurement, whether it has moved and whether its
        last measurement came from a bridge."""
        return [TrackView(m.tid, m.state, m.tsu, m.moved, m.bridged)
                for m in self.meta if m.tid > 0]

    def moving_boxes(self, margin: float = 0.1, unseen: int = 2,
                     slower: float | None = None) -> np.ndarray:
        """Boxes (N, 4) where established tracks that have travelled at least :data:`MOVED` of
        their height and were seen in the last ``unseen`` frames are expected next frame
        (current box moved by one step of velocity, grown by ``margin`` of its size on each
        side); with ``slower``, only those whose speed is below that many box heights a frame.
        Used to protect them from being learnt into the background, and to keep people who stop
        in the mask."""
        keep = [i for i, m in enumerate(self.meta) if m.moved and m.state != TrackState.TENTATIVE
                and m.tsu <= unseen]
        if keep and slower is not None:
            x = self.x[keep]
            speed = np.hypot(x[:, 4], x[:, 5])
            keep = [i for i, s, h in zip(keep, speed, x[:, 3]) if s < slower * h]
        if not keep:
            return np.zeros((0, 4))
        x = self.x[keep]
        b = kalman.z_to_box(x[:, :4] + x[:, 4:8])
        grow = margin * b[:, 2:4]
        return np.column_stack([b[:, :2] - grow, b[:, 2:4] + 2 * grow])

    def named_boxes(self) -> np.ndarray:
        """(N, 4) the current boxes of the named tracks (confirmed or lost)."""
        named = [i for i, m in enumerate(self.meta) if m.tid > 0]
        return self._boxes()[named] if named else np.zeros((0, 4))

    def camera_moved(self, step: np.ndarray) -> None:
        """The camera moved between the previous frame and the next: every track's state, its
        trail and where it started are carried by ``step`` ((2, 3) similarity, previous frame's
        pixels → the next frame's, original-frame pixels), so prediction and association see the
        objects' own motion rather than the camera's (camera-motion compensation of the track
        states, as BoT-SORT's)."""
        if not len(self.meta):
            return
        lin, t = np.asarray(step[:, :2], float), np.asarray(step[:, 2], float)
        k = float(np.sqrt(abs(np.linalg.det(lin))))       # the similarity's scale
        self.x[:, 0:2] = self.x[:, 0:2] @ lin.T + t
        self.x[:, 4:6] = self.x[:, 4:6] @ lin.T
        self.x[:, 2:4] *= k
        self.x[:, 6:8] *= k
        for m in self.meta:
            if m.history:
                pts = np.asarray(m.history, float) @ lin.T + t
                m.history = deque(map(tuple, pts), maxlen=m.history.maxlen)
            if m.origin is not None:
                ox, oy = np.asarray(m.origin, float) @ lin.T + t
                m.origin = (float(ox), float(oy))

    @property
    def active_count(self) -> int:
        """Tracks currently held (any state)."""
        return len(self.meta)
