"""Live sources over HTTP, served by a small server on 127.0.0.1 started by each test: MJPEG
streams (multipart/x-mixed-replace of JPEG frames) that drop, stall or stop, and a video file.
A stop request ends a run within 2 s whatever the stream is doing; a file over HTTP is read once;
a stream that keeps failing gives up."""

from __future__ import annotations

import json
import logging
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from helpers.mjpeg_server import MjpegServer, moving_box, serve_folder
from motiontrack.cli import main
from motiontrack.config import load_config
from motiontrack.errors import ConfigError, SourceError
from motiontrack.io.sources import LiveSource, open_source
from motiontrack.run import track_job

#: the longest a stop request may take to end a run (s)
STOP_WITHIN = 2.0


def _picture(i: int) -> np.ndarray:
    """Frame ``i`` of the served scene: a white square moving right on a grey background."""
    return moving_box(i, size=(64, 48), box=(4, 14, 14, 34), step=2, period=25)


@pytest.fixture(autouse=True)
def _restore_logging():
    """``main()`` points the package's log at this test's captured stderr: point it back, so
    that later tests' reader threads do not log to a closed stream."""
    logger = logging.getLogger("motiontrack")
    saved = (logger.handlers[:], logger.level, logger.propagate)
    yield
    logger.handlers[:], logger.level, logger.propagate = saved[0], saved[1], saved[2]


@pytest.fixture
def mjpeg():
    servers = []

    def start(frames: int, then: str = "close") -> MjpegServer:
        """A stream whose every connection gets ``frames`` pictures at 25 fps, then ``then``."""
        servers.append(MjpegServer([_picture(i) for i in range(frames)], frames, then))
        return servers[-1]

    yield start
    for s in servers:
        if not s.stopped.is_set():
            s.stop()


@pytest.fixture
def served_clip(tmp_path):
    """A 40-frame MJPG AVI (10 fps) served by http.server; yields its URL."""
    root = tmp_path / "www"
    root.mkdir()
    w = cv2.VideoWriter(str(root / "clip.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 10, (64, 48))
    for i in range(40):
        w.write(_picture(i))
    w.release()

    httpd = serve_folder(root)
    yield f"http://127.0.0.1:{httpd.server_address[1]}/clip.avi"
    httpd.shutdown()
    httpd.server_close()


# ------------------------------------------------------------------------ a file over HTTP
def test_a_video_file_over_http_is_read_once_to_its_end(served_clip, tmp_path, capsys):
    # OpenCV knows the length of a served file (40 frames): its end is the end, not a drop to
    # reconnect from (which would restart the clip: frames without end, new ids every loop)
    src = open_source(served_clip, max_frames=200)
    frames = list(src)
    assert len(frames) == 40 and not src.truncated and src.reconnects == 0
    assert (src.info.frame_count, src.info.live, src.info.fps) == (40, False, 10.0)
    assert [f.timestamp for f in frames[:3]] == [0.0, 0.1, 0.2]   # index / fps, like a file
    out = tmp_path / "o"
    assert main(["track", served_clip, "-o", str(out), "--codec", "mjpg",
                 "--max-frames", "200"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["frames"], summary["status"], summary["truncated"]) == (40, "complete", False)
    assert "reconnecting" not in capsys.readouterr().err


def test_start_past_the_end_of_a_video_file_over_http_is_refused(served_clip):
    with pytest.raises(ConfigError, match="start frame 40 .* past the end .* has 40 frames"):
        open_source(served_clip, start=40)
    assert [f.index for f in open_source(served_clip, start=39)] == [39]


# ------------------------------------------------------------------------ the failure budget
def test_a_stream_that_keeps_dropping_fails_after_its_reconnect_attempts(mjpeg):
    # every connection delivers 4 frames, then the server closes it; each reconnection works.
    # The attempts are counted until 250 frames in a row arrive, which never happens: the
    # connection plus 3 reconnections give 4 * 4 frames, then the source fails
    server = mjpeg(4)
    src = open_source(server.url, max_frames=200, reconnect_attempts=3, backoff=0.01,
                      backoff_max=0.02)
    got = []
    t0 = time.monotonic()
    with pytest.raises(SourceError, match="failed after 16 frames and 3 reconnection attempts"):
        for f in src:
            got.append(f)
    assert len(got) == 16 and src.reconnects == 3 and server.connections == 4
    assert src.truncated and time.monotonic() - t0 < 10


@pytest.mark.slow
def test_a_stalled_stream_times_out_and_counts_in_the_budget(mjpeg):
    # every connection delivers 3 frames, then stays open without sending anything: each
    # stall ends after the read timeout (0.5 s) and costs one reconnect attempt of 2
    server = mjpeg(3, then="stall")
    src = open_source(server.url, reconnect_attempts=2, backoff=0.01, read_timeout=0.5)
    got = []
    t0 = time.monotonic()
    with pytest.raises(SourceError, match="failed after 9 frames and 2 reconnection attempts"):
        for f in src:
            got.append(f)
    elapsed = time.monotonic() - t0
    assert len(got) == 9 and server.connections == 3
    assert 3 * 0.5 <= elapsed < 3 * 0.5 + 3.0      # three stalls of 0.5 s, not 30 s each


@pytest.mark.slow
def test_the_read_timeout_comes_from_the_config(mjpeg, tmp_path, capsys):
    server = mjpeg(3, then="stall")
    out = tmp_path / "o"
    t0 = time.monotonic()
    code = main(["track", server.url, "-o", str(out), "--codec", "mjpg",
                 "--set", "source.read_timeout_s=0.5", "--set", "source.reconnect_attempts=1",
                 "--set", "source.reconnect_backoff=0.01"])
    assert code == 3 and time.monotonic() - t0 < 20
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 6 and summary["status"].startswith("source failed")
    assert "failed after 6 frames and 1 reconnection attempts" in capsys.readouterr().err


# ------------------------------------------------------------------------ stopping a job
def _stopped_job(url: str, out: Path, after: threading.Event, delay: float):
    """Run the track job on ``url``, asking it to stop ``delay`` s after ``after`` is set.
    Returns the seconds from the stop request to the end of :meth:`Job.run`."""
    job = track_job(url, load_config(None, ['output.codec="mjpg"']), out)
    asked: list[float] = []

    def ask() -> None:
        if after.wait(30):
            time.sleep(delay)
            asked.append(time.monotonic())

    threading.Thread(target=ask, daemon=True).start()
    with pytest.raises(KeyboardInterrupt):
        job.run(should_stop=lambda: bool(asked))
    return time.monotonic() - asked[0]


@pytest.mark.slow
@pytest.mark.parametrize("phase", ["backing off", "stalled"])
def test_a_stop_request_ends_a_job_on_a_live_stream_within_two_seconds(mjpeg, tmp_path, phase):
    # backing off: 20 frames, then the server stops, so reconnections are refused and the source
    # waits 0.5, 1, 2, 4, 8 s between them; stalled: 20 frames, then the connection stays open
    # and silent, so the read waits for its 5 s timeout. The stop comes 0.5 s into either.
    server = mjpeg(20, then="close" if phase == "backing off" else "stall")
    if phase == "backing off":
        threading.Thread(target=lambda: server.served.wait(30) and server.stop(),
                         daemon=True).start()
    out = tmp_path / "o"
    latency = _stopped_job(server.url, out, server.served, 0.5)
    assert latency < STOP_WITHIN
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True and summary["status"] == "interrupted"
    assert summary["frames"] == 20
    assert (out / "tracks.txt").is_file() and (out / "config.toml").is_file()
    assert not list(out.glob(".*.part")) and not list(out.glob("*.part"))


# ------------------------------------------------------------------------ signals, end to end
@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
@pytest.mark.parametrize("phase", ["backing off", "stalled"])
def test_a_signal_ends_a_live_run_within_two_seconds(mjpeg, tmp_path, sig, phase):
    """``motiontrack track URL``: the signal comes while the stream backs off (the server has
    stopped) or while a read waits on a silent connection; the run ends within 2 s with every
    output finalised and exit 130. A stopped command does not wait for a read it cannot
    interrupt (the read timeout is 5 s)."""
    server = mjpeg(20, then="close" if phase == "backing off" else "stall")
    out = tmp_path / "o"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "motiontrack", "track", server.url, "-o",
                             str(out), "--codec", "mjpg"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    err: list[str] = []
    backing_off = threading.Event()

    def read_stderr() -> None:
        for line in iter(proc.stderr.readline, b""):
            err.append(line.decode(errors="replace"))
            if "attempt 2/5" in err[-1]:
                backing_off.set()

    reader = threading.Thread(target=read_stderr, daemon=True)
    reader.start()
    try:
        assert server.served.wait(60), "".join(err)
        if phase == "backing off":
            server.stop()
            assert backing_off.wait(30), "".join(err)   # in the 1 s wait before attempt 2
            time.sleep(0.3)
        else:
            time.sleep(0.5)                             # 0.5 s into the 5 s read timeout
        t0 = time.monotonic()
        proc.send_signal(sig)
        summary_path = out / "summary.json"
        while not summary_path.exists() and time.monotonic() - t0 < 10:
            time.sleep(0.02)
        finalised = time.monotonic() - t0
        proc.wait(timeout=15)
        exited = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        reader.join(5)
        proc.stdout.close()
        proc.stderr.close()
    text = "".join(err)
    assert proc.returncode == 130, text
    assert finalised < STOP_WITHIN, (finalised, text)
    assert exited < STOP_WITHIN, (exited, text)
    summary = json.loads(summary_path.read_text())
    assert summary["interrupted"] is True and 0 < summary["frames"] <= 20
    assert (out / "tracks.txt").is_file() and (out / "config.toml").is_file()
    assert not list(out.glob(".*.part")) and "Traceback" not in text
    print(f"{sig.name} while {phase}: outputs final in {finalised:.2f} s, exit in {exited:.2f} s")


@pytest.mark.slow
def test_a_live_source_left_open_at_interpreter_exit_ends_the_process_cleanly(mjpeg, tmp_path):
    # the reader thread sits in a read of a silent stream (0.5 s timeout) when the interpreter
    # exits, and finalisation is slow (an object whose finaliser takes 1.5 s): were the read to
    # return during finalisation, the thread would abort the process (C++ terminate, exit 134);
    # exit waits for it first
    server = mjpeg(3, then="stall")
    code = ("import builtins, threading, time\n"
            "from motiontrack.io.sources import open_source\n"
            "class SlowToFinalise:\n"
            "    def __del__(self, sleep=time.sleep):\n"
            "        sleep(1.5)\n"
            "builtins.slow_to_finalise = SlowToFinalise()\n"
            f"src = open_source({server.url!r}, read_timeout=0.5)\n"
            "it = iter(src)\nfor _ in range(3):\n    next(it)\n"
            "threading.Thread(target=next, args=(it, None), daemon=True).start()\n"
            "time.sleep(0.2)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr and "terminate" not in proc.stderr
