"""A looping camera of ``serve`` in process (:func:`~motiontrack.serve.worker.run_camera`), its
file paced by a clock of the test's own: the second play of the file gives the events of the
first, after one ``discontinuity`` record, and the segment's ``events.jsonl`` says so too."""

from __future__ import annotations

import json

from motiontrack.io.events import read_events
from motiontrack.io.pacing import Pacer
from motiontrack.serve.cameras import CameraSpec
from motiontrack.serve.worker import _Flag, _Frames, run_camera
from motiontrack.types import Discontinuity

#: a person leaves a bag and walks on: stays of the person and of the bag each play
LEFTBAG = "synth:leftbag?width=96&height=72&n_frames=120&noise=0"
N = 120
SCENE = """\
[stationary]
after_s = 2.0
radius_px = 15

[[zone]]
name = "all"
polygon = [[0, 0], [96, 0], [96, 72], [0, 72]]
"""


class _Channel:
    """The camera side of a channel: the events kept in a list, the rest dropped."""

    def __init__(self) -> None:
        self.got: list[dict] = []

    def frame(self, jpeg, index, fps, wall=None) -> bool:
        return True

    def events(self, events) -> None:
        self.got.extend(events)

    def counts(self, counts) -> None:
        pass

    def status(self, status) -> None:
        pass

    def close(self) -> None:
        pass


class _Plays(Pacer):
    """No waiting (the plays run as fast as they are processed); the run stops when frame
    ``last`` is due."""

    def __init__(self, last: int) -> None:
        super().__init__(clock=lambda: 0.0, sleep=lambda s: False)
        self.last = last

    def wait(self, n: int, fps: float) -> bool:
        return n >= self.last


def _shifted(events: list[dict], offset: int) -> list[tuple]:
    return [(e["type"], e["frame"] - offset, e.get("zone"), e.get("duration_s")) for e in events]


def test_a_looped_file_gives_the_events_of_its_first_play_again(tmp_path):
    (tmp_path / "scene.toml").write_text(SCENE)
    spec = CameraSpec(name="bag", source=LEFTBAG, scene=tmp_path / "scene.toml", loop=True)
    channel = _Channel()
    code = run_camera(spec, tmp_path / "out", channel, _Flag(), pacer=_Plays(2 * N))
    assert code == 0
    records = [e for e in channel.got if e["type"] == "discontinuity"]
    assert [(r["reason"], r["frame"]) for r in records] == [("loop", N + 1)]
    events = [e for e in channel.got if e["type"] != "discontinuity"]
    first = [e for e in events if e["frame"] <= N]
    second = [e for e in events if e["frame"] > N]
    assert any(e["type"] == "stationary_start" for e in first)
    assert _shifted(second, N) == _shifted(first, 0)
    # the segment's events file: the same events, the record before the second play's
    (segment,) = (tmp_path / "out").iterdir()
    ef = read_events(segment / "events.jsonl")
    assert ef.header["source"] == json.loads((segment / "summary.json").read_text())["source"]
    assert ef.header["source"].startswith("synth:leftbag")     # the camera's source, by name
    assert ef.discontinuities == ((N + 1, Discontinuity("loop")),)
    assert [e.to_json()["type"] for e in ef.events] == [e["type"] for e in events]


def test_a_faster_speed_plays_a_file_faster_and_keeps_its_times():
    from motiontrack.config import load_config

    rates: list[float] = []

    class Recorder(Pacer):
        def __init__(self) -> None:
            super().__init__(clock=lambda: 0.0, sleep=lambda s: False)

        def wait(self, n: int, fps: float) -> bool:
            rates.append(fps)
            return False

    spec = CameraSpec(name="fast", source="synth:walker?n_frames=5", speed=20.0)
    frames = _Frames(spec, load_config(None, []), _Flag(), Recorder())
    try:
        got = [frames.next() for _ in range(3)]
    finally:
        frames.close()
    assert rates == [500.0] * 3                      # 25 fps played 20 times faster
    assert [f.timestamp for f in got] == [0.0, 0.04, 0.08]   # times of the 25 fps
