"""The active shape tracker's numerics for several people at once (:mod:`.shape_tracker`).

Per frame the shape tracker places each person's outline, searches along its normals for edges
and solves for a new pose and shape (Cootes et al. 1995, section 5.2). Done one person at a time
this is a few hundred NumPy calls on arrays of 48 points: call overhead, not arithmetic. Here the
same formulas run on stacked arrays ``(A, …)`` of ``A`` people, so one call serves everyone.

The arithmetic is the one-person arithmetic, term by term: element-wise operations do not care
how arrays are stacked, NumPy runs a stacked matrix product slice by slice through the same
BLAS call, and row sums add along a contiguous row as a 1-D sum does. Where a one-person formula
sums over a varying subset of points (the weighted similarity), those sums are taken person by
person over the same subset. So fitting people together gives the tracks fitting them one by
one gives (``tools/identical_tracks.py``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np

from . import bspline
from .shape_model import ShapeModel

__all__ = ["Outlines", "OutlineSet", "FitInput", "fit_people", "similarity", "search_edges",
           "visible_points", "window_gradients", "dense_boxes", "limit_tilt"]

#: multiplies a tangent ``(dy, dx)`` (columns swapped) into the normal ``(dy, -dx)``
_TURN = np.array([1.0, -1.0])


#: (a, b, tx, ty) → (a, a, -b, b, tx, ty), see :func:`_apply`
_SPREAD, _SIGNS = [0, 0, 1, 1, 2, 3], np.array([1.0, 1.0, -1.0, 1.0, 1.0, 1.0])


def similarity(pose: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """:func:`~.shape_model.apply_similarity` of each person's pose ``(A, 4)`` to their points
    ``(A, M, 2)``."""
    return _apply((pose[:, _SPREAD] * _SIGNS)[:, None, :], pts)


def _apply(c: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Points ``(A, M, 2)`` under similarities given as ``(a, a, -b, b, tx, ty)`` ``(A, 1, 6)``.

    ``x' = a x - b y + tx, y' = b x + a y + ty`` computed as ``(a, a) (x, y) + (-b, b) (y, x) +
    (tx, ty)``: the same products and sums (``a x + (-b y)`` is ``a x - b y`` exactly, and
    ``a y + b x`` is ``b x + a y``), so the one-person formula's values."""
    return pts * c[..., 0:2] + pts[..., ::-1] * c[..., 2:4] + c[..., 4:6]


def _inverse_similarity(pose: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Points ``(A, M, 2)`` under the inverses (:func:`~.shape_model.invert_similarity`) of
    poses ``(A, 4)`` whose scales are > 0."""
    ab, t = pose[:, :2], pose[:, 2:]
    s2 = np.add.reduce(ab * ab, axis=1)[:, None]           # a a + b b
    iab = ab * _SIGNS[1:3] / s2                               # (a / s2, -b / s2)
    c = np.empty((len(pose), 1, 6))
    c[:, 0, :4] = iab[:, _SPREAD[:4]] * _SIGNS[:4]            # (ia, ia, -ib, ib)
    # (-(ia tx - ib ty), -(ib tx + ia ty)) as above
    c[:, 0, 4:] = -(t * c[:, 0, 0:2] + t[:, ::-1] * c[:, 0, 2:4])
    return _apply(c, pts)


@dataclass
class OutlineSet:
    """Outlines of ``A`` people (work pixels).

    Attributes
    ----------
    shape : (A, N, 2)
        Control points in the model frame (``model.shape(b)``).
    control : (A, N, 2)
        Control points.
    points : (A, K, 2)
        Sample points.
    normals : (A, K, 2)
        Unit outward normals at the sample points.
    """

    shape: np.ndarray
    control: np.ndarray
    points: np.ndarray
    normals: np.ndarray


class Outlines:
    """The spline matrices of a shape model sampled at ``samples`` points, and what is computed
    from them for several people at once.

    Parameters
    ----------
    model : ShapeModel
    samples : int
        Sample points ``K`` along the outline.
    """

    def __init__(self, model: ShapeModel, samples: int) -> None:
        self.model = model
        n = model.n_control
        t = bspline.uniform_params(n, samples)
        self.B = bspline.basis_matrix(t, n)                    # (K, N): control → samples
        self.dB = bspline.basis_matrix(t, n, derivative=1)
        self.BdB = np.vstack([self.B, self.dB])                # both in one product
        self.pinv = np.linalg.pinv(self.B)                     # (N, K): samples → control
        self.Bbox = bspline.basis_matrix(bspline.uniform_params(n, 4 * n), n)  # dense, for boxes
        self.k = samples
        self._mean = model.mean.reshape(-1)
        self._next = np.r_[1:n, 0]

    # ------------------------------------------------------------------ outlines
    def shapes(self, b: np.ndarray) -> np.ndarray:
        """``model.shape(b)`` of weights ``(A, t)``: ``(A, N, 2)``."""
        m = self.model
        if m.n_modes == 0:
            return np.broadcast_to(m.mean, (len(b),) + m.mean.shape).copy()
        return (self._mean + (m.modes @ b[:, :, None])[:, :, 0]).reshape(len(b), -1, 2)

    def outlines(self, pose: np.ndarray, b: np.ndarray) -> OutlineSet:
        """Control points, sample points and unit outward normals of poses ``(A, 4)`` and
        weights ``(A, t)``."""
        shape = self.shapes(b)
        ctrl = similarity(pose, shape)
        both = self.BdB @ ctrl
        pts, d = both[:, :self.k], both[:, self.k:]
        nrm = d[..., ::-1] * _TURN                             # the tangent turned to (dy, -dx)
        ln = np.sqrt(np.add.reduce(nrm * nrm, axis=2))[..., None]
        ln[self._clockwise(ctrl)] *= -1                        # n / -l == -(n / l): outwards
        if (ln != 0).all():
            nrm = nrm / ln
        else:
            nrm = np.divide(nrm, ln, out=np.zeros_like(nrm), where=ln != 0)
        return OutlineSet(shape, ctrl, pts, nrm)

    def _clockwise(self, ctrl: np.ndarray) -> np.ndarray:
        """Boolean ``(A,)``: the control polygon's :func:`~.bspline.signed_area` is negative.

        The areas are summed here as rows; a sign that rounding could flip (an area within a
        billionth of the sum of its terms, never a person's outline) is taken from
        :func:`~.bspline.signed_area` itself."""
        x, y = ctrl[..., 0], ctrl[..., 1]
        t1, t2 = x * y[:, self._next], x[:, self._next] * y
        area = (t1 - t2).sum(axis=1)
        unsure = np.abs(area) <= 1e-9 * (np.abs(t1) + np.abs(t2)).sum(axis=1)
        for i in np.flatnonzero(unsure):
            area[i] = bspline.signed_area(ctrl[i])
        return area < 0

    def dense(self, control: np.ndarray) -> np.ndarray:
        """Dense outline points ``(A, 4N, 2)`` of control points ``(A, N, 2)``."""
        return self.Bbox @ control

    def boxes(self, pose: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Bounding boxes ``(A, 4)`` (x, y, w, h) of the dense outlines."""
        return dense_boxes(self.dense(similarity(pose, self.shapes(b))))

    # ------------------------------------------------------------------ the solve
    def solve(self, b: np.ndarray, shape: np.ndarray, target: np.ndarray, strength: np.ndarray,
              found: np.ndarray, s0: np.ndarray, max_tilt: float, max_scale_change: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Step 3 of the shape tracker for ``A`` people (Cootes et al. 1995, section 5.2).

        ``shape`` ``(A, N, 2)`` is ``model.shape(b)``; ``target`` ``(A, K, 2)`` the edge points
        the sample points found (``found``, with weights ``strength``); ``s0`` ``(A,)`` the
        scales the fit started from. Returns ``(pose, b, ok)``: the weighted similarity from the
        model outline to the found points (tilt cut to ``max_tilt`` radians, scale held within
        ``max_scale_change`` of ``s0`` about the outline's centre), the constrained weights of
        the points mapped back into the model frame, and which people's pose did not degenerate
        (the others' rows are to be ignored).
        """
        model_pts = self.B @ shape
        pose = _weighted_similarities(model_pts, target, strength, found)
        ok = ~(np.hypot(pose[:, 0], pose[:, 1]) <= 0)
        _limit_tilt(pose, max_tilt, ok)
        _limit_scale(pose, model_pts, s0, max_scale_change, ok)
        safe = np.where(ok[:, None], pose, [[1.0, 0.0, 0.0, 0.0]])
        local = _inverse_similarity(safe, target)
        # Points without an edge keep the model's own position (no information there).
        local[~found] = model_pts[~found]
        ctrl_local = self.pinv @ local
        m = self.model
        x = ctrl_local.reshape(len(local), -1) - self._mean
        weights = (m.modes.T @ x[:, :, None])[:, :, 0]
        return pose, _constrain(weights, m), ok


def dense_boxes(dense: np.ndarray) -> np.ndarray:
    """Bounding boxes ``(A, 4)`` (x, y, w, h) of points ``(A, M, 2)``."""
    lo, hi = dense.min(axis=1), dense.max(axis=1)
    return np.concatenate([lo, hi - lo], axis=1)


def limit_tilt(pose: np.ndarray, max_tilt: float) -> np.ndarray:
    """Poses ``(A, 4)`` with their tilt cut to ``max_tilt`` radians (a new array)."""
    pose = pose.copy()
    _limit_tilt(pose, max_tilt, np.ones(len(pose), bool))
    return pose


def _limit_tilt(pose: np.ndarray, lim: float, rows: np.ndarray) -> None:
    """Cuts the tilt of ``pose[rows]`` to ``lim`` in place (people stand upright)."""
    ang = np.arctan2(pose[:, 1], pose[:, 0])
    for i in np.flatnonzero(rows & (np.abs(ang) > lim)):
        a, b = pose[i, 0], pose[i, 1]
        s = np.hypot(a, b)
        t = lim if ang[i] > lim else -lim
        pose[i, 0], pose[i, 1] = s * np.cos(t), s * np.sin(t)


def _limit_scale(pose: np.ndarray, model_pts: np.ndarray, s0: np.ndarray, change: float,
                 rows: np.ndarray) -> None:
    """Holds the scale of ``pose[rows]`` within ``change`` of ``s0`` in place, about the centre
    of the outline ``model_pts`` (model frame), so a partly occluded person's outline does not
    collapse."""
    s_new = np.hypot(pose[:, 0], pose[:, 1])
    s_lim = np.minimum(np.maximum(s_new, s0 * (1 - change)), s0 * (1 + change))
    cut = np.flatnonzero(rows & (s_lim != s_new))
    if not len(cut):
        return
    # keep the fitted outline's centre while limiting its scale
    c = model_pts[cut].mean(axis=1)
    cx, cy = c[:, 0], c[:, 1]
    p = pose[cut]
    a, b, tx, ty = p.T
    centre_x, centre_y = a * cx - b * cy + tx, b * cx + a * cy + ty
    p[:, :2] *= (s_lim[cut] / s_new[cut])[:, None]
    a, b, tx, ty = p.T
    p[:, 2] += centre_x - (a * cx - b * cy + tx)
    p[:, 3] += centre_y - (b * cx + a * cy + ty)
    pose[cut] = p


def _constrain(b: np.ndarray, model: ShapeModel) -> np.ndarray:
    """:meth:`~.shape_model.ShapeModel.constrain` of weights ``(A, t)``."""
    if b.shape[1] == 0:
        return b.copy()
    d = np.sqrt(np.sum(b * b / model.variances, axis=1))
    out = b.copy()
    over = ~(d <= model.dmax)
    out[over] = b[over] * (model.dmax / d[over])[:, None]
    return out


def _weighted_similarities(s: np.ndarray, d: np.ndarray, w: np.ndarray, found: np.ndarray
                           ) -> np.ndarray:
    """:func:`~.shape_model.weighted_similarity` of each person's ``found`` points: ``(A, 4)``.

    The sums along the points that are pairwise in NumPy (1-D) are taken person by person over
    that person's found points, so they add in the same order; the centroids are column sums
    (added in order) and may run over all points with the others weighted zero."""
    n, k = w.shape
    # each person's found points laid end to end (compress keeps rows contiguous): a slice of
    # them adds up as the 1-D sum over that person's found points
    flat = found.reshape(-1)
    ends = np.cumsum(np.count_nonzero(found, axis=1)).tolist()
    spans = list(zip([0] + ends[:-1], ends))
    fw = w.reshape(-1).compress(flat)
    total = np.array([fw[i:j].sum() for i, j in spans])
    wz = np.where(found, w, 0.0)[..., None]
    # (a person without weight gets the identity below; 1 keeps their division quiet)
    safe = np.where(total > 0, total, 1.0)[:, None]
    ms = (wz * s).sum(axis=1) / safe
    md = (wz * d).sum(axis=1) / safe
    s0, d0 = s - ms[:, None, :], d - md[:, None, :]
    sx, sy, dx, dy = s0[..., 0], s0[..., 1], d0[..., 0], d0[..., 1]
    terms = np.empty((3, n, k))
    np.multiply(w, (s0 ** 2).sum(axis=2), out=terms[0])
    np.multiply(w, sx * dx + sy * dy, out=terms[1])
    np.multiply(w, sx * dy - sy * dx, out=terms[2])
    terms = terms.reshape(3, -1).compress(flat, axis=1)
    out = np.empty((n, 4))
    counts = np.count_nonzero(found & (w > 0), axis=1).tolist()
    msl, mdl, totals = ms.tolist(), md.tolist(), total.tolist()
    for i, (lo, hi) in enumerate(spans):
        if counts[i] < 2 or totals[i] <= 0:
            out[i] = (1.0, 0.0, 0.0, 0.0)
            continue
        den, an, bn = terms[:, lo:hi].sum(axis=1).tolist()
        (msx, msy), (mdx, mdy) = msl[i], mdl[i]
        if den <= 0:
            out[i] = (1.0, 0.0, mdx - msx, mdy - msy)
            continue
        a, b = an / den, bn / den
        out[i] = (a, b, mdx - (a * msx - b * msy), mdy - (b * msx + a * msy))
    return out


# ---------------------------------------------------------------------- reading the images
@dataclass
class FitInput:
    """What one person's fit reads: the difference image's derivatives in a window, the motion
    mask there, and where the window is.

    Attributes
    ----------
    gradients : (h, w, 2) or (h, w)
        ``(gx, gy)`` of the window (int16 Sobel sums, or float already scaled: see
        :func:`window_gradients`), or an edge-magnitude image.
    fg : (h, w) uint8 or None
        Visibility mask of the window (None: every point visible).
    origin : (2,) float64
        The window's top-left corner (work px).
    """

    gradients: np.ndarray
    fg: np.ndarray | None
    origin: np.ndarray


def window_gradients(diff: np.ndarray) -> tuple[np.ndarray, float]:
    """``(gx, gy)`` of an image window as one ``(h, w, 2)`` array, and the gain that scales
    them to grey levels (the 3×3 Sobel derivatives / 4): of uint8 the Sobel sums as int16 (one
    :func:`cv2.spatialGradient`), of anything else float32 already scaled."""
    if diff.dtype == np.uint8:
        return cv2.merge(cv2.spatialGradient(diff)), 0.25
    d = diff.astype(np.float32)
    return cv2.merge((cv2.Sobel(d, cv2.CV_32F, 1, 0, ksize=3, scale=0.25),
                      cv2.Sobel(d, cv2.CV_32F, 0, 1, ksize=3, scale=0.25))), 1.0


@functools.lru_cache(maxsize=256)
def steps(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The offsets ``-n … n`` (float) of a normal search and their penalties ``1e-6 |offset|``
    (among equal edges the nearer wins). Read only."""
    s = np.arange(-n, n + 1, dtype=np.float64)
    return _frozen(s), _frozen(1e-6 * np.abs(s)[None, :])


@functools.lru_cache(maxsize=64)
def _arange(n: int) -> np.ndarray:
    """``0 … n-1`` (read only)."""
    return _frozen(np.arange(n))


def _frozen(a: np.ndarray) -> np.ndarray:
    """``a`` made read-only (shared through a cache)."""
    a.setflags(write=False)
    return a


def _remap(image: np.ndarray, at: np.ndarray, dst: np.ndarray) -> None:
    """``dst`` = ``image`` read at the pixels ``at`` (float32 ``(…, 2)`` whole numbers x, y), 0
    off the image (nearest neighbour, constant border: no separate bounds test)."""
    cv2.remap(image, at, None, cv2.INTER_NEAREST, dst=dst, borderMode=cv2.BORDER_CONSTANT,
              borderValue=0)


def search_edges(inputs: list[FitInput], gain: float, rel: np.ndarray, nrm: np.ndarray,
                 n: np.ndarray, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """Strongest edge along each normal, for ``A`` people at once
    (:func:`~.shape_tracker.search_normals`).

    ``rel``, ``nrm`` ``(A, K, 2)``: sample points in each person's window and unit normals;
    ``n`` ``(A,)``: search ``-n … n`` px. The inputs' ``gradients`` are ``(gx, gy)`` (only
    edges where the image falls going outwards count) or one edge-magnitude channel, times
    ``gain`` (a power of two). Returns ``offsets, strength`` ``(A, K)``.
    """
    a, k = rel.shape[:2]
    nmax = int(n.max())
    st, penalty = steps(nmax)
    if (n != nmax).any():
        # a person searching fewer steps never picks one beyond them
        penalty = np.where(np.abs(st) <= n[:, None], penalty, np.inf)[:, None, :]
    # x, y of every search point rounded to its pixel, made (2, A, K, S) (the long axis last
    # is several times quicker in NumPy) and written out as the (A, K, S, 2) maps cv2.remap
    # reads (whole numbers are exact in float32)
    at = np.empty((a, k, len(st), 2), np.float32)
    np.rint(rel.transpose(2, 0, 1)[..., None] + nrm.transpose(2, 0, 1)[..., None] * st,
            out=at.transpose(3, 0, 1, 2), casting="unsafe")
    first = inputs[0].gradients
    oriented = first.ndim == 3
    g = np.empty(at.shape if oriented else at.shape[:3], first.dtype)
    for i, inp in enumerate(inputs):
        _remap(inp.gradients, at[i], g[i])
    if oriented:
        # -((g gain) . n) as g . (-gain n): scaling by a power of two is exact, so the products
        # round as the one-person formula's do
        w = nrm * -gain
        vals = np.maximum(g[..., 0] * w[..., 0:1] + g[..., 1] * w[..., 1:2], 0.0)
    else:
        vals = g.astype(np.float64) if gain == 1.0 else g * gain
    # Prefer the nearer edge among equals: a tiny penalty on |offset|.
    j = np.argmax(vals - penalty, axis=2)
    strength = vals.reshape(a * k, -1)[_arange(a * k), j.reshape(-1)].reshape(a, k)
    off = st[j]
    weak = strength < threshold
    strength[weak] = 0.0
    off[weak] = 0.0
    return off, strength


def visible_points(inputs: list[FitInput], rel: np.ndarray, nrm: np.ndarray) -> np.ndarray:
    """Boolean ``(A, K)``: sample point k of person a (``rel``: in their window) is visible, i.e.
    its inside neighbour (2 px in from the outline along the normal) is foreground in their
    ``fg`` (every point of a person without one)."""
    inner = np.rint(rel - 2.0 * nrm).astype(np.float32)[:, :, None, :]
    vis = np.empty(inner.shape[:3], np.uint8)
    for i, inp in enumerate(inputs):
        if inp.fg is None:
            vis[i] = 1
        else:
            _remap(inp.fg, inner[i], vis[i])
    return vis[..., 0] > 0


# ---------------------------------------------------------------------- the fit
def fit_people(outlines: Outlines, pose: np.ndarray, b: np.ndarray, inputs: list[FitInput],
               gain: float, *, iterations: int, search: float, min_search: float,
               edge_threshold: float, min_support: float, max_tilt: float,
               max_scale_change: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Steps 2–3 of the shape tracker for ``A`` people at once (see
    :class:`~.shape_tracker.ShapeTrackerParams` for the parameters; ``max_tilt`` in radians).

    Each round places the outlines of poses ``(A, 4)`` and weights ``(A, t)``, searches
    ``±max(min_search, search × height)`` px along their normals in the person's window
    (``inputs``), keeps the found edges whose sample point is visible, and — for the people whose
    support is at least ``min_support`` — solves for a new pose and weights. A person drops out
    of the rounds when their support falls short or their pose degenerates.

    Returns ``(pose, b, support, visible)``: the fits, the fraction of each person's sample
    points that found an edge (and are visible) in their last round, and the visible fraction
    of their predicted outline.
    """
    pose, b = pose.copy(), b.copy()
    n_people, k = len(pose), outlines.k
    s0 = np.hypot(pose[:, 0], pose[:, 1])
    support = np.zeros(n_people)
    visible = np.ones(n_people)
    origins = np.array([inp.origin for inp in inputs]).reshape(-1, 2)
    masked = any(inp.fg is not None for inp in inputs)
    active = np.arange(n_people)
    for it in range(iterations):
        if not len(active):
            break
        ins = [inputs[i] for i in active]
        o = outlines.outlines(pose[active], b[active])
        ys = o.points[..., 1]
        half = np.maximum(min_search, search * (ys.max(axis=1) - ys.min(axis=1)))
        rel = o.points - origins[active][:, None, :]
        off, strength = search_edges(ins, gain, rel, o.normals, np.ceil(half).astype(np.int64),
                                     edge_threshold)
        found = strength > 0
        if masked:
            vis = visible_points(ins, rel, o.normals)
            if it == 0:
                visible[active] = np.count_nonzero(vis, axis=1) / k
            found &= vis
        sup = np.count_nonzero(found, axis=1) / k
        support[active] = sup
        go = np.flatnonzero(sup >= min_support)
        if not len(go):
            break
        target = o.points[go] + off[go][..., None] * o.normals[go]
        new_pose, new_b, ok = outlines.solve(b[active[go]], o.shape[go], target, strength[go],
                                             found[go], s0[active[go]], max_tilt,
                                             max_scale_change)
        active = active[go][ok]
        pose[active] = new_pose[ok]
        b[active] = new_b[ok]
    return pose, b, support, visible
