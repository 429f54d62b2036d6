"""Discontinuities of a source through ``track``'s job: a live source that reconnects after a
gap and a file read from a start frame reset the stages, and ``events.jsonl`` records each
jump before the frame's events."""

from __future__ import annotations

import itertools
import json

import numpy as np

from motiontrack.config import load_config
from motiontrack.io.events import read_events
from motiontrack.io.mot import read_mot
from motiontrack.io.sources import LiveSource
from motiontrack.run import track_job
from motiontrack.types import Discontinuity

SCENE = """\
# the whole picture
[[zone]]
name = "all"
polygon = [[0, 0], [96, 0], [96, 72], [0, 72]]
"""
#: frames per connection of the camera below
PER_CONNECTION = 16


class _Camera:
    """A camera whose every connection shows a white square crossing a grey picture from the
    left, ``PER_CONNECTION`` frames, then drops."""

    def __init__(self) -> None:
        self.n = 0

    def isOpened(self) -> bool:
        return True

    def read(self):
        if self.n >= PER_CONNECTION:
            return False, None
        img = np.full((72, 96, 3), 60, np.uint8)
        x = 4 + 4 * self.n
        img[30:45, x:x + 12] = 255
        self.n += 1
        return True, img

    def get(self, prop) -> float:
        return 0.0

    def release(self) -> None:
        pass


def _lines(path):
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_a_reconnection_ends_the_tracks_and_is_recorded_in_the_events_file(tmp_path):
    (tmp_path / "scene.toml").write_text(SCENE)
    src = LiveSource(0, max_frames=2 * PER_CONNECTION, backoff=0.0, opener=lambda t: _Camera(),
                     sleep=lambda s: None, clock=itertools.count(0.0, 0.04).__next__)
    cfg = load_config(None, ["motion.warmup=2", "output.video=false",
                             "output.mask_video=false"])
    track_job(src, cfg, tmp_path / "out", scene=tmp_path / "scene.toml").run()
    cut = PER_CONNECTION + 1          # the first frame after the reconnection, 1-based
    lines = _lines(tmp_path / "out" / "events.jsonl")
    assert {"type": "discontinuity", "reason": "reconnect", "frame": cut} in lines
    # the square is one track in each connection: the first one ends at the jump (no
    # zone_exit: it did not leave), the second one enters the zone afresh
    record = lines.index({"type": "discontinuity", "reason": "reconnect", "frame": cut})
    before = [e for e in lines[1:record]]
    after = [e for e in lines[record + 1:]]
    assert [e["type"] for e in before] == ["zone_enter"]
    assert [e["type"] for e in after] == ["zone_enter"] and after[0]["frame"] > cut
    assert after[0]["track"] != before[0]["track"]
    tracks = read_mot(tmp_path / "out" / "tracks.txt")
    first = set(tracks.ids[tracks.frames < cut].tolist())
    second = set(tracks.ids[tracks.frames >= cut].tolist())
    assert first and second and not first & second
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["analytics"]["discontinuities"] == {"reconnect": 1}


def test_a_run_from_a_start_frame_records_the_seek(tmp_path):
    (tmp_path / "scene.toml").write_text(SCENE.replace("96, 72", "160, 120").replace(
        "[96, 0]", "[160, 0]").replace("[0, 72]", "[0, 120]"))
    cfg = load_config(None, ["source.start=5", "source.max_frames=5", "output.video=false",
                             "output.mask_video=false"])
    track_job("synth:walker?n_frames=20&width=160&height=120", cfg, tmp_path / "out",
              scene=tmp_path / "scene.toml").run()
    ef = read_events(tmp_path / "out" / "events.jsonl")
    assert ef.discontinuities == ((6, Discontinuity("seek")),)


def test_events_files_check_their_discontinuity_records(tmp_path):
    import pytest

    from motiontrack.errors import InputError

    head = '{"schema": "motiontrack.events", "version": 1, "fps": 25.0}\n'
    path = tmp_path / "events.jsonl"
    for record, message in (('{"type": "discontinuity", "reason": "rewind", "frame": 3}',
                             "reason must be one of loop, reconnect, seek, got 'rewind'"),
                            ('{"type": "discontinuity", "reason": "loop", "frame": 0}',
                             "frame must be an integer >= 1, got 0"),
                            ('{"type": "discontinuity", "reason": "loop", "frame": 2, "x": 1}',
                             "unknown keys x")):
        path.write_text(head + record + "\n")
        with pytest.raises(InputError, match=f"events.jsonl:2: .*{message}"):
            read_events(path)
