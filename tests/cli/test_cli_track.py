"""`motiontrack track` and `motiontrack list` from the command line: outputs, errors, interruption."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import cv2
import pytest

from motiontrack.cli import main
from motiontrack.config import load_config
from motiontrack.io.mot import read_mot

SCENE = "synth:walker?n_frames=60"


def test_track_writes_every_output(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["track", SCENE, "-o", str(out), "--codec", "mjpg"]) == 0
    printed = capsys.readouterr().out
    assert "frames    60" in printed and "HOTA" in printed
    for name in ("tracks.txt", "summary.json", "config.toml", "annotated.avi", "gt.txt"):
        assert (out / name).is_file(), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 60 and summary["interrupted"] is False
    assert summary["processing_scale"] == 0.6  # automatic: 640x480 keeps about 384x288 pixels
    assert summary["status"] == "complete" and summary["tracks"] >= 1
    assert 0.0 <= summary["accuracy"]["MOTA"] <= 1.0
    tracks = read_mot(out / "tracks.txt")
    assert tracks.frames.min() >= 1 and set(tracks.ids) == {1}
    cap = cv2.VideoCapture(str(out / "annotated.avi"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 60
    # the resolved config reproduces the run
    assert load_config(out / "config.toml") == load_config(None, ['output.codec="mjpg"'])
    assert not list(out.glob("*.part*"))


@pytest.mark.slow
def test_default_video_is_webm(tmp_path):
    out = tmp_path / "o"
    assert main(["track", "synth:walker?n_frames=20", "-o", str(out)]) == 0
    assert (out / "annotated.webm").read_bytes()[:4] == b"\x1a\x45\xdf\xa3"   # EBML (WebM) magic
    cap = cv2.VideoCapture(str(out / "annotated.webm"))
    assert cap.read()[0]


def test_existing_outputs_need_force(tmp_path, capsys):
    out = tmp_path / "o"
    args = ["track", "synth:walker?n_frames=10", "-o", str(out), "--no-video"]
    assert main(args) == 0
    assert main(args) == 2
    assert "use --force" in capsys.readouterr().err
    assert main(args + ["--force"]) == 0


@pytest.mark.parametrize("args, message", [
    (["track", "/no/such/video.mp4"], "video file not found"),
    (["track", "synth:nope"], "unknown"),
    (["track", SCENE, "--set", "motion.method=magic"], "unknown motion detector 'magic'; valid names"),
    (["track", SCENE, "--set", "regions.max_size=3"], "must be in [0.0, 1.0]"),
    (["track", SCENE, "--set", "tracker.nope=1"], "unknown config key 'tracker.nope'"),
    (["track", SCENE, "--gt", "/no/gt.txt"], "not found"),
    (["track", SCENE, "--show", "--port", "70000"], "--port must be in 0..65535"),
])
def test_bad_input_is_one_line_and_nonzero(tmp_path, capsys, args, message):
    code = main(args + ["-o", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0
    assert len(err) == 1 and err[0].startswith("motiontrack: error:"), err
    assert message in err[0]


def test_detections_replace_motion(tmp_path, data):
    seq = data("mot17-mini", "train", "MOT17-09-FRCNN")
    out = tmp_path / "o"
    code = main(["track", str(seq / "img1"), "--detections", str(seq / "det" / "det.txt"),
                 "--min-score", "0.5", "--set", "tracker.confirm_hits=1", "--no-video", "-o", str(out)])
    assert code == 0
    tracks = read_mot(out / "tracks.txt")
    det = read_mot(seq / "det" / "det.txt", kind="det")
    det = det.select(det.scores >= 0.5)
    assert len(tracks) > 0 and set(tracks.frames) <= set(det.frames)


def test_list_names_every_stage(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in ("mog2", "knn", "median", "frame_diff", "cnt", "gsoc", "farneback", "kalman",
                 "walker", "column", "crossing"):
        assert name in out


@pytest.mark.slow
def test_interrupt_keeps_everything_processed(tmp_path):
    """SIGINT mid-run: valid tracks file and video, summary says interrupted, exit 130."""
    out = tmp_path / "o"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "motiontrack", "track", "synth:crowd?n_frames=2000", "-o", str(out),
         "--codec", "mjpg"], stderr=subprocess.PIPE, stdout=subprocess.PIPE, env=env)
    deadline = time.time() + 60
    # the run has started once its tracks file is being written (under a temporary name)
    while not list(out.glob(".tracks.txt.*.part")) and time.time() < deadline:
        time.sleep(0.1)
    time.sleep(2.0)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err.decode()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True and 0 < summary["frames"] < 2000
    tracks = read_mot(out / "tracks.txt")
    assert len(tracks) > 0 and tracks.frames.max() <= summary["frames"]
    cap = cv2.VideoCapture(str(out / "annotated.avi"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == summary["frames"]
    assert "Traceback" not in err.decode()


def test_camera_adds_world_positions_and_measurements(tmp_path, data):
    video = data("pets09-s2l1", "video.avi")
    out = tmp_path / "o"
    code = main(["track", str(video), "--max-frames", "40", "--no-video", "-o", str(out),
                 "--camera", str(data("pets09-s2l1", "View_001.xml"))])
    assert code == 0
    tracks = read_mot(out / "tracks.txt")
    assert len(tracks) > 0
    # the PETS ground plane spans roughly -15..5 m (x) and -15..0 m (y) in view 1
    assert (tracks.world[:, 0] > -30).all() and (tracks.world[:, 0] < 20).all()
    assert (tracks.world[:, 1] > -30).all() and (tracks.world[:, 1] < 10).all()
    m = json.loads((out / "summary.json").read_text())["measurements"]
    assert m and all(1.0 < v["height_m"] < 2.2 for v in m.values() if v["height_m"] is not None)


def test_save_intermediate_movies(tmp_path):
    out = tmp_path / "o"
    assert main(["track", "synth:walker?n_frames=30", "-o", str(out), "--no-video", "--codec", "mjpg",
                 "--save", "background,difference,motion"]) == 0
    for stream in ("background", "difference", "motion"):
        cap = cv2.VideoCapture(str(out / f"{stream}.avi"))
        assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 30, stream
    summary = json.loads((out / "summary.json").read_text())
    assert {"background", "difference", "motion"} <= set(summary["outputs"])


def test_save_annotated_with_the_annotated_video_writes_one_file(tmp_path):
    out = tmp_path / "o"
    assert main(["track", "synth:walker?n_frames=12", "-o", str(out), "--codec", "mjpg",
                 "--save", "annotated,motion"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    paths = list(summary["outputs"].values())
    assert len(paths) == len(set(paths))
    cap = cv2.VideoCapture(str(out / "annotated.avi"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 12
    # without the annotated video, --save annotated still writes it
    out2 = tmp_path / "o2"
    assert main(["track", "synth:walker?n_frames=12", "-o", str(out2), "--codec", "mjpg",
                 "--no-video", "--save", "annotated"]) == 0
    assert "annotated" in json.loads((out2 / "summary.json").read_text())["outputs"]


def test_save_unknown_stream_is_an_error(tmp_path, capsys):
    assert main(["track", SCENE, "-o", str(tmp_path / "o"), "--save", "nope"]) == 2
    assert "unknown --save stream" in capsys.readouterr().err


def test_frame_loop_ticks_the_bar_and_stops_after_a_complete_frame():
    from motiontrack.cli._common import FrameLoop, accuracy_line

    counted, asked = [], [False]
    loop = FrameLoop(counted.append, lambda: asked[0])
    loop.tick()
    assert counted == [1]
    asked[0] = True
    with pytest.raises(KeyboardInterrupt):
        loop.tick()
    assert counted == [1, 1]  # the frame is counted before the stop surfaces
    assert accuracy_line({"HOTA": 0.5, "MOTA": 0.25, "IDSW": 3.0}) == \
        "accuracy  HOTA 0.500  MOTA 0.250  IDSW 3"
