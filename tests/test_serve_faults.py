"""``motiontrack serve`` under faults: a camera whose stream drops reconnects while the other
camera keeps its rate, and twenty viewers of one camera all receive its pictures while it keeps
running (the fps cost of viewers is measured by ``benchmarks/serve.py``, not timed here).

The dropping camera reads an MJPEG stream from a small HTTP server on 127.0.0.1 that the test
stops and starts again on the same port; the steady camera is a looping synthetic scene played
at its own 25 fps.
"""

from __future__ import annotations

import http.server
import os
import signal
import socket
import socketserver
import subprocess
import sys
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

pytest.importorskip("starlette")
pytest.importorskip("uvicorn")
httpx = pytest.importorskip("httpx")

pytestmark = pytest.mark.slow

#: frames a second of the served stream
STREAM_FPS = 20.0


def _picture(i: int) -> np.ndarray:
    """Frame ``i`` of the served stream: a white box moving right on a grey background."""
    img = np.full((120, 160, 3), 90, np.uint8)
    x = 5 + 3 * (i % 40)
    cv2.rectangle(img, (x, 40), (x + 14, 80), (255, 255, 255), -1)
    return img


class _HTTPServer(socketserver.ThreadingMixIn, http.server.HTTPServer):
    daemon_threads = True
    block_on_close = False
    allow_reuse_address = True


class Stream:
    """An endless MJPEG stream on a fixed 127.0.0.1 port that can be stopped (listening ends,
    open connections are closed) and started again."""

    def __init__(self) -> None:
        self.parts = [cv2.imencode(".jpg", _picture(i))[1].tobytes() for i in range(40)]
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            self.port = s.getsockname()[1]
        self.url = f"http://127.0.0.1:{self.port}/s.mjpg"
        self.httpd = None
        self.start()

    def start(self) -> None:
        stopped = self.stopped = threading.Event()
        parts = self.parts

        class Handler(http.server.BaseHTTPRequestHandler):
            def log_message(self, *args):
                pass

            def do_GET(self):
                self.send_response(200)
                self.send_header("Content-Type", "multipart/x-mixed-replace; boundary=frame")
                self.end_headers()
                i = 0
                try:
                    while not stopped.is_set():
                        jpeg = parts[i % len(parts)]
                        self.wfile.write(b"--frame\r\nContent-Type: image/jpeg\r\nContent-Length: "
                                         b"%d\r\n\r\n" % len(jpeg) + jpeg + b"\r\n")
                        self.wfile.flush()
                        i += 1
                        time.sleep(1 / STREAM_FPS)
                except (BrokenPipeError, ConnectionResetError):
                    pass
                self.close_connection = True

        self.httpd = _HTTPServer(("127.0.0.1", self.port), Handler)
        threading.Thread(target=self.httpd.serve_forever, daemon=True).start()

    def stop(self) -> None:
        self.stopped.set()
        self.httpd.shutdown()
        self.httpd.server_close()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Serve:
    """``motiontrack serve`` with the cameras ``drop`` (the stream) and ``steady`` (synth)."""

    def __init__(self, root: Path, stream_url: str) -> None:
        self.root, self.port = root, _free_port()
        (root / "live.toml").write_text(
            "[source]\nreconnect_attempts = 1000\nreconnect_backoff = 0.2\n"
            "reconnect_backoff_max = 0.5\nread_timeout_s = 1.0\n")
        (root / "cameras.toml").write_text(
            f'[[camera]]\nname = "drop"\nsource = "{stream_url}"\nconfig = "live.toml"\n\n'
            '[[camera]]\nname = "steady"\nsource = "synth:walker"\nloop = true\n')
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        env.pop("MOTIONTRACK_TOKEN", None)
        self.log = open(root / "serve.log", "w")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "motiontrack", "serve", str(root / "cameras.toml"), "--port",
             str(self.port), "--out", str(root / "out")],
            cwd=root, stdout=self.log, stderr=subprocess.STDOUT, env=env)
        self.url = f"http://127.0.0.1:{self.port}"
        self.client = httpx.Client(base_url=self.url, timeout=10)
        self.wait(lambda: all(c["status"] == "running" and c["frames"] > 20
                              for c in self.cameras().values()) and len(self.cameras()) == 2,
                  90, "both cameras running")

    def cameras(self) -> dict[str, dict]:
        try:
            return {c["name"]: c for c in self.client.get("/api/cameras").json()}
        except httpx.TransportError:
            assert self.proc.poll() is None, self.logs()
            return {}

    def wait(self, cond, timeout: float, what: str):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            got = cond()
            if got:
                return got
            time.sleep(0.1)
        raise AssertionError(f"not within {timeout} s: {what}\n{self.logs()}")

    def rate(self, name: str, seconds: float) -> float:
        """Frames a second the camera processed over the next ``seconds``."""
        f0, t0 = self.cameras()[name]["frames"], time.monotonic()
        time.sleep(seconds)
        return (self.cameras()[name]["frames"] - f0) / (time.monotonic() - t0)

    def logs(self) -> str:
        self.log.flush()
        return (self.root / "serve.log").read_text()[-3000:]

    def stop(self) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            return self.proc.wait(30)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait(10)
            self.client.close()
            self.log.close()


@pytest.fixture(scope="module")
def stream():
    s = Stream()
    yield s
    if not s.stopped.is_set():
        s.stop()


@pytest.fixture(scope="module")
def serve(tmp_path_factory, stream):
    srv = Serve(tmp_path_factory.mktemp("faults"), stream.url)
    yield srv
    assert srv.stop() == 0


def test_a_dropped_stream_reconnects_while_the_other_camera_keeps_its_rate(serve, stream):
    before = serve.rate("steady", 3.0)
    assert before > 15, serve.logs()          # synth:walker plays at 25 fps
    reconnects = serve.cameras()["drop"]["reconnects"]

    stream.stop()                              # the stream drops and stays away ~5 s
    serve.wait(lambda: serve.cameras()["drop"]["status"] == "reconnecting", 15,
               "the dropped camera reported as reconnecting")
    during = serve.rate("steady", 3.0)
    frames_down = serve.cameras()["drop"]["frames"]
    stream.start()

    serve.wait(lambda: (lambda c: c["status"] == "running" and c["frames"] > frames_down + 20
                        and c["reconnects"] > reconnects)(serve.cameras()["drop"]),
               30, "the dropped camera running again with its reconnection counted")
    after = serve.rate("steady", 3.0)
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
