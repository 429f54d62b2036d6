"""Sparse optical-flow tracking: feature points inside moving regions, grouped into objects.

Each frame (the steps of :meth:`SparseFlowTracker.update`, each a method of its own):

1. Motion mask from a motion detector (default MOG2), cleaned with :func:`~motiontrack.motion.clean_mask`;
   its connected components ("blobs") above the region size limits.
2. Pyramidal Lucas–Kanade (Bouguet, "Pyramidal implementation of the Lucas Kanade feature
   tracker", Intel 2000; ``cv2.calcOpticalFlowPyrLK``) moves every point from the previous frame;
   a point survives only if the backward flow brings it back within ``fb_threshold`` pixels
   (forward–backward error, Kalal, Mikolajczyk & Matas, ICPR 2010) and its displacement agrees with
   its object's median displacement.
3. Points are grouped into objects by *ownership*: a point keeps the id of the object it was
   detected on. An object claims the blobs that hold enough of its points; a blob claimed by one
   object gives that object its box (the blob's bounding box, so the box covers the whole moving
   body, not just the features); a blob claimed by several objects (people crossing) is not used,
   and each of those objects moves its previous box by the median displacement of its own points,
   so identities survive the merge.
4. Blobs that hold no points and do not overlap an object start a new object; features
   (Shi & Tomasi, "Good features to track", CVPR 1994; ``cv2.goodFeaturesToTrack``) are detected
   inside the blob. Every ``redetect_every`` frames (or when an object runs short of points),
   features are re-detected inside the object's blobs, away from existing points.
5. An object without points or blob coasts on its last velocity for up to ``max_lost`` frames
   (re-acquired with the same id when a blob reappears on its predicted box), then is deleted.

Objects come out as :class:`~motiontrack.types.Track` like any tracker's; :meth:`trails` gives the
recent path of each feature point for drawing (:func:`draw_feature_trails`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, fields, replace
from typing import Any

import cv2
import numpy as np

from ..config import CleanupConfig, MotionConfig, PreprocessConfig, RegionsConfig
from ..errors import ConfigError
from ..imaging import to_gray
from ..motion import clean_mask, create_detector
from ..preprocess import preprocess
from ..types import Box, Track, TrackState

log = logging.getLogger(__name__)

__all__ = ["SparseFlowParams", "SparseFlowTracker", "forward_backward_lk"]


@dataclass(frozen=True)
class SparseFlowParams:
    """Parameters of :class:`SparseFlowTracker` (pixels are original-frame pixels).

    Attributes
    ----------
    per_object : int
        Feature points kept per object (re-detection tops up to this number).
    quality : float
        Shi–Tomasi quality level: corners weaker than ``quality`` × the strongest are rejected.
    min_distance : float
        Minimum distance between feature points, px.
    block_size : int
        Shi–Tomasi neighbourhood, px.
    win_size : int
        Lucas–Kanade window (square), px.
    levels : int
        Pyramid levels above the base image (0 = no pyramid).
    fb_threshold : float
        Forward–backward error above which a point is dropped, px.
    redetect_every : int
        Re-detect features on every object every this many frames.
    min_points : int
        Points an object needs to claim a blob or to be moved by flow.
    claim_fraction : float
        An object claims a blob holding at least this fraction of its points.
    max_lost : int
        Frames an object may coast with neither points nor blob before it is deleted.
    confirm_frames : int
        Frames an object must exist before it is reported (suppresses flicker).
    trail : int
        Positions kept per feature point for drawing trails.
    history : int
        Box centres kept per object (``Track.history``).
    """

    per_object: int = 40
    quality: float = 0.01
    min_distance: float = 4.0
    block_size: int = 5
    win_size: int = 15
    levels: int = 3
    fb_threshold: float = 1.0
    redetect_every: int = 5
    min_points: int = 3
    claim_fraction: float = 0.2
    max_lost: int = 10
    confirm_frames: int = 3
    trail: int = 12
    history: int = 64

    def __post_init__(self) -> None:
        limits = {
            "per_object": (1, 10000), "quality": (1e-6, 1.0), "min_distance": (0.0, 1000.0),
            "block_size": (2, 64), "win_size": (3, 201), "levels": (0, 10),
            "fb_threshold": (0.0, 1000.0), "redetect_every": (1, 100000), "min_points": (1, 10000),
            "claim_fraction": (0.0, 1.0), "max_lost": (0, 100000), "confirm_frames": (1, 1000),
            "trail": (0, 10000), "history": (0, 100000),
        }
        for f in fields(self):
            v = getattr(self, f.name)
            lo, hi = limits[f.name]
            if not lo <= v <= hi:
                raise ConfigError(f"sparse flow {f.name} must be in [{lo}, {hi}], got {v}")


def forward_backward_lk(prev: np.ndarray, cur: np.ndarray, pts: np.ndarray, win_size: int = 15,
                        levels: int = 3, fb_threshold: float = 1.0
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Track points from ``prev`` to ``cur`` with pyramidal Lucas–Kanade and check them backwards.

    Parameters
    ----------
    prev, cur : (H, W) uint8 gray images.
    pts : (P, 2) float points ``(x, y)`` in ``prev``, pixels.
    win_size, levels : LK window (px) and pyramid levels.
    fb_threshold : maximum forward–backward error, px (Kalal et al., ICPR 2010).

    Returns
    -------
    new_pts : (P, 2) float32 positions in ``cur`` (meaningless where ``good`` is False).
    good : (P,) bool, tracked both ways with FB error ≤ ``fb_threshold`` and inside the image.
    fb_error : (P,) float64 ``‖p − LK_back(LK_fwd(p))‖``, px (inf where tracking failed).
    """
    p0 = np.asarray(pts, np.float32).reshape(-1, 1, 2)
    n = len(p0)
    if n == 0:
        return np.zeros((0, 2), np.float32), np.zeros(0, bool), np.zeros(0)
    lk = dict(winSize=(int(win_size), int(win_size)), maxLevel=int(levels),
              criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01))
    p1, st1, _ = cv2.calcOpticalFlowPyrLK(prev, cur, p0, None, **lk)
    p0b, st2, _ = cv2.calcOpticalFlowPyrLK(cur, prev, p1, None, **lk)
    err = np.linalg.norm((p0 - p0b).reshape(-1, 2), axis=1).astype(np.float64)
    ok = (st1.reshape(-1) == 1) & (st2.reshape(-1) == 1)
    err[~ok] = np.inf
    new = p1.reshape(-1, 2)
    h, w = cur.shape[:2]
    inside = (new[:, 0] >= 0) & (new[:, 1] >= 0) & (new[:, 0] <= w - 1) & (new[:, 1] <= h - 1)
    good = ok & inside & (err <= fb_threshold)
    return new, good, err


@dataclass
class _Object:
    id: int
    box: np.ndarray  # (4,) x, y, w, h
    age: int = 1
    hits: int = 1
    missed: int = 0
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(2))
    history: list = field(default_factory=list)
    measured: bool = True


def _median_motion(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Median displacement ``(2,)`` float64 of one object's points ``d`` ``(n, 2)``, and which of
    them move unlike it: ``(n,)`` bool, off the median by more than 2 px and than its length."""
    d = d.astype(np.float64)
    m = np.median(d, axis=0)
    dev = np.linalg.norm(d - m, axis=1)
    return m, dev > max(2.0, float(np.linalg.norm(m)))


def _union_box(stats: np.ndarray) -> np.ndarray:
    """Union of component boxes ``(K, >=4)`` x, y, w, h → (4,)."""
    x1 = stats[:, 0].min()
    y1 = stats[:, 1].min()
    x2 = (stats[:, 0] + stats[:, 2]).max()
    y2 = (stats[:, 1] + stats[:, 3]).max()
    return np.array([x1, y1, x2 - x1, y2 - y1], np.float64)


def _overlap_fraction(a: np.ndarray, b: np.ndarray) -> float:
    """Area of ``a ∩ b`` divided by the area of ``a`` (boxes x, y, w, h)."""
    ix = min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0])
    iy = min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1])
    if ix <= 0 or iy <= 0 or a[2] * a[3] <= 0:
        return 0.0
    return float(ix * iy / (a[2] * a[3]))


class SparseFlowTracker:
    """Multi-object tracking by sparse optical flow (see the module docstring for the steps).

    Parameters
    ----------
    image_size : (width, height) of the frames, px.
    params : SparseFlowParams
    motion : MotionConfig selecting the motion detector (default MOG2).
    cleanup, regions, preprocess : the usual stage configs (blob size limits come from
        ``regions.min_area``/``max_area``/``min_size``/``max_size``).
    detector : an already created motion detector (overrides ``motion``).
    """

    def __init__(self, image_size: tuple[int, int], params: SparseFlowParams | None = None,
                 motion: MotionConfig | None = None, cleanup: CleanupConfig | None = None,
                 regions: RegionsConfig | None = None, preprocess: PreprocessConfig | None = None,
                 detector: Any = None) -> None:
        self.width, self.height = int(image_size[0]), int(image_size[1])
        if self.width <= 0 or self.height <= 0:
            raise ConfigError(f"image size must be positive, got {image_size}")
        self.p = params or SparseFlowParams()
        self.motion = motion or MotionConfig()
        self.detector = detector if detector is not None else create_detector(self.motion)
        self.cleanup = cleanup or CleanupConfig()
        self.regions = regions or RegionsConfig()
        self.pre = preprocess
        if self.pre is not None and getattr(self.detector, "wants_color", False) and self.pre.grayscale:
            self.pre = replace(self.pre, grayscale=False)
        area = float(self.width * self.height)
        r = self.regions
        self._min_area = max(r.min_area, r.min_size * area, 1.0)
        limits = [v for v in (r.max_area, r.max_size * area) if v > 0]
        self._max_area = min(limits) if limits else np.inf
        self._prev: np.ndarray | None = None
        self.pts = np.zeros((0, 2), np.float32)
        self.owner = np.zeros(0, np.int64)
        self._trail = np.zeros((0, max(1, self.p.trail), 2), np.float32)
        self._trail_len = np.zeros(0, np.int64)
        self.objects: dict[int, _Object] = {}
        self._next_id = 1
        self.frames_seen = 0
        #: cleaned motion mask of the last frame, (H, W) uint8 0/255 at original resolution
        self.last_mask: np.ndarray | None = None

    # ------------------------------------------------------------------------------ helpers
    def _motion_mask(self, image: np.ndarray) -> np.ndarray:
        small = preprocess(image, self.pre) if self.pre is not None else image
        mask = clean_mask(self.detector.apply(small), self.cleanup)
        if mask.shape[:2] != (self.height, self.width):
            mask = cv2.resize(mask, (self.width, self.height), interpolation=cv2.INTER_NEAREST)
        if self.frames_seen < self.motion.warmup:
            mask = np.zeros_like(mask)
        return mask

    def _blobs(self, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Labels (H, W) int32 with small/huge blobs set to 0, and stats (K+1, 5)."""
        n, labels, stats, _ = cv2.connectedComponentsWithStats(
            mask, connectivity=self.regions.connectivity, ltype=cv2.CV_32S)
        area = stats[:, cv2.CC_STAT_AREA].astype(np.float64)
        keep = (area >= self._min_area) & (area <= self._max_area)
        keep[0] = False
        if not keep[1:].all():
            lut = np.where(keep, np.arange(n), 0).astype(np.int32)
            labels = lut[labels]
        return labels, stats

    def _detect(self, gray: np.ndarray, region_mask: np.ndarray, box: np.ndarray,
                n_max: int) -> np.ndarray:
        """Shi–Tomasi corners inside ``region_mask`` within ``box``, away from current points."""
        if n_max <= 0:
            return np.zeros((0, 2), np.float32)
        x1 = int(max(0, np.floor(box[0])))
        y1 = int(max(0, np.floor(box[1])))
        x2 = int(min(self.width, np.ceil(box[0] + box[2])))
        y2 = int(min(self.height, np.ceil(box[1] + box[3])))
        if x2 - x1 < 3 or y2 - y1 < 3:
            return np.zeros((0, 2), np.float32)
        m = region_mask[y1:y2, x1:x2].copy()
        if len(self.pts):
            r = max(1, int(round(self.p.min_distance)))
            near = self.pts[(self.pts[:, 0] >= x1 - r) & (self.pts[:, 0] < x2 + r)
                            & (self.pts[:, 1] >= y1 - r) & (self.pts[:, 1] < y2 + r)]
            for x, y in near:
                cv2.circle(m, (int(round(x)) - x1, int(round(y)) - y1), r, 0, -1)
        if not m.any():
            return np.zeros((0, 2), np.float32)
        c = cv2.goodFeaturesToTrack(gray[y1:y2, x1:x2], maxCorners=int(n_max),
                                    qualityLevel=self.p.quality, minDistance=self.p.min_distance,
                                    mask=m, blockSize=self.p.block_size)
        if c is None:
            return np.zeros((0, 2), np.float32)
        return (c.reshape(-1, 2) + np.array([x1, y1], np.float32)).astype(np.float32)

    def _add_points(self, pts: np.ndarray, owner: int) -> None:
        if len(pts) == 0:
            return
        k = self._trail.shape[1]
        trail = np.zeros((len(pts), k, 2), np.float32)
        trail[:, -1] = pts
        self.pts = np.concatenate([self.pts, pts.astype(np.float32)])
        self.owner = np.concatenate([self.owner, np.full(len(pts), owner, np.int64)])
        self._trail = np.concatenate([self._trail, trail])
        self._trail_len = np.concatenate([self._trail_len, np.ones(len(pts), np.int64)])

    def _keep_points(self, keep: np.ndarray) -> None:
        self.pts = self.pts[keep]
        self.owner = self.owner[keep]
        self._trail = self._trail[keep]
        self._trail_len = self._trail_len[keep]

    def _clip(self, box: np.ndarray) -> np.ndarray | None:
        x1, y1 = max(0.0, box[0]), max(0.0, box[1])
        x2, y2 = min(float(self.width), box[0] + box[2]), min(float(self.height), box[1] + box[3])
        if x2 - x1 < 1 or y2 - y1 < 1:
            return None
        return np.array([x1, y1, x2 - x1, y2 - y1])

    # ------------------------------------------------------------------------------ update
    def update(self, image: np.ndarray) -> list[Track]:
        """Process one frame ``(H, W, 3)`` or ``(H, W)`` uint8 and return the reported tracks
        (steps 1–5 of the module docstring)."""
        if image.shape[:2] != (self.height, self.width):
            raise ConfigError(f"frame size {image.shape[1]}x{image.shape[0]} differs from the "
                              f"tracker's {self.width}x{self.height}")
        gray = to_gray(image)
        labels, stats = self._motion_blobs(image)
        disp = self._move_points(gray)
        claims, med = self._group_points(labels, disp)
        owned = self._move_objects(claims, med, stats)
        self._take_unclaimed_blobs(gray, labels, stats, claims, owned)
        self._redetect(gray, labels, owned)
        self._drop_stray_points()
        out = self._lifecycle()
        self.frames_seen += 1
        return out

    # ------------------------------------------------------------------------ steps of update
    def _motion_blobs(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Step 1: the cleaned motion mask (kept as :attr:`last_mask`) and its blobs within the
        region size limits: labels ``(H, W) int32`` (0 = none) and stats ``(K+1, 5)``."""
        mask = self._motion_mask(image)
        self.last_mask = mask
        return self._blobs(mask)

    def _move_points(self, gray: np.ndarray) -> np.ndarray:
        """Step 2: move every point with forward-backward checked pyramidal LK from the previous
        frame, dropping those that fail; their trails move on. Returns the displacements
        ``(P, 2) float32`` of the surviving points."""
        p = self.p
        disp = np.zeros((len(self.pts), 2), np.float32)
        if self._prev is not None and len(self.pts):
            new, good, _ = forward_backward_lk(self._prev, gray, self.pts, p.win_size, p.levels,
                                               p.fb_threshold)
            disp = new - self.pts
            self.pts = np.where(good[:, None], new, self.pts)
            self._keep_points(good)
            disp = disp[good]
            self._trail[:, :-1] = self._trail[:, 1:]
            self._trail[:, -1] = self.pts
            self._trail_len = np.minimum(self._trail_len + 1, self._trail.shape[1])
        self._prev = gray
        return disp

    def _group_points(self, labels: np.ndarray, disp: np.ndarray
                      ) -> tuple[dict[int, list[int]], dict[int, np.ndarray]]:
        """Step 3, grouping: per object, the median displacement of its points; points moving
        unlike it are dropped (background caught at the silhouette's edge); an object with at
        least ``min_points`` points claims each blob holding ``claim_fraction`` of them.

        Returns ``claims`` (blob label → claiming object ids) and ``med`` (object id → median
        displacement ``(2,)``, px).
        """
        p = self.p
        lab = labels[np.clip(np.round(self.pts[:, 1]).astype(int), 0, self.height - 1),
                     np.clip(np.round(self.pts[:, 0]).astype(int), 0, self.width - 1)]
        keep = np.ones(len(self.pts), bool)
        claims: dict[int, list[int]] = {}
        med: dict[int, np.ndarray] = {}
        for oid in self.objects:
            idx = np.flatnonzero(self.owner == oid)
            if len(idx) == 0:
                continue
            med[oid], bad = _median_motion(disp[idx])
            keep[idx[bad]] = False
            idx = idx[~bad]
            if len(idx) < p.min_points:
                continue
            labs, counts = np.unique(lab[idx], return_counts=True)
            need = max(p.min_points, p.claim_fraction * len(idx))
            for lb, c in zip(labs, counts):
                if lb > 0 and c >= need:
                    claims.setdefault(int(lb), []).append(oid)
        self._keep_points(keep)
        return claims, med

    def _move_objects(self, claims: dict[int, list[int]], med: dict[int, np.ndarray],
                      stats: np.ndarray) -> dict[int, list[int]]:
        """Step 3, boxes: an object owning blobs (claimed by it alone) takes their union box; one
        sharing its blob (crossing) or without a blob moves by its points' median displacement
        when it has ``min_points`` of them; any other coasts on its velocity, unmeasured.

        Returns ``owned``: object id → labels of the blobs it owns.
        """
        owned: dict[int, list[int]] = {}
        for lb, oids in claims.items():
            if len(oids) == 1:
                owned.setdefault(oids[0], []).append(lb)
        for oid, obj in self.objects.items():
            n_pts = int((self.owner == oid).sum())
            obj.age += 1
            if oid in owned:
                new_box = _union_box(stats[owned[oid]])
                obj.velocity = (new_box[:2] + new_box[2:] / 2) - (obj.box[:2] + obj.box[2:] / 2)
                obj.box = new_box
                obj.measured = True
            elif oid in med and n_pts >= self.p.min_points:
                # shared blob (crossing) or no blob: move with the object's own points
                obj.velocity = med[oid]
                obj.box = obj.box + np.r_[med[oid], 0.0, 0.0]
                obj.measured = True
            else:
                obj.box = obj.box + np.r_[obj.velocity, 0.0, 0.0]
                obj.measured = False
        return owned

    def _take_unclaimed_blobs(self, gray: np.ndarray, labels: np.ndarray, stats: np.ndarray,
                              claims: dict[int, list[int]], owned: dict[int, list[int]]) -> None:
        """Step 4: each blob no object claimed starts a new object with fresh features when it
        overlaps none, is part of a coasting or fragmented object when that object covers at
        least half of it (:meth:`_join_blob`), and is left alone when it only touches one.
        ``owned`` gains the blobs taken."""
        present = np.zeros(len(stats), bool)
        present[np.unique(labels)] = True
        present[0] = False
        for lb in np.flatnonzero(present):
            lb = int(lb)
            if lb in claims:
                continue
            bbox = stats[lb, :4].astype(np.float64)
            best, best_ov = None, 0.0
            for oid, obj in self.objects.items():
                ov = _overlap_fraction(bbox, obj.box)
                if ov > best_ov:
                    best, best_ov = oid, ov
            if best is None:
                self._start_object(gray, labels, lb, bbox, owned)
            elif best_ov >= 0.5:
                self._join_blob(best, lb, bbox, claims, owned)
            # otherwise it only touches an object: wait until it separates or is claimed

    def _join_blob(self, oid: int, lb: int, bbox: np.ndarray, claims: dict[int, list[int]],
                   owned: dict[int, list[int]]) -> None:
        """Blob ``lb`` (box ``bbox``) joins object ``oid`` unless that object shares a blob with
        another: a measured owner grows its box over it, an unmeasured object is re-acquired with
        the blob's box."""
        obj = self.objects[oid]
        shared = any(oid in oids and len(oids) > 1 for oids in claims.values())
        if shared:
            return
        if obj.measured and oid in owned:
            obj.box = _union_box(np.vstack([obj.box, bbox]))
        elif not obj.measured:
            obj.box = bbox  # re-acquired
            obj.measured = True
        owned.setdefault(oid, []).append(lb)

    def _start_object(self, gray: np.ndarray, labels: np.ndarray, lb: int, bbox: np.ndarray,
                      owned: dict[int, list[int]]) -> None:
        """A new object on blob ``lb`` with up to ``per_object`` Shi–Tomasi features inside it."""
        oid = self._next_id
        self._next_id += 1
        self.objects[oid] = _Object(id=oid, box=bbox)
        owned[oid] = [lb]
        self._add_points(self._detect(gray, np.where(labels == lb, 255, 0).astype(np.uint8),
                                      bbox, self.p.per_object), oid)

    def _redetect(self, gray: np.ndarray, labels: np.ndarray, owned: dict[int, list[int]]) -> None:
        """Step 4b: every ``redetect_every`` frames of an object's age, or when it holds fewer
        than half of ``per_object`` points, top its points up with features inside its own
        blobs."""
        p = self.p
        for oid, obj in self.objects.items():
            if oid not in owned:
                continue
            n_pts = int((self.owner == oid).sum())
            if obj.age % p.redetect_every != 0 and n_pts >= p.per_object // 2:
                continue
            blob = np.isin(labels, owned[oid]).astype(np.uint8) * 255
            self._add_points(self._detect(gray, blob, obj.box, p.per_object - n_pts), oid)

    def _drop_stray_points(self) -> None:
        """Drop points more than 10 % of the box size outside their object's box (static
        background points the object walked away from)."""
        if not len(self.pts):
            return
        keep = np.ones(len(self.pts), bool)
        for oid, obj in self.objects.items():
            idx = np.flatnonzero(self.owner == oid)
            if len(idx) == 0:
                continue
            b = obj.box
            mx, my = 0.1 * b[2], 0.1 * b[3]
            x, y = self.pts[idx, 0], self.pts[idx, 1]
            keep[idx] = ((x >= b[0] - mx) & (x <= b[0] + b[2] + mx)
                         & (y >= b[1] - my) & (y <= b[1] + b[3] + my))
        self._keep_points(keep)

    def _lifecycle(self) -> list[Track]:
        """Step 5: count hits and misses; delete an object missed more than ``max_lost`` frames
        or out of the image (with its points); clip the others' boxes to the image, extend their
        history and report the measured ones at least ``confirm_frames`` old."""
        p = self.p
        out: list[Track] = []
        for oid in list(self.objects):
            obj = self.objects[oid]
            if obj.measured:
                obj.hits += 1
                obj.missed = 0
            else:
                obj.missed += 1
            clipped = self._clip(obj.box)
            if obj.missed > p.max_lost or clipped is None:
                del self.objects[oid]
                self._keep_points(self.owner != oid)
                continue
            obj.box = clipped
            cx, cy = clipped[0] + clipped[2] / 2, clipped[1] + clipped[3] / 2
            if p.history:
                obj.history.append((float(cx), float(cy)))
                del obj.history[:-p.history]
            if obj.age < p.confirm_frames or not obj.measured:
                continue
            out.append(self._track(obj))
        return out

    def _track(self, obj: _Object) -> Track:
        """The reported :class:`Track` of ``obj``; its score is its share of ``per_object`` points."""
        p = self.p
        n_pts = int((self.owner == obj.id).sum())
        return Track(
            id=obj.id, box=Box(*(float(v) for v in obj.box)), state=TrackState.CONFIRMED,
            velocity=(float(obj.velocity[0]), float(obj.velocity[1])), hits=obj.hits,
            age=obj.age, time_since_update=obj.missed, history=tuple(obj.history),
            score=float(min(1.0, n_pts / p.per_object)),
        )

    def trails(self) -> list[tuple[int, np.ndarray]]:
        """Recent positions of every feature point: ``[(object id, (k, 2) float32), ...]``,
        oldest first (``k`` ≤ ``params.trail``)."""
        k = self._trail.shape[1]
        return [(int(o), self._trail[i, k - int(n):]) for i, (o, n)
                in enumerate(zip(self.owner, self._trail_len))]
