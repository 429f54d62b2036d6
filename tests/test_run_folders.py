"""Default output folders: without ``-o`` each run of track, follow and flow gets its own
``runs/<command>/<name>``, named after its source; ``-o`` keeps its meaning."""

from __future__ import annotations

import json

import pytest

from motiontrack.cli import main
from motiontrack.io.video import VideoSink
from motiontrack.run.folders import new_run_folder, source_name

WALKER = "synth:walker?n_frames=5"


def _tree(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


@pytest.mark.parametrize("spec, name", [
    ("synth:crossing?seed=3", "synth-crossing"),      # the scene, not its parameters
    ("0", "camera0"),
    (2, "camera2"),
    ("rtsp://user:secret@cam.example.org:554/live", "cam.example.org"),   # never the password
    ("http://10.0.0.7:8080/video.mjpg", "10.0.0.7"),
    ("clips/My Video (1).mp4", "My-Video-1"),         # no spaces or brackets
    ("../../etc/passwd", "passwd"),                    # only the last component
    (".hidden.mp4", "hidden"),                         # no hidden folder
    ("in0000*.jpg", "in0000"),                         # a glob in the working folder
    ("weird:name.mp4", "weird-name"),                  # not a registered scheme: a file name
    ("x" * 300 + ".mp4", "x" * 60),                    # bounded
    ("...", "run"),
])
def test_source_names_are_short_safe_folder_names(spec, name):
    assert source_name(spec) == name


def test_an_image_folder_and_its_glob_are_named_after_the_folder(tmp_path):
    (tmp_path / "input").mkdir()
    assert source_name(tmp_path / "input") == "input"
    assert source_name(str(tmp_path / "input" / "*.jpg")) == "input"
    video = tmp_path / "street cam.avi"
    video.write_bytes(b"")
    assert source_name(f"file://{video}") == "street-cam"


def test_two_runs_of_one_source_land_in_two_folders(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    for _ in range(2):
        assert main(["track", WALKER, "--no-video"]) == 0
    out = capsys.readouterr()
    for folder in ("runs/track/synth-walker", "runs/track/synth-walker-2"):
        assert json.loads((tmp_path / folder / "summary.json").read_text())["frames"] == 5
        assert f"output folder {folder}" in out.err and f"{folder}/tracks.txt" in out.out
    assert new_run_folder("track", WALKER).as_posix() == "runs/track/synth-walker-3"


@pytest.mark.parametrize("command, extra", [("flow", []), ("follow", ["--box", "10,10,20,40"])])
def test_flow_and_follow_get_their_own_run_folders(tmp_path, monkeypatch, command, extra):
    monkeypatch.chdir(tmp_path)
    assert main([command, WALKER, "--no-video", *extra]) == 0
    assert (tmp_path / "runs" / command / "synth-walker" / "summary.json").is_file()


def test_an_explicit_folder_keeps_its_meaning(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["track", WALKER, "--no-video", "-o", "mine"]) == 0
    assert main(["track", WALKER, "--no-video", "-o", "mine"]) == 2
    assert "output exists" in capsys.readouterr().err
    assert main(["track", WALKER, "--no-video", "-o", "mine", "--force"]) == 0
    assert not (tmp_path / "runs").exists()


def test_a_run_that_fails_leaves_no_folder_behind(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["track", "/no/such/video.mp4"]) != 0            # before the run
    assert not (tmp_path / "runs").exists()

    def refuse(self, w, h):
        raise OSError("encoder gave up")

    monkeypatch.setattr(VideoSink, "_open", refuse)                # during the run
    assert main(["track", WALKER]) != 0
    assert _tree(tmp_path) == []
