"""OpenCV chessboard calibration: real photos vs OpenCV's reference, synthetic known camera, YAML."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiontrack.calibrate.camera import load_camera
from motiontrack.calibrate.chessboard import (OpenCVCamera, board_points, calibrate_chessboard,
                                              parse_pattern, read_opencv_yaml, write_opencv_yaml)
from motiontrack.errors import ConfigError, InputError

K_TRUE = np.array([[600.0, 0, 330.0], [0, 600.0, 235.0], [0, 0, 1]])
DIST_TRUE = np.array([-0.12, 0.05, 0.0, 0.0, 0.0])
SIZE = (640, 480)


def render_board(rvec, tvec, pattern=(9, 6), square=0.03, px=40, margin=60):
    """Image of a chessboard seen by (K_TRUE, DIST_TRUE) at pose (rvec, tvec): the ideal image is a
    perspective warp of a board texture; distortion is applied by sampling that ideal image at the
    undistorted position of every distorted pixel."""
    cols, rows = pattern[0] + 1, pattern[1] + 1
    tex = np.full((rows * px + 2 * margin, cols * px + 2 * margin), 255, np.uint8)
    for r in range(rows):
        for c in range(cols):
            if (r + c) % 2 == 0:
                tex[margin + r * px: margin + (r + 1) * px, margin + c * px: margin + (c + 1) * px] = 0
    # texture pixel -> board metres (the first inner corner is the board origin)
    S = np.array([[square / px, 0, -(margin + px) * square / px],
                  [0, square / px, -(margin + px) * square / px], [0, 0, 1]])
    R, _ = cv2.Rodrigues(np.asarray(rvec, float))
    H = K_TRUE @ np.column_stack([R[:, 0], R[:, 1], np.asarray(tvec, float)]) @ S
    ideal = cv2.warpPerspective(tex, H, SIZE, flags=cv2.INTER_AREA, borderValue=128)
    xs, ys = np.meshgrid(np.arange(SIZE[0], dtype=np.float64), np.arange(SIZE[1], dtype=np.float64))
    und = cv2.undistortPoints(np.stack([xs.ravel(), ys.ravel()], 1).reshape(-1, 1, 2), K_TRUE,
                              DIST_TRUE, None, None, K_TRUE,
                              (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-10))
    m = und.reshape(SIZE[1], SIZE[0], 2).astype(np.float32)
    return cv2.remap(ideal, m[..., 0], m[..., 1], cv2.INTER_LINEAR, borderValue=128)


POSES = [  # (rvec, tvec metres): board roughly 0.24 x 0.15 m at 0.4-0.6 m
    ((0.0, 0.0, 0.0), (-0.12, -0.08, 0.45)),
    ((0.4, 0.0, 0.0), (-0.12, -0.08, 0.45)),
    ((-0.4, 0.1, 0.0), (-0.12, -0.06, 0.5)),
    ((0.0, 0.45, 0.1), (-0.1, -0.08, 0.45)),
    ((0.1, -0.45, -0.1), (-0.14, -0.08, 0.5)),
    ((0.3, 0.3, 0.2), (-0.13, -0.1, 0.55)),
    ((-0.3, -0.3, -0.2), (-0.1, -0.05, 0.5)),
    ((0.2, -0.2, 0.5), (-0.05, -0.14, 0.5)),
]


def test_synthetic_board_recovers_known_camera():
    images = [render_board(r, t) for r, t in POSES]
    res = calibrate_chessboard(images, (9, 6), 0.03, flags=0)
    K = res.camera.K
    assert len(res.used) == len(POSES)
    assert res.rms < 0.2
    assert K[0, 0] == pytest.approx(600.0, rel=0.005)
    assert K[1, 1] == pytest.approx(600.0, rel=0.005)
    assert K[0, 2] == pytest.approx(330.0, abs=2.0)
    assert K[1, 2] == pytest.approx(235.0, abs=2.0)
    # k1..k3 trade off against each other; what must agree is the distortion they describe
    grid = np.stack(np.meshgrid(np.linspace(-0.35, 0.35, 11), np.linspace(-0.25, 0.25, 9)), -1)
    rays = np.column_stack([grid.reshape(-1, 2), np.ones(99)])
    true, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K_TRUE, DIST_TRUE)
    est, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, res.camera.dist)
    assert np.abs(true - est).max() < 1.0  # pixels, over the central image
    # the recovered board distance of the first view is the true 0.45 m
    assert res.tvecs[0][2] == pytest.approx(0.45, rel=0.01)


@pytest.mark.data
def test_real_chessboard_matches_opencv_reference(data, tmp_path):
    folder = data("chessboard-left")
    paths = sorted(folder.glob("left*.jpg"))
    assert len(paths) == 13
    res = calibrate_chessboard([cv2.imread(str(p)) for p in paths], (9, 6), 0.025,
                               [p.name for p in paths])
    ref = cv2.FileStorage(str(folder / "reference_intrinsics.yml"), cv2.FILE_STORAGE_READ)
    K_ref = ref.getNode("camera_matrix").mat()
    ref.release()
    K = res.camera.K
    assert K[0, 0] == pytest.approx(K_ref[0, 0], rel=0.01)
    assert K[1, 1] == pytest.approx(K_ref[1, 1], rel=0.01)
    assert abs(K[0, 2] - K_ref[0, 2]) < 3 and abs(K[1, 2] - K_ref[1, 2]) < 3
    assert res.rms < 0.5                      # measured: 0.409 px
    assert res.per_view.shape == (13,) and res.per_view.max() < 1.5
    assert res.skipped == ()

    out = tmp_path / "camera.yml"
    write_opencv_yaml(out, res.camera, res)
    fs = cv2.FileStorage(str(out), cv2.FILE_STORAGE_READ)
    np.testing.assert_allclose(fs.getNode("camera_matrix").mat(), K)
    np.testing.assert_allclose(fs.getNode("distortion_coefficients").mat().ravel(), res.camera.dist)
    assert fs.getNode("avg_reprojection_error").real() == pytest.approx(res.rms)
    assert fs.getNode("per_view_reprojection_errors").mat().shape == (13, 1)
    fs.release()
    cam = load_camera(out)
    assert isinstance(cam, OpenCVCamera) and cam.size == (640, 480) and not cam.has_pose


def test_pattern_not_found_is_input_error():
    blank = [np.full((120, 160), 255, np.uint8)] * 2
    with pytest.raises(InputError, match="no 9x6 chessboard found in any of the 2"):
        calibrate_chessboard(blank, (9, 6), 0.025)


@pytest.mark.parametrize("text, expected", [("9x6", (9, 6)), ("7X5", (7, 5))])
def test_parse_pattern(text, expected):
    assert parse_pattern(text) == expected


@pytest.mark.parametrize("text", ["9", "9x", "axb", "1x6"])
def test_parse_pattern_errors(text):
    with pytest.raises(ConfigError):
        parse_pattern(text)


def test_board_points_layout():
    p = board_points((3, 2), 0.5)
    np.testing.assert_array_equal(p[:4], [[0, 0, 0], [0.5, 0, 0], [1.0, 0, 0], [0, 0.5, 0]])


def test_posed_camera_round_trip_and_yaml(tmp_path):
    cam = OpenCVCamera(K=K_TRUE, dist=DIST_TRUE, size=SIZE, rvec=np.array([2.2, 0.0, 0.0]),
                       tvec=np.array([0.0, 1.0, 6.0]))
    rng = np.random.default_rng(1)
    px = np.column_stack([rng.uniform(100, 540, 30), rng.uniform(300, 470, 30)])
    w = cam.image_to_world(px)
    assert np.isfinite(w).all()
    np.testing.assert_allclose(cam.world_to_image(w), px, atol=1e-6)
    write_opencv_yaml(tmp_path / "c.yml", cam)
    cam2 = read_opencv_yaml(tmp_path / "c.yml")
    np.testing.assert_allclose(cam2.image_to_world(px), w, atol=1e-9)
    assert cam.world_to_image(np.zeros((0, 3))).shape == (0, 2)


@pytest.mark.parametrize("text, message", [
    ("%YAML:1.0\n---\nfoo: [1, 2\n", "malformed OpenCV camera YAML"),
    ("%YAML:1.0\n---\nimage_width: 640\n", "needs camera_matrix"),
])
def test_malformed_yaml(tmp_path, text, message):
    p = tmp_path / "c.yml"
    p.write_text(text)
    with pytest.raises(InputError, match=message):
        load_camera(p)


@pytest.mark.data
def test_photo_of_another_size_is_skipped_with_a_warning(data, caplog):
    # a glob such as right*.jpg also matches a stray right.jpg; it sorts first, so the size the
    # calibration keeps is the one most photos share, not the first photo's
    paths = sorted(data("chessboard-left").glob("left*.jpg"))[:4]
    images = [cv2.imread(str(p)) for p in paths]
    names = [p.name for p in paths]
    stray = cv2.resize(images[0], (320, 240), interpolation=cv2.INTER_AREA)
    alone = calibrate_chessboard(images, (9, 6), 0.025, names)
    with caplog.at_level("WARNING", logger="motiontrack"):
        res = calibrate_chessboard([stray, *images], (9, 6), 0.025, ["left.jpg", *names])
    warned = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert warned == ["left.jpg: image size 320x240 differs from 640x480 (most of the photos), "
                      "skipped"]
    assert res.other_size == ("left.jpg",) and res.skipped == () and res.used == tuple(names)
    assert res.camera.size == (640, 480)
    # equal up to OpenCV's multithreaded summation order (~1e-9 relative between runs)
    np.testing.assert_allclose(res.camera.K, alone.camera.K, rtol=1e-7)
    np.testing.assert_allclose(res.camera.dist, alone.camera.dist, rtol=1e-6, atol=1e-9)
    assert res.rms == pytest.approx(alone.rms, rel=1e-7)


def test_no_board_in_any_photo_of_the_common_size_is_input_error():
    blank = [np.full((120, 160), 255, np.uint8)] * 2 + [np.full((60, 80), 255, np.uint8)]
    with pytest.raises(InputError, match=r"no 9x6 chessboard found in any of the 3 image\(s\) "
                                         r"\(1 of another size than 160x120 skipped\)"):
        calibrate_chessboard(blank, (9, 6), 0.025)
