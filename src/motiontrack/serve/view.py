"""``track --show`` without a GUI: the ``serve`` page for the one source, in the ``track`` process.

OpenCV's headless build (the default install) has no windows, so ``track --show`` serves the
live page of :mod:`.app` on 127.0.0.1 instead: a :class:`LiveView` runs uvicorn in a thread over
a one-camera :class:`~.hub.Hub`, and its :meth:`LiveView.writer` is one more output of the track
job that hands the hub each annotated picture (at most :data:`~.worker.VIEW_FPS` a second),
each event (with ``seq`` and ``wall``) and the counts. The job, its outputs and its interruption
rules stay ``track``'s own. ``track --show`` plays a file at its own frame rate
(:class:`~motiontrack.io.pacing.PacedSource`, as ``serve`` does); after the run the page keeps the
last picture, the events and the counts. With ``--scene`` the page's editor edits that scene
file (the running job keeps the scene it started with; the next run reads the saved one).
"""

from __future__ import annotations

import os
import re
import socket
import sys
import threading
import time
from pathlib import Path
from typing import Sequence

import cv2

from ..errors import ConfigError
from ..run.job import JobContext, JobSummary, Writer
from ..types import FrameResult
from .app import create_app
from .cameras import CameraSpec
from .hosts import allowed_hosts
from .hub import CameraState, Hub
from .worker import JPEG_QUALITY, STATUS_EVERY, VIEW_FPS, _Camera

__all__ = ["LiveView", "display_available", "view_name"]


def view_name(source: str) -> str:
    """The camera name of the page (it is part of the API's paths): the source's name with
    anything but letters, digits, ``_`` and ``-`` replaced."""
    return re.sub(r"[^A-Za-z0-9_-]+", "-", source).strip("-")[:40] or "camera"


class _ToHub:
    """The camera side of a :class:`~.channel.Channel`, delivered straight to the hub's state
    (camera and server share the process)."""

    def __init__(self, state: CameraState) -> None:
        self.state = state

    def frame(self, jpeg: bytes, index: int, fps: float, wall: float | None = None) -> bool:
        self.state.put_frame(jpeg, index, wall)
        return True

    def events(self, events: list[dict]) -> None:
        if events:
            self.state.put_events(events)

    def counts(self, counts: dict) -> None:
        self.state.put_counts(counts)

    def status(self, status: dict) -> None:
        self.state.put_status(status)


class _ViewWriter(Writer):
    """The track job's frames, events and counts for the page."""

    def __init__(self, cam: _Camera, state: CameraState) -> None:
        self.paths = {}
        self.cam, self.state = cam, state
        self._ctx: JobContext | None = None
        self._reported = 0.0

    def start(self, ctx: JobContext) -> None:
        self._ctx = ctx
        analytics = getattr(ctx.processor, "analytics", None)
        self.cam.scene_started(analytics.scene if analytics is not None else None)
        self.state.put_status({"status": "starting", "width": ctx.info.width,
                               "height": ctx.info.height, "pid": os.getpid()})

    def write(self, result: FrameResult) -> None:
        cam, now, wall = self.cam, time.monotonic(), time.time()
        cam.frame_done(now)
        if result.scene is not None:
            cam.scene_frame(result.scene, wall)
        if now - cam.last_picture >= 1.0 / VIEW_FPS:
            cam.last_picture = now
            self._picture(result, wall)
        if now - self._reported >= STATUS_EVERY:
            self._reported = now
            self._report("running")

    def _picture(self, result: FrameResult, wall: float | None = None) -> None:
        ok, buf = cv2.imencode(".jpg", self._ctx.annotated(result),
                               [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
        if ok:
            self.cam.channel.frame(buf.tobytes(), self.cam.frames, self.cam.fps, wall)

    def _report(self, status: str) -> None:
        self.state.put_status({"status": status, "fps": round(self.cam.fps, 2),
                               "frames": self.cam.frames,
                               "reconnects": int(getattr(self._ctx.source, "reconnects", 0))})

    def finish(self, summary: JobSummary) -> None:
        self._report("ended")


class LiveView:
    """The page of one source on ``http://host:port/`` (port 0: a free one), served from a
    thread until :meth:`close`, answering to the host names of
    :func:`~.guard.allowed_hosts` (``host``'s and ``allowed``); ``scene``: the run's scene file,
    which the page's editor edits."""

    def __init__(self, name: str, host: str = "127.0.0.1", port: int = 0,
                 scene: str | Path | None = None, allowed: Sequence[str] = ()) -> None:
        import uvicorn

        self.name = name
        hosts = allowed_hosts(host, allowed)   # the names it answers to (bad ones: ConfigError)
        scene_path = Path(scene) if scene is not None else None
        self.hub = Hub([(name, scene_path is not None)])
        self.state = self.hub.get(name)
        self._stopping = threading.Event()
        app = create_app(self.hub, None, {name: scene_path}, stopping=self._stopping.is_set,
                         hosts=hosts)
        try:
            self._sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            self._sock.bind((host, port))
            # listening before the address is printed: a browser opened at once is queued
            # until the server thread accepts, instead of refused
            self._sock.listen(64)
        except OSError as exc:
            self._sock.close()
            raise ConfigError(f"--show: cannot listen on {host}:{port}: "
                              f"{exc.strerror or exc}") from None
        self.port = self._sock.getsockname()[1]
        self.url = f"http://{host}:{self.port}/"
        config = uvicorn.Config(app, log_level="warning", lifespan="off", access_log=False,
                                timeout_graceful_shutdown=1)
        # uvicorn installs no signal handlers outside the main thread: Ctrl-C stays track's
        self._server = uvicorn.Server(config)
        self._thread = threading.Thread(target=self._server.run, kwargs={"sockets": [self._sock]},
                                        name="live-view", daemon=True)
        self._thread.start()

    def writer(self) -> Writer:
        """An output for the track job that feeds this page."""
        spec = CameraSpec(name=self.name, source=self.name)
        return _ViewWriter(_Camera(spec, _ToHub(self.state)), self.state)

    def open_browser(self) -> bool:
        """Open the page in the user's browser when there is a display to show it on."""
        if not display_available():
            return False
        import webbrowser

        try:
            return bool(webbrowser.open(self.url))
        except Exception:   # no usable browser: the printed address is enough
            return False

    def close(self) -> None:
        self._stopping.set()
        self._server.should_exit = True
        self._thread.join(5)
        self.hub.close()
        self._sock.close()


def display_available() -> bool:
    """A desktop to open a browser on (macOS and Windows always have one)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
