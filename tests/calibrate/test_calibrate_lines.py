"""The thesis' line method: κ1 by straightening, sub-pixel line refinement, coplanar Tsai fit."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from motiontrack.calibrate.lines import (SensorGeometry, estimate_kappa1, fit_coplanar_tsai,
                                         intersect_grid, refine_line_points, render_grid,
                                         straightness_cost)
from motiontrack.calibrate.tsai import TsaiCamera, rotation_to_tsai_angles
from motiontrack.errors import InputError

XS = np.arange(0.0, 9.0)   # world grid lines X = const (metres)
YS = np.arange(0.0, 8.0)   # world grid lines Y = const


def synthetic_camera(kappa1: float = 0.012) -> TsaiCamera:
    """A camera 7 m above the ground at (4, -5) m looking at (4, 3.5, 0) m; 7.5 µm pixels."""
    C = np.array([4.0, -5.0, 7.0])
    z = np.array([4.0, 3.5, 0.0]) - C
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(z, x), z])
    rx, ry, rz = rotation_to_tsai_angles(R)
    tx, ty, tz = -R @ (C * 1000.0)
    return TsaiCamera(768, 576, 768, 768, 0.0075, 0.0075, 0.0075, 0.0075, 4.5, kappa1, 390.0, 280.0,
                      1.0, tx, ty, tz, rx, ry, rz)


def exact_lines(cam, n=30):
    t = np.linspace(0, 1, n)
    xl = [cam.world_to_image(np.column_stack([np.full(n, x), -0.3 + 7.6 * t])) for x in XS]
    yl = [cam.world_to_image(np.column_stack([-0.3 + 8.6 * t, np.full(n, y)])) for y in YS]
    return xl, yl


@pytest.mark.parametrize("kappa1", [0.0, 0.012, 0.03, -0.01])
def test_kappa1_from_exact_lines_with_noise(kappa1):
    cam = synthetic_camera(kappa1)
    geom = SensorGeometry.from_camera(cam)
    rng = np.random.default_rng(7)
    xl, yl = exact_lines(cam)
    noisy = [p + rng.normal(0, 0.05, p.shape) for p in xl + yl]
    k, cost = estimate_kappa1(noisy, geom)
    assert k == pytest.approx(kappa1, abs=0.0005)
    assert cost < 0.06  # ~ the 0.05 px noise


def test_straightness_cost_zero_at_true_kappa():
    cam = synthetic_camera(0.02)
    geom = SensorGeometry.from_camera(cam)
    xl, yl = exact_lines(cam)
    assert straightness_cost(xl + yl, 0.02, geom) < 1e-9
    assert straightness_cost(xl + yl, 0.0, geom) > 0.5
    assert straightness_cost([], 0.0, geom) == 0.0


@pytest.mark.parametrize("x_true, mode, polarity", [
    (50.3, "ridge", "dark"),
    (61.75, "ridge", "bright"),
])
def test_refine_ridge_subpixel(x_true, mode, polarity):
    img = np.full((100, 120), 200 if polarity == "dark" else 30, np.uint8)
    val = 20 if polarity == "dark" else 220
    cv2.line(img, (round(x_true * 16), 0), (round(x_true * 16), 99 * 16), val, 2, cv2.LINE_AA, shift=4)
    rough = np.array([[x_true + 3.0, 10.0], [x_true - 2.0, 90.0]])   # off by a few pixels
    pts = refine_line_points(img, rough, half_width=6, mode=mode, polarity=polarity)
    assert len(pts) >= 30
    assert np.abs(np.median(pts[:, 0]) - x_true) < 0.15


def test_refine_step_edge():
    img = np.zeros((80, 80), np.float32)
    img[:, 40:] = 200.0  # edge between pixels 39 and 40, i.e. at x = 39.5
    pts = refine_line_points(img, np.array([[42.0, 5.0], [37.0, 75.0]]), mode="edge")
    assert np.abs(pts[:, 0] - 39.5).max() < 0.05


def test_refine_degenerate_inputs():
    img = np.zeros((20, 20), np.uint8)
    assert refine_line_points(img, np.zeros((1, 2))).shape == (0, 2)
    with pytest.raises(ValueError, match="mode"):
        refine_line_points(img, np.zeros((2, 2)), mode="blob")
    with pytest.raises(InputError):
        estimate_kappa1([np.zeros((2, 2))], SensorGeometry.default(20, 20))


def test_intersections_of_exact_lines():
    cam = synthetic_camera(0.012)
    geom = SensorGeometry.from_camera(cam)
    xl, yl = exact_lines(cam)
    pts = intersect_grid(xl, yl, cam.kappa1, geom)
    W = np.stack(np.meshgrid(XS, YS, indexing="ij"), -1).reshape(-1, 2)
    np.testing.assert_allclose(pts.reshape(-1, 2), cam.world_to_image(W), atol=1e-6)


def test_whole_thesis_method_on_rendered_grid():
    """Render distorted grid lines, refine from rough κ1 = 0 predictions, straighten, intersect,
    fit: κ1 and f come back."""
    cam = synthetic_camera(0.012)
    img = render_grid(cam, XS, YS, (-0.5, 8.5, -0.5, 7.5))
    geom = SensorGeometry.from_camera(cam)
    rough_cam = replace(cam, kappa1=0.0)
    t = np.linspace(0, 1, 12)
    xl = [refine_line_points(img, rough_cam.world_to_image(
        np.column_stack([np.full_like(t, x), -0.3 + 7.6 * t])), half_width=8) for x in XS]
    yl = [refine_line_points(img, rough_cam.world_to_image(
        np.column_stack([-0.3 + 8.6 * t, np.full_like(t, y)])), half_width=8) for y in YS]
    k, cost = estimate_kappa1(xl + yl, geom)
    assert k == pytest.approx(0.012, rel=0.03)          # measured 0.01189
    corners = intersect_grid(xl, yl, k, geom).reshape(-1, 2)
    W = np.stack(np.meshgrid(XS, YS, indexing="ij"), -1).reshape(-1, 2)
    assert np.abs(corners - cam.world_to_image(W)).max() < 0.3  # measured 0.14 px
    fit = fit_coplanar_tsai(corners, W * 1000.0, geom, kappa1=k)
    c = fit.camera
    assert fit.rms < 0.1                                 # measured 0.041 px
    assert c.focal == pytest.approx(4.5, rel=0.01)       # measured 4.501 mm
    assert c.kappa1 == pytest.approx(0.012, rel=0.02)    # measured 0.01203
    np.testing.assert_allclose(c.center, cam.center, atol=0.05)


def test_coplanar_fit_exact_points_with_centre():
    cam = synthetic_camera(0.01)
    W = np.stack(np.meshgrid(XS, YS, indexing="ij"), -1).reshape(-1, 2)
    px = cam.world_to_image(W)
    geom = replace(SensorGeometry.from_camera(cam), cx=380.0, cy=290.0)  # centre off by 10 px
    fit = fit_coplanar_tsai(px, W * 1000.0, geom, kappa1=0.0, fit_center=True)
    assert fit.rms < 1e-3
    assert fit.camera.focal == pytest.approx(4.5, rel=1e-3)
    assert fit.camera.kappa1 == pytest.approx(0.01, rel=1e-2)


def test_coplanar_fit_needs_points():
    geom = SensorGeometry.default(100, 100)
    with pytest.raises(InputError, match="at least 5"):
        fit_coplanar_tsai(np.zeros((3, 2)), np.zeros((3, 2)), geom)
