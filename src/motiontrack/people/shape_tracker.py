"""Active shape tracker (Baumberg & Hogg 1995; Siebel's thesis, section 2.3 / 4.4).

Each tracked person carries an outline from the point-distribution model (:mod:`.shape_model`):
a pose ``(a, b, tx, ty)`` (similarity transform, model frame → work image) and shape weights
``b``. Per frame, for every person:

1. **Predict** the pose with a constant-velocity, Kalman-style (alpha-beta, i.e. steady-state
   Kalman gain) filter on the position ``tx, ty`` and a random walk on ``a, b`` (scale/rotation).
2. **Measure**: place ``K`` sample points on the predicted spline; along the outward normal at
   each, search ``±L`` px of the *difference image* edge map — the Sobel gradient magnitude of
   ``|frame − background|`` (largest colour channel) — for the strongest edge above
   ``edge_threshold`` (thesis section 2.3.4; Cootes et al. 1995 section 5 use the same normal
   search).
3. **Solve** (Cootes et al. 1995, section 5.2): weighted least-squares similarity from the model
   outline to the found edge points; map the found points back into the model frame, fit control
   points (pseudo-inverse of the sampling matrix), project onto the modes and **constrain** the
   weights to ``D_m <= D_max``; repeat ``iterations`` times.
4. **Correct** the filter with the fitted pose when enough sample points found an edge
   (``min_support``); otherwise the person coasts on the prediction (occlusion) for at most
   ``max_coast`` frames.

Initialisation places the mean shape in a region-tracker box (height from the box, horizontal
position from a head when one is given). Work happens at the background's resolution; outlines
and boxes are returned in original-frame pixels.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from ..imaging import to_gray
from ..types import Box
from .shape_batch import (FitInput, Outlines, dense_boxes, fit_people, limit_tilt, search_edges,
                          window_gradients)
from .shape_model import ShapeModel

log = logging.getLogger(__name__)

__all__ = ["ShapeTrackerParams", "FittedShape", "ShapeTracker", "edge_image", "difference_gradients",
           "search_normals"]


@dataclass(frozen=True)
class ShapeTrackerParams:
    """Parameters of :class:`ShapeTracker`.

    Attributes
    ----------
    samples : int
        Sample points ``K`` along the outline.
    search : float
        Normal search half-length ``L`` as a fraction of the outline's height.
    min_search : float
        Lower bound of ``L`` in work pixels.
    edge_threshold : float
        Weakest Sobel magnitude (grey levels per pixel, ``ksize=3`` Sobel / 4) counted as an edge.
    iterations : int
        Measure/solve rounds per frame.
    min_support : float
        Fraction of sample points that must find an edge for the fit to count as a measurement.
    alpha, beta : float
        Filter gains for position (alpha) and velocity (beta) (alpha-beta filter = steady-state
        constant-velocity Kalman filter; Kalata 1984).
    max_coast : int
        Frames a shape may go without a measurement before it is dropped.
    max_rotation : float
        Largest allowed tilt of the outline, degrees (people stand upright).
    max_scale_change : float
        Largest relative change of the outline's scale per frame (a partly occluded person must
        not make the outline collapse).
    velocity_support : float
        The velocity is only corrected by fits with at least this support whose predicted outline
        is at least this visible in the motion mask (a partly occluded person's fit lags behind
        and would stall the prediction).
    reinit_iou : float
        A measured track whose box overlaps its shape's box less than this re-initialises it,
        when the shape has been coasting for at least ``reinit_coast`` frames.
    reinit_coast : int
        See ``reinit_iou``.
    reinit_frames : int
        A shape that disagrees with its measured track (IoU < ``reinit_iou``) this many frames in a
        row is re-initialised even while it finds edges (it follows something else).
    min_visible : float
        A person whose predicted outline is less visible than this coasts on the prediction.
    occlusion_margin : float
        Another person occludes only if their foot point is lower by more than this fraction of
        the height.
    duplicate_iou : float
        A new track whose box overlaps another person's outline box at least this much gets no
        shape (it is most likely a duplicate of that person).
    """

    samples: int = 48
    search: float = 0.12
    min_search: float = 3.0
    edge_threshold: float = 8.0
    iterations: int = 2
    min_support: float = 0.35
    alpha: float = 0.6
    beta: float = 0.2
    max_coast: int = 25
    max_rotation: float = 10.0
    max_scale_change: float = 0.02
    velocity_support: float = 0.7
    reinit_iou: float = 0.3
    reinit_coast: int = 2
    reinit_frames: int = 3
    duplicate_iou: float = 0.5
    min_visible: float = 0.5
    occlusion_margin: float = 0.02

    def __post_init__(self) -> None:
        if self.samples < 8 or self.iterations < 1:
            raise ValueError(f"samples must be >= 8 and iterations >= 1, got {self.samples}, "
                             f"{self.iterations}")
        for name in ("alpha", "beta", "min_support", "reinit_iou", "velocity_support"):
            v = getattr(self, name)
            if not 0 <= v <= 1:
                raise ValueError(f"{name} must be in [0, 1], got {v}")
        if self.search < 0 or self.min_search < 0 or self.max_coast < 0:
            raise ValueError("search, min_search and max_coast must be >= 0")


@dataclass(frozen=True)
class FittedShape:
    """One person's fitted outline this frame (original-frame pixels).

    Attributes
    ----------
    track_id : int
    outline : (K, 2) float64
        Points along the spline.
    control : (N, 2) float64
        Control points.
    box : Box
        Bounding box of the outline.
    support : float
        Fraction of sample points that found an edge (0 while coasting unseen).
    coasting : int
        Frames since the last good measurement.
    normals : (K, 2) float64
        Unit outward normals at the outline points (for drawing the search lines).
    search : float
        Search half-length in original pixels.
    unseen : int
        Frames since the region tracker last reported this track (0 = reported in ``tracks``).
    visible : float
        Fraction of the predicted outline's sample points that were visible this frame (inside
        the motion mask and not behind a nearer tracked person).
    agreement : float
        IoU of the outline's box with the region tracker's box the last time the track was
        measured (-1 before that): a shape that agreed with its track is a credible hypothesis.
    """

    track_id: int
    outline: np.ndarray = field(repr=False)
    control: np.ndarray = field(repr=False)
    box: Box
    support: float
    coasting: int
    normals: np.ndarray = field(repr=False)
    search: float = 0.0
    unseen: int = 0
    visible: float = 1.0
    agreement: float = -1.0

    def __iter__(self):
        """Unpack as ``(track_id, outline, box)``."""
        return iter((self.track_id, self.outline, self.box))


def edge_image(frame: np.ndarray, background: np.ndarray) -> np.ndarray:
    """Sobel gradient magnitude of the difference image ``|frame − background|``.

    Parameters
    ----------
    frame, background : (h, w[, 3]) uint8
        Same shape.

    Returns
    -------
    (h, w) float32
        ``(|Gx| + |Gy|) / 4`` of the largest-channel absolute difference (3×3 Sobel; the division
        makes a step of ``g`` grey levels give ``g / 2`` per pixel-ish, keeping thresholds in grey
        levels).
    """
    gx, gy = _gradients(difference_image(frame, background), 1.0)
    return (np.abs(gx) + np.abs(gy)) * 0.25


def difference_gradients(frame: np.ndarray, background: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sobel derivatives ``(gx, gy)`` of the difference image ``|frame − background|``.

    Returns two ``(h, w) float32`` arrays scaled by 1/4 (so a step of ``g`` grey levels gives
    about ``g / 2``, keeping thresholds in grey levels).
    """
    return _gradients(difference_image(frame, background))


def difference_image(frame: np.ndarray, background: np.ndarray) -> np.ndarray:
    """``|frame − background|``, the largest channel's for colour images: ``(h, w)``, the
    inputs' type.

    Pointwise, so a crop of it equals it computed on the crops: the shape tracker makes it once
    per frame. (The channel maximum is OpenCV's: numpy's maximum over a 3-long last axis takes
    about 30 times as long.)
    """
    d = cv2.absdiff(frame, background)
    if d.ndim == 3:
        channels = cv2.split(d)
        d = channels[0]
        for c in channels[1:]:
            d = cv2.max(d, c)
    return d


def _gradients(d: np.ndarray, scale: float = 0.25) -> tuple[np.ndarray, np.ndarray]:
    """3×3 Sobel derivatives ``(gx, gy)`` of a single-channel image times ``scale``, float32
    (from uint8 directly: integer sums and a power-of-two scale are exact either way)."""
    if d.dtype != np.uint8:
        d = d.astype(np.float32)
    return (cv2.Sobel(d, cv2.CV_32F, 1, 0, ksize=3, scale=scale),
            cv2.Sobel(d, cv2.CV_32F, 0, 1, ksize=3, scale=scale))


def search_normals(edges, points: np.ndarray, normals: np.ndarray, half: float,
                   threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """Strongest edge along each normal.

    Parameters
    ----------
    edges : (h, w) float, or tuple (gx, gy) of (h, w) float
        Edge magnitude image, or the difference image's derivatives: then only edges where the
        difference *drops* going outwards count (silhouette polarity: person inside, background
        outside), with strength ``-(g · n)``.
    points, normals : (K, 2) float
        Sample points (x, y) and unit normals, in ``edges`` pixels.
    half : float
        Search ``[-half, +half]`` px along the normal in 1-px steps.
    threshold : float
        Edges weaker than this do not count.

    Returns
    -------
    offsets : (K,) float64
        Signed distance along the normal of the strongest edge (0 when none).
    strength : (K,) float64
        Its magnitude (0 when below threshold or outside the image).
    """
    p = np.asarray(points, np.float64).reshape(-1, 2)
    nrm = np.asarray(normals, np.float64).reshape(-1, 2)
    if len(p) == 0:
        return np.zeros(0), np.zeros(0)
    image = np.dstack(edges) if isinstance(edges, tuple) else np.asarray(edges)
    if image.dtype not in _REMAP_TYPES:
        image = image.astype(np.float64)
    off, strength = search_edges([FitInput(image, None, np.zeros(2))], 1.0, p[None], nrm[None],
                                 np.array([int(np.ceil(half))]), threshold)
    return off[0], strength[0]


#: image types :func:`cv2.remap` reads
_REMAP_TYPES = (np.dtype(np.uint8), np.dtype(np.uint16), np.dtype(np.int16),
                np.dtype(np.float32), np.dtype(np.float64))


class _Person:
    """Mutable per-track state: pose, pose velocity, shape weights, coast counter."""

    def __init__(self, pose: np.ndarray, b: np.ndarray) -> None:
        self.pose = pose.astype(np.float64)
        self.vel = np.zeros(4)
        self.b = b.astype(np.float64)
        self.coast = 0
        self.support = 0.0
        self.unseen = 0  # frames since the region tracker last reported the track
        self.agreement = -1.0  # IoU with the track's box when last measured (-1: not yet)
        self.disagree = 0  # consecutive measured frames with agreement < reinit_iou


class ShapeTracker:
    """Active shape tracker for the people the region tracker follows.

    Parameters
    ----------
    model : ShapeModel
        Point-distribution model (e.g. :func:`~.shape_model.load_default_model`).
    params : ShapeTrackerParams, optional
    """

    def __init__(self, model: ShapeModel, params: ShapeTrackerParams | None = None) -> None:
        self.model = model
        self.params = params or ShapeTrackerParams()
        self._outlines = Outlines(model, self.params.samples)
        self._max_tilt = float(np.deg2rad(self.params.max_rotation))
        dense = self._outlines.Bbox @ model.shape()
        self._mean_top = dense[np.argmin(dense[:, 1])]
        self._mean_lo = dense.min(axis=0)
        self._mean_hi = dense.max(axis=0)
        self.people: dict[int, _Person] = {}

    # ------------------------------------------------------------------ helpers
    def _init_pose(self, box: np.ndarray, head_x: float | None) -> np.ndarray:
        """Pose placing the mean shape's bounding box on ``box`` (work px, x y w h)."""
        x, y, w, h = box
        s = h / max(self._mean_hi[1] - self._mean_lo[1], 1e-9)
        cx_m = (self._mean_lo[0] + self._mean_hi[0]) / 2
        tx = x + w / 2 - s * cx_m if head_x is None else head_x - s * self._mean_top[0]
        ty = y - s * self._mean_lo[1]
        return np.array([s, 0.0, tx, ty])

    def _boxes(self, ids) -> dict[int, np.ndarray]:
        """Outline boxes ``(x, y, w, h)`` (work px) of the people ``ids``."""
        ids = list(ids)
        if not ids:
            return {}
        people = [self.people[t] for t in ids]
        boxes = self._outlines.boxes(np.array([q.pose for q in people]),
                                     np.array([q.b for q in people]).reshape(len(ids), -1))
        return dict(zip(ids, boxes))

    # ------------------------------------------------------------------ public
    def reset(self) -> None:
        self.people.clear()

    def update(self, frame: np.ndarray, background: np.ndarray | None, regions, tracks,
               heads=None, mask: np.ndarray | None = None, work: np.ndarray | None = None
               ) -> list[FittedShape]:
        """Track the outlines of ``tracks`` in ``frame``.

        Parameters
        ----------
        frame : (H, W[, 3]) uint8
            Current frame at original resolution.
        background : (h, w[, 3]) uint8 or None
            Background estimate (any resolution with the frame's aspect ratio; work happens at
            this resolution). ``None``: the edges of ``mask`` are used instead.
        regions : sequence of Region
            This frame's motion regions (original pixels); kept for API symmetry — the fit is
            driven by the edge image, the region tracker's boxes initialise it.
        tracks : sequence of Track
            The region tracker's current tracks (original pixels); new track ids get a shape,
            ``time_since_update == 0`` tracks may re-initialise a drifted shape.
        heads : sequence of Head, optional
            Head positions (original pixels) used to place new shapes horizontally.
        mask : (h, w) uint8, optional
            Motion mask, used when ``background`` is None.
        work : (h, w[, 3]) uint8, optional
            The frame exactly as the background model saw it (the pipeline's preprocessed image).
            Strongly recommended: without it a frame larger than the background is resized
            (area) and Gaussian-blurred (5×5, the default preprocessing), a frame of the same size
            is used as it is, and any other preprocessing difference shows up as spurious edges
            (e.g. along static scene edges).

        Returns
        -------
        list of FittedShape
            One per tracked person kept this frame (iterable as ``(track_id, outline (K, 2),
            box)``), in fitting order: nearest the camera (lowest foot point) first.
        """
        view = _work_view(frame, background, mask, work)
        self._predict()
        boxes = self._adopt_tracks(tracks, heads, view)
        return self._measure_people(view, boxes)

    # ------------------------------------------------------------------ the steps of update
    def _predict(self) -> None:
        """Step 1: every person's pose moves on by its velocity (scale and rotation have none),
        its tilt limited, and counts one more frame unseen by the region tracker
        (:meth:`_adopt_tracks` resets that when the person's track is reported)."""
        people = list(self.people.values())
        if not people:
            return
        poses = limit_tilt(np.array([q.pose for q in people]) + np.array([q.vel for q in people]),
                           self._max_tilt)
        for person, pose in zip(people, poses):
            person.pose = pose
            person.unseen += 1

    def _adopt_tracks(self, tracks, heads, view: _WorkView) -> dict[int, np.ndarray]:
        """Births and re-initialisation from the region tracker's ``tracks``.

        A new track gets the mean shape in its box, unless its box overlaps another person's
        outline box by ``duplicate_iou`` (most likely a duplicate of that person). A track
        measured this frame (``time_since_update == 0``) updates its shape's agreement; a shape
        that has drifted away from it is placed anew (:meth:`_drifted`), keeping its velocity.
        Returns every person's outline box (work px).
        """
        p = self.params
        head_list = list(heads or ())
        boxes_now = self._boxes(self.people)
        placed = []
        tracks = list(tracks)
        if not tracks:
            return boxes_now
        track_boxes = np.array([(t.box.x, t.box.y, t.box.w, t.box.h) for t in tracks],
                               np.float64) * view.to_work
        row = {tid: i for i, tid in enumerate(boxes_now)}
        # IoU of every person's outline box (rows) with every track's box (columns)
        iou = _iou_matrix(np.array(list(boxes_now.values())).reshape(-1, 4), track_boxes)
        dup = iou >= p.duplicate_iou
        n_dup = dup.sum(axis=0).tolist()
        for k, tr in enumerate(tracks):
            tb = track_boxes[k]
            person = self.people.get(tr.id)
            r = row.get(tr.id)
            # overlapped by another person's outline
            crowded = n_dup[k] - (r is not None and bool(dup[r, k])) > 0
            if person is not None:
                person.unseen = 0
                if tr.time_since_update != 0:
                    continue
                person.agreement = float(iou[r, k])
                person.disagree = person.disagree + 1 if person.agreement < p.reinit_iou else 0
                if crowded or not self._drifted(person):
                    continue
            elif crowded:
                continue
            new = _Person(self._init_pose(tb, _head_x(tr.box, head_list, view.sx)),
                          np.zeros(self.model.n_modes))
            if person is not None:
                new.vel[2:] = person.vel[2:]
            self.people[tr.id] = new
            placed.append(tr.id)
        boxes = dict(boxes_now)
        boxes.update(self._boxes(dict.fromkeys(placed)))
        return boxes

    def _drifted(self, person: _Person) -> bool:
        """Whether a shape has drifted away from its measured track (IoU below ``reinit_iou``)
        and either lost its edges (coasting ``reinit_coast`` frames) or stayed away
        ``reinit_frames`` frames in a row: then it follows something else and is placed anew.
        (A crowded track, whose box another person's shape overlaps, is ambiguous and never
        re-initialises.)"""
        p = self.params
        return not (person.disagree == 0 or (person.coast < p.reinit_coast
                                             and person.disagree < p.reinit_frames))

    def _measure_people(self, view: _WorkView, boxes: dict[int, np.ndarray]
                        ) -> list[FittedShape]:
        """Steps 2–4 for every person, front to back; drops the people lost or out of the image.

        Occlusion reasoning: fit front to back (lower foot point = nearer the camera on a ground
        plane seen from above); a person's sample points inside the outline of someone nearer
        are occluded and ignored (Siebel's thesis, section 4.4.3). ``boxes`` are the predicted
        outline boxes (work px).

        People are fitted in groups (:func:`~.shape_batch.fit_people`): the next people in that
        order whose search windows do not touch (:meth:`_group`). A fit is kept only if none of
        the people fitted before it in its group turned out to hide part of it; from the first
        that is hidden the rest are fitted again, behind the outlines now known, so every
        person is fitted exactly as one at a time.
        """
        out: list[FittedShape] = []
        drop = []
        order = sorted(self.people, key=lambda t: -(boxes[t][1] + boxes[t][3]))
        fitted_polys: list[tuple[float, np.ndarray, np.ndarray]] = []  # (foot y, box, outline)
        while order:
            group = self._group(order, boxes)
            done = self._measure_group(group, boxes, view, fitted_polys, out, drop)
            order = order[done:]
        for tid in drop:
            self.people.pop(tid, None)
        return out

    def _group(self, order: list[int], boxes: dict[int, np.ndarray]) -> list[int]:
        """The first people of ``order`` none of whom is likely to hide part of another: their
        predicted boxes do not overlap. (Only a guess, for speed: whether a fit must be done
        again is decided from the fitted outlines; on PETS one fit in 1,800 is.)"""
        group = [order[0]]
        grown = []
        for tid in order:
            x, y, w, h = boxes[tid].tolist()
            box = (x, y, x + w, y + h)
            if any(box[0] < g[2] and g[0] < box[2] and box[1] < g[3] and g[1] < box[3]
                   for g in grown):
                break
            if grown:
                group.append(tid)
            grown.append(box)
        return group

    def _measure_group(self, group: list[int], boxes: dict[int, np.ndarray], view: _WorkView,
                       fitted_polys: list[tuple[float, np.ndarray, np.ndarray]],
                       out: list[FittedShape], drop: list[int]) -> int:
        """Steps 2–4 for the people ``group`` (front to back) fitted together, behind the
        outlines ``fitted_polys`` of the people before them; keeps them in order until one
        turns out to be hidden by a person of the group fitted before them (that one and the
        rest are to be fitted again). Appends their outlines to ``fitted_polys``, their shapes to
        ``out`` and the people to drop to ``drop``; returns how many people it kept."""
        p = self.params
        fit_ids, inputs, gain = [], [], 1.0
        for tid in group:
            box = boxes[tid]
            window = _search_window(box, max(p.min_search, p.search * box[3]) + 2, view.w,
                                    view.h)
            if window is None:
                continue
            x1, y1, x2, y2 = window
            grads, gain = window_gradients(view.diff[y1:y2, x1:x2])
            inputs.append(FitInput(grads, self._visible_mask(view, window, box, fitted_polys),
                                   np.array([x1, y1], np.float64)))
            fit_ids.append(tid)
        state = self._fitted_state(fit_ids, inputs, gain, view)
        start = len(fitted_polys)
        for done, tid in enumerate(group):
            if done and self._front(boxes[tid], fitted_polys[start:]):
                return done
            shape = self._keep(tid, state.get(tid), view, fitted_polys)
            if shape is None:
                drop.append(tid)
            else:
                out.append(shape)
        return len(group)

    def _fitted_state(self, ids: list[int], inputs: list[FitInput], gain: float,
                      view: _WorkView) -> dict[int, dict]:
        """Steps 2–4 for the people ``ids`` without changing them: their fits, the state
        :meth:`_correct` would give them and its outlines (original pixels, and the dense work
        outline and box), by track id."""
        if not ids:
            return {}
        p = self.params
        people = [self.people[t] for t in ids]
        pose0 = np.array([q.pose for q in people])
        b0 = np.array([q.b for q in people]).reshape(len(ids), -1)
        pose, b, support, visible = fit_people(
            self._outlines, pose0, b0, inputs, gain, iterations=p.iterations, search=p.search,
            min_search=p.min_search, edge_threshold=p.edge_threshold, min_support=p.min_support,
            max_tilt=self._max_tilt, max_scale_change=p.max_scale_change)
        # step 4, the alpha-beta correction, for everyone at once
        good = (support >= p.min_support) & (visible >= p.min_visible)
        r = pose - pose0
        new_pose = np.where(good[:, None], pose0 + p.alpha * r, pose0)
        new_b = np.where(good[:, None], b, b0)
        speed = good & (np.minimum(support, visible) >= p.velocity_support)
        o = self._outlines.outlines(new_pose, new_b)
        dense = self._outlines.dense(o.control)
        bx = dense_boxes(dense)
        back = np.array([1 / view.sx, 1 / view.sy])
        points, control = o.points * back, o.control * back
        ob = (bx / view.to_work).tolist()
        reach = (np.maximum(p.min_search, p.search * bx[:, 3]) / view.sy).tolist()
        dv = p.beta * r[:, 2:]
        good, speed = good.tolist(), speed.tolist()
        support, visible = support.tolist(), visible.tolist()
        return {tid: dict(pose=new_pose[i], b=new_b[i], good=good[i], speed=speed[i], dv=dv[i],
                          support=support[i], visible=visible[i], dense=dense[i], bx=bx[i],
                          ob=ob[i], reach=reach[i], control=control[i], points=points[i],
                          normals=o.normals[i])
                for i, tid in enumerate(ids)}

    def _front(self, box: np.ndarray, polys: list[tuple[float, np.ndarray, np.ndarray]]
               ) -> list[np.ndarray]:
        """The outlines of ``polys`` ``(foot y, box, outline)`` that hide part of the person
        whose predicted box is ``box``: overlapping it, with a foot point lower by more than
        ``occlusion_margin`` of its height."""
        foot = box[1] + box[3]
        return [poly for fy, fb, poly in polys
                if fy > foot + self.params.occlusion_margin * box[3] and _iou(fb, box) > 0]

    def _keep(self, tid: int, st: dict | None, view: _WorkView,
              fitted_polys: list[tuple[float, np.ndarray, np.ndarray]]) -> FittedShape | None:
        """Applies the fitted ``st`` (:meth:`_fitted_state`; None: no search window) to the
        person ``tid`` and returns their shape; ``None`` when the person is to be dropped: search
        window too small, coasting or unseen longer than ``max_coast``, or outline outside the
        image. The outline of a person kept that long is appended to ``fitted_polys``."""
        p = self.params
        if st is None:
            return None
        person = self.people[tid]
        self._correct(person, st)
        if person.coast > p.max_coast or person.unseen > p.max_coast:
            return None
        bx = st["bx"]
        fitted_polys.append((bx[1] + bx[3], bx, st["dense"]))
        if bx[2] <= 0 or bx[3] <= 0 or bx[0] >= view.w or bx[1] >= view.h or bx[0] + bx[2] <= 0 \
                or bx[1] + bx[3] <= 0:
            return None
        return FittedShape(
            track_id=tid, outline=st["points"], control=st["control"],
            box=Box(*st["ob"]), support=st["support"], coasting=person.coast,
            normals=st["normals"], search=st["reach"], unseen=person.unseen,
            visible=st["visible"], agreement=person.agreement)

    def _visible_mask(self, view: _WorkView, window: tuple[int, int, int, int], box: np.ndarray,
                      fitted_polys: list[tuple[float, np.ndarray, np.ndarray]]
                      ) -> np.ndarray | None:
        """The motion mask inside ``window`` with the outlines of nearer people overlapping ``box``
        cleared (occluders: foot point lower by more than ``occlusion_margin`` of the height);
        ``None`` when there is neither a mask nor an occluder."""
        x1, y1, x2, y2 = window
        fg = view.fg[y1:y2, x1:x2] if view.fg is not None else None
        front = self._front(box, fitted_polys)
        if front:
            occ = np.zeros((y2 - y1, x2 - x1), np.uint8)
            cv2.fillPoly(occ, [np.rint(poly - [x1, y1]).astype(np.int32) for poly in front], 1)
            base = fg if fg is not None else np.full_like(occ, 255)
            fg = np.where(occ > 0, 0, base).astype(np.uint8)
        return fg

    @staticmethod
    def _correct(person: _Person, st: dict) -> None:
        """Step 4 as :meth:`_fitted_state` worked it out: alpha-beta correction with the fitted
        pose and weights when enough sample points found an edge and enough of the outline is
        visible (``good``); otherwise (no edges, or mostly hidden by the scene or a nearer
        person) the person coasts on the prediction."""
        person.support = st["support"]
        if st["good"]:
            # position has velocity, scale/rotation do not
            person.pose = st["pose"]
            if st["speed"]:
                person.vel[2:] = person.vel[2:] + st["dv"]
            person.b = st["b"]
            person.coast = 0
        else:
            person.coast += 1


@dataclass(frozen=True)
class _WorkView:
    """The images of one frame the shapes are fitted in, at the work (background) resolution.

    Attributes
    ----------
    diff : (h, w) uint8
        The difference image whose edges the outlines are fitted to (:func:`difference_image`
        of the frame and the background).
    fg : (h, w) uint8 or None
        Motion mask (visibility of sample points); None without both a background and a mask.
    w, h : int
        Work size, px.
    sx, sy : float
        Work pixels per original pixel.
    """

    diff: np.ndarray
    fg: np.ndarray | None
    w: int
    h: int
    sx: float
    sy: float

    @property
    def to_work(self) -> np.ndarray:
        """Factors taking a box ``(x, y, w, h)`` from original to work pixels."""
        return np.array([self.sx, self.sy, self.sx, self.sy])


def _work_view(frame: np.ndarray, background: np.ndarray | None, mask: np.ndarray | None,
               work: np.ndarray | None) -> _WorkView:
    """The difference image and the motion mask at the background's resolution (see
    :meth:`ShapeTracker.update` for the arguments): of frame and background; else the mask;
    else the grey frame."""
    H, W = frame.shape[:2]
    if background is not None:
        h, w = background.shape[:2]
        img = work
        if img is None or img.shape[:2] != (h, w):
            img = frame
            if (h, w) != (H, W):
                # a smaller background comes from the pipeline's preprocessing: mimic it
                img = cv2.resize(frame, (w, h), interpolation=cv2.INTER_AREA)
                img = cv2.GaussianBlur(img, (5, 5), 0)
        bg = background
        if img.ndim != bg.ndim:
            img, bg = to_gray(img), to_gray(bg)
        diff = difference_image(img, bg)
    elif mask is not None:
        h, w = mask.shape[:2]
        diff = mask
    else:
        h, w = H, W
        diff = to_gray(frame)
    fg_full = None
    if mask is not None and background is not None:
        fg_full = mask if mask.shape[:2] == (h, w) else cv2.resize(
            mask, (w, h), interpolation=cv2.INTER_NEAREST)
    return _WorkView(diff, fg_full, w, h, w / W, h / H)


def _head_x(box: Box, heads: list, sx: float) -> float | None:
    """Work-pixel x of the first head near the top of ``box`` (original px): inside it
    horizontally, between 10 % of its height above its top and 40 % below; None when none is."""
    for hd in heads:
        if box.x <= hd.x <= box.x2 and box.y - 0.1 * box.h <= hd.y <= box.y + 0.4 * box.h:
            return hd.x * sx
    return None


def _search_window(box: np.ndarray, half: float, w: int, h: int
                   ) -> tuple[int, int, int, int] | None:
    """``(x1, y1, x2, y2)``: ``box`` (work px) grown by ``half`` on every side and cut to the
    ``w`` × ``h`` image; None when less than 3 px remain either way."""
    x, y, bw, bh = box.tolist()
    x1 = max(0, math.floor(x - half))
    y1 = max(0, math.floor(y - half))
    x2 = min(w, math.ceil(x + bw + half))
    y2 = min(h, math.ceil(y + bh + half))
    if x2 - x1 < 3 or y2 - y1 < 3:
        return None
    return x1, y1, x2, y2


def _iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`_iou` of every box of ``a`` ``(n, 4)`` with every box of ``b`` ``(m, 4)``:
    ``(n, m)``."""
    a, b = a[:, None, :], b[None, :, :]
    ix = np.maximum(0.0, np.minimum(a[..., 0] + a[..., 2], b[..., 0] + b[..., 2])
                    - np.maximum(a[..., 0], b[..., 0]))
    iy = np.maximum(0.0, np.minimum(a[..., 1] + a[..., 3], b[..., 1] + b[..., 3])
                    - np.maximum(a[..., 1], b[..., 1]))
    inter = ix * iy
    union = a[..., 2] * a[..., 3] + b[..., 2] * b[..., 3] - inter
    out = np.zeros(inter.shape)
    np.divide(inter, union, out=out, where=union > 0)
    return out


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a.tolist(), b.tolist()   # four Python floats each: scalar maths without NumPy's
    ix = max(0.0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    inter = ix * iy
    union = a[2] * a[3] + b[2] * b[3] - inter
    return inter / union if union > 0 else 0.0
