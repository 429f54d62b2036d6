"""``motiontrack serve`` under faults: a camera whose stream drops reconnects while the other
camera keeps its rate, and twenty viewers of one camera all receive its pictures while it keeps
running (the fps cost of viewers is measured by ``benchmarks/serve.py``, not timed here).

The dropping camera reads an MJPEG stream from a small HTTP server on 127.0.0.1 that the test
stops and starts again on the same port; the steady camera is a looping synthetic scene played
at its own 25 fps.
"""

from __future__ import annotations

import threading
import time

import cv2
import numpy as np
import pytest

pytest.importorskip("starlette")
pytest.importorskip("uvicorn")
httpx = pytest.importorskip("httpx")

from helpers.mjpeg_server import MjpegServer, moving_box  # noqa: E402
from helpers.serve_process import ServeProcess  # noqa: E402

pytestmark = pytest.mark.slow

#: frames a second of the served stream
STREAM_FPS = 20.0


def _picture(i: int) -> np.ndarray:
    """Frame ``i`` of the served stream: a white box moving right on a grey background."""
    return moving_box(i, size=(160, 120), box=(5, 40, 19, 80), step=3, period=40)


def _rate(serve: ServeProcess, name: str, seconds: float) -> float:
    """Frames a second the camera processed over the next ``seconds``."""
    f0, t0 = serve.cameras()[name]["frames"], time.monotonic()
    time.sleep(seconds)
    return (serve.cameras()[name]["frames"] - f0) / (time.monotonic() - t0)


@pytest.fixture(scope="module")
def stream():
    """An endless MJPEG stream on a fixed port, which the test stops and starts again."""
    s = MjpegServer([_picture(i) for i in range(40)], fps=STREAM_FPS)
    yield s
    if not s.stopped.is_set():
        s.stop()


@pytest.fixture(scope="module")
def serve(tmp_path_factory, stream):
    """``motiontrack serve`` with the cameras ``drop`` (the stream) and ``steady`` (synth)."""
    root = tmp_path_factory.mktemp("faults")
    (root / "live.toml").write_text(
        "[source]\nreconnect_attempts = 1000\nreconnect_backoff = 0.2\n"
        "reconnect_backoff_max = 0.5\nread_timeout_s = 1.0\n")
    cameras = {"drop": {"source": stream.url, "config": "live.toml"},
               "steady": {"source": "synth:walker", "loop": True}}
    with ServeProcess(root, cameras) as srv:
        srv.wait_running(frames=20, timeout=90)
        yield srv
        assert srv.stop() == 0


def test_a_dropped_stream_reconnects_while_the_other_camera_keeps_its_rate(serve, stream):
    before = _rate(serve, "steady", 3.0)
    assert before > 15, serve.logs()          # synth:walker plays at 25 fps
    reconnects = serve.cameras()["drop"]["reconnects"]

    stream.stop()                              # the stream drops and stays away ~5 s
    serve.wait("the dropped camera reported as reconnecting",
               lambda: serve.cameras()["drop"]["status"] == "reconnecting", 15)
    during = _rate(serve, "steady", 3.0)
    frames_down = serve.cameras()["drop"]["frames"]
    stream.start()

    serve.wait("the dropped camera running again with its reconnection counted",
               lambda: (lambda c: c["status"] == "running" and c["frames"] > frames_down + 20
                        and c["reconnects"] > reconnects)(serve.cameras()["drop"]), 30)
    after = _rate(serve, "steady", 3.0)
    cams = serve.cameras()
    assert abs(during - before) <= 0.2 * before, (before, during)
    assert abs(after - before) <= 0.2 * before, (before, after)
    assert cams["drop"]["restarts"] == 0 and cams["steady"]["restarts"] == 0
    assert cams["steady"]["status"] == "running"


def _viewer(url: str, want: int, got: list, errors: list, ready: threading.Barrier) -> None:
    """One MJPEG viewer: read until ``want`` pictures have arrived (each checked to decode)."""
    try:
        n, buf = 0, b""
        with httpx.Client(timeout=20) as c, c.stream("GET", url) as r:
            assert r.status_code == 200
            ready.wait(30)
            for chunk in r.iter_bytes():
                buf += chunk
                while True:
                    head = buf.find(b"\r\n\r\n")
                    if head < 0:
                        break
                    length = int([h for h in buf[:head].split(b"\r\n") if h.lower().startswith(
                        b"content-length:")][0].split(b":")[1])
                    if len(buf) < head + 4 + length + 2:
                        break
                    jpeg = buf[head + 4:head + 4 + length]
                    assert cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR) is not None
                    # each part says when its frame was read: seconds ago, not minutes
                    wall = float([h for h in buf[:head].split(b"\r\n") if h.lower().startswith(
                        b"x-frame-wall:")][0].split(b":")[1])
                    assert 0 <= time.time() - wall < 5
                    buf = buf[head + 4 + length + 2:]
                    n += 1
                if n >= want:
                    break
        got.append(n)
    except Exception as exc:   # reported by the test, with the others
        errors.append(repr(exc))


def test_twenty_viewers_of_one_camera_all_receive_pictures(serve):
    url = f"{serve.url}/api/cameras/steady/stream.mjpg"
    frames0 = serve.cameras()["steady"]["frames"]
    got: list[int] = []
    errors: list[str] = []
    ready = threading.Barrier(20)
    threads = [threading.Thread(target=_viewer, args=(url, 30, got, errors, ready))
               for _ in range(20)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert not errors, errors
    assert got == [30] * 20                      # every viewer had 30 pictures (2 s at 15 a second)
    cam = serve.cameras()["steady"]
    assert cam["status"] == "running" and cam["restarts"] == 0
    assert cam["frames"] > frames0 + 40          # the camera kept processing meanwhile
