"""``motiontrack calibrate ...`` and ``motiontrack world``: end to end, and errors as one line."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from motiontrack.calibrate.camera import load_camera
from motiontrack.calibrate.chessboard import OpenCVCamera, write_opencv_yaml
from motiontrack.calibrate.lines import render_grid
from motiontrack.calibrate.tsai import write_tsai_xml
from motiontrack.cli import main
from motiontrack.io.mot import read_mot

from test_calibrate_lines import XS, YS, synthetic_camera


def run(capsys, *argv):
    code = main(list(map(str, argv)))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.data
def test_world_command_on_pets(data, tmp_path, capsys):
    out = tmp_path / "gt_world.txt"
    code, _, err = run(capsys, "world", "--camera", data("pets09-s2l1", "View_001.xml"),
                       data("pets09-s2l1", "gt_mot15.txt"), "-o", out)
    assert code == 0, err
    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")
    res = read_mot(out, kind="gt")
    assert len(res) == len(gt)
    keep = res.consider
    err_m = np.linalg.norm(res.world[keep, :2] - gt.world[keep, :2], axis=1)
    assert np.median(err_m) < 0.15
    assert (res.world[:, 2] == 0).all()


@pytest.mark.data
def test_show_command_on_pets_frame(data, tmp_path, capsys):
    out = tmp_path / "check.png"
    code, _, err = run(capsys, "calibrate", "show", data("pets09-s2l1", "View_001.xml"),
                       data("pets09-s2l1", "video.avi"), "-o", out)
    assert code == 0, err
    img = cv2.imread(str(out))
    assert img.shape == (576, 768, 3)
    yellow = (img[..., 0] < 60) & (img[..., 1] > 200) & (img[..., 2] > 200)
    assert yellow.sum() > 2000  # grid lines were drawn


def test_undistorted_grid_overlays_rendered_lines():
    """The projected (undistorted) grid falls on the dark lines of the undistorted rendering."""
    cam = synthetic_camera(0.02)
    und = cam.undistort(render_grid(cam, XS, YS, (-0.5, 8.5, -0.5, 7.5), thickness=3))
    t = np.linspace(0.1, 0.9, 50)
    pts = np.vstack([np.column_stack([np.full_like(t, x), 7 * t]) for x in XS])
    px = cam.world_to_image(pts, distorted=False)
    vals = und[np.round(px[:, 1]).astype(int), np.round(px[:, 0]).astype(int)]
    assert np.median(vals) < 60
    # and the uncorrected image does NOT line up with the undistorted projection everywhere
    raw = render_grid(cam, XS, YS, (-0.5, 8.5, -0.5, 7.5), thickness=3)
    assert np.mean(raw[np.round(px[:, 1]).astype(int), np.round(px[:, 0]).astype(int)] > 128) > 0.2


def test_lines_command_recovers_camera(tmp_path, capsys):
    cam = synthetic_camera(0.012)
    cv2.imwrite(str(tmp_path / "grid.png"), render_grid(cam, XS, YS, (-0.5, 8.5, -0.5, 7.5)))
    geom_file = tmp_path / "geometry.xml"
    write_tsai_xml(replace(cam, kappa1=0.0, focal=3.0), geom_file)  # only the Geometry is used
    rough = replace(cam, kappa1=0.0)
    rows = ["line,axis,value,u,v"]
    t = np.linspace(0, 1, 4)
    for x in XS:
        for u, v in rough.world_to_image(np.column_stack([np.full_like(t, x), -0.3 + 7.6 * t])):
            rows.append(f"x{x:g},x,{x},{u:.1f},{v:.1f}")
    for y in YS:
        for u, v in rough.world_to_image(np.column_stack([-0.3 + 8.6 * t, np.full_like(t, y)])):
            rows.append(f"y{y:g},y,{y},{u:.1f},{v:.1f}")
    (tmp_path / "lines.csv").write_text("\n".join(rows) + "\n")
    out = tmp_path / "cam.toml"
    code, stdout, err = run(capsys, "calibrate", "lines", tmp_path / "grid.png", "--lines",
                            tmp_path / "lines.csv", "--geometry", geom_file, "--half-width", 8,
                            "-o", out)
    assert code == 0, err
    fitted = load_camera(out)
    assert fitted.kappa1 == pytest.approx(0.012, rel=0.03)
    assert fitted.focal == pytest.approx(4.5, rel=0.01)
    assert "kappa1" in stdout


def test_ground_command_homography_and_pose(tmp_path, capsys):
    K = np.array([[600.0, 0, 320], [0, 600, 240], [0, 0, 1]])
    posed = OpenCVCamera(K=K, dist=np.zeros(5), size=(640, 480), rvec=np.array([2.2, 0.0, 0.0]),
                         tvec=np.array([0.0, 1.0, 6.0]))
    world = np.array([[x, y] for x in (-2.0, 0.0, 2.0) for y in (0.0, 3.0, 6.0)])
    px = posed.world_to_image(world)
    (tmp_path / "pairs.csv").write_text(
        "u,v,x,y\n" + "".join(f"{u},{v},{x},{y}\n" for (u, v), (x, y) in zip(px, world)))
    code, out, err = run(capsys, "calibrate", "ground", "--points", tmp_path / "pairs.csv",
                         "-o", tmp_path / "ground.toml")
    assert code == 0, err
    g = load_camera(tmp_path / "ground.toml")
    np.testing.assert_allclose(g.image_to_world(px), world, atol=1e-5)

    write_opencv_yaml(tmp_path / "intr.yml", replace(posed, rvec=None, tvec=None))
    code, out, err = run(capsys, "calibrate", "ground", "--points", tmp_path / "pairs.csv",
                         "--intrinsics", tmp_path / "intr.yml", "-o", tmp_path / "posed.yml")
    assert code == 0, err
    cam = load_camera(tmp_path / "posed.yml")
    np.testing.assert_allclose(cam.image_to_world(px), world, atol=1e-5)
    np.testing.assert_allclose(cam.center, posed.center, atol=1e-4)


@pytest.mark.data
def test_chessboard_command(data, tmp_path, capsys):
    images = sorted(data("chessboard-left").glob("left*.jpg"))
    code, out, err = run(capsys, "calibrate", "chessboard", *images, "--pattern", "9x6",
                         "--square", 0.025, "-o", tmp_path / "camera.yml")
    assert code == 0, err
    assert "RMS reprojection error" in out and out.count(" px\n") >= 13
    fs = cv2.FileStorage(str(tmp_path / "camera.yml"), cv2.FILE_STORAGE_READ)
    assert fs.getNode("camera_matrix").mat().shape == (3, 3)
    fs.release()


@pytest.mark.data
def test_chessboard_command_skips_a_photo_of_another_size(data, tmp_path, capsys):
    folder = tmp_path / "photos"
    folder.mkdir()
    for p in sorted(data("chessboard-left").glob("left*.jpg"))[:4]:
        (folder / p.name).write_bytes(p.read_bytes())
    img = cv2.imread(str(folder / "left01.jpg"))
    cv2.imwrite(str(folder / "left.jpg"), cv2.resize(img, (800, 600)))
    code, out, err = run(capsys, "calibrate", "chessboard", *sorted(folder.glob("left*.jpg")),
                         "-o", tmp_path / "with.yml")
    assert code == 0, err
    assert "views used: 4 of 5" in out and "left.jpg: not 640x480 like the others (skipped)" in out
    assert "left.jpg: image size 800x600 differs from 640x480" in err
    (folder / "left.jpg").unlink()
    code, _, err = run(capsys, "calibrate", "chessboard", *sorted(folder.glob("left*.jpg")),
                       "-o", tmp_path / "without.yml")
    assert code == 0, err
    with_, without = (load_camera(tmp_path / n) for n in ("with.yml", "without.yml"))
    assert with_.size == without.size == (640, 480)
    np.testing.assert_allclose(with_.K, without.K, rtol=1e-7)
    np.testing.assert_allclose(with_.dist, without.dist, rtol=1e-6, atol=1e-9)


def _bad_xml(tmp_path):
    p = tmp_path / "bad.xml"
    p.write_text("<Camera><Geometry width='1'/>")
    return p


def _blank_png(tmp_path):
    p = tmp_path / "blank.png"
    cv2.imwrite(str(p), np.full((60, 80), 255, np.uint8))
    return p


def _bad_lines(tmp_path):
    p = tmp_path / "lines.csv"
    p.write_text("line,axis,value,u,v\nL1,z,0,1,2\n")
    return p


@pytest.mark.parametrize("argv, message", [
    (lambda t: ["world", "--camera", t / "none.xml", t / "tracks.txt", "-o", t / "o.txt"],
     "camera file not found"),
    (lambda t: ["calibrate", "show", _bad_xml(t), t / "x.png", "-o", t / "o.png"],
     "malformed Tsai camera XML"),
    (lambda t: ["calibrate", "chessboard", _blank_png(t), "-o", t / "c.yml"],
     "no 9x6 chessboard found in any"),
    (lambda t: ["calibrate", "chessboard", t / "missing.jpg", "-o", t / "c.yml"],
     "image not found"),
    (lambda t: ["calibrate", "chessboard", _blank_png(t), "--pattern", "9by6", "-o", t / "c.yml"],
     "pattern must look like 9x6"),
    (lambda t: ["calibrate", "ground", "--points", t / "none.csv", "-o", t / "g.toml"],
     "point-pairs file not found"),
    (lambda t: ["calibrate", "lines", _blank_png(t), "--lines", _bad_lines(t), "-o", t / "c.toml"],
     "expected line,axis"),
])
def test_bad_input_is_one_line_error(tmp_path, capsys, argv, message):
    code, out, err = run(capsys, *argv(tmp_path))
    assert code == 2
    lines = [ln for ln in err.splitlines() if ln.startswith("motiontrack: error:")]
    assert len(lines) == 1 and message in lines[0]
    assert "Traceback" not in err


@pytest.mark.data
def test_chessboard_takes_a_quoted_glob_as_the_files_it_matches(data, tmp_path, capsys):
    folder = data("chessboard-left")
    listed = sorted(folder.glob("left0[1-4].jpg"))
    code, out_listed, err = run(capsys, "calibrate", "chessboard", *listed,
                                "-o", tmp_path / "listed.yml")
    assert code == 0, err
    # the pattern as a shell that does not expand it (or quotes) passes it on
    code, out_glob, err = run(capsys, "calibrate", "chessboard", folder / "left0[1-4].jpg",
                              "-o", tmp_path / "glob.yml")
    assert code == 0, err
    assert "views used: 4 of 4" in out_glob
    assert out_glob.replace("glob.yml", "") == out_listed.replace("listed.yml", "")
    np.testing.assert_array_equal(load_camera(tmp_path / "glob.yml").K,
                                  load_camera(tmp_path / "listed.yml").K)


def test_a_glob_that_matches_no_photo_is_one_line(tmp_path, capsys):
    code, _, err = run(capsys, "calibrate", "chessboard", tmp_path / "right*.jpg",
                       "-o", tmp_path / "camera.yml")
    assert code == 2
    assert err.strip().splitlines() == [f"motiontrack: error: no images match "
                                        f"{tmp_path / 'right*.jpg'}"]
    assert not (tmp_path / "camera.yml").exists()
