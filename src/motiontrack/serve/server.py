"""``motiontrack serve``: a process per camera, supervised, and the web app on uvicorn.

:func:`serve` checks the cameras file, its scene and config files, then starts every camera in a
process of its own (``multiprocessing`` "spawn": a fresh interpreter, no state forked from the
server's threads), the hub's reader threads and uvicorn. A camera process that dies is started
again after a back-off (1, 2, 4 ... at most 30 s; back to 1 s after a minute of running); one
whose source ended (a file without ``loop``) stays ended. SIGTERM or SIGINT stops the cameras
first (each commits its current segment's outputs), then the web server; the exit code is 0.
What a camera process that was killed (the OOM killer's SIGKILL) had written of its segment is
committed before it starts again (:func:`salvage_segments`).
"""

from __future__ import annotations

import logging
import multiprocessing
import signal
import socket
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

from ..config import load_config
from ..errors import ConfigError, MotionTrackError
from ..io.event_store import STORE_NAME
from ..run.folder import RunFolder
from .app import create_app
from .cameras import CameraSpec, load_cameras
from .channel import Channel
from .hosts import allowed_hosts
from .hub import Hub
from .retention import Retention, RetentionThread
from .scenes import SceneFiles, check_scene_files
from .worker import camera_main

log = logging.getLogger(__name__)

__all__ = ["serve", "Supervisor", "default_out", "salvage_segments"]

#: seconds a camera gets to commit its outputs after SIGTERM before it is killed
STOP_TIMEOUT = 20.0
BACKOFF_MAX = 30.0
#: a camera that ran this long before dying is restarted after the shortest back-off again
STABLE_S = 60.0


def default_out(cameras_file: str | Path) -> Path:
    return Path("runs") / "serve" / Path(cameras_file).stem


def salvage_segments(folder: Path, source: str, status: dict[str, Any], code: int | None
                     ) -> list[Path]:
    """Commit the segments a killed camera process left unfinished in ``folder`` (its output
    folder): each segment folder without ``summary.json`` is salvaged
    (:meth:`~motiontrack.run.folder.RunFolder.salvage`): the tracks and events written so far,
    up to the last whole line, under their names, and a ``summary.json`` that says so
    (``"status": "killed (exit code N)"``, ``"truncated": true``, the frame size and rate from
    the camera's last ``status``, so that ``motiontrack analyze`` reads the tracks as it reads a
    finished segment's). Call it while no process of the camera runs. Returns the segment
    folders committed."""
    segments = sorted(d for d in folder.iterdir() if d.is_dir()) if folder.is_dir() else []
    return [seg for seg in segments if RunFolder(seg).salvage(source, status, code)]


@dataclass
class _Proc:
    spec: CameraSpec
    process: Any = None
    channel: Channel | None = None
    readers: list = field(default_factory=list)
    started: float = 0.0
    backoff: float = 1.0
    restart_at: float | None = None
    ended: bool = False


class Supervisor:
    """The camera processes: started, watched, restarted with back-off, stopped."""

    def __init__(self, specs: tuple[CameraSpec, ...], out: Path, hub: Hub, *,
                 rotate_s: float = 3600.0, rotate_mb: float = 0.0,
                 log_level: int = logging.INFO) -> None:
        self.ctx = multiprocessing.get_context("spawn")
        self.out, self.hub = out, hub
        self.rotate_s, self.rotate_mb, self.log_level = rotate_s, rotate_mb, log_level
        self.procs = {s.name: _Proc(s) for s in specs}
        self.stopping = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="supervisor", daemon=True)
        self._lock = threading.Lock()

    def start(self) -> None:
        for p in self.procs.values():
            self._start(p)
        self._thread.start()

    def _start(self, p: _Proc) -> None:
        for t in p.readers:
            t.done.set()
        p.channel = Channel(self.ctx)
        p.process = self.ctx.Process(
            target=camera_main, name=f"motiontrack-camera-{p.spec.name}",
            args=(p.spec, self.out / p.spec.name, p.channel, self.rotate_s, self.rotate_mb,
                  self.log_level))
        p.process.start()
        p.started = time.monotonic()
        p.restart_at = None
        p.readers = self.hub.attach(p.spec.name, p.channel)

    def _watch(self) -> None:
        while not self.stopping.wait(0.2):
            with self._lock:
                if self.stopping.is_set():
                    return
                now = time.monotonic()
                for p in self.procs.values():
                    self._check(p, now)

    def _check(self, p: _Proc, now: float) -> None:
        cam = self.hub.get(p.spec.name)
        if p.ended:
            return
        if p.restart_at is not None:
            if now >= p.restart_at:
                cam.restarts += 1
                log.info("camera %s: starting again", p.spec.name)
                self._start(p)
            return
        if p.process.is_alive():
            return
        code = p.process.exitcode
        with cam.lock:
            said = cam.status.get("status")
        if code == 0 and said == "ended":
            p.ended = True
            log.info("camera %s: its source ended", p.spec.name)
            return
        self._salvage(p, code)
        if now - p.started >= STABLE_S:
            p.backoff = 1.0
        log.warning("camera %s: process ended (exit code %s); starting again in %.0f s",
                    p.spec.name, code, p.backoff)
        cam.set_status("restarting")
        p.restart_at = now + p.backoff
        p.backoff = min(p.backoff * 2, BACKOFF_MAX)

    def _salvage(self, p: _Proc, code: int | None) -> None:
        """What the dead process ``p`` had written of its segment, committed."""
        cam = self.hub.get(p.spec.name)
        with cam.lock:
            status = dict(cam.status)
        try:
            for seg in salvage_segments(self.out / p.spec.name, str(p.spec.source), status, code):
                log.warning("camera %s: the process ended (exit code %s) in segment %s; what it "
                            "had written is kept there", p.spec.name, code, seg.name)
        except OSError as exc:   # the camera starts again all the same
            log.error("camera %s: cannot keep what the ended process wrote: %s", p.spec.name, exc)

    def stop(self) -> None:
        """SIGTERM to every camera, wait for each to commit its outputs (killed after
        :data:`STOP_TIMEOUT`)."""
        self.stopping.set()
        with self._lock:
            running = [p for p in self.procs.values()
                       if p.process is not None and p.process.is_alive()]
            for p in running:
                p.process.terminate()
            deadline = time.monotonic() + STOP_TIMEOUT
            for p in running:
                p.process.join(max(0.0, deadline - time.monotonic()))
                if p.process.is_alive():
                    log.warning("camera %s did not stop in %.0f s; killing it", p.spec.name,
                                STOP_TIMEOUT)
                    p.process.kill()
                    p.process.join(5)
                    self._salvage(p, p.process.exitcode)
            for p in self.procs.values():
                for t in p.readers:
                    t.done.set()


def _check_configs(specs: tuple[CameraSpec, ...]) -> None:
    for i, s in enumerate(specs, 1):
        try:
            load_config(s.config, preset=s.preset)
        except ConfigError as exc:
            raise ConfigError(f"camera[{i}] ({s.name}): {exc}") from None


def _check_calibrations(specs: tuple[CameraSpec, ...]) -> None:
    """Every ``camera =`` calibration file of the cameras file readable and valid before any
    camera starts (a camera process that cannot read it would fail at every start)."""
    from ..calibrate import load_camera

    for i, s in enumerate(specs, 1):
        if s.camera is None:
            continue
        try:
            load_camera(s.camera)
        except MotionTrackError as exc:
            raise ConfigError(f"camera[{i}] ({s.name}): camera = {s.camera.name}: {exc}"
                              ) from None


def serve(cameras_file: str | Path, host: str = "127.0.0.1", port: int = 8080,
          out: str | Path | None = None, token: str | None = None, *,
          rotate_s: float = 3600.0, rotate_mb: float = 0.0,
          log_level: int = logging.INFO, allowed: Sequence[str] = (),
          retention: Retention = Retention()) -> int:
    """Run the cameras of ``cameras_file`` and the web app until SIGTERM or SIGINT; 0.
    ``allowed``: more host names the app answers to (:func:`~.guard.allowed_hosts`);
    ``retention``: how long and how much of the output segments to keep (:mod:`.retention`)."""
    import uvicorn

    hosts = allowed_hosts(host, allowed)
    specs = load_cameras(cameras_file)
    _check_configs(specs)
    _check_calibrations(specs)
    scenes = {s.name: s.scene for s in specs}
    calibrations = {s.name: s.camera for s in specs}
    check_scene_files(scenes, calibrations)
    if not (rotate_s > 0):
        raise ConfigError(f"--rotate-s must be > 0 seconds, got {rotate_s}")
    if rotate_mb < 0:
        raise ConfigError(f"--rotate-mb must be >= 0 (0 = no size limit), got {rotate_mb}")
    check_port(host, port)
    out_dir = Path(out) if out is not None else default_out(cameras_file)
    out_dir.mkdir(parents=True, exist_ok=True)
    hub = Hub([(s.name, s.scene is not None) for s in specs])
    sup = Supervisor(specs, out_dir, hub, rotate_s=rotate_s, rotate_mb=rotate_mb,
                     log_level=log_level)
    app = create_app(hub, token, SceneFiles(scenes, calibrations), stopping=sup.stopping.is_set,
                     hosts=hosts, store=out_dir / STORE_NAME)

    class _Server(uvicorn.Server):
        def handle_exit(self, sig: int, frame: Any) -> None:
            # the cameras stop at once, in parallel with the web server; no re-raised signal
            # afterwards (uvicorn's default), so the exit code stays 0
            if not sup.stopping.is_set():
                log.info("stopping: cameras commit their outputs")
                threading.Thread(target=sup.stop, name="stop-cameras", daemon=True).start()
            self.should_exit = True

    config = uvicorn.Config(app, host=host, port=port, log_level="warning", lifespan="off",
                            timeout_graceful_shutdown=3, access_log=False)
    server = _Server(config)
    keeper = RetentionThread(out_dir, retention, lambda: [
        f"{name}/{c['segment']}" for name, c in ((n, cam.describe()) for n, cam in
                                                  hub.cameras.items()) if c["segment"]])
    sup.start()
    keeper.start()
    log.info("serving %d camera(s) on http://%s:%d/ ; outputs in %s", len(specs), host, port,
             out_dir)
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        server.run()
    finally:
        for s in previous:   # a second Ctrl-C while the cameras commit is ignored
            signal.signal(s, signal.SIG_IGN)
        keeper.stop()
        sup.stop()
        hub.close()
        for s, h in previous.items():
            signal.signal(s, h)
    return 0


def check_port(host: str, port: int) -> None:
    """The address can be listened on (before any camera starts)."""
    try:
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        with socket.socket(family, socket.SOCK_STREAM) as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            s.bind((host, port))
    except OSError as exc:
        raise ConfigError(f"cannot listen on {host}:{port}: {exc.strerror or exc}") from None
