"""Sources: files, truncated files, image folders/globs, synthetic scenes, live reconnection."""

from __future__ import annotations

import itertools
import re
import threading
import time

import cv2
import numpy as np
import pytest

from motiontrack.errors import ConfigError, InputError, SourceError
from motiontrack.io.sources import (ArraySource, ImageSequenceSource, LiveSource, VideoFileSource,
                                    open_source, prefetch)
from motiontrack.synth import SyntheticSource


@pytest.mark.parametrize("content, message", [
    (None, "not found"),
    (b"", "empty"),
    (bytes(range(256)) * 20, "cannot open|no frames"),
])
def test_bad_video_files(tmp_path, content, message):
    p = tmp_path / "v.avi"
    if content is not None:
        p.write_bytes(content)
    with pytest.raises(SourceError, match=message):
        open_source(str(p))


MOT_ROWS = "1,1,10.5,20,30,90,1,-1,-1,-1\n2,1,11.5,20,30,90,1,-1,-1,-1\n" * 40


# .txt and .nfo: FFmpeg's tty demuxer opens them and draws the characters as frames ("ansi");
# .csv and .avi: FFmpeg cannot open them at all
@pytest.mark.parametrize("name, content", [
    ("gt.txt", MOT_ROWS), ("notes.nfo", "readme\n" * 50), ("gt.csv", MOT_ROWS),
    ("notes.avi", "this is not a video\n" * 50), ("café.txt", "naïve, ünïcode text\n" * 300),
])
def test_a_text_file_is_not_a_video(tmp_path, name, content):
    p = tmp_path / name
    p.write_text(content, encoding="utf-8")
    with pytest.raises(InputError, match=f"{re.escape(str(p))} is a text file, not a video"):
        open_source(str(p))


def _write_raw_mjpeg(path, n):
    """Concatenated JPEGs: a video whose length FFmpeg learns only by reading it."""
    with open(path, "wb") as f:
        for i in range(n):
            f.write(cv2.imencode(".jpg", np.full((48, 64, 3), i * 30, np.uint8))[1].tobytes())


def test_start_past_the_end_of_a_source_of_known_length_is_refused_at_open(tmp_path):
    p = tmp_path / "v.avi"
    _write_video(p)   # 12 frames
    for spec in (str(p), "synth:walker?n_frames=12"):
        with pytest.raises(ConfigError, match="start frame 12 .* past the end .* has 12 frames"):
            open_source(spec, start=12)
        assert [f.index for f in open_source(spec, start=11)] == [11]
    for i in range(3):
        cv2.imwrite(str(tmp_path / f"in{i}.png"), np.zeros((8, 8, 3), np.uint8))
    with pytest.raises(ConfigError, match="start frame 7 .* has 3 frames"):
        open_source(str(tmp_path / "in*.png"), start=7)


@pytest.mark.parametrize("start", [6, 9])
def test_start_past_the_end_of_a_video_of_unknown_length_fails_at_the_first_read(tmp_path, start):
    p = tmp_path / "v.mjpeg"
    _write_raw_mjpeg(p, 6)
    src = open_source(str(p), start=start)
    assert src.info.frame_count is None
    with pytest.raises(ConfigError, match=f"start frame {start} .* past the end .* has 6 frames"):
        list(src)
    assert [f.index for f in open_source(str(p), start=5)] == [5]


def test_set_fps_replaces_the_stored_rate_in_info_and_timestamps(tmp_path):
    p = tmp_path / "v.avi"
    _write_video(p)   # stored at 10 fps
    src = open_source(str(p), start=2, max_frames=2)
    src.set_fps(7.0)
    assert (src.info.fps, src.info.stored_fps) == (7.0, 10.0)
    assert "7 fps (source.fps; stored 10 fps)" in src.info.describe()
    assert [f.timestamp for f in src] == pytest.approx([2 / 7, 3 / 7])
    synth = open_source("synth:walker?n_frames=3")
    synth.set_fps(5.0)
    assert [f.timestamp for f in synth] == pytest.approx([0.0, 0.2, 0.4])
    with pytest.raises(ConfigError, match="source.fps"):
        synth.set_fps(0.0)


def _write_video(path, n=12, size=(64, 48)):
    w = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10, size)
    for i in range(n):
        w.write(np.full((size[1], size[0], 3), i * 10, np.uint8))
    w.release()


def test_video_file_info_start_and_max_frames(tmp_path):
    p = tmp_path / "v.avi"
    _write_video(p)
    src = open_source(str(p), start=3, max_frames=4)
    assert isinstance(src, VideoFileSource)
    assert (src.info.width, src.info.height, src.info.fps, src.info.frame_count) == (64, 48, 10.0, 12)
    frames = list(src)
    assert [f.index for f in frames] == [3, 4, 5, 6]
    assert frames[0].timestamp == pytest.approx(0.3)
    assert src.expected_frames() == 4 and not src.truncated


@pytest.mark.parametrize("name", ["video[1080p].avi", "what?.avi", "all*.avi", "[v].avi"])
def test_an_existing_file_is_the_file_whatever_its_name_holds(tmp_path, name):
    p = tmp_path / name
    _write_video(p)
    for spec in (str(p), f"file://{p}"):
        src = open_source(spec)
        assert isinstance(src, VideoFileSource)
        assert len(list(src)) == 12


@pytest.mark.data
def test_truncated_pets_clip_keeps_what_decodes(data, tmp_path, caplog):
    video = data("pets09-s2l1", "video.avi")
    cut = tmp_path / "cut.avi"
    cut.write_bytes(video.read_bytes()[: 400_000])   # about the first tenth of the file
    src = open_source(str(cut))
    with caplog.at_level("WARNING"):
        frames = list(src)
    assert 5 < len(frames) < 300
    assert src.truncated
    assert "truncated" in caplog.text


def test_image_folder_and_glob(tmp_path):
    for i in (1, 2, 10):   # natural order: 1, 2, 10 (not 1, 10, 2)
        cv2.imwrite(str(tmp_path / f"in{i}.png"), np.full((8, 9, 3), i, np.uint8))
    (tmp_path / "notes.txt").write_text("x")
    for spec in (str(tmp_path), str(tmp_path / "in*.png")):
        src = open_source(spec)
        assert isinstance(src, ImageSequenceSource)
        assert [int(f.image[0, 0, 0]) for f in src] == [1, 2, 10]


def test_image_folder_errors(tmp_path):
    with pytest.raises(SourceError, match="no images"):
        open_source(str(tmp_path / "*.jpg"))
    cv2.imwrite(str(tmp_path / "a1.png"), np.zeros((8, 8, 3), np.uint8))
    cv2.imwrite(str(tmp_path / "a2.png"), np.zeros((9, 8, 3), np.uint8))
    with pytest.raises(SourceError, match="expected 8x8"):
        list(open_source(str(tmp_path)))


def test_synthetic_source_has_ground_truth():
    src = open_source("synth:walker?n_frames=30")
    assert isinstance(src, SyntheticSource)
    assert src.info.frame_count == 30 and src.info.fps == 25.0
    assert len(list(src)) == 30
    assert src.ground_truth().frames.max() <= 30


class FakeCapture:
    """A camera that delivers ``frames`` images per connection, then drops."""

    def __init__(self, log, opens_ok, frames):
        self.log, self.frames = log, frames
        self.ok = next(opens_ok)
        self.n = 0

    def isOpened(self):
        return self.ok

    def read(self):
        if self.n >= self.frames:
            return False, None
        self.n += 1
        return True, np.zeros((4, 4, 3), np.uint8)

    def get(self, prop):
        return 0.0

    def release(self):
        self.log.append("release")


@pytest.mark.parametrize("opens, per_connection, attempts, reset_frames, max_frames, "
                         "frames, reconnects, sleeps, fails", [
    # 3 frames, two failed reopens, a reopen that works (attempt 3 of 3), 3 frames, drop: the
    # budget is spent, since 3 frames are fewer than the 250 that would restore it
    ([True, False, False, True] + [True] * 10, 3, 3, 250, 0,
     3 + 3, 1, [0.5, 1.0, 1.0], True),
    # a stream that comes back for 2 frames after every reconnection: 4 reconnections in all,
    # each succeeding, then it fails (a reconnect that works does not restore the budget)
    ([True] * 20, 2, 4, 250, 100,
     2 + 4 * 2, 4, [0.5, 1.0, 1.0, 1.0], True),
    # 6 frames per connection and a budget restored after 5 in a row: one attempt is enough
    # every time, and the back-off starts afresh (0.5 s each time); 30 frames = 5 connections
    ([True] * 20, 6, 1, 5, 30,
     30, 4, [0.5] * 4, False),
])
def test_live_source_failure_budget(opens, per_connection, attempts, reset_frames, max_frames,
                                    frames, reconnects, sleeps, fails):
    log, waited = [], []
    it = iter(opens)
    src = LiveSource(0, max_frames=max_frames, reconnect_attempts=attempts, backoff=0.5,
                     backoff_max=1.0, reset_frames=reset_frames,
                     opener=lambda t: FakeCapture(log, it, per_connection), sleep=waited.append,
                     clock=itertools.count().__next__)
    got = []
    if fails:
        with pytest.raises(SourceError, match=f"failed after {frames} frames and {attempts} "
                                              "reconnection attempts"):
            for f in src:
                got.append(f)
    else:
        got = list(src)
    assert len(got) == frames
    assert src.reconnects == reconnects
    assert waited == sleeps                       # doubling, capped at backoff_max
    assert [f.timestamp for f in got] == sorted(f.timestamp for f in got)   # wall-clock stamps
    assert src.info.live and src.info.frame_count is None


@pytest.mark.parametrize("kwargs, message", [
    ({"read_timeout": 0.0}, "read_timeout must be a finite number > 0"),
    ({"backoff": float("nan")}, "backoff must be a finite number >= 0"),
    ({"backoff_max": float("inf")}, "backoff_max must be a finite number >= 0"),
    ({"reset_frames": 0}, "reset_frames must be a finite number >= 1"),
    ({"reconnect_attempts": -1}, "reconnect_attempts must be a finite number >= 0"),
])
def test_live_source_rejects_bad_options(kwargs, message):
    with pytest.raises(SourceError, match=message):
        LiveSource(0, opener=lambda t: FakeCapture([], iter([True]), 3), **kwargs)


class KnownLengthCapture(FakeCapture):
    """A capture of a file of ``length`` frames (OpenCV reports its frame count), which ends
    after ``frames``."""

    def __init__(self, log, opens_ok, frames, length):
        super().__init__(log, opens_ok, frames)
        self.length = length

    def get(self, prop):
        return {cv2.CAP_PROP_FRAME_COUNT: float(self.length), cv2.CAP_PROP_FPS: 10.0}.get(prop, 0.0)


@pytest.mark.parametrize("frames, truncated", [(40, False), (25, True)])
def test_a_stream_of_known_length_ends_instead_of_reconnecting(frames, truncated):
    log, waited = [], []
    opens = iter([True] * 5)
    src = LiveSource("http://127.0.0.1:9/clip.avi", reconnect_attempts=3,
                     opener=lambda t: KnownLengthCapture(log, opens, frames, 40),
                     sleep=waited.append)
    got = list(src)
    assert len(got) == frames and waited == [] and src.reconnects == 0
    assert src.truncated is truncated
    assert (src.info.frame_count, src.info.live, src.expected_frames()) == (40, False, 40)
    assert [f.timestamp for f in got[:3]] == [0.0, 0.1, 0.2]      # index / fps, like a file


def test_a_stop_request_ends_a_live_source_during_its_back_off():
    # every reopen fails and the back-off is 30 s: only the stop request ends the iteration
    opens = iter([True] + [False] * 10)
    src = LiveSource(0, reconnect_attempts=5, backoff=30.0, backoff_max=30.0,
                     opener=lambda t: FakeCapture([], opens, 3))
    asked = []
    src.stop_requested = lambda: bool(asked)
    got = []
    t0 = time.monotonic()
    for f in src:
        got.append(f)
        if len(got) == 3:
            threading.Timer(0.3, asked.append, [True]).start()
    assert len(got) == 3 and not src.truncated
    assert 0.3 <= time.monotonic() - t0 < 1.5


def test_live_source_that_never_opens():
    opens = iter([False])
    with pytest.raises(SourceError, match="cannot open camera 0"):
        LiveSource(0, opener=lambda t: FakeCapture([], opens, 0))


def test_prefetch_passes_exceptions_and_stops_early():
    def gen():
        yield 1
        yield 2
        raise SourceError("boom")

    it = prefetch(gen())
    assert next(it) == 1 and next(it) == 2
    with pytest.raises(SourceError, match="boom"):
        next(it)
    closed = []

    def endless():
        try:
            for i in itertools.count():
                yield i
        finally:
            closed.append(True)

    it = prefetch(endless(), size=2)
    assert [next(it) for _ in range(3)] == [0, 1, 2]
    it.close()
    assert closed == [True]


def test_prepared_runs_in_the_reading_thread_of_sources_that_decode_ahead(tmp_path):
    # the pipeline preprocesses in the thread that decodes (Source.prepared): same frames, same
    # order, start and length as plain iteration; sources without a reading thread run it inline
    import threading

    p = tmp_path / "v.avi"
    _write_video(p)
    for i in (1, 2, 10):
        cv2.imwrite(str(tmp_path / f"in{i}.png"), np.full((8, 9, 3), i, np.uint8))

    def where(frame):
        return threading.current_thread().name, int(frame.image[0, 0, 0])

    cases = [(open_source(str(p), start=3, max_frames=4), "motiontrack-decode"),
             (open_source(str(tmp_path / "in*.png")), "motiontrack-decode"),
             (ArraySource([np.full((4, 4, 3), i, np.uint8) for i in range(5)], max_frames=3),
              threading.current_thread().name)]
    for src, thread in cases:
        plain = [(f.index, int(f.image[0, 0, 0])) for f in src]
        pairs = list(src.prepared(where))
        assert [(f.index, int(f.image[0, 0, 0])) for f, _ in pairs] == plain
        assert [value for f, (_, value) in pairs] == [v for _, v in plain]
        assert {name for _, (name, _) in pairs} == {thread}


def test_array_source_and_bad_arguments():
    src = ArraySource([np.zeros((4, 4, 3), np.uint8)] * 5, max_frames=2)
    assert len(list(src)) == 2
    with pytest.raises(SourceError, match="start must be >= 0"):
        ArraySource([np.zeros((4, 4), np.uint8)], start=-1)


def test_live_source_marks_the_first_frame_after_each_reconnection():
    # 3 frames per connection, 8 frames: connections give frames 0-2, 3-5, 6-7; frames 3 and
    # 6 are the first after a reconnection, frame 0 the first of all (no jump before it)
    it = iter([True] * 10)
    src = LiveSource(0, max_frames=8, backoff=0.0, reset_frames=2,
                     opener=lambda t: FakeCapture([], it, 3), sleep=lambda s: None,
                     clock=itertools.count().__next__)
    marks = [(f.index, f.discontinuity.reason) for f in src if f.discontinuity is not None]
    assert marks == [(3, "reconnect"), (6, "reconnect")]


@pytest.mark.parametrize("start, marked", [(0, []), (5, [(5, "seek")])])
def test_sources_mark_a_start_frame_as_a_seek(start, marked):
    images = [np.full((8, 8, 3), i, np.uint8) for i in range(10)]
    for src in (ArraySource(images, start=start), open_source("synth:walker?n_frames=10&width=96"
                                                              "&height=72", start=start)):
        got = [(f.index, f.discontinuity.reason) for f in src if f.discontinuity is not None]
        assert got == marked
