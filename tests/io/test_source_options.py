"""What every command that reads video (track, follow, flow, overlay) does with its SOURCE,
--start and --fps: a text file is not a video, a start past the end is an error, and a frame
rate given with --fps is the one every duration, speed and output video uses."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.config import load_config
from motiontrack.io.mot import read_mot
from motiontrack.pipeline import TrackRun

SCENE = "synth:walker?n_frames=6"


def _command(name, source, out, *extra):
    """``name SOURCE`` with the options it needs to run, writing into ``out``."""
    args = {"track": ["track", source, "-o", str(out), "--no-video"],
            "follow": ["follow", source, "--box", "613,300,27,91", "-o", str(out), "--no-video"],
            "flow": ["flow", source, "-o", str(out), "--no-video"],
            "overlay": ["overlay", source, "-o", str(out / "overlay.avi")]}[name]
    return args + list(extra)


def _error(capsys):
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    errors = [ln for ln in err if "error" in ln]
    assert len(errors) == 1 and "Traceback" not in "\n".join(err), err
    return errors[0]


@pytest.mark.data
@pytest.mark.parametrize("command", ["track", "follow", "flow", "overlay"])
def test_an_annotation_file_as_source_is_one_line_error(data, tmp_path, capsys, command):
    gt = data("pets09-s2l1", "gt_mot15.txt")
    out = tmp_path / "o"
    extra = ["--gt", str(gt)] if command == "overlay" else []
    assert main(_command(command, str(gt), out, *extra)) == 2
    assert f"{gt} is a text file, not a video or image" in _error(capsys)
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize("command, start", [
    ("track", ["--start", "6"]), ("follow", ["--start", "9"]), ("flow", ["--start", "6"]),
    ("overlay", ["--frames", "7:9"]),
])
def test_start_past_the_end_is_an_error_before_anything_is_written(tmp_path, capsys, command,
                                                                   start):
    out = tmp_path / "o"
    assert main(_command(command, SCENE, out, *start)) == 2
    assert f"past the end of {SCENE}: it has 6 frames (0-5)" in _error(capsys)
    assert not (out / "summary.json").exists() and not (out / "overlay.avi").exists()


@pytest.mark.data
def test_start_past_the_end_of_a_video_file(data, tmp_path, capsys):
    video = data("pets09-s2l1", "video.avi")
    assert main(["track", str(video), "--start", "300", "-o", str(tmp_path / "o")]) == 2
    assert "start frame 300 (0-based; 301 counting from 1) is past the end" in _error(capsys)


def test_fps_sets_the_frames_of_every_duration():
    """``tracker.max_lost_s`` (2 s) in frames: at the scene's 25 fps and at --fps 5."""
    for fps, frames in ((0.0, 50), (5.0, 10)):
        cfg = load_config(None, [f"source.fps={fps}"])
        with TrackRun(SCENE, cfg) as run:
            assert run.pipeline.tracker.max_lost == frames
            assert run.source.info.fps == (fps or 25.0)


@pytest.mark.data
def test_fps_scales_speeds_and_sets_the_video_rate_and_the_summary(data, tmp_path):
    video, xml = data("pets09-s2l1", "video.avi"), data("pets09-s2l1", "View_001.xml")
    common = ["track", str(video), "--max-frames", "40", "--camera", str(xml)]
    # the same time-out (10 frames) and hold speed (0.02 box heights a frame) in frames at every
    # rate, so the tracks are the same
    assert main(common + ["--no-video", "-o", str(tmp_path / "a"),
                          "--set", "tracker.max_lost_s=1.0"]) == 0
    assert main(common + ["--fps", "5", "--codec", "mjpg", "-o", str(tmp_path / "b"),
                          "--set", "tracker.max_lost_s=2.0",
                          "--set", "motion.knn.hold_speed=0.1"]) == 0
    assert main(common + ["--fps", "20", "--no-video", "-o", str(tmp_path / "c"),
                          "--set", "tracker.max_lost_s=0.5",
                          "--set", "motion.knn.hold_speed=0.4"]) == 0
    a, b, c = (json.loads((tmp_path / n / "summary.json").read_text()) for n in "abc")
    assert (a["source_fps"], "source_stored_fps" in a) == (10.0, False)
    assert (b["source_fps"], b["source_stored_fps"]) == (5.0, 10.0)
    ta, tb, tc = (read_mot(tmp_path / n / "tracks.txt") for n in "abc")
    assert len(ta) > 0 and len(ta) == len(tb) == len(tc)
    assert all((ta.boxes == t.boxes).all() and (ta.ids == t.ids).all() for t in (tb, tc))
    # the same path in twice or half the time: each speed is over 1 s, so over 5, 10 or 20
    # frames of it, and the ratios are near 1/2 and 2 rather than exact
    for run, fps in ((b, 5.0), (c, 20.0)):
        ratios = [run["measurements"][k]["mean_speed_mps"] / m["mean_speed_mps"]
                  for k, m in a["measurements"].items()
                  if m["mean_speed_mps"] and run["measurements"][k]["mean_speed_mps"]]
        assert len(ratios) >= 3
        assert np.median(ratios) == pytest.approx(fps / 10.0, rel=0.15)
        assert {m["speed_fps"] for m in run["measurements"].values()} == {fps}
    cap = cv2.VideoCapture(str(tmp_path / "b" / "annotated.avi"))
    assert cap.get(cv2.CAP_PROP_FPS) == pytest.approx(5.0)
    cap.release()


def test_fps_of_overlay_is_the_output_video_rate(tmp_path):
    out = tmp_path / "o.avi"
    assert main(["overlay", SCENE, "--fps", "5", "-o", str(out)]) == 0
    cap = cv2.VideoCapture(str(out))
    assert cap.get(cv2.CAP_PROP_FPS) == pytest.approx(5.0)
    cap.release()


def test_a_negative_fps_is_refused(tmp_path, capsys):
    assert main(["track", SCENE, "--fps", "-1", "-o", str(tmp_path / "o")]) == 2
    assert "fps must be in [0.0, 1000.0], got -1.0" in _error(capsys)
