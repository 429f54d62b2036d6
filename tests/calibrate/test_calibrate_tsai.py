"""Tsai camera model: rotation convention, distortion both ways, PETS 2009 View_001 evidence."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motiontrack.calibrate.camera import load_camera
from motiontrack.calibrate.measure import foot_points
from motiontrack.calibrate.tsai import (TsaiCamera, distort_sensor, read_tsai_toml, read_tsai_xml,
                                        rotation_to_tsai_angles, tsai_rotation, undistort_sensor,
                                        write_tsai_toml, write_tsai_xml)
from motiontrack.errors import InputError
from motiontrack.io.mot import read_mot


def simple_camera(**kw) -> TsaiCamera:
    """Looks straight down the world Z axis from 10 m: f = 10 mm, 0.01 mm pixels, centre (100, 100)."""
    p = dict(width=200, height=200, ncx=200, nfx=200, dx=0.01, dy=0.01, dpx=0.01, dpy=0.01,
             focal=10.0, kappa1=0.0, cx=100.0, cy=100.0, sx=1.0, tx=0.0, ty=0.0, tz=10000.0,
             rx=0.0, ry=0.0, rz=0.0)
    p.update(kw)
    return TsaiCamera(**p)


@pytest.mark.parametrize("angles, expected", [
    ((0.0, 0.0, 0.0), np.eye(3)),
    ((math.pi / 2, 0.0, 0.0), np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])),   # about x
    ((0.0, math.pi / 2, 0.0), np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]])),   # about y
    ((0.0, 0.0, math.pi / 2), np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]])),   # about z
])
def test_tsai_rotation_axes(angles, expected):
    np.testing.assert_allclose(tsai_rotation(*angles), expected, atol=1e-12)


def test_tsai_rotation_order_is_rz_ry_rx():
    rx, ry, rz = 0.3, -0.5, 1.1
    np.testing.assert_allclose(
        tsai_rotation(rx, ry, rz),
        tsai_rotation(0, 0, rz) @ tsai_rotation(0, ry, 0) @ tsai_rotation(rx, 0, 0), atol=1e-12)


@pytest.mark.parametrize("angles", [(0.3, -0.5, 1.1), (2.0405458695, -0.89337703748, -0.43056124791),
                                    (-3.0, 1.2, 2.9)])
def test_rotation_angles_round_trip(angles):
    R = tsai_rotation(*angles)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(tsai_rotation(*rotation_to_tsai_angles(R)), R, atol=1e-12)


@pytest.mark.parametrize("kappa1", [0.0, 1e-12, 5.1113e-3, 0.05, 3.0, -0.01])
def test_distortion_round_trip(kappa1):
    rng = np.random.default_rng(0)
    xd, yd = rng.uniform(-2, 2, (2, 50))
    xu, yu = undistort_sensor(xd, yd, kappa1)
    xd2, yd2 = distort_sensor(xu, yu, kappa1)
    np.testing.assert_allclose(np.stack([xd2, yd2]), np.stack([xd, yd]), atol=1e-12)


def test_distortion_handles_empty_and_centre():
    assert distort_sensor(np.zeros(0), np.zeros(0), 0.1)[0].shape == (0,)
    np.testing.assert_array_equal(np.stack(distort_sensor(np.zeros(1), np.zeros(1), 0.1)), 0.0)
    # kappa1 < 0: no distorted radius exists beyond ru = 2 / (3 sqrt(3 * 0.1)) = 1.217 mm
    xd, _ = distort_sensor(np.array([1.2, 1.3]), np.zeros(2), -0.1)
    assert np.isfinite(xd[0]) and np.isnan(xd[1])


@pytest.mark.parametrize("world, pixel", [
    ((0.0, 0.0), (100.0, 100.0)),
    # Xu = f X / Z = 10 * 1000 / 10000 = 1 mm -> Xf = 1 / 0.01 + 100
    ((1.0, 0.5), (1 / 0.01 + 100, 0.5 / 0.01 + 100)),
    ((-2.0, 1.0), (-2 / 0.01 + 100, 1 / 0.01 + 100)),
])
def test_hand_computed_projection(world, pixel):
    cam = simple_camera()
    np.testing.assert_allclose(cam.world_to_image(np.array([world])), [pixel], atol=1e-9)
    np.testing.assert_allclose(cam.image_to_world(np.array([pixel])), [world], atol=1e-12)


def test_sx_and_distortion_in_projection():
    # Xu = 1 mm; with kappa1 = 0.1: Xd (1 + 0.1 Xd²) = 1 -> Xd = 0.9216989942; Xf = sx Xd / dpx + Cx
    cam = simple_camera(kappa1=0.1, sx=1.2)
    xd = 0.9216989942
    assert xd * (1 + 0.1 * xd ** 2) == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(cam.world_to_image([[1.0, 0.0]]), [[1.2 * xd / 0.01 + 100, 100]],
                               atol=1e-6)


def test_empty_inputs_and_horizon():
    cam = simple_camera(rx=math.pi / 2)  # looks horizontally: upper half of the image is sky
    assert cam.world_to_image(np.zeros((0, 2))).shape == (0, 2)
    assert cam.image_to_world(np.zeros((0, 2))).shape == (0, 2)
    w = cam.image_to_world([[100.0, 10.0], [100.0, 190.0]])
    assert np.isnan(w[0]).all() != np.isnan(w[1]).all()  # exactly one of them is above the horizon


def test_invalid_parameters_rejected():
    with pytest.raises(ValueError, match="focal"):
        simple_camera(focal=-1.0)
    with pytest.raises(ValueError, match="finite"):
        simple_camera(tx=float("nan"))


@pytest.fixture
def pets(data):
    return read_tsai_xml(data("pets09-s2l1", "View_001.xml"))


@pytest.mark.data
def test_pets_xml_values(pets):
    assert (pets.width, pets.height) == (768, 576)
    assert pets.focal == pytest.approx(5.5549183034)
    assert pets.kappa1 == pytest.approx(5.1113043639e-03)
    assert pets.rx == pytest.approx(2.0405458695)


@pytest.mark.data
def test_pets_ground_truth_world_positions(pets, data):
    """Evidence: image -> world of every consider=1 box's bottom centre vs published metres."""
    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")
    gt = gt.select(gt.consider)
    assert len(gt) > 1000
    err = np.linalg.norm(pets.image_to_world(foot_points(gt.boxes)) - gt.world[:, :2], axis=1)
    assert np.median(err) < 0.15          # measured: 0.128 m
    assert np.percentile(err, 99) < 0.3   # measured: 0.257 m


@pytest.mark.data
def test_pets_round_trips(pets, data):
    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")
    w = gt.world[:, :2]
    back = pets.image_to_world(pets.world_to_image(w))
    assert np.abs(back - w).max() < 1e-6
    px = foot_points(gt.boxes)
    np.testing.assert_allclose(pets.world_to_image(pets.image_to_world(px)), px, atol=1e-6)


@pytest.mark.data
def test_pets_camera_above_ground(pets):
    assert pets.center[2] > 2.0  # metres above the ground plane


@pytest.mark.data
def test_xml_and_toml_round_trip(pets, tmp_path):
    write_tsai_xml(pets, tmp_path / "cam.xml")
    write_tsai_toml(pets, tmp_path / "cam.toml")
    for cam in (read_tsai_xml(tmp_path / "cam.xml"), read_tsai_toml(tmp_path / "cam.toml"),
                load_camera(tmp_path / "cam.toml"), load_camera(tmp_path / "cam.xml")):
        for name, v in pets.to_dict().items():
            assert getattr(cam, name) == pytest.approx(v, rel=1e-9), name


@pytest.mark.parametrize("text, message", [
    ("<Camera>", "malformed"),
    ("<Camera><Geometry/></Camera>", "no attribute 'width'"),
    ("<Camera></Camera>", "missing <Geometry>"),
])
def test_malformed_xml(tmp_path, text, message):
    p = tmp_path / "bad.xml"
    p.write_text(text)
    with pytest.raises(InputError, match=message):
        load_camera(p)


@pytest.mark.parametrize("name, text, message", [
    ("missing.xml", None, "not found"),
    ("bad.toml", "model = [", "malformed camera TOML"),
    ("bad2.toml", 'model = "fisheye"', "model must be"),
    ("cam.txt", "x", "unknown camera file type"),
])
def test_load_camera_errors(tmp_path, name, text, message):
    p = tmp_path / name
    if text is not None:
        p.write_text(text)
    with pytest.raises(InputError, match=message):
        load_camera(p)
