"""Closed uniform cubic B-splines: basis, evaluation, normals, least-squares fit."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.people import bspline


@pytest.mark.parametrize("n", [4, 7, 16, 32])
def test_basis_rows_sum_to_one_and_derivative_rows_to_zero(n):
    t = np.linspace(0, n, 101)
    assert np.allclose(bspline.basis_matrix(t, n).sum(axis=1), 1.0)
    assert np.allclose(bspline.basis_matrix(t, n, derivative=1).sum(axis=1), 0.0)


def test_basis_at_knot_is_one_sixth_two_thirds_one_sixth():
    # At u = 0 the cubic basis is (1/6, 4/6, 1/6, 0) on C_{i-1}, C_i, C_{i+1}, C_{i+2}.
    B = bspline.basis_matrix(np.array([0.0, 2.0]), 5)
    assert np.allclose(B[0], [4 / 6, 1 / 6, 0, 0, 1 / 6])
    assert np.allclose(B[1], [0, 1 / 6, 4 / 6, 1 / 6, 0])


def test_periodic_parameter():
    n = 6
    t = np.array([0.3, 2.7])
    assert np.allclose(bspline.basis_matrix(t, n), bspline.basis_matrix(t + n, n))


def test_square_control_polygon_evaluates_to_known_points():
    # Square control points: at a knot, r = (C_{i-1} + 4 C_i + C_{i+1}) / 6.
    c = np.array([[0.0, 0.0], [6.0, 0.0], [6.0, 6.0], [0.0, 6.0]])
    r = bspline.evaluate(c, np.array([1.0]))
    assert np.allclose(r, [[(0 + 4 * 6 + 6) / 6, (0 + 0 + 6) / 6]])


@pytest.mark.parametrize(
    "a, b, n, tol",
    [
        (30.0, 30.0, 12, 0.05),   # circle
        (20.0, 45.0, 16, 0.05),   # upright ellipse (person-like aspect)
        (50.0, 10.0, 24, 0.05),   # flat ellipse
    ],
)
def test_least_squares_fit_of_sampled_ellipse_reproduces_it(a, b, n, tol):
    theta = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    pts = np.stack([100 + a * np.cos(theta), 80 + b * np.sin(theta)], axis=1)
    c = bspline.fit_closed(pts, n)
    assert c.shape == (n, 2)
    t = bspline.arc_length_params(pts, n)
    back = bspline.evaluate(c, t)
    err = np.linalg.norm(back - pts, axis=1)
    assert err.max() < tol * min(a, b)
    # and the fitted curve stays on the ellipse at new parameters too
    dense = bspline.evaluate(c, np.linspace(0, n, 1000, endpoint=False))
    radial = ((dense[:, 0] - 100) / a) ** 2 + ((dense[:, 1] - 80) / b) ** 2
    assert np.abs(np.sqrt(radial) - 1).max() < tol


def test_normals_point_outwards_for_both_orientations():
    theta = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    circle = np.stack([50 + 20 * np.cos(theta), 40 + 20 * np.sin(theta)], axis=1)
    for pts in (circle, circle[::-1]):
        c = bspline.fit_closed(pts, 12)
        t = np.linspace(0, 12, 24, endpoint=False)
        p = bspline.evaluate(c, t)
        nrm = bspline.normals(c, t)
        radial = (p - [50, 40]) / np.linalg.norm(p - [50, 40], axis=1, keepdims=True)
        assert np.allclose(np.linalg.norm(nrm, axis=1), 1.0)
        assert (np.sum(nrm * radial, axis=1) > 0.99).all()


def test_signed_area_of_unit_square():
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    assert bspline.signed_area(sq) == pytest.approx(1.0)
    assert bspline.signed_area(sq[::-1]) == pytest.approx(-1.0)
    assert bspline.signed_area(np.zeros((0, 2))) == 0.0


@pytest.mark.parametrize("bad", [3, 0])
def test_too_few_control_points_rejected(bad):
    with pytest.raises(ValueError, match="at least 4"):
        bspline.basis_matrix(np.zeros(3), bad)


def test_fit_needs_enough_points_and_handles_empty_params():
    with pytest.raises(ValueError, match="at least 8"):
        bspline.fit_closed(np.zeros((5, 2)), 8)
    assert bspline.arc_length_params(np.zeros((0, 2)), 8).shape == (0,)
    assert bspline.evaluate(np.zeros((4, 2)), np.zeros(0)).shape == (0, 2)
