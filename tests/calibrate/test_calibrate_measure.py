"""Ground homography, world positions, per-track speed / path length / height."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motiontrack.calibrate.camera import load_camera
from motiontrack.calibrate.ground import (GroundHomography, fit_homography, read_ground_toml,
                                          read_point_pairs, write_ground_toml)
from motiontrack.calibrate.measure import (box_heights, foot_points, track_measurements,
                                           world_positions)
from motiontrack.calibrate.tsai import read_tsai_xml
from motiontrack.errors import ConfigError, InputError

# 1 pixel = 1 cm on the ground, image origin at world (-2, -1) m
SCALE = GroundHomography(H=np.array([[0.01, 0, -2.0], [0, 0.01, -1.0], [0, 0, 1]]))


@pytest.mark.parametrize("pixel, world", [
    ((0.0, 0.0), (-2.0, -1.0)),
    ((200.0, 100.0), (200 * 0.01 - 2, 100 * 0.01 - 1)),
    ((50.0, 350.0), (0.5 - 2, 3.5 - 1)),
])
def test_homography_maps_both_ways(pixel, world):
    np.testing.assert_allclose(SCALE.image_to_world([pixel]), [world], atol=1e-12)
    np.testing.assert_allclose(SCALE.world_to_image([world]), [pixel], atol=1e-9)


def test_homography_rejects_heights_and_handles_empty():
    with pytest.raises(ConfigError, match="Z = 0"):
        SCALE.world_to_image([[0.0, 0.0, 1.0]])
    assert SCALE.image_to_world(np.zeros((0, 2))).shape == (0, 2)
    assert SCALE.world_to_image(np.zeros((0, 2))).shape == (0, 2)


def test_fit_homography_from_pairs_and_toml(tmp_path):
    rng = np.random.default_rng(3)
    img = rng.uniform(0, 700, (8, 2))
    world = SCALE.image_to_world(img)
    g = fit_homography(img, world, size=(768, 576))
    assert g.rms < 1e-6  # metres (OpenCV's DLT + refinement, measured 9e-8)
    np.testing.assert_allclose(g.H, SCALE.H, atol=1e-6)
    write_ground_toml(g, tmp_path / "ground.toml")
    for g2 in (read_ground_toml(tmp_path / "ground.toml"), load_camera(tmp_path / "ground.toml")):
        np.testing.assert_allclose(g2.H, g.H)
        assert g2.size == (768, 576)


def test_fit_homography_needs_four_pairs():
    with pytest.raises(InputError, match="at least 4"):
        fit_homography(np.zeros((3, 2)), np.zeros((3, 2)))


@pytest.mark.parametrize("text, message", [
    ("u,v,x,y\n1,2,3\n", "expected 4"),
    ("1,2,3,4\n1,a,3,4\n", "expected numbers"),
])
def test_point_pairs_malformed(tmp_path, text, message):
    p = tmp_path / "pairs.csv"
    p.write_text(text)
    with pytest.raises(InputError, match=message):
        read_point_pairs(p)


def test_point_pairs_header_and_comments(tmp_path):
    p = tmp_path / "pairs.csv"
    p.write_text("u,v,x,y\n# a comment\n1,2,3,4\n5,6,7,8\n")
    img, world = read_point_pairs(p)
    np.testing.assert_array_equal(img, [[1, 2], [5, 6]])
    np.testing.assert_array_equal(world, [[3, 4], [7, 8]])


def test_foot_points_and_empty():
    np.testing.assert_array_equal(foot_points([[10, 20, 4, 30]]), [[10 + 4 / 2, 20 + 30]])
    assert world_positions(np.zeros((0, 4)), SCALE).shape == (0, 2)
    assert box_heights(np.zeros((0, 4)), SCALE).shape == (0,)
    assert track_measurements([], [], np.zeros((0, 4)), SCALE, 10.0) == {}


def test_track_speed_and_length_hand_built():
    # track 1 walks 100 px = 1 m per frame to the right for 5 frames at 10 fps; track 2 stands
    # still for 3 frames. A 0.4 s window is 4 frames: speeds from frame 3 (2 frames back, half a
    # window) on, each 1 m per frame = 10 m/s
    frames = [1, 2, 3, 4, 5, 1, 2, 3]
    ids = [1, 1, 1, 1, 1, 2, 2, 2]
    boxes = [[100 * i, 0, 20, 50] for i in range(5)] + [[0, 0, 20, 50]] * 3
    m = track_measurements(frames, ids, boxes, SCALE, fps=10.0, window_s=0.4)
    assert m[1]["path_length_m"] == pytest.approx(4 * 1.0)
    assert m[1]["duration_s"] == pytest.approx((5 - 1) / 10.0)
    assert m[1]["mean_speed_mps"] == pytest.approx(1.0 * 10.0)
    assert (m[1]["speed_window_s"], m[1]["speed_fps"]) == (0.4, 10.0)
    assert m[1]["height_m"] is None  # a homography cannot measure heights
    assert m[2]["path_length_m"] == 0.0 and m[2]["mean_speed_mps"] == 0.0
    json.dumps(m)  # valid JSON (no NaN)


def test_track_speed_ignores_jitter_across_the_way():
    # 1 m per second along x at 10 fps for 3 s, the foot point jumping 0.1 m across the way
    # every frame: the frame-to-frame path is 1.4 times the walk, the speed over 1 s is not
    frames = list(range(1, 31))
    boxes = [[10 * i - 10, 10 * (i % 2), 20, 50] for i in range(30)]
    m = track_measurements(frames, [1] * 30, boxes, SCALE, fps=10.0)[1]
    assert m["path_length_m"] / m["duration_s"] > 1.4
    assert m["mean_speed_mps"] == pytest.approx(1.0, abs=0.01)


def test_track_shorter_than_half_a_window_has_no_speed():
    m = track_measurements([3], [7], [[0, 0, 10, 10]], SCALE, fps=25.0)
    assert m[7]["mean_speed_mps"] is None and m[7]["frames"] == 1
    m = track_measurements(range(1, 13), [7] * 12, [[i, 0, 10, 10] for i in range(12)], SCALE,
                           fps=25.0)   # 11 frames apart: under half a second
    assert m[7]["mean_speed_mps"] is None


def test_bad_fps():
    with pytest.raises(ValueError, match="fps"):
        track_measurements([1], [1], [[0, 0, 1, 1]], SCALE, fps=0.0)


@pytest.mark.data
@pytest.mark.parametrize("foot, height", [((-5.0, -8.0), 1.80), ((-11.0, -5.5), 1.60),
                                          ((0.0, 0.0), 1.95)])
def test_height_of_synthetic_person_on_pets_camera(data, foot, height):
    """Box from the projections of a foot point and the head 'height' metres above it."""
    cam = read_tsai_xml(data("pets09-s2l1", "View_001.xml"))
    f_px = cam.world_to_image([[*foot, 0.0]])[0]
    h_px = cam.world_to_image([[*foot, height]])[0]
    box = [[f_px[0] - 10, h_px[1], 20, f_px[1] - h_px[1]]]
    assert box_heights(box, cam)[0] == pytest.approx(height, abs=0.03)
    np.testing.assert_allclose(world_positions(box, cam), [foot], atol=1e-9)


@pytest.mark.data
def test_pets_ground_truth_heights_plausible(data):
    from motiontrack.io.mot import read_mot

    cam = load_camera(data("pets09-s2l1", "View_001.xml"))
    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")
    gt = gt.select(gt.consider)
    m = track_measurements(gt.frames, gt.ids, gt.boxes, cam, fps=7.0)
    heights = [v["height_m"] for v in m.values() if v["frames"] > 20]
    speeds = [v["mean_speed_mps"] for v in m.values() if v["frames"] > 20]
    assert 1.5 < np.median(heights) < 2.0      # adults
    assert 0.3 < np.median(speeds) < 2.5       # walking
