"""The thesis' calibration method: κ1 from straight lines, sub-pixel grid lines, coplanar Tsai fit.

Steps (thesis §2.1, figures 2.3 and 2.5):

1. **Sub-pixel lines** (figure 2.5): starting from rough points on each grid line (clicked or
   predicted), sample the image along the local normal of the line, find the extremum of the
   profile (the dark/bright line centre, ``mode="ridge"``, or the strongest gradient,
   ``mode="edge"``), and take the centroid of the peak above the profile's baseline as the sub-pixel
   position.
2. **κ1 by straightening** (figure 2.3): lines that are straight in the world are straight in the
   undistorted image. For a trial κ1 every point is undistorted (Tsai eq. 3,
   ``Xu = Xd (1 + κ1 r²)``) and a total-least-squares line is fitted to each line's points; the cost is
   the RMS perpendicular distance (in pixels). A step-halving search walks κ1 downhill: try
   ``κ ± step``; move where the cost drops, otherwise halve the step; stop when the step is below
   ``tol``.
3. **Intersections**: each undistorted line is fitted again and the grid corners are the
   intersections of the "x = const" lines with the "y = const" lines (homogeneous cross products),
   then distorted back to pixels.
4. **Coplanar Tsai fit**: with the sensor geometry (dpx, dpy, sx) fixed, the focal length ``f``, κ1,
   the angles ``rx, ry, rz`` and ``T`` (and optionally ``Cx, Cy``) minimise the pixel reprojection
   error of the corners with Levenberg–Marquardt (``scipy.optimize.least_squares(method="lm")``,
   Tsai 1987 §III stage 2 does the same non-linear refinement). The start values come from a
   planar homography calibration (Zhang 2000, via ``cv2.calibrateCamera`` on the one view,
   principal point and aspect ratio fixed) instead of Tsai's linear RAC stage.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Sequence

import cv2
import numpy as np
from scipy.optimize import least_squares

from ..errors import InputError
from .tsai import (TsaiCamera, distort_sensor, rotation_to_tsai_angles, tsai_rotation,
                   undistort_sensor)

log = logging.getLogger(__name__)

__all__ = [
    "SensorGeometry",
    "straightness_cost",
    "estimate_kappa1",
    "refine_line_points",
    "intersect_grid",
    "fit_coplanar_tsai",
    "render_grid",
    "CoplanarFit",
]


@dataclass(frozen=True)
class SensorGeometry:
    """Fixed sensor geometry for the line method (PETS ``<Geometry>`` plus ``Cx, Cy, sx``).

    ``dpx, dpy`` in mm; ``cx, cy`` pixels. κ1 is estimated in 1/mm² of this sensor.
    """

    width: int
    height: int
    ncx: float
    nfx: float
    dx: float
    dy: float
    dpx: float
    dpy: float
    cx: float
    cy: float
    sx: float = 1.0

    def __post_init__(self) -> None:
        for n in ("width", "height", "dpx", "dpy", "sx"):
            if not getattr(self, n) > 0:
                raise ValueError(f"sensor geometry {n} must be > 0, got {getattr(self, n)}")

    @classmethod
    def default(cls, width: int, height: int, pixel_mm: float = 0.01) -> "SensorGeometry":
        """Square pixels of ``pixel_mm``, principal point at the image centre."""
        return cls(width, height, width, width, pixel_mm, pixel_mm, pixel_mm, pixel_mm,
                   (width - 1) / 2.0, (height - 1) / 2.0, 1.0)

    @classmethod
    def from_camera(cls, cam: TsaiCamera) -> "SensorGeometry":
        return cls(cam.width, cam.height, cam.ncx, cam.nfx, cam.dx, cam.dy, cam.dpx, cam.dpy,
                   cam.cx, cam.cy, cam.sx)

    def to_sensor(self, px: np.ndarray) -> np.ndarray:
        return np.stack([self.dpx * (px[:, 0] - self.cx) / self.sx, self.dpy * (px[:, 1] - self.cy)], 1)

    def to_pixels(self, s: np.ndarray) -> np.ndarray:
        return np.stack([s[:, 0] * self.sx / self.dpx + self.cx, s[:, 1] / self.dpy + self.cy], 1)

    def undistort_pixels(self, px: np.ndarray, kappa1: float) -> np.ndarray:
        """Distorted → undistorted pixels (Tsai eq. 3 in sensor units)."""
        s = self.to_sensor(np.asarray(px, dtype=np.float64).reshape(-1, 2))
        xu, yu = undistort_sensor(s[:, 0], s[:, 1], kappa1)
        return self.to_pixels(np.stack([xu, yu], 1))

    def distort_pixels(self, px: np.ndarray, kappa1: float) -> np.ndarray:
        s = self.to_sensor(np.asarray(px, dtype=np.float64).reshape(-1, 2))
        xd, yd = distort_sensor(s[:, 0], s[:, 1], kappa1)
        return self.to_pixels(np.stack([xd, yd], 1))


def _tls_line(pts: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """Total least squares line: (unit normal n, offset c with n·p = c, residuals)."""
    mu = pts.mean(axis=0)
    _, _, vt = np.linalg.svd(pts - mu, full_matrices=False)
    n = vt[-1]
    c = float(n @ mu)
    return n, c, pts @ n - c


def straightness_cost(lines: Sequence[np.ndarray], kappa1: float, geom: SensorGeometry) -> float:
    """RMS distance (pixels) of undistorted points from their best straight lines.

    Parameters
    ----------
    lines : sequence of (M_i, 2) float arrays, distorted pixels, M_i >= 3.
    """
    res = []
    for pts in lines:
        u = geom.undistort_pixels(pts, kappa1)
        res.append(_tls_line(u)[2])
    if not res:
        return 0.0
    r = np.concatenate(res)
    return float(np.sqrt(np.mean(r * r)))


def estimate_kappa1(lines: Sequence[np.ndarray], geom: SensorGeometry, kappa0: float = 0.0,
                    step: float | None = None, tol: float | None = None,
                    max_iter: int = 2000) -> tuple[float, float]:
    """Step-halving search for κ1 that makes the lines straightest (thesis figure 2.3).

    Parameters
    ----------
    lines : sequence of (M_i, 2) distorted pixel points, one array per world-straight line.
    geom : sensor geometry (sets the units of κ1, 1/mm²).
    step : initial step; default ``0.1 / r_max²`` (r_max = sensor half-diagonal, mm), i.e. a 10 %
        radial change at the corner.
    tol : stop when the step is below this; default ``step * 1e-7``.

    Returns
    -------
    (kappa1, cost) : float, float (cost = RMS straightness error in pixels).
    """
    lines = [np.asarray(p, dtype=np.float64).reshape(-1, 2) for p in lines]
    lines = [p for p in lines if len(p) >= 3]
    if not lines:
        raise InputError("κ1 estimation needs at least one line with 3 or more points")
    if step is None:
        rmax2 = (geom.width * geom.dpx / 2) ** 2 + (geom.height * geom.dpy / 2) ** 2
        step = 0.1 / rmax2
    tol = step * 1e-7 if tol is None else tol
    k = float(kappa0)
    cost = straightness_cost(lines, k, geom)
    it = 0
    while step > tol and it < max_iter:
        it += 1
        moved = False
        for cand in (k + step, k - step):
            c = straightness_cost(lines, cand, geom)
            if c < cost:
                k, cost, moved = cand, c, True
                break
        if not moved:
            step /= 2.0
    log.debug("kappa1 search: %d iterations, kappa1=%g, cost=%g px", it, k, cost)
    return k, cost


def _bilinear(gray: np.ndarray, xy: np.ndarray) -> np.ndarray:
    m = xy.astype(np.float32)
    return cv2.remap(gray, m[..., 0], m[..., 1], interpolation=cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REPLICATE)


def refine_line_points(gray: np.ndarray, points: np.ndarray, half_width: float = 6.0,
                       samples: int = 40, mode: str = "ridge", polarity: str = "dark",
                       step: float = 0.25, min_contrast: float = 0.5) -> np.ndarray:
    """Move rough points of one line onto the sub-pixel line centre / edge (thesis figure 2.5).

    Parameters
    ----------
    gray : (H, W) uint8 or float image.
    points : (M, 2) rough pixel points along one line (in order, M >= 2).
    half_width : search distance along the normal (pixels).
    samples : number of points to return, spread evenly along the polyline through ``points``.
    mode : ``"ridge"`` (extremum of intensity: a thin painted line) or ``"edge"`` (extremum of the
        derivative along the normal: a step edge).
    polarity : ``"dark"`` or ``"bright"`` line (ridge), or edge sign ignored (edge: largest |grad|).
    step : sampling step along the normal (pixels).
    min_contrast : keep a point only when its profile's peak stands above both ends by at least
        this fraction of the median such contrast along the line.

    Returns
    -------
    (K, 2) float64 refined points (points whose profile has no interior extremum are dropped).
    """
    if mode not in ("ridge", "edge"):
        raise ValueError(f"mode must be 'ridge' or 'edge', got {mode!r}")
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(pts) < 2:
        return np.zeros((0, 2))
    g = gray.astype(np.float32)
    if g.ndim == 3:
        g = cv2.cvtColor(g, cv2.COLOR_BGR2GRAY)
    g = cv2.GaussianBlur(g, (0, 0), 1.0)
    p, normal = _resample(pts, samples)
    offs = np.arange(-half_width, half_width + step / 2, step)
    prof = _normal_profiles(g, p, normal, offs, step, mode, polarity)
    # a clean profile has one extremum well above both ends; where another line crosses, the
    # profile runs along that line and is flat, so such points are dropped
    peak = prof.max(axis=1)
    contrast = peak - np.maximum(prof[:, 0], prof[:, -1])
    good = contrast > min_contrast * np.median(contrast) if len(contrast) else contrast > 0
    out = []
    for k in range(len(p)):
        j = int(np.argmax(prof[k]))
        if j == 0 or j == len(offs) - 1 or not good[k]:
            continue
        shift = _peak_offset(prof[k], j, offs)
        if shift is not None:
            out.append(p[k] + shift * normal[k])
    return _drop_outliers(np.asarray(out).reshape(-1, 2))


def _resample(pts: np.ndarray, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """``samples`` points spread evenly along the polyline ``pts``, and the unit normal at each
    (from the local segment direction)."""
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    s = np.concatenate([[0], np.cumsum(seg)])
    t = np.linspace(0, s[-1], samples)
    p = np.stack([np.interp(t, s, pts[:, 0]), np.interp(t, s, pts[:, 1])], 1)
    tangent = np.gradient(p, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    return p, np.stack([-tangent[:, 1], tangent[:, 0]], 1)


def _normal_profiles(g: np.ndarray, p: np.ndarray, normal: np.ndarray, offs: np.ndarray,
                     step: float, mode: str, polarity: str) -> np.ndarray:
    """(K, S) response sampled at ``offs`` along each point's normal, largest on the line: the
    intensity (negated for a dark line) or, for an edge, the derivative's magnitude."""
    grid = p[:, None, :] + offs[None, :, None] * normal[:, None, :]  # (K, S, 2)
    prof = _bilinear(g, grid).astype(np.float64)
    if mode == "edge":
        prof = np.abs(np.gradient(prof, step, axis=1))
    elif polarity == "dark":
        prof = -prof
    return prof


def _peak_offset(prof: np.ndarray, j: int, offs: np.ndarray) -> float | None:
    """Sub-pixel position along the normal of the peak at sample ``j``: the centroid of the
    profile above its baseline over the contiguous peak (unbiased for a symmetric line/edge
    response, unlike a parabola through interpolated samples, which is pulled towards pixel
    centres). None when nothing stands above the baseline."""
    w = prof - max(prof[0], prof[-1])
    lo = j
    while lo > 0 and w[lo - 1] > 0:
        lo -= 1
    hi = j
    while hi < len(w) - 1 and w[hi + 1] > 0:
        hi += 1
    ww = np.clip(w[lo:hi + 1], 0, None)
    if ww.sum() <= 0:
        return None
    return float(ww @ offs[lo:hi + 1] / ww.sum())


def _drop_outliers(pts: np.ndarray, rounds: int = 4, floor: float = 0.75) -> np.ndarray:
    """Drop points that jumped to a neighbouring line or a line end.

    A distorted straight line bends only slightly, so a parabola across the line fits it. The first
    fit uses the central half of the points (outliers gather at the ends, near other lines), later
    fits use the inliers; residuals above ``max(3 robust sigmas, floor)`` pixels are rejected.
    """
    if len(pts) < 6:
        return pts
    n, c, r = _tls_line(pts)
    u = pts @ np.array([n[1], -n[0]])
    u = u - np.median(u)
    q1, q3 = np.percentile(u, [25, 75])
    keep = (u >= q1) & (u <= q3)
    for _ in range(rounds):
        if keep.sum() < 3:
            return pts
        coef = np.polyfit(u[keep], r[keep], 2)
        e = r - np.polyval(coef, u)
        sigma = 1.4826 * np.median(np.abs(e[keep] - np.median(e[keep])))
        new = np.abs(e) <= max(3.0 * sigma, floor)
        if np.array_equal(new, keep):
            break
        keep = new
    return pts[keep]


def intersect_grid(xlines: Sequence[np.ndarray], ylines: Sequence[np.ndarray], kappa1: float,
                   geom: SensorGeometry) -> np.ndarray:
    """Intersections of every x-line with every y-line, as distorted pixels.

    Lines are fitted straight in the undistorted image (using ``kappa1``), intersected with
    homogeneous cross products, and the intersections are distorted back.

    Returns
    -------
    (len(xlines), len(ylines), 2) float64 pixels.
    """
    def hom(pts):
        n, c, _ = _tls_line(geom.undistort_pixels(pts, kappa1))
        return np.array([n[0], n[1], -c])

    hx = [hom(p) for p in xlines]
    hy = [hom(p) for p in ylines]
    out = np.full((len(hx), len(hy), 2), np.nan)
    for i, a in enumerate(hx):
        for j, b in enumerate(hy):
            q = np.cross(a, b)
            if abs(q[2]) > 1e-12:
                out[i, j] = q[:2] / q[2]
    flat = out.reshape(-1, 2)
    ok = np.all(np.isfinite(flat), axis=1)
    flat[ok] = geom.distort_pixels(flat[ok], kappa1)
    return flat.reshape(out.shape)


@dataclass(frozen=True)
class CoplanarFit:
    """Result of :func:`fit_coplanar_tsai`: the camera and its RMS reprojection error (pixels)."""

    camera: TsaiCamera
    rms: float
    residuals: np.ndarray


def _project(params: np.ndarray, geom: SensorGeometry, world: np.ndarray, fit_center: bool):
    f, k1, rx, ry, rz, tx, ty, tz = params[:8]
    cx, cy = (params[8], params[9]) if fit_center else (geom.cx, geom.cy)
    pc = world @ tsai_rotation(rx, ry, rz).T + np.array([tx, ty, tz])
    xu = f * pc[:, 0] / pc[:, 2]
    yu = f * pc[:, 1] / pc[:, 2]
    xd, yd = distort_sensor(xu, yu, k1)
    return np.stack([xd * geom.sx / geom.dpx + cx, yd / geom.dpy + cy], 1)


def fit_coplanar_tsai(image_pts: np.ndarray, world_pts: np.ndarray, geom: SensorGeometry,
                      kappa1: float = 0.0, fit_center: bool = False) -> CoplanarFit:
    """Coplanar Tsai calibration by Levenberg–Marquardt.

    Parameters
    ----------
    image_pts : (N, 2) distorted pixels, N >= 5 (6+ recommended).
    world_pts : (N, 2) or (N, 3) world points on ``Z = 0``, in mm.
    geom : fixed sensor geometry (dpx, dpy, sx; Cx, Cy as start values or fixed).
    kappa1 : start value (e.g. from :func:`estimate_kappa1`).
    fit_center : also estimate ``Cx, Cy`` (poorly conditioned for a single plane).
    """
    img = np.asarray(image_pts, dtype=np.float64).reshape(-1, 2)
    W = np.asarray(world_pts, dtype=np.float64)
    W = W.reshape(len(img), -1) if len(img) else np.zeros((0, 3))
    if W.shape[1] == 2:
        W = np.hstack([W, np.zeros((len(W), 1))])
    if len(img) < 5:
        raise InputError(f"coplanar Tsai calibration needs at least 5 points, got {len(img)}")
    if np.any(W[:, 2] != 0):
        raise InputError("coplanar calibration needs world points with Z = 0")
    # start values: remove κ1, then a one-view planar calibration with fixed centre and aspect
    und = geom.undistort_pixels(img, kappa1).astype(np.float32)
    fy0 = max(geom.width, geom.height)
    aspect = geom.sx * geom.dpy / geom.dpx  # fx / fy in pixels
    K0 = np.array([[fy0 * aspect, 0, geom.cx], [0, fy0, geom.cy], [0, 0, 1]], dtype=np.float64)
    flags = (cv2.CALIB_USE_INTRINSIC_GUESS | cv2.CALIB_FIX_PRINCIPAL_POINT | cv2.CALIB_FIX_ASPECT_RATIO
             | cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K1 | cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3)
    try:
        _, K, _, rv, tv = cv2.calibrateCamera([W.astype(np.float32)], [und.reshape(-1, 1, 2)],
                                              (geom.width, geom.height), K0, np.zeros(5),
                                              flags=flags)
    except cv2.error:
        raise InputError(f"the {len(img)} grid points do not determine a camera (all on one "
                         "line, or world positions repeated?)") from None
    R, _ = cv2.Rodrigues(rv[0])
    rx, ry, rz = rotation_to_tsai_angles(R)
    f0 = K[1, 1] * geom.dpy
    x0 = [f0, kappa1, rx, ry, rz, *np.asarray(tv[0]).reshape(3)]
    if fit_center:
        x0 += [geom.cx, geom.cy]
    x0 = np.asarray(x0, dtype=np.float64)

    def resid(p):
        r = (_project(p, geom, W, fit_center) - img).ravel()
        return np.where(np.isfinite(r), r, 1e6)

    sol = least_squares(resid, x0, method="lm", x_scale="jac", max_nfev=5000)
    p = sol.x
    cx, cy = (p[8], p[9]) if fit_center else (geom.cx, geom.cy)
    try:
        cam = TsaiCamera(width=int(geom.width), height=int(geom.height), ncx=geom.ncx,
                         nfx=geom.nfx, dx=geom.dx, dy=geom.dy, dpx=geom.dpx, dpy=geom.dpy,
                         focal=float(p[0]), kappa1=float(p[1]), cx=float(cx), cy=float(cy),
                         sx=geom.sx, tx=float(p[5]), ty=float(p[6]), tz=float(p[7]),
                         rx=float(p[2]), ry=float(p[3]), rz=float(p[4]))
    except ValueError as exc:  # e.g. a negative focal length: the points fit no real camera
        raise InputError(f"the coplanar Tsai fit found no valid camera for these "
                         f"{len(img)} points ({exc})") from None
    r = sol.fun.reshape(-1, 2)
    return CoplanarFit(camera=cam, rms=float(np.sqrt(np.mean(np.sum(r * r, axis=1)))),
                       residuals=np.linalg.norm(r, axis=1))


def render_grid(cam: TsaiCamera, xs: Sequence[float], ys: Sequence[float], extent: tuple,
                thickness: int = 2) -> np.ndarray:
    """Synthetic (H, W) uint8 image of dark world grid lines ``X = xs`` and ``Y = ys`` (metres) on
    white, seen through ``cam`` (with its distortion). ``extent = (xmin, xmax, ymin, ymax)`` metres.
    """
    img = np.full((cam.height, cam.width), 255, np.uint8)
    x0, x1, y0, y1 = extent
    t = np.linspace(0, 1, 400)
    segs = [np.stack([np.full_like(t, x), y0 + (y1 - y0) * t], 1) for x in xs]
    segs += [np.stack([x0 + (x1 - x0) * t, np.full_like(t, y)], 1) for y in ys]
    for s in segs:
        px = cam.world_to_image(s)
        px = px[np.all(np.isfinite(px), axis=1)]
        cv2.polylines(img, [np.round(px * 16).astype(np.int32).reshape(-1, 1, 2)], False, 0,
                      thickness, cv2.LINE_AA, shift=4)
    return img


