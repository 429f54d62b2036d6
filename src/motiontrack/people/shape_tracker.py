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
from dataclasses import dataclass, field

import cv2
import numpy as np

from ..imaging import to_gray
from ..types import Box
from . import bspline
from .shape_model import ShapeModel, apply_similarity, fit_similarity, invert_similarity

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
    d = cv2.absdiff(frame, background)
    if d.ndim == 3:
        d = d.max(axis=2)
    d = d.astype(np.float32)
    gx = cv2.Sobel(d, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(d, cv2.CV_32F, 0, 1, ksize=3)
    return (np.abs(gx) + np.abs(gy)) * 0.25


def difference_gradients(frame: np.ndarray, background: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sobel derivatives ``(gx, gy)`` of the difference image ``|frame − background|``.

    Returns two ``(h, w) float32`` arrays scaled by 1/4 (so a step of ``g`` grey levels gives
    about ``g / 2``, keeping thresholds in grey levels).
    """
    d = cv2.absdiff(frame, background)
    if d.ndim == 3:
        d = d.max(axis=2)
    d = d.astype(np.float32)
    gx = cv2.Sobel(d, cv2.CV_32F, 1, 0, ksize=3, scale=0.25)
    gy = cv2.Sobel(d, cv2.CV_32F, 0, 1, ksize=3, scale=0.25)
    return gx, gy


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
    k = len(p)
    if k == 0:
        return np.zeros(0), np.zeros(0)
    steps = np.arange(-int(np.ceil(half)), int(np.ceil(half)) + 1, dtype=np.float64)
    xs = np.rint(p[:, 0:1] + steps[None, :] * nrm[:, 0:1]).astype(np.int64)
    ys = np.rint(p[:, 1:2] + steps[None, :] * nrm[:, 1:2]).astype(np.int64)
    oriented = isinstance(edges, tuple)
    h, w = (edges[0] if oriented else edges).shape[:2]
    inside = (xs >= 0) & (xs < w) & (ys >= 0) & (ys < h)
    vals = np.zeros(xs.shape, dtype=np.float64)
    yi, xi = ys[inside], xs[inside]
    if oriented:
        gx, gy = edges
        nx = np.broadcast_to(nrm[:, 0:1], xs.shape)[inside]
        ny = np.broadcast_to(nrm[:, 1:2], xs.shape)[inside]
        vals[inside] = np.maximum(-(gx[yi, xi] * nx + gy[yi, xi] * ny), 0.0)
    else:
        vals[inside] = edges[yi, xi]
    # Prefer the nearer edge among equals: a tiny penalty on |offset|.
    j = np.argmax(vals - 1e-6 * np.abs(steps)[None, :], axis=1)
    strength = vals[np.arange(k), j]
    off = steps[j]
    weak = strength < threshold
    strength[weak] = 0.0
    off[weak] = 0.0
    return off, strength


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
        n, k = model.n_control, self.params.samples
        t = bspline.uniform_params(n, k)
        self._t = t
        self._B = bspline.basis_matrix(t, n)              # (K, N): control → samples
        self._dB = bspline.basis_matrix(t, n, derivative=1)
        self._pinv = np.linalg.pinv(self._B)              # (N, K): samples → control (least squares)
        self._Bbox = bspline.basis_matrix(bspline.uniform_params(n, 4 * n), n)  # dense, for boxes
        mean = model.shape()
        dense = self._Bbox @ mean
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

    def _limit_pose(self, pose: np.ndarray) -> np.ndarray:
        a, b = pose[0], pose[1]
        s = np.hypot(a, b)
        ang = np.arctan2(b, a)
        lim = np.deg2rad(self.params.max_rotation)
        if abs(ang) > lim:
            ang = np.clip(ang, -lim, lim)
            pose = pose.copy()
            pose[0], pose[1] = s * np.cos(ang), s * np.sin(ang)
        return pose

    def _outline(self, pose: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Control points, sample points and unit normals in work pixels."""
        ctrl = apply_similarity(pose, self.model.shape(b))
        pts = self._B @ ctrl
        d = self._dB @ ctrl
        nrm = np.stack([d[:, 1], -d[:, 0]], axis=1)
        ln = np.linalg.norm(nrm, axis=1, keepdims=True)
        nrm = np.divide(nrm, ln, out=np.zeros_like(nrm), where=ln > 0)
        if bspline.signed_area(ctrl) < 0:
            nrm = -nrm
        return ctrl, pts, nrm

    def _fit(self, person: _Person, edges, origin: np.ndarray, fg: np.ndarray | None = None
             ) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Steps 2–3 on one person, without touching ``person``.

        ``fg`` (a crop of the motion mask with the same ``origin``) marks which sample points
        are visible: a point whose inside neighbour (2 px in from the outline) is not foreground
        is taken as occluded and ignored.

        Returns ``(pose, b, support, visible)``: the fit, the fraction of sample points that found
        an edge (and are visible), and the visible fraction of the *predicted* outline.
        """
        p = self.params
        pose, b = person.pose.copy(), person.b.copy()
        s0 = np.hypot(pose[0], pose[1])
        support = 0.0
        visible_frac = 1.0
        for it in range(p.iterations):
            ctrl, pts, nrm = self._outline(pose, b)
            height = float(pts[:, 1].max() - pts[:, 1].min())
            half = max(p.min_search, p.search * height)
            off, strength = search_normals(edges, pts - origin, nrm, half, p.edge_threshold)
            found = strength > 0
            if fg is not None:
                visible = _visible_points(fg, pts, nrm, origin)
                if it == 0:
                    visible_frac = float(visible.mean()) if len(visible) else 0.0
                found &= visible
            support = float(found.mean()) if len(found) else 0.0
            if support < p.min_support:
                break
            solved = self._solve(b, pts + off[:, None] * nrm, strength, found, s0)
            if solved is None:
                break
            pose, b = solved
        return pose, b, support, visible_frac

    def _solve(self, b: np.ndarray, target: np.ndarray, strength: np.ndarray, found: np.ndarray,
               s0: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Step 3 (Cootes et al. 1995, section 5.2): pose and constrained weights for the edge
        points ``target`` ``(K, 2)`` (work px) that the sample points of weights ``b`` found.

        The pose is the ``strength``-weighted similarity from the model outline to the ``found``
        points, its tilt and its scale change from ``s0`` limited; the points mapped back into the
        model frame give control points (pseudo-inverse of the sampling matrix) whose projection
        onto the modes is constrained to ``D_m <= D_max``. ``None`` when the pose degenerates.
        """
        model_pts = self._B @ self.model.shape(b)
        new_pose = fit_similarity(model_pts[found], target[found], strength[found])
        if np.hypot(new_pose[0], new_pose[1]) <= 0:
            return None
        new_pose = self._limit_scale(self._limit_pose(new_pose), model_pts, s0)
        local = apply_similarity(invert_similarity(new_pose), target)
        # Points without an edge keep the model's own position (no information there).
        local[~found] = model_pts[~found]
        ctrl_local = self._pinv @ local
        return new_pose, self.model.constrain(self.model.project(ctrl_local))

    def _limit_scale(self, pose: np.ndarray, model_pts: np.ndarray, s0: float) -> np.ndarray:
        """``pose`` with its scale held within ``max_scale_change`` of ``s0``, about the centre of
        the outline ``model_pts`` (model frame), so a partly occluded person's outline does not
        collapse. Modifies and returns ``pose``."""
        p = self.params
        s_new = np.hypot(pose[0], pose[1])
        s_lim = np.clip(s_new, s0 * (1 - p.max_scale_change), s0 * (1 + p.max_scale_change))
        if s_lim != s_new:
            # keep the fitted outline's centre while limiting its scale
            c_model = model_pts.mean(axis=0)
            centre = apply_similarity(pose, c_model[None, :])[0]
            pose[:2] *= s_lim / s_new
            pose[2:] += centre - apply_similarity(pose, c_model[None, :])[0]
        return pose

    def _box(self, pose: np.ndarray, b: np.ndarray) -> np.ndarray:
        dense = self._Bbox @ apply_similarity(pose, self.model.shape(b))
        lo, hi = dense.min(axis=0), dense.max(axis=0)
        return np.array([lo[0], lo[1], hi[0] - lo[0], hi[1] - lo[1]])

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
        self._adopt_tracks(tracks, heads, view)
        return self._measure_people(view)

    # ------------------------------------------------------------------ the steps of update
    def _predict(self) -> None:
        """Step 1: every person's pose moves on by its velocity (scale and rotation have none),
        its tilt limited, and counts one more frame unseen by the region tracker
        (:meth:`_adopt_tracks` resets that when the person's track is reported)."""
        for person in self.people.values():
            person.pose = self._limit_pose(person.pose + person.vel)
            person.unseen += 1

    def _adopt_tracks(self, tracks, heads, view: _WorkView) -> None:
        """Births and re-initialisation from the region tracker's ``tracks``.

        A new track gets the mean shape in its box, unless its box overlaps another person's
        outline box by ``duplicate_iou`` (most likely a duplicate of that person). A track
        measured this frame (``time_since_update == 0``) updates its shape's agreement; a shape
        that has drifted away from it is placed anew (:meth:`_drifted`), keeping its velocity.
        """
        p = self.params
        head_list = list(heads or ())
        boxes_now = {tid: self._box(q.pose, q.b) for tid, q in self.people.items()}
        for tr in tracks:
            tb = tr.box.as_array() * view.to_work
            person = self.people.get(tr.id)
            crowded = any(_iou(ob, tb) >= p.duplicate_iou for oid, ob in boxes_now.items()
                          if oid != tr.id)
            if person is not None:
                person.unseen = 0
                if tr.time_since_update != 0:
                    continue
                person.agreement = _iou(boxes_now[tr.id], tb)
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

    def _drifted(self, person: _Person) -> bool:
        """Whether a shape has drifted away from its measured track (IoU below ``reinit_iou``)
        and either lost its edges (coasting ``reinit_coast`` frames) or stayed away
        ``reinit_frames`` frames in a row: then it follows something else and is placed anew.
        (A crowded track, whose box another person's shape overlaps, is ambiguous and never
        re-initialises.)"""
        p = self.params
        return not (person.disagree == 0 or (person.coast < p.reinit_coast
                                             and person.disagree < p.reinit_frames))

    def _measure_people(self, view: _WorkView) -> list[FittedShape]:
        """Steps 2–4 for every person, front to back; drops the people lost or out of the image.

        Occlusion reasoning: fit front to back (lower foot point = nearer the camera on a ground
        plane seen from above); a person's sample points inside the outline of someone nearer
        are occluded and ignored (Siebel's thesis, section 4.4.3).
        """
        out: list[FittedShape] = []
        drop = []
        boxes = {tid: self._box(q.pose, q.b) for tid, q in self.people.items()}
        order = sorted(self.people, key=lambda t: -(boxes[t][1] + boxes[t][3]))
        fitted_polys: list[tuple[float, np.ndarray, np.ndarray]] = []  # (foot y, box, outline)
        for tid in order:
            shape = self._measure_person(tid, boxes[tid], view, fitted_polys)
            if shape is None:
                drop.append(tid)
            else:
                out.append(shape)
        for tid in drop:
            self.people.pop(tid, None)
        return out

    def _measure_person(self, tid: int, box: np.ndarray, view: _WorkView,
                        fitted_polys: list[tuple[float, np.ndarray, np.ndarray]]
                        ) -> FittedShape | None:
        """Steps 2–4 for one person whose predicted outline box is ``box`` (work px).

        ``fitted_polys`` holds the outlines of the people already fitted (nearer the camera); this
        person's is appended. ``None`` when the person is to be dropped: search window too small,
        coasting or unseen longer than ``max_coast``, or outline outside the image.
        """
        p = self.params
        person = self.people[tid]
        window = _search_window(box, max(p.min_search, p.search * box[3]) + 2, view.w, view.h)
        if window is None:
            return None
        x1, y1, x2, y2 = window
        edges = difference_gradients(view.diff[0][y1:y2, x1:x2], view.diff[1][y1:y2, x1:x2])
        fg = self._visible_mask(view, window, box, fitted_polys)
        pose, b, support, visible = self._fit(person, edges, np.array([x1, y1], np.float64), fg)
        self._correct(person, pose, b, support, visible)
        if person.coast > p.max_coast or person.unseen > p.max_coast:
            return None
        ctrl, pts, nrm = self._outline(person.pose, person.b)
        bx = self._box(person.pose, person.b)
        fitted_polys.append((bx[1] + bx[3], bx, self._Bbox @ ctrl))
        if bx[2] <= 0 or bx[3] <= 0 or bx[0] >= view.w or bx[1] >= view.h or bx[0] + bx[2] <= 0 \
                or bx[1] + bx[3] <= 0:
            return None
        scale_back = np.array([1 / view.sx, 1 / view.sy])
        ob = bx / view.to_work
        return FittedShape(
            track_id=tid, outline=pts * scale_back, control=ctrl * scale_back,
            box=Box(float(ob[0]), float(ob[1]), float(ob[2]), float(ob[3])),
            support=support, coasting=person.coast, normals=nrm,
            search=max(p.min_search, p.search * bx[3]) / view.sy, unseen=person.unseen,
            visible=visible, agreement=person.agreement)

    def _visible_mask(self, view: _WorkView, window: tuple[int, int, int, int], box: np.ndarray,
                      fitted_polys: list[tuple[float, np.ndarray, np.ndarray]]
                      ) -> np.ndarray | None:
        """The motion mask inside ``window`` with the outlines of nearer people overlapping ``box``
        cleared (occluders: foot point lower by more than ``occlusion_margin`` of the height);
        ``None`` when there is neither a mask nor an occluder."""
        x1, y1, x2, y2 = window
        fg = view.fg[y1:y2, x1:x2] if view.fg is not None else None
        foot = box[1] + box[3]
        front = [poly for fy, fb, poly in fitted_polys
                 if fy > foot + self.params.occlusion_margin * box[3] and _iou(fb, box) > 0]
        if front:
            occ = np.zeros((y2 - y1, x2 - x1), np.uint8)
            cv2.fillPoly(occ, [np.rint(poly - [x1, y1]).astype(np.int32) for poly in front], 1)
            base = fg if fg is not None else np.full_like(occ, 255)
            fg = np.where(occ > 0, 0, base).astype(np.uint8)
        return fg

    def _correct(self, person: _Person, pose: np.ndarray, b: np.ndarray, support: float,
                 visible: float) -> None:
        """Step 4: alpha-beta correction with the fitted ``pose`` and weights ``b`` when enough
        sample points found an edge and enough of the outline is visible; otherwise (no edges,
        or mostly hidden by the scene or a nearer person) the person coasts on the prediction."""
        p = self.params
        person.support = support
        if support >= p.min_support and visible >= p.min_visible:
            # position has velocity, scale/rotation do not
            r = pose - person.pose
            person.pose = person.pose + p.alpha * r
            if min(support, visible) >= p.velocity_support:
                person.vel[2:] = person.vel[2:] + p.beta * r[2:]
            person.b = b
            person.coast = 0
        else:
            person.coast += 1


@dataclass(frozen=True)
class _WorkView:
    """The images of one frame the shapes are fitted in, at the work (background) resolution.

    Attributes
    ----------
    diff : pair of (h, w[, 3]) uint8
        Image and reference whose difference image holds the edges.
    fg : (h, w) uint8 or None
        Motion mask (visibility of sample points); None without both a background and a mask.
    w, h : int
        Work size, px.
    sx, sy : float
        Work pixels per original pixel.
    """

    diff: tuple[np.ndarray, np.ndarray]
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
    """The difference-image pair and the motion mask at the background's resolution (see
    :meth:`ShapeTracker.update` for the arguments): frame and background; else the mask and
    zeros; else the grey frame and zeros."""
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
        diff_pair = (img, bg)
    elif mask is not None:
        h, w = mask.shape[:2]
        diff_pair = (mask, np.zeros_like(mask))
    else:
        h, w = H, W
        gray = to_gray(frame)
        diff_pair = (gray, np.zeros_like(gray))
    fg_full = None
    if mask is not None and background is not None:
        fg_full = mask if mask.shape[:2] == (h, w) else cv2.resize(
            mask, (w, h), interpolation=cv2.INTER_NEAREST)
    return _WorkView(diff_pair, fg_full, w, h, w / W, h / H)


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
    x1 = int(max(0, np.floor(box[0] - half)))
    y1 = int(max(0, np.floor(box[1] - half)))
    x2 = int(min(w, np.ceil(box[0] + box[2] + half)))
    y2 = int(min(h, np.ceil(box[1] + box[3] + half)))
    if x2 - x1 < 3 or y2 - y1 < 3:
        return None
    return x1, y1, x2, y2


def _visible_points(fg: np.ndarray, pts: np.ndarray, nrm: np.ndarray, origin: np.ndarray
                    ) -> np.ndarray:
    """Boolean ``(K,)``: sample point k is visible, i.e. its inside neighbour (2 px in from the
    outline along the normal) is foreground in ``fg``, a mask crop whose corner is ``origin``."""
    inner = np.rint(pts - origin - 2.0 * nrm).astype(np.int64)
    fh, fw = fg.shape[:2]
    ok = (inner[:, 0] >= 0) & (inner[:, 0] < fw) & (inner[:, 1] >= 0) & (inner[:, 1] < fh)
    visible = np.zeros(len(pts), bool)
    visible[ok] = fg[inner[ok, 1], inner[ok, 0]] > 0
    return visible


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    ix = max(0.0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    inter = ix * iy
    union = a[2] * a[3] + b[2] * b[3] - inter
    return inter / union if union > 0 else 0.0
