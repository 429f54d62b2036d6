"""Closed uniform cubic B-splines: evaluation, normals, least-squares fit to an outline.

A closed uniform cubic B-spline with ``N`` control points ``C_0 .. C_{N-1}`` is parametrised by
``t`` in ``[0, N)``; on segment ``i = floor(t)`` with local parameter ``u = t - i``

    r(t) = b0(u) C_{i-1} + b1(u) C_i + b2(u) C_{i+1} + b3(u) C_{i+2}      (indices mod N)

with the uniform cubic basis ``b0 = (1-u)^3/6``, ``b1 = (3u^3 - 6u^2 + 4)/6``,
``b2 = (-3u^3 + 3u^2 + 3u + 1)/6``, ``b3 = u^3/6`` (Bartels, Beatty & Barsky, *An Introduction to
Splines for use in Computer Graphics and Geometric Modeling*, 1987, ch. 4; Baumberg & Hogg 1995
and Siebel's thesis, section 2.3, use the same closed cubic B-spline for pedestrian outlines).

Since ``r`` is linear in the control points, evaluating at ``K`` parameters is a matrix product
``r = B @ C`` with ``B`` of shape ``(K, N)`` (:func:`basis_matrix`); a least-squares fit of control
points to outline points is then ``C = lstsq(B, points)`` (:func:`fit_closed`).

Coordinates are image pixels ``(x, y)`` with ``y`` pointing down; all arrays are ``float64``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "basis_matrix",
    "uniform_params",
    "evaluate",
    "tangents",
    "normals",
    "signed_area",
    "arc_length_params",
    "fit_closed",
]


def _check_n(n: int) -> int:
    n = int(n)
    if n < 4:
        raise ValueError(f"a closed cubic B-spline needs at least 4 control points, got {n}")
    return n


def basis_matrix(t: np.ndarray, n: int, derivative: int = 0) -> np.ndarray:
    """Matrix ``B`` with ``r(t) = B @ C`` for a closed uniform cubic B-spline.

    Parameters
    ----------
    t : (K,) array of float
        Curve parameters; taken modulo ``n`` (one turn = ``n``).
    n : int
        Number of control points (>= 4).
    derivative : {0, 1}
        0 for positions, 1 for ``dr/dt``.

    Returns
    -------
    (K, n) float64
        Each row holds the four non-zero basis weights of one parameter (rows sum to 1 for
        ``derivative=0`` and to 0 for ``derivative=1``).
    """
    n = _check_n(n)
    t = np.mod(np.asarray(t, dtype=np.float64).reshape(-1), n)
    k = len(t)
    seg = np.floor(t).astype(np.int64)
    seg[seg >= n] = n - 1  # guards t == n after rounding
    u = t - seg
    if derivative == 0:
        w = np.stack([(1 - u) ** 3 / 6.0,
                      (3 * u ** 3 - 6 * u ** 2 + 4) / 6.0,
                      (-3 * u ** 3 + 3 * u ** 2 + 3 * u + 1) / 6.0,
                      u ** 3 / 6.0], axis=1)
    elif derivative == 1:
        w = np.stack([-((1 - u) ** 2) / 2.0,
                      (3 * u ** 2 - 4 * u) / 2.0,
                      (-3 * u ** 2 + 2 * u + 1) / 2.0,
                      u ** 2 / 2.0], axis=1)
    else:
        raise ValueError(f"derivative must be 0 or 1, got {derivative}")
    B = np.zeros((k, n), dtype=np.float64)
    rows = np.repeat(np.arange(k), 4)
    cols = (seg[:, None] + np.arange(-1, 3)[None, :]) % n
    # np.add.at: with n == 4 no column repeats, but keep it exact in general.
    np.add.at(B, (rows, cols.reshape(-1)), w.reshape(-1))
    return B


def uniform_params(n: int, k: int) -> np.ndarray:
    """``k`` equally spaced parameters over one turn of an ``n``-point spline, ``(k,) float64``."""
    n = _check_n(n)
    return np.arange(int(k), dtype=np.float64) * (n / max(int(k), 1))


def _as_points(c: np.ndarray) -> np.ndarray:
    c = np.asarray(c, dtype=np.float64)
    if c.ndim != 2 or c.shape[1] != 2:
        raise ValueError(f"control points must have shape (N, 2), got {c.shape}")
    return c


def evaluate(control: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Curve points ``(K, 2)`` at parameters ``t`` ``(K,)`` for control points ``(N, 2)``."""
    c = _as_points(control)
    return basis_matrix(t, len(c)) @ c


def tangents(control: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Derivatives ``dr/dt`` ``(K, 2)`` (pixels per unit parameter)."""
    c = _as_points(control)
    return basis_matrix(t, len(c), derivative=1) @ c


def signed_area(points: np.ndarray) -> float:
    """Shoelace area of a closed polygon ``(M, 2)`` (pixels²).

    Positive when the outward normal is the direction of travel ``(dx, dy)`` turned to
    ``(dy, -dx)`` (the usual counter-clockwise test in the ``(x, y)`` plane; with ``y`` drawn
    downwards this is clockwise on screen).
    """
    p = np.asarray(points, dtype=np.float64)
    if len(p) < 3:
        return 0.0
    x, y = p[:, 0], p[:, 1]
    # np.roll(v, -1), without its generic axis handling (a tenth of the cost on short outlines)
    return 0.5 * float(np.dot(x, np.concatenate((y[1:], y[:1])))
                       - np.dot(np.concatenate((x[1:], x[:1])), y))


def normals(control: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Unit outward normals ``(K, 2)`` at parameters ``t``.

    The normal is the tangent rotated by 90° and oriented away from the enclosed area (sign from
    the control polygon's shoelace area). A zero tangent gives a zero normal.
    """
    c = _as_points(control)
    d = tangents(c, t)
    nrm = np.stack([d[:, 1], -d[:, 0]], axis=1)
    length = np.linalg.norm(nrm, axis=1, keepdims=True)
    out = np.divide(nrm, length, out=np.zeros_like(nrm), where=length > 0)
    return out if signed_area(c) >= 0 else -out


def arc_length_params(points: np.ndarray, n: int) -> np.ndarray:
    """Spline parameters ``(M,)`` in ``[0, n)`` proportional to the arc length along a closed outline.

    The first point gets ``t = 0``; the closing segment back to it counts towards the length.
    """
    n = _check_n(n)
    p = np.asarray(points, dtype=np.float64)
    if len(p) == 0:
        return np.zeros(0)
    seg = np.linalg.norm(np.diff(np.vstack([p, p[:1]]), axis=0), axis=1)
    total = float(seg.sum())
    if total <= 0:
        return np.zeros(len(p))
    return n * np.concatenate([[0.0], np.cumsum(seg[:-1])]) / total


def fit_closed(points: np.ndarray, n: int, t: np.ndarray | None = None) -> np.ndarray:
    """Least-squares control points ``(n, 2)`` of a closed cubic B-spline through an outline.

    Parameters
    ----------
    points : (M, 2) float
        Ordered outline points (M >= n), pixels.
    n : int
        Number of control points.
    t : (M,) float, optional
        Parameters of the points; default :func:`arc_length_params` (uniform speed from the first
        point, which becomes ``t = 0``).

    Returns
    -------
    (n, 2) float64
        Minimises ``sum_j |B(t_j) C - p_j|^2`` (normal equations solved by ``numpy.linalg.lstsq``).
    """
    n = _check_n(n)
    p = _as_points(points)
    if len(p) < n:
        raise ValueError(f"need at least {n} outline points to fit {n} control points, got {len(p)}")
    if t is None:
        t = arc_length_params(p, n)
    B = basis_matrix(t, n)
    c, *_ = np.linalg.lstsq(B, p, rcond=None)
    return c
