"""Mistaken inputs that are one clear line and exit 2, not an internal error: integers beyond
any float in a scene file, URLs with an unclosed IPv6 bracket, a tracker OpenCV cannot start on
tiny frames; and a run with standard error closed (``2>&-``) that runs and keeps its outputs."""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from helpers.cli_errors import user_error
from motiontrack.analytics import parse_scene
from motiontrack.cli import main
from motiontrack.errors import ConfigError
from motiontrack.io.sinks import parse_mqtt, parse_webhook
from motiontrack.run.folders import source_name

HUGE = int("9" * 400)


@pytest.mark.parametrize("scene, message", [
    ({"hysteresis_px": HUGE}, "hysteresis_px must be a finite number, got an integer of 400 "
                              "digits"),
    ({"hysteresis_px": -HUGE}, "hysteresis_px must be a finite number"),
    ({"zone": [{"name": "z", "polygon": [[0, 0], [HUGE, 0], [0, 5]]}]},
     "zone[1].polygon[2][1] must be a finite number, got an integer of 400 digits"),
    ({"stationary": {"after_s": HUGE, "radius_px": 3}}, "stationary.after_s must be a finite"),
])
def test_integers_beyond_any_float_in_a_scene_are_named(scene, message):
    with pytest.raises(ConfigError) as caught:
        parse_scene(scene)
    assert str(caught.value) == message or str(caught.value).startswith(message)


def test_analyze_with_a_400_digit_integer_in_the_scene_file(tmp_path, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text(f"hysteresis_px = {HUGE}\n")
    tracks = tmp_path / "tracks.txt"
    tracks.write_text("1,1,10,10,5,5,1,-1,-1,-1\n")
    code = main(["analyze", str(tracks), "--scene", str(scene), "--fps", "10",
                 "-o", str(tmp_path / "out")])
    user_error(code, capsys.readouterr().err, "scene file scene.toml: hysteresis_px must be a "
                                              "finite number, got an integer of 400 digits")


@pytest.mark.parametrize("parse, url, option", [
    (parse_webhook, "http://[::1", "--webhook"),
    (parse_webhook, "https://user:secret@[::1/hook", "--webhook"),
    (parse_mqtt, "mqtt://[::1", "--mqtt"),
    (parse_mqtt, "mqtts://user:secret@[fe80::1/cams", "--mqtt"),
])
def test_a_url_with_an_unclosed_ipv6_bracket_is_refused(parse, url, option):
    with pytest.raises(ConfigError, match=rf"^{option} '.*' is not a valid URL: Invalid IPv6 "
                                          "URL$") as caught:
        parse(url)
    assert "secret" not in str(caught.value) and "user" not in str(caught.value)


@pytest.mark.parametrize("option, url", [("--webhook", "http://[::1"), ("--mqtt", "mqtt://[::1")])
def test_track_with_an_unclosed_ipv6_bracket(tmp_path, capsys, option, url):
    code = main(["track", "synth:walker?n_frames=2", "-o", str(tmp_path / "t"), option, url])
    user_error(code, capsys.readouterr().err, f"{option} '{url}' is not a valid URL")
    assert not (tmp_path / "t").exists()


def test_a_stream_url_with_an_unclosed_bracket_gets_a_folder_name():
    assert source_name("rtsp://[::1") == "stream"


def _tiny_video(path: Path, size: int = 8, frames: int = 5) -> Path:
    w = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10, (size, size))
    for i in range(frames):
        w.write(np.full((size, size, 3), 40 * i, np.uint8))
    w.release()
    return path


def test_follow_with_a_tracker_that_cannot_start_on_tiny_frames(tmp_path, capsys):
    video = _tiny_video(tmp_path / "tiny.avi")
    code = main(["follow", str(video), "--tracker", "mil", "--box", "1,1,4,4",
                 "-o", str(tmp_path / "f")])
    user_error(code, capsys.readouterr().err,
               "the mil tracker cannot start on box 1,1,4,4 of the 8x8 frame", "OpenCV says")


def test_track_with_standard_error_closed_runs_and_keeps_its_outputs(tmp_path):
    out = tmp_path / "t"
    cmd = (f"{shlex.quote(sys.executable)} -m motiontrack track 'synth:walker?n_frames=3' "
           f"-o {shlex.quote(str(out))} 2>&-")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2] / "src")}
    done = subprocess.run(["sh", "-c", cmd], capture_output=False, stdout=subprocess.PIPE,
                          env=env, timeout=120, text=True)
    assert done.returncode == 0, done.stdout
    assert "status    complete" in done.stdout
    assert {"tracks.txt", "summary.json", "config.toml"} <= {p.name for p in out.iterdir()}
