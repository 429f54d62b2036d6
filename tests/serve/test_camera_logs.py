"""The log of a camera process: a failure that recurs on every loop of a file (a video damaged
part-way) is logged once with a count, and FFmpeg's own lines stay out of it."""

from __future__ import annotations

import logging
import re
import multiprocessing
import time

import pytest

from helpers import require
from motiontrack.serve.cameras import CameraSpec
from motiontrack.serve.channel import Channel
from motiontrack.serve.worker import RepeatFilter, camera_main


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def _record(msg, *args, level=logging.WARNING, name="motiontrack.io.sources"):
    return logging.LogRecord(name, level, __file__, 1, msg, args, None)


def test_identical_records_are_logged_once_then_with_their_count():
    clock = Clock()
    f = RepeatFilter(every=60.0, clock=clock)
    cut = "%s: decoding stopped at frame %d of %d"
    # t=0: first time: logged as it is
    assert f.filter(_record(cut, "a.avi", 16, 300))
    # t=1..3: the same message (a loop each second): counted, not logged
    for clock.t in (1.0, 2.0, 3.0):
        assert not f.filter(_record(cut, "a.avi", 16, 300))
    # another message, or the same text at another level or from another logger: logged
    assert f.filter(_record(cut, "b.avi", 16, 300))
    assert f.filter(_record(cut, "a.avi", 16, 300, level=logging.ERROR))
    assert f.filter(_record(cut, "a.avi", 16, 300, name="motiontrack.run"))
    # t=61: 60 s after it was logged: logged again with the 4 repeats (3 before, this one)
    clock.t = 61.0
    rec = _record(cut, "a.avi", 16, 300)
    assert f.filter(rec)
    assert rec.getMessage() == ("a.avi: decoding stopped at frame 16 of 300 "
                                "(repeated 4 times in 61 s)")
    # t=62: counted again, from t=61
    clock.t = 62.0
    assert not f.filter(_record(cut, "a.avi", 16, 300))


def test_flush_logs_the_repeats_not_reported_yet(caplog):
    f = RepeatFilter(every=60.0, clock=Clock())
    for _ in range(3):
        f.filter(_record("camera %s: %s", "cut", "source ended"))
    f.filter(_record("logged once and never again"))
    with caplog.at_level(logging.WARNING, logger="motiontrack"):
        f.flush()
    assert [r.getMessage() for r in caplog.records] == [
        "camera cut: source ended (repeated 2 times more)"]


def test_a_bounded_number_of_messages_is_remembered():
    f = RepeatFilter(clock=Clock(), size=2)
    for i in range(5):
        assert f.filter(_record("frame %d", i))
    assert len(f.seen) == 2
    assert f.filter(_record("frame %d", 0))     # forgotten: logged again


@pytest.mark.slow
def test_a_camera_looping_a_damaged_file_logs_its_failure_once(tmp_path, capfd):
    video = tmp_path / "cut.avi"          # PETS frames 1-16 and part of the 17th
    video.write_bytes(require("pets09-s2l1", "video.avi").read_bytes()[:300_000])
    ctx = multiprocessing.get_context("spawn")
    channel = Channel(ctx)
    spec = CameraSpec(name="cut", source=str(video), loop=True, fps=500.0)
    proc = ctx.Process(target=camera_main, args=(spec, tmp_path / "out", channel),
                       kwargs={"log_level": logging.WARNING})
    proc.start()
    err: list[str] = []
    try:
        end = time.monotonic() + 60
        while not any("decoding stopped" in ln for ln in err) and time.monotonic() < end:
            err += capfd.readouterr().err.splitlines()
            time.sleep(0.1)
        time.sleep(2.0)                   # a few more loops, about 0.5 s each
    finally:
        proc.terminate()                  # SIGTERM: the camera ends, its log is flushed
        while proc.is_alive():
            for q in (channel.messages, channel.frames):   # let it write its last messages
                while not q.empty():
                    try:
                        q.get_nowait()
                    except Exception:   # noqa: BLE001 - emptied meanwhile
                        break
            proc.join(0.1)
    err += capfd.readouterr().err.splitlines()
    cut = [line for line in err if "decoding stopped at frame" in line]
    assert len(cut) == 2, err             # once, then once with the count when it ends
    assert "repeated" not in cut[0]
    # one loop or more after the first (fewer on a busy machine): a count, never a line each
    assert re.search(r"\(repeated (once|\d+ times) more\)$", cut[1]), cut
    assert not [line for line in err if line.startswith("[")], err   # no FFmpeg line
