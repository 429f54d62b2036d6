"""`motiontrack analyze` and `track --scene`: events.jsonl, counts.csv, summary.json."""

from __future__ import annotations

import csv
import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

try:
    import tomllib
except ImportError:  # Python < 3.11
    import tomli as tomllib

from motiontrack.analytics import parse_scene
from motiontrack.cli import main
from motiontrack.render.scene import LINE_COLOR, ZONE_COLOR, draw_scene
from motiontrack.io.events import read_events
from motiontrack.io.mot import read_mot
from motiontrack.run.analyze import analysed_events, analyze_tracks
from motiontrack.run.folder import RunFolder
from motiontrack.types import EVENTS_SCHEMA, Annotations, Event, SceneFrame

SCENE_TOML = """
[[line]]
name = "gate"
points = [[0, 100], [200, 100]]
[[zone]]
name = "pen"
polygon = [[0, 0], [200, 0], [200, 60], [0, 60]]
"""


def _rows(path, rows):
    """A MOTChallenge tracks file: rows of (frame, id, foot x, foot y) with 10x20 boxes."""
    path.write_text("".join(f"{f},{i},{x - 5},{y - 20},10,20,1,-1,-1,-1\n" for f, i, x, y in rows))
    return path


@pytest.fixture
def scene_file(tmp_path):
    p = tmp_path / "scene.toml"
    p.write_text(SCENE_TOML)
    return p


def test_analyze_writes_events_counts_and_summary(tmp_path, scene_file, capsys):
    tracks = _rows(tmp_path / "tracks.txt", [
        (1, 1, 100, 40),   # track 1 starts in the pen: zone_enter at frame 1
        (2, 1, 100, 80),   # left the pen (20 px out): zone_exit, dwell 1 frame = 0.5 s
        (3, 1, 100, 120),  # below the gate: in
        (4, 2, 50, 130),   # track 2 below the gate
        (5, 2, 50, 70),    # above it: out (t = 2.0 s, in the second 1.5 s bin)
    ])
    out = tmp_path / "out"
    assert main(["analyze", str(tracks), "--scene", str(scene_file), "--fps", "2", "-o", str(out),
                 "--bin-s", "1.5"]) == 0
    assert "4 events over 5 frames; gate in 1 out 1" in capsys.readouterr().out
    lines = (out / "events.jsonl").read_text().splitlines()
    header = json.loads(lines[0])
    assert header["schema"] == EVENTS_SCHEMA and header["version"] == 1 and header["fps"] == 2.0
    events = [Event.from_json(json.loads(ln)) for ln in lines[1:]]
    assert [(e.type, e.frame, e.t, e.track) for e in events] == [
        ("zone_enter", 1, 0.0, 1), ("zone_exit", 2, 0.5, 1), ("line_cross", 3, 1.0, 1),
        ("line_cross", 5, 2.0, 2)]
    assert [e.direction for e in events[2:]] == ["in", "out"] and events[1].dwell_s == 0.5
    with open(out / "counts.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    # bin 0: frames 1-3 (t 0, 0.5, 1.0); bin 1: frames 4-5 (t 1.5, 2.0)
    assert [(r["bin"], r["frames"], r["line:gate:in"], r["line:gate:out"]) for r in rows] == [
        ("0", "3", "1", "0"), ("1", "2", "0", "1")]
    assert [(r["zone:pen:mean"], r["zone:pen:peak"]) for r in rows] == [("0.3333", "1"),
                                                                      ("0.0", "0")]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 5 and summary["tracks"] == 2
    assert summary["analytics"]["lines"] == {"gate": {"in": 1, "out": 1}}
    assert summary["analytics"]["zones"]["pen"]["enters"] == 1
    assert summary["analytics"]["events"]["line_cross"] == 2


def test_analyze_of_no_tracks_writes_headers_only(tmp_path):
    out = tmp_path / "out"
    summary = analyze_tracks(Annotations.empty(), parse_scene(tomllib.loads(SCENE_TOML)), 5.0, out)
    assert summary["frames"] == 0 and summary["analytics"]["lines"]["gate"] == {"in": 0, "out": 0}
    assert len((out / "events.jsonl").read_text().splitlines()) == 1
    assert (out / "counts.csv").read_text().splitlines() == [
        "bin,start_s,end_s,frames,line:gate:in,line:gate:out,zone:pen:mean,zone:pen:peak"]


@pytest.mark.parametrize("extra, scene, message", [
    ([], SCENE_TOML, "needs the frame rate of tracks.txt: give --fps"),
    (["--fps", "0"], SCENE_TOML, "frame rate > 0"),
    (["--fps", "5", "--bin-s", "0"], SCENE_TOML, "--bin-s must be > 0"),
    (["--fps", "5"], "[[line]]\nname = 'g'\npoints = [[1, 1]]\n", "line[1].points must be two"),
    (["--fps", "5"], "[speed]\nlimit_mps = 2\n", "speed.limit_mps is in metres and needs a camera"),
    (["--fps", "5"], "[[zone]\n", "malformed scene file"),
])
def test_analyze_bad_input_is_one_line_and_nonzero(tmp_path, capsys, extra, scene, message):
    tracks = _rows(tmp_path / "tracks.txt", [(1, 1, 10, 10)])
    (tmp_path / "s.toml").write_text(scene)
    code = main(["analyze", str(tracks), "--scene", str(tmp_path / "s.toml"), "-o",
                 str(tmp_path / "o"), *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0 and len(err) == 1 and message in err[0], err


def test_analyze_refuses_detections_without_track_ids(tmp_path, scene_file, capsys):
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,5,5,0.9,-1,-1,-1\n")
    assert main(["analyze", str(det), "--scene", str(scene_file), "--fps", "5", "-o",
                 str(tmp_path / "o")]) != 0
    assert "without a track id" in capsys.readouterr().err


def test_analyze_needs_force_to_replace_outputs(tmp_path, scene_file, capsys):
    tracks = _rows(tmp_path / "tracks.txt", [(1, 1, 10, 10)])
    args = ["analyze", str(tracks), "--scene", str(scene_file), "--fps", "5", "-o", str(tmp_path / "o")]
    assert main(args) == 0
    assert main(args) != 0 and "--force" in capsys.readouterr().err
    assert main(args + ["--force"]) == 0


def test_frame_rate_comes_from_the_run_summary_beside_the_tracks(tmp_path):
    tracks = _rows(tmp_path / "tracks.txt", [(1, 1, 10, 10)])
    assert RunFolder.beside(tracks).frame_rate() is None
    (tmp_path / "summary.json").write_text(json.dumps({"source_fps": 12.5}))
    assert RunFolder.beside(tracks).frame_rate() == 12.5


def test_scene_drawing_shows_lines_zones_and_counts():
    scene = parse_scene({"line": [{"name": "g", "points": [[10, 100], [300, 100]]}],
                         "zone": [{"name": "z", "polygon": [[50, 150], [250, 150], [150, 230]]}]})
    img = np.zeros((240, 320, 3), np.uint8)
    frame = SceneFrame(1, (), {"g": (2, 1)}, {"z": 1})
    draw_scene(img, scene.lines, scene.zones, frame)
    assert tuple(img[100, 200]) == LINE_COLOR          # on the line
    assert tuple(img[150, 200]) == ZONE_COLOR          # on the zone's top edge
    inside = img[190, 150]
    assert 0 < inside[0] < ZONE_COLOR[0]               # tinted, not painted over
    assert img[:95, :].any()                           # the count label above the line's start


@pytest.mark.slow
def test_track_scene_and_analyze_on_its_tracks_find_the_same_events(tmp_path):
    # the walker enters from the right at frame 22 and walks left at about 2.9 px per frame
    scene = tmp_path / "walk.toml"
    scene.write_text("""
[[line]]
name = "gate"
points = [[560, 479], [560, 150]]
[[zone]]
name = "right"
polygon = [[520, 200], [639, 200], [639, 479], [520, 479]]
""")
    run = tmp_path / "run"
    assert main(["track", "synth:walker?n_frames=90", "--scene", str(scene), "--no-video",
                 "-o", str(run)]) == 0
    live = (run / "events.jsonl").read_text().splitlines()
    types = [json.loads(x)["type"] for x in live[1:]]
    assert "line_cross" in types and "zone_enter" in types and "zone_exit" in types
    summary = json.loads((run / "summary.json").read_text())
    assert summary["analytics"]["lines"]["gate"] == {"in": 0, "out": 1}  # right to left: out
    again = tmp_path / "again"
    assert main(["analyze", str(run / "tracks.txt"), "--scene", str(scene), "-o", str(again)]) == 0
    assert (again / "events.jsonl").read_text().splitlines()[1:] == live[1:]


def test_an_interrupted_analyze_keeps_the_frames_analysed_and_says_so(tmp_path):
    scene = parse_scene(tomllib.loads(SCENE_TOML))
    tracks = read_mot(_rows(tmp_path / "tracks.txt", [(f, 1, 100, 20 * f) for f in range(1, 8)]),
                      kind="results")
    polls = iter(range(100))
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):   # a stop asked after the third frame
        analyze_tracks(tracks, scene, 2.0, out, should_stop=lambda: next(polls) >= 2)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 3 and summary["status"] == "interrupted"
    assert summary["interrupted"] is True
    rows = list(csv.DictReader((out / "counts.csv").read_text().splitlines()))
    assert [r["frames"] for r in rows] == ["3"]
    assert not (out / ".motiontrack.lock").exists()


def test_analyze_forced_into_the_tracked_runs_folder_keeps_that_runs_files(tmp_path, scene_file):
    run = tmp_path / "run"
    assert main(["track", "synth:walker?n_frames=30", "--no-video", "-o", str(run)]) == 0
    tracks = (run / "tracks.txt").read_bytes()
    assert main(["analyze", str(run / "tracks.txt"), "--scene", str(scene_file), "-o", str(run),
                 "--force"]) == 0
    # the tracks it read and the track run's other outputs stay; the analysis is added
    assert (run / "tracks.txt").read_bytes() == tracks
    assert (run / "config.toml").is_file() and (run / "gt.txt").is_file()
    assert (run / "events.jsonl").is_file() and (run / "counts.csv").is_file()


@pytest.mark.slow
def test_sigterm_stops_analyze_keeping_the_frames_analysed(tmp_path, scene_file):
    # one track at frame 1 and frame 2,000,000: two million frames to step, so it is still running
    tracks = _rows(tmp_path / "tracks.txt", [(1, 1, 100, 20), (2_000_000, 1, 100, 40)])
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "motiontrack", "analyze", str(tracks),
                             "--scene", str(scene_file), "--fps", "25", "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not (out / ".motiontrack.lock").exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.5)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=20)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True and 0 < summary["frames"] < 2_000_000
    rows = list(csv.DictReader((out / "counts.csv").read_text().splitlines()))
    assert rows and int(rows[-1]["frames"]) <= summary["frames"]


def test_analysed_events_in_memory_are_those_analyze_writes(tmp_path):
    scene = parse_scene(tomllib.loads(SCENE_TOML))
    tracks = read_mot(_rows(tmp_path / "tracks.txt", [
        (1, 1, 100, 40), (2, 1, 100, 80), (3, 1, 100, 120), (4, 2, 50, 130), (5, 2, 50, 70)]),
        kind="results")
    analyze_tracks(tracks, scene, 2.0, tmp_path / "out")
    written = read_events(tmp_path / "out" / "events.jsonl").events
    assert len(written) == 4 and analysed_events(tracks, scene, 2.0) == written
