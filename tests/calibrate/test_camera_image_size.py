"""A camera calibrated on one image size, used with a video of another: a scaled copy of the
video (same aspect ratio) gets the camera scaled to it; any other size is an error naming both."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from motiontrack.calibrate import fit_to_image, load_camera
from motiontrack.calibrate.chessboard import OpenCVCamera
from motiontrack.calibrate.ground import GroundHomography
from motiontrack.calibrate.measure import box_heights, foot_points
from motiontrack.calibrate.tsai import pixel_scaling
from motiontrack.cli import main
from motiontrack.errors import InputError
from motiontrack.io.mot import read_mot

#: image points of the 768x576 PETS view 1 across its ground plane
POINTS = np.array([[100.0, 500.0], [384.0, 300.0], [700.0, 400.0], [50.0, 200.0], [600, 560]])


def _scaled(points, size, new_size):
    """``points`` of an image of ``size`` in the same image resized to ``new_size``."""
    return (np.c_[points, np.ones(len(points))] @ pixel_scaling(size, new_size).T)[:, :2]


def test_pixel_scaling_keeps_pixel_centres_as_cv2_resize_does():
    A = pixel_scaling((768, 576), (480, 360))
    # pixel 0's centre at 0 spans [-0.5, 0.5); the image's edges stay its edges
    edges = _scaled(np.array([[-0.5, -0.5], [767.5, 575.5]]), (768, 576), (480, 360))
    np.testing.assert_allclose(edges, [[-0.5, -0.5], [479.5, 359.5]])
    assert A[0, 0] == A[1, 1] == 0.625


@pytest.mark.data
@pytest.mark.parametrize("size", [(480, 360), (1536, 1152), (384, 288)])
def test_tsai_camera_scaled_to_a_resized_video_measures_the_same(data, size):
    cam = load_camera(data("pets09-s2l1", "View_001.xml"))
    small = fit_to_image(cam, *size, "View_001.xml")
    assert small.image_size == size
    pts = _scaled(POINTS, (768, 576), size)
    np.testing.assert_allclose(small.image_to_world(pts), cam.image_to_world(POINTS), atol=1e-9)
    np.testing.assert_allclose(small.world_to_image(cam.image_to_world(POINTS)), pts, atol=1e-6)
    # a person 120 px tall at (300, 200) in the full frame: the same height in the scaled one
    box = np.array([[300.0, 200.0, 40.0, 120.0]])
    k = size[0] / 768
    sbox = np.c_[_scaled(box[:, :2], (768, 576), size), box[:, 2:] * k]
    assert box_heights(sbox, small)[0] == pytest.approx(box_heights(box, cam)[0], abs=1e-9)


@pytest.mark.data
def test_the_unscaled_camera_would_be_metres_off(data):
    """What the scaling prevents: the 768x576 camera applied to 480x360 pixels."""
    cam = load_camera(data("pets09-s2l1", "View_001.xml"))
    pts = _scaled(POINTS, (768, 576), (480, 360))
    err = np.linalg.norm(cam.image_to_world(pts) - cam.image_to_world(POINTS), axis=1)
    assert err.max() > 5.0


def test_opencv_camera_and_homography_scale_with_the_video():
    K = np.array([[800.0, 0, 319.5], [0, 800.0, 239.5], [0, 0, 1]])
    cam = OpenCVCamera(K=K, dist=np.array([-0.2, 0.05, 0, 0, 0]), size=(640, 480),
                       rvec=np.array([1.9, 0.1, 0.05]), tvec=np.array([0.2, 1.0, 6.0]))
    pts = np.array([[100.0, 400.0], [320.0, 300.0], [600.0, 470.0]])
    small = fit_to_image(cam, 320, 240, "c.yml")
    np.testing.assert_allclose(small.K, [[400, 0, 159.5], [0, 400, 119.5], [0, 0, 1]])
    np.testing.assert_allclose(small.image_to_world(_scaled(pts, (640, 480), (320, 240))),
                               cam.image_to_world(pts), atol=1e-7)
    H = np.array([[0.01, 0.002, -3.0], [0.0005, 0.02, -5.0], [0.0, 0.001, 1.0]])
    g = GroundHomography(H=H, size=(640, 480))
    gs = fit_to_image(g, 1280, 960, "g.toml")
    np.testing.assert_allclose(gs.image_to_world(_scaled(pts, (640, 480), (1280, 960))),
                               g.image_to_world(pts), atol=1e-9)


def test_a_camera_of_the_same_size_is_used_as_it_is_and_one_without_size_too(caplog):
    g = GroundHomography(H=np.eye(3), size=(640, 480))
    assert fit_to_image(g, 640, 480, "g.toml") is g
    unsized = GroundHomography(H=np.eye(3))
    with caplog.at_level("INFO", logger="motiontrack"):   # whatever an earlier -q left
        assert fit_to_image(unsized, 320, 240, "g.toml") is unsized
    assert "states no image size" in caplog.text


@pytest.mark.parametrize("size", [(640, 360), (720, 576), (768, 600)])
def test_another_aspect_ratio_is_an_error_naming_both_sizes(size):
    g = GroundHomography(H=np.eye(3), size=(768, 576))
    with pytest.raises(InputError, match=f"768x576 images but the video is {size[0]}x{size[1]}"):
        fit_to_image(g, *size, "g.toml")


def test_rounding_of_a_scaled_size_is_the_same_aspect_ratio():
    g = GroundHomography(H=np.eye(3), size=(1280, 720))
    assert fit_to_image(g, 854, 480, "g.toml").image_size == (854, 480)   # 853.3 rounded


def _pets_frames(video, folder, size, n=20):
    folder.mkdir()
    cap = cv2.VideoCapture(str(video))
    for i in range(n):
        ok, img = cap.read()
        assert ok
        cv2.imwrite(str(folder / f"{i + 1:06d}.png"),
                    cv2.resize(img, size, interpolation=cv2.INTER_AREA))
    cap.release()


@pytest.mark.data
def test_track_with_a_camera_on_a_downscaled_copy_of_the_video(data, tmp_path, capsys):
    video, xml = data("pets09-s2l1", "video.avi"), data("pets09-s2l1", "View_001.xml")
    frames = tmp_path / "small"
    _pets_frames(video, frames, (480, 360))
    out = tmp_path / "o"
    assert main(["track", str(frames), "--no-video", "-o", str(out), "--camera", str(xml)]) == 0
    err = capsys.readouterr().err
    assert "WARNING" in err and "calibrated on 768x576 images; the video is 480x360" in err
    tracks = read_mot(out / "tracks.txt")
    assert len(tracks) > 0
    # each row's world position is the full-size camera's at the foot point in full-size pixels
    feet = _scaled(foot_points(tracks.boxes), (480, 360), (768, 576))
    np.testing.assert_allclose(tracks.world[:, :2], load_camera(xml).image_to_world(feet),
                               atol=0.01)
    heights = [m["height_m"] for m in json.loads((out / "summary.json").read_text())
               ["measurements"].values() if m["height_m"] is not None]
    assert heights and all(1.2 < h < 2.2 for h in heights)


@pytest.mark.data
def test_track_with_a_camera_on_a_video_of_another_aspect_ratio_fails(data, tmp_path, capsys):
    frames = tmp_path / "wide"
    _pets_frames(data("pets09-s2l1", "video.avi"), frames, (640, 360), n=3)
    out = tmp_path / "o"
    code = main(["track", str(frames), "--no-video", "-o", str(out), "--camera",
                 str(data("pets09-s2l1", "View_001.xml"))])
    err = capsys.readouterr().err
    assert code == 2
    assert "calibrated on 768x576 images but the video is 640x360" in err
    assert not (out / "tracks.txt").exists()
