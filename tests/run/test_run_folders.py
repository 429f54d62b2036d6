"""Default output folders: without ``-o`` each run of track, follow and flow gets its own
``runs/<command>/<name>``, named after its source; ``-o`` keeps its meaning."""

from __future__ import annotations

import json

import pytest

from motiontrack.cli import main
from motiontrack.io.video import VideoSink
from motiontrack.io.atomic import AtomicFile
from motiontrack.run.folder import RunFolder
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


# ------------------------------------------------------------------------- RunFolder
def test_run_folder_names_the_outputs_of_a_run(tmp_path):
    run = RunFolder(tmp_path / "r")
    assert [p.name for p in (run.tracks, run.summary_path, run.config, run.events, run.counts,
                             run.gt, run.heatmap, run.heatmap_world)] == [
        "tracks.txt", "summary.json", "config.toml", "events.jsonl", "counts.csv", "gt.txt",
        "heatmap.png", "heatmap_world.png"]
    assert RunFolder.beside(tmp_path / "r" / "tracks.txt").path == (tmp_path / "r").resolve()


def test_run_folder_summary_round_trips_and_an_unreadable_one_is_none(tmp_path):
    run = RunFolder(tmp_path)
    assert run.summary() is None and not run.has_summary()
    run.write_summary({"frames": 3, "status": "complete"})
    assert run.summary() == {"frames": 3, "status": "complete"}
    assert run.summary_path.read_text().endswith("}\n")
    run.summary_path.write_text("{not json")
    assert run.summary() is None
    run.summary_path.write_text("[1, 2]")            # JSON, but not a summary
    assert run.summary() is None


@pytest.mark.parametrize("summary, seqinfo, fps, size", [
    ({"source_fps": 12.5, "width": 64, "height": 48}, None, 12.5, (64, 48)),
    (None, "[Sequence]\nframeRate=7\nimWidth=320\nimHeight=180\n", 7.0, (320, 180)),
    # the summary states neither (a killed run's unknown rate): the seqinfo.ini still counts
    ({"source_fps": None, "width": None}, "[Sequence]\nframeRate=5\n", 5.0, None),
    ({"source_fps": 0, "width": 0, "height": 10}, None, None, None),
    (None, None, None, None),
])
def test_run_folder_states_frame_rate_and_size_from_summary_then_seqinfo(
        tmp_path, summary, seqinfo, fps, size):
    run = RunFolder(tmp_path / "seq" / "gt")
    run.path.mkdir(parents=True)
    if summary is not None:
        run.summary_path.write_text(json.dumps(summary))
    if seqinfo is not None:   # MOTChallenge: seqinfo.ini is in the folder above gt/gt.txt
        (tmp_path / "seq" / "seqinfo.ini").write_text(seqinfo)
    assert run.frame_rate() == fps
    assert run.frame_size() == size


def test_salvage_commits_a_killed_runs_lines_and_says_so(tmp_path):
    run = RunFolder(tmp_path)
    tracks = AtomicFile(run.tracks)
    tracks.write("1,1,10,20,30,40\n2,1,11,")         # killed mid-line
    tracks._flush()
    assert run.salvage("cam", {"width": 64, "height": 48, "source_fps": 10.0}, -9)
    assert run.tracks.read_text() == "1,1,10,20,30,40\n"
    s = run.summary()
    assert s["status"] == "killed (exit code -9)" and s["truncated"] and s["interrupted"]
    assert s["outputs"] == {"tracks": str(run.tracks)}
    assert (run.frame_rate(), run.frame_size()) == (10.0, (64, 48))
    assert not run.salvage("cam", {}, -9)            # a folder with a summary is left alone


def test_a_partial_folder_is_renamed_into_place_replacing_the_old_one(tmp_path):
    final = RunFolder(tmp_path / "video")
    final.path.mkdir()
    (final.path / "old.txt").write_text("old run\n")
    part = final.partial()
    assert part.path == tmp_path / ".video.partial"
    part.path.mkdir()
    part.tracks.write_text("")
    part.write_summary({"frames": 2, "outputs": {"tracks": str(part.tracks)}})
    final.commit_partial({"batch": {"name": "video"}})
    assert not part.path.exists() and not (tmp_path / ".video.old").exists()
    assert sorted(p.name for p in final.path.iterdir()) == ["summary.json", "tracks.txt"]
    assert final.summary() == {"frames": 2, "outputs": {"tracks": str(final.tracks)},
                               "batch": {"name": "video"}}
