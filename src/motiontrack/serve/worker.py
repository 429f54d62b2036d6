"""One camera of ``motiontrack serve``, in a process of its own (the GIL must not couple cameras).

:func:`camera_main` runs ``track``'s job (:func:`~motiontrack.run.track_job`, scene analytics
when the camera has a scene) over the camera's frames, segment after segment, and publishes the
annotated picture, events, counts and status through a :class:`~.channel.Channel`:

* the source is opened once and read across segments; a video file (or a synthetic scene) is
  played at its own frame rate (the reader sleeps to real time) and starts again at its end when
  ``loop = true``, its first frame marked with a ``loop``
  :class:`~motiontrack.types.Discontinuity` (the pipeline and the analytics reset; the event
  stream gets a ``discontinuity`` record); a live source reconnects by the run layer's rules;
* each segment is one run into ``OUT/<camera>/<segment>/`` (``tracks.txt``, ``events.jsonl``,
  ``counts.csv``, ``heatmap.png``, ``summary.json``, ``config.toml``), with the run layer's
  output rules; a segment ends after ``rotate_s`` seconds, when its folder reaches
  ``rotate_mb`` megabytes, or when the scene file changes (the next segment runs the new
  scene, the camera keeps running);
* a scene file that becomes invalid (a hand edit with a mistake, a deleted file) does not stop
  the camera: it keeps its last valid scene (:class:`SceneKeeper`), logs the problem once and
  reports it in its status (``scene_error``) until the file is valid again;
* SIGTERM or SIGINT ends the current segment after the frame in hand, its outputs committed.

A looping file that is damaged part-way fails the same way on every loop: identical log records
(:class:`RepeatFilter`) are logged once, then once more with their count at most every
:data:`REPEAT_EVERY_S` seconds and when the camera ends. FFmpeg's own lines are silenced as in
every process that opens a video (:mod:`motiontrack.io.native_logs`).

The picture is JPEG-encoded here, at most :data:`VIEW_FPS` times a second, so the server only
copies bytes.
"""

from __future__ import annotations

import collections
import gc
import itertools
import logging
import math
import os
import signal
import sys
import threading
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, Iterator, Sequence

import cv2

from ..analytics import load_scene
from ..config import load_config
from ..config_flags import flag_overrides
from ..errors import MotionTrackError
from ..io.event_store import STORE_NAME
from ..io.pacing import Pacer
from ..io.sources import Source
from ..pipeline import open_configured_source
from ..run import track_job
from ..run.event_store_writer import EventStoreWriter
from ..run.job import JobContext, Writer
from ..types import Discontinuity, FrameResult
from .cameras import CameraSpec
from .channel import Channel

log = logging.getLogger(__name__)

__all__ = ["camera_main", "Segments", "SceneKeeper", "RepeatFilter", "VIEW_FPS", "JPEG_QUALITY",
           "REPEAT_EVERY_S"]

#: pictures a second sent to viewers at most
VIEW_FPS = 15.0
JPEG_QUALITY = 80
#: most tracks a status message lists
MAX_LISTED = 100
#: seconds between status messages
STATUS_EVERY = 0.5
#: a live source silent this long is reported as reconnecting
SILENT_S = 2.0
#: a repeated log record is logged again, with its count, at most this often (seconds)
REPEAT_EVERY_S = 60.0


class RepeatFilter(logging.Filter):
    """Log a record identical to an earlier one (same logger, level and message) only when
    ``every`` seconds have passed since that message was last logged, with the number of
    repeats in between; :meth:`flush` logs the repeats not reported yet. At most ``size``
    messages are remembered (the least recent are forgotten)."""

    def __init__(self, every: float = REPEAT_EVERY_S, clock: Any = time.monotonic,
                 size: int = 256) -> None:
        super().__init__()
        self.every, self.clock, self.size = every, clock, size
        #: (logger, level, message) -> [repeats not logged, when last logged]
        self.seen: collections.OrderedDict = collections.OrderedDict()
        self.lock = threading.Lock()

    def filter(self, record: logging.LogRecord) -> bool:
        key = (record.name, record.levelno, record.getMessage())
        now = self.clock()
        with self.lock:
            entry = self.seen.get(key)
            if entry is None:
                self.seen[key] = [0, now]
                if len(self.seen) > self.size:
                    self.seen.popitem(last=False)
                return True
            self.seen.move_to_end(key)
            entry[0] += 1
            if now - entry[1] < self.every:
                return False
            repeats, since = entry[0], now - entry[1]
            entry[:] = [0, now]
        record.msg, record.args = f"{key[2]} (repeated {_times(repeats)} in {since:.0f} s)", None
        return True

    def flush(self) -> None:
        """Log each message repeated since it was last logged once more, with the count."""
        with self.lock:
            pending = [(k, n) for k, (n, _) in self.seen.items() if n]
            self.seen.clear()
        for (name, level, message), n in pending:
            logging.getLogger(name).log(level, "%s (repeated %s more)", message, _times(n))


def _times(n: int) -> str:
    return "once" if n == 1 else f"{n} times"


class _Flag:
    def __init__(self) -> None:
        self.event = threading.Event()

    def __call__(self) -> bool:
        return self.event.is_set()


class _Frames:
    """The camera's frames across segments: looped and paced to real time when the source is a
    file, as they come when it is live."""

    def __init__(self, spec: CameraSpec, cfg: Any, stop: _Flag,
                 pacer: Pacer | None = None) -> None:
        self.spec, self.cfg, self.stop = spec, cfg, stop
        self.pacer = pacer or Pacer(sleep=stop.event.wait)
        self.source = self._open()
        self.info = self.source.info
        self.live = bool(self.info.live)
        self.fps = float(self.info.fps or 25.0)
        self.loops = 0
        self._it = self._frames()

    def _open(self) -> Source:
        src = open_configured_source(self.spec.source, self.cfg.source)
        src.stop_requested = self.stop
        return src

    @property
    def reconnects(self) -> int:
        return int(getattr(self.source, "reconnects", 0))

    def _frames(self) -> Iterator[Any]:
        n = 0
        while True:
            got = False
            for frame in self.source:
                if self.loops and not got:   # the jump from the last frame to the first
                    frame = replace(frame, discontinuity=Discontinuity("loop"))
                got = True
                # a file plays at its own rate (times the cameras file's speed)
                if not self.live and self.pacer.wait(n, self.fps * self.spec.speed):
                    return
                n += 1
                yield frame
            if self.stop() or not (self.spec.loop and got and not self.live):
                return
            self.source.close()
            self.source = self._open()
            self.loops += 1

    def next(self) -> Any:
        return next(self._it, None)

    def close(self) -> None:
        self._it.close()
        self.source.close()


class Segments(Source):
    """One segment's view of the camera's frames: a :class:`Source` for one run, numbered from
    0, that leaves the camera's source open when the run closes it."""

    def __init__(self, frames: _Frames) -> None:
        super().__init__()
        self.frames = frames
        self.info = replace(frames.info, frame_count=None, fps=frames.fps,
                            stored_fps=None)
        self.ended = False
        #: (frame index, wall-clock time it was read) of the latest frames
        self.walls: collections.deque = collections.deque(maxlen=64)

    def wall(self, index: int) -> float | None:
        for i, t in reversed(list(self.walls)):   # a copy: the reader thread appends
            if i == index:
                return t
        return None

    def __iter__(self) -> Iterator[Any]:
        for i in itertools.count():
            frame = self.frames.next()
            if frame is None:
                self.ended = True
                return
            ts = frame.timestamp if self.frames.live else i / self.frames.fps
            self.walls.append((i, time.time()))
            yield replace(frame, index=i, timestamp=ts)

    def ground_truth(self) -> None:
        return None   # a looped scene's ground truth no longer matches its frame numbers

    def close(self) -> None:
        pass   # the camera's source outlives the segment


class LiveWriter(Writer):
    """The run's live outputs: the picture, events and counts sent to the server, and the end
    of the segment when it is due (time, size or a changed scene)."""

    def __init__(self, cam: "_Camera", segments: Segments, rotate_s: float,
                 rotate_bytes: float) -> None:
        self.paths = {}
        self.cam, self.segments = cam, segments
        self.rotate_s, self.rotate_bytes = rotate_s, rotate_bytes
        self._ctx: JobContext | None = None

    def start(self, ctx: JobContext) -> None:
        self._ctx = ctx
        self._t0 = time.monotonic()
        self._checked = self._t0
        analytics = getattr(ctx.processor, "analytics", None)
        self.cam.scene_started(analytics.scene if analytics is not None else None)

    def write(self, result: FrameResult) -> None:
        cam, now = self.cam, time.monotonic()
        cam.frame_done(now, result.tracks)
        wall = self.segments.wall(result.index)
        if result.scene is not None:
            cam.scene_frame(result.scene, wall)
        if now - cam.last_picture >= 1.0 / VIEW_FPS:
            cam.last_picture = now
            ok, buf = cv2.imencode(".jpg", self._ctx.annotated(result),
                                   [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
            if ok:
                cam.channel.frame(buf.tobytes(), cam.frames, cam.fps, wall)
        if now - self._checked >= 0.5:
            self._checked = now
            reason = self._due(now)
            if reason:
                self._ctx.request_stop(reason)

    def _due(self, now: float) -> str | None:
        if now - self._t0 >= self.rotate_s:
            return "segment rotated (time)"
        if self.rotate_bytes and _folder_bytes(self._ctx.out) >= self.rotate_bytes:
            return "segment rotated (size)"
        if self.cam.scene_changed():
            return "segment rotated (scene changed)"
        return None


class SceneKeeper:
    """A camera's scene: its scene file's while the file is valid, else the last valid one.

    :meth:`load` is the track job's ``scene`` (a function of the fitted camera): each segment
    reads the file again. A file that cannot be read or checked (a hand edit with a mistake, a
    deleted file) leaves the camera running with the scene it had and sets :attr:`error`, which
    the camera's status reports; each new problem is logged once, and the first valid version
    of the file is used again. A camera process started while the file is invalid has no scene
    to keep: it runs without lines and zones until the file is valid.
    """

    def __init__(self, camera: str, path: Path) -> None:
        self.camera, self.path = camera, path
        #: the last valid scene (None before the first)
        self.scene: Any = None
        #: what is wrong with the file and what the camera does meanwhile; None when valid
        self.error: str | None = None

    def load(self, fitted: Any) -> Any:
        """The scene to run, with the camera model ``fitted`` to the source (or None)."""
        try:
            scene = load_scene(self.path, fitted)
        except MotionTrackError as exc:
            kept = ("the camera keeps its last valid scene" if self.scene is not None else
                    "the camera runs without lines and zones")
            error = f"{exc}; {kept} until the file is valid"
            if error != self.error:
                log.error("camera %s: %s", self.camera, error)
            self.error = error
            return self.scene
        if self.error is not None:
            log.info("camera %s: scene file %s is valid again: it is applied", self.camera,
                     self.path.name)
        self.scene, self.error = scene, None
        return scene


def _folder_bytes(folder: Path) -> int:
    """Bytes of the files in ``folder``, temporary ones (outputs being written) included."""
    total = 0
    with os.scandir(folder) as it:
        for e in it:
            try:
                if e.is_file(follow_symlinks=False):
                    total += e.stat(follow_symlinks=False).st_size
            except OSError:
                continue
    return total


def _mtime(path: Path | None) -> float | None:
    try:
        return path.stat().st_mtime_ns if path is not None else None
    except OSError:
        return None


class _Camera:
    """State of the camera process shared by its segments: totals the server shows."""

    def __init__(self, spec: CameraSpec, channel: Channel) -> None:
        self.spec, self.channel = spec, channel
        self.frames = 0
        self.fps = 0.0
        self.status = "starting"
        self.segment = ""
        self.last_frame = time.monotonic()
        self.last_picture = 0.0
        self.lines: dict[str, dict[str, int]] = {}
        self.zones: dict[str, dict[str, int]] = {}
        #: the latest frame's tracks, id and class (the page's track list)
        self.tracks: list[dict[str, Any]] = []
        self.scene_mtime = _mtime(spec.scene)
        self.scenes = SceneKeeper(spec.name, spec.scene) if spec.scene is not None else None
        self._times: list[float] = []
        self.source: _Frames | None = None
        self.lock = threading.Lock()

    # ---------------------------------------------------------------- frames and events
    def frame_done(self, now: float, tracks: Sequence[Any] = ()) -> None:
        with self.lock:
            self.tracks = [{"id": int(t.id), "class": t.label} for t in tracks[:MAX_LISTED]]
            self.frames += 1
            self.last_frame = now
            self._times.append(now)
            if len(self._times) > 50:
                del self._times[0]
            if len(self._times) >= 2 and self._times[-1] > self._times[0]:
                self.fps = (len(self._times) - 1) / (self._times[-1] - self._times[0])
            self.status = "running"

    def scene_started(self, scene: Any) -> None:
        """A segment starts with ``scene``: counts of lines and zones it still has are kept."""
        if scene is None:
            self.lines, self.zones = {}, {}
        else:
            self.lines = {ln.name: self.lines.get(ln.name, {"in": 0, "out": 0})
                          for ln in scene.lines}
            self.zones = {z.name: {"occupancy": 0,
                                   "entered": self.zones.get(z.name, {}).get("entered", 0)}
                          for z in scene.zones}
        self.channel.counts(self.counts())

    def scene_frame(self, sf: Any, wall: float | None) -> None:
        """A frame's events and occupancy; ``wall``: when the frame was read (epoch seconds),
        sent with each event for latency measurements."""
        changed = False
        events = []
        stamp = {"segment": self.segment} | ({"wall": round(wall, 4)} if wall is not None else {})
        if sf.discontinuity is not None:
            events.append(sf.discontinuity.to_json(sf.frame) | stamp)
        for e in sf.events:
            events.append(e.to_json() | stamp)
            if e.type == "line_cross" and e.line in self.lines and e.direction in ("in", "out"):
                self.lines[e.line][e.direction] += 1
                changed = True
            elif e.type == "zone_enter" and e.zone in self.zones:
                self.zones[e.zone]["entered"] += 1
                changed = True
        for name, occ in sf.occupancy.items():
            z = self.zones.get(name)
            if z is not None and z["occupancy"] != int(occ):
                z["occupancy"] = int(occ)
                changed = True
        self.channel.events(events)
        if changed:
            self.channel.counts(self.counts())

    def counts(self) -> dict:
        return {"lines": {k: dict(v) for k, v in self.lines.items()},
                "zones": {k: dict(v) for k, v in self.zones.items()}}

    def scene_changed(self) -> bool:
        m = _mtime(self.spec.scene)
        return m is not None and m != self.scene_mtime

    # ------------------------------------------------------------------------- status
    def report(self) -> None:
        with self.lock:
            status = self.status
            live = self.source is not None and self.source.live
            if status == "running" and live and time.monotonic() - self.last_frame > SILENT_S:
                status = "reconnecting"
            self.channel.status({
                "status": status, "fps": round(self.fps, 2), "frames": self.frames,
                "reconnects": self.source.reconnects if self.source is not None else 0,
                "segment": self.segment, "pid": os.getpid(),
                "width": self.source.info.width if self.source is not None else None,
                "height": self.source.info.height if self.source is not None else None,
                "source_fps": self.source.info.fps if self.source is not None else None,
                "scene_error": self.scenes.error if self.scenes is not None else None,
                "tracks": list(self.tracks),
            })


def _segment_name(out: Path) -> str:
    """``YYYYmmdd-HHMMSS`` (local time), with ``-2``, ``-3``... when taken."""
    base = time.strftime("%Y%m%d-%H%M%S")
    name, k = base, 1
    while (out / name).exists():
        k += 1
        name = f"{base}-{k}"
    return name


def _config(spec: CameraSpec) -> Any:
    # the cameras file's fps and camera are the flags of the same names (config_flags)
    overrides = ["output.video=false", "output.mask_video=false"] + flag_overrides(
        {"fps": spec.fps or None, "camera": None if spec.camera is None else str(spec.camera)})
    return load_config(spec.config, overrides, preset=spec.preset)


def run_camera(spec: CameraSpec, out_dir: Path, channel: Channel, stop: _Flag,
               rotate_s: float = 3600.0, rotate_mb: float = 0.0,
               pacer: Pacer | None = None) -> int:
    """Run one camera until its source ends or ``stop``; the exit code of the process.
    ``pacer`` plays a file at its frame rate (tests give one with a clock of their own)."""
    cam = _Camera(spec, channel)
    beat_stop = threading.Event()

    parent = os.getppid()

    def beat() -> None:
        while not beat_stop.wait(STATUS_EVERY):
            if os.getppid() != parent:   # the server is gone (killed): stop, outputs committed
                stop.event.set()
            cam.report()

    beater = threading.Thread(target=beat, name=f"status-{spec.name}", daemon=True)
    beater.start()
    code = 0
    try:
        cfg = _config(spec)
        cam.source = frames = _Frames(spec, cfg, stop, pacer)
        rotate_bytes = rotate_mb * 1e6 if rotate_mb and math.isfinite(rotate_mb) else 0.0
        try:
            while not stop():
                cam.scene_mtime = _mtime(spec.scene)
                seg = Segments(frames)
                cam.segment = _segment_name(out_dir)
                scene = cam.scenes.load if cam.scenes is not None else None
                # one event store for the whole server, beside the cameras' folders
                store = EventStoreWriter(out_dir.parent / STORE_NAME, spec.name,
                                         f"{out_dir.name}/{cam.segment}", owned=False,
                                         evidence=out_dir / cam.segment)
                job = track_job(seg, cfg, out_dir / cam.segment, scene=scene, store_events=False,
                                writers=[LiveWriter(cam, seg, rotate_s, rotate_bytes), store])
                try:
                    job.run(should_stop=stop)
                except KeyboardInterrupt:
                    break
                finally:
                    # the segment's pipeline goes now, whatever reference cycle it is in: a
                    # camera runs for months, and cycles wait for a full collection, rare in a
                    # long-lived process, with megabytes of OpenCV's memory each
                    del job
                    gc.collect()
                if seg.ended:
                    cam.status = "ended"
                    break
        finally:
            frames.close()
    except MotionTrackError as exc:
        log.error("camera %s: %s", spec.name, exc)
        cam.status, code = "failed", 3
    except Exception as exc:   # a bug: the supervisor restarts the camera
        log.exception("camera %s failed: %s", spec.name, exc)
        cam.status, code = "failed", 1
    finally:
        beat_stop.set()
        beater.join()
        if cam.status == "running":
            cam.status = "ended"
        cam.report()
    return code


def camera_main(spec: CameraSpec, out_dir: str | Path, channel: Channel,
                rotate_s: float = 3600.0, rotate_mb: float = 0.0,
                log_level: int = logging.INFO) -> None:
    """The camera process's entry point (``multiprocessing`` "spawn"): SIGTERM and SIGINT end
    the run after the current frame with every output committed; the exit code is 0 then, or
    when the source ended, and non-zero when the camera failed."""
    stop = _Flag()

    def on_signal(signum: int, _frame: Any) -> None:
        stop.event.set()

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    logging.basicConfig(level=log_level, format=f"motiontrack[{spec.name}]: %(levelname)s: "
                                                "%(message)s")
    repeats = RepeatFilter()
    for handler in logging.getLogger().handlers:
        handler.addFilter(repeats)
    try:
        code = run_camera(spec, Path(out_dir), channel, stop, rotate_s, rotate_mb)
    finally:
        repeats.flush()
    channel.close()
    if code:
        sys.exit(code)
