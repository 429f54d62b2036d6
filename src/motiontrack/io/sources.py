"""Video sources: files, cameras, streams, image folders/globs and synthetic scenes.

Every source is an iterable of :class:`~motiontrack.types.Frame` with known (or ``None``) size, fps
and frame count. Opening problems raise :class:`~motiontrack.errors.SourceError` with one clear
message; a file that stops decoding early (truncated) ends with a warning and keeps what decoded.
Live sources (cameras, streams) reconnect with bounded exponential back-off, stamp frames with
wall-clock time, and end at once when :attr:`Source.stop_requested` says so, whatever they are
waiting for.
"""

from __future__ import annotations

import atexit
import glob
import logging
import math
import os
import queue
import re
import threading
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable, Iterator

import cv2
import numpy as np

from ..errors import ConfigError, InputError, SourceError
from ..registry import Registry
from ..types import Annotations, Discontinuity, Frame
from . import native_logs
from .imagesize import DEFAULT_MAX_PIXELS, check_frame_size, check_image
from .paths import natural_key

log = logging.getLogger(__name__)

# before any video is opened: FFmpeg's own lines would stand beside our one-line messages
native_logs.quiet()

__all__ = ["SourceInfo", "Source", "VideoFileSource", "LiveSource", "ImageSequenceSource",
           "ArraySource", "SCHEMES", "open_source", "IMAGE_EXTENSIONS", "blocked_live_sources"]

IMAGE_EXTENSIONS = (".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".ppm", ".pgm")
_URL = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*://")

#: sources named ``SCHEME:REST`` (e.g. ``synth:crossing``): scheme → factory called as
#: ``factory(spec, start, max_frames)``. Packages above io register their own (``synth``
#: registers itself when imported), so io depends on none of them.
SCHEMES: "Registry[Source]" = Registry("source scheme")


@dataclass(frozen=True)
class SourceInfo:
    """What is known about a source before reading it (``None`` = unknown)."""

    name: str
    width: int
    height: int
    fps: float | None
    frame_count: int | None
    live: bool = False
    #: when ``fps`` was set instead of the source's own rate (``source.fps``): the rate the
    #: source states (0.0 = it states none); None = ``fps`` is the source's own
    stored_fps: float | None = None

    def describe(self) -> str:
        fps = f"{self.fps:g} fps" if self.fps else "fps unknown"
        if self.stored_fps is not None:
            stored = f"{self.stored_fps:g} fps" if self.stored_fps else "none"
            fps += f" (source.fps; stored {stored})"
        n = f"{self.frame_count} frames" if self.frame_count is not None else "length unknown"
        return f"{self.name}: {self.width}x{self.height}, {fps}, {n}"


def _never() -> bool:
    return False


class Source:
    """Base class: ``info`` plus iteration over frames from ``start`` for ``max_frames`` frames."""

    info: SourceInfo
    #: polled while a source waits (a live stream backing off, reconnecting or waiting for a
    #: frame): when it returns True the iteration ends at once, without an error.
    #: :meth:`motiontrack.run.Job.run` sets it to its ``should_stop``.
    stop_requested: Callable[[], bool] = staticmethod(_never)

    def __init__(self, start: int = 0, max_frames: int = 0) -> None:
        if start < 0:
            raise SourceError(f"start must be >= 0, got {start}")
        if max_frames < 0:
            raise SourceError(f"max_frames must be >= 0 (0 = all), got {max_frames}")
        self.start = start
        self.max_frames = max_frames
        #: set when reading ended before the expected end (truncated file, dropped stream)
        self.truncated = False

    def __iter__(self) -> Iterator[Frame]:  # pragma: no cover - abstract
        raise NotImplementedError

    def prepared(self, prepare: Callable[[Frame], Any]) -> Iterator[tuple[Frame, Any]]:
        """``(frame, prepare(frame))`` for every frame. Sources that decode ahead in a thread
        (video files, image folders) call ``prepare`` in that thread, so per-frame image work
        that needs nothing but the frame (the pipeline's resizing and blurring) runs beside the
        consumer's instead of before it."""
        return ((frame, prepare(frame)) for frame in self)

    def ground_truth(self) -> Annotations | None:
        """The exact ground truth of a source that knows it (synthetic scenes), else None."""
        return None

    def seek_mark(self, index: int) -> Discontinuity | None:
        """The :class:`~motiontrack.types.Discontinuity` of frame ``index``: ``seek`` on the
        first frame of a source positioned at ``start > 0``, else None. Every source marks its
        first frame with it."""
        return Discontinuity("seek") if self.start > 0 and index == self.start else None

    def set_fps(self, fps: float) -> None:
        """Take ``fps`` as the frame rate instead of the one the source states (``source.fps``):
        for footage stored at another rate than it was recorded at. Frame timestamps, and
        everything a run derives from the rate, follow it. Call it before iterating."""
        if not (fps > 0 and math.isfinite(fps)):
            raise ConfigError(f"source.fps must be a finite number > 0, got {fps!r}")
        stored = self.info.fps if self.info.stored_fps is None else self.info.stored_fps
        self.info = replace(self.info, fps=float(fps), stored_fps=float(stored or 0.0))

    def expected_frames(self) -> int | None:
        """Frames this iteration should yield, when known (for progress bars)."""
        n = self.info.frame_count
        if n is None:
            return self.max_frames or None
        n = max(0, n - self.start)
        return min(n, self.max_frames) if self.max_frames else n

    def close(self) -> None:
        pass

    def __enter__(self) -> "Source":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def prefetch(frames: Iterator[Frame], size: int = 4) -> Iterator[Frame]:
    """Decode ahead in a background thread (OpenCV releases the GIL while decoding), so decoding
    overlaps with processing on a second core. Exceptions are re-raised in the consumer; closing
    the returned generator stops the reader thread."""
    q: queue.Queue = queue.Queue(maxsize=size)
    stop = threading.Event()
    done = object()

    def reader() -> None:
        try:
            for item in frames:
                while not stop.is_set():
                    try:
                        q.put(item, timeout=0.1)
                        break
                    except queue.Full:
                        continue
                if stop.is_set():
                    break
            q.put(done)
        except BaseException as exc:  # handed to the consumer
            q.put(exc)

    thread = threading.Thread(target=reader, name="motiontrack-decode", daemon=True)
    thread.start()
    try:
        while True:
            item = q.get()
            if item is done:
                return
            if isinstance(item, BaseException):
                raise item
            yield item
    finally:
        stop.set()
        while thread.is_alive():
            try:
                q.get_nowait()
            except queue.Empty:
                thread.join(timeout=0.05)
        close = getattr(frames, "close", None)
        if close is not None:
            close()


def _open_capture(target: Any, what: str) -> cv2.VideoCapture:
    cap = cv2.VideoCapture(target)
    if not cap.isOpened():
        cap.release()
        raise SourceError(f"cannot open {what}")
    return cap


class _DecodedAhead(Source):
    """A source that reads in a background thread (:func:`prefetch`) what ``_frames`` yields."""

    def __iter__(self) -> Iterator[Frame]:
        return prefetch(self._frames())

    def prepared(self, prepare: Callable[[Frame], Any]) -> Iterator[tuple[Frame, Any]]:
        return prefetch((frame, prepare(frame)) for frame in self._frames())

    def _frames(self) -> Iterator[Frame]:  # pragma: no cover - abstract
        raise NotImplementedError


#: bytes of a file's start that :func:`_is_text` looks at
_SNIFF_BYTES = 4096
#: codecs FFmpeg reads text files with: its ``tty`` demuxer draws the characters of a ``.txt``,
#: ``.asc`` or ``.nfo`` file as a picture (``ansi``), so a MOT CSV would "play" as a video
_TEXT_CODECS = frozenset({"ansi"})


def _is_text(path: Path) -> bool:
    """Whether the start of ``path`` is text (UTF-8, no control characters but white space):
    an annotation, config or camera file given where a video belongs. Every video container and
    image format starts with binary bytes (a text-headed one, such as Y4M or PGM, has binary
    pixel data right after its header line)."""
    try:
        with open(path, "rb") as f:
            head = f.read(_SNIFF_BYTES)
    except OSError:
        return False
    if not head or b"\0" in head:
        return False
    try:
        text = head.decode("utf-8")
    except UnicodeDecodeError as exc:
        if exc.start < len(head) - 3:   # not a character cut by the sample's end
            return False
        text = head[:exc.start].decode("utf-8")
    return all(ch.isprintable() or ch in "\t\n\r\f\v" for ch in text)


def _fourcc(cap: cv2.VideoCapture) -> str:
    code = int(cap.get(cv2.CAP_PROP_FOURCC) or 0)
    if code <= 0:
        return ""
    return code.to_bytes(4, "little").decode("latin-1").strip("\0 ").lower()


def _not_media(path: Path) -> InputError:
    return InputError(f"{path} is a text file, not a video or image (give a video file, an image "
                      "folder or glob, a camera index, a stream URL or synth:NAME)")


def _start_past_end(start: int, name: str, frames: int) -> ConfigError:
    last = f" (0-{frames - 1})" if frames > 0 else ""
    return ConfigError(f"start frame {start} (0-based; {start + 1} counting from 1) is past the "
                       f"end of {name}: it has {frames} frames{last}")


class VideoFileSource(_DecodedAhead):
    """A video file decoded with OpenCV (FFmpeg backend). A text file (an annotation or config
    file given by mistake) is an :class:`~motiontrack.errors.InputError`, also when FFmpeg
    would render its characters as a picture."""

    def __init__(self, path: str | Path, start: int = 0, max_frames: int = 0,
                 max_pixels: int = DEFAULT_MAX_PIXELS) -> None:
        super().__init__(start, max_frames)
        self.path = Path(path)
        if not self.path.exists():
            raise SourceError(f"video file not found: {self.path}")
        if self.path.is_dir():
            raise SourceError(f"{self.path} is a folder with no images")
        if self.path.stat().st_size == 0:
            raise SourceError(f"video file is empty: {self.path}")
        check_image(self.path, max_pixels)   # a picture opened as a one-frame video
        cap = cv2.VideoCapture(str(self.path))
        opened = cap.isOpened()
        text_codec = opened and _fourcc(cap) in _TEXT_CODECS
        if not opened or text_codec:
            cap.release()
            if text_codec or _is_text(self.path):
                raise _not_media(self.path)
            raise SourceError(f"cannot open {self.path} as a video (not a video file, or an "
                              "unsupported codec)")
        try:   # the frame size the container states, before a frame is decoded
            check_frame_size(str(self.path), int(cap.get(cv2.CAP_PROP_FRAME_WIDTH) or 0),
                             int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT) or 0), max_pixels)
        except InputError:
            cap.release()
            raise
        ok, first = cap.read()
        if not ok or first is None:
            cap.release()
            if _is_text(self.path):
                raise _not_media(self.path)
            raise SourceError(f"no frames could be decoded from {self.path} (not a video, or corrupt)")
        count = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        cap.release()
        self.info = SourceInfo(
            name=str(self.path), width=first.shape[1], height=first.shape[0],
            fps=fps if 0 < fps < 1000 else None, frame_count=count if count > 0 else None,
        )

    def _frames(self) -> Iterator[Frame]:
        cap = _open_capture(str(self.path), f"{self.path} as a video")
        fps = self.info.fps or 25.0
        try:
            index = 0
            # Frame-exact positioning: grab (no decode) up to start; seeking by CAP_PROP_POS_FRAMES
            # is keyframe-approximate for many codecs.
            while index < self.start:
                if not cap.grab():
                    raise _start_past_end(self.start, str(self.path), index)
                index += 1
            produced = 0
            while not self.max_frames or produced < self.max_frames:
                ok, img = cap.read()
                if not ok or img is None:
                    if produced == 0 and self.start > 0:   # the file's length was not known
                        raise _start_past_end(self.start, str(self.path), index)
                    break
                yield Frame(index=index, image=img, timestamp=index / fps,
                            discontinuity=self.seek_mark(index))
                index += 1
                produced += 1
            expected = self.info.frame_count
            done = not self.max_frames or produced < self.max_frames
            if done and expected is not None and index < expected - 1:
                self.truncated = True
                log.warning("%s: decoding stopped at frame %d of %d; the file may be truncated or "
                            "corrupt; keeping the %d frames processed", self.path, index, expected,
                            produced)
        finally:
            cap.release()


#: how often a live source's waits look at its stop request (s)
_POLL = 0.05
#: how long a camera's read can block (s): OpenCV's V4L backend gives up after 10 s
_CAMERA_CALL_BOUND = 10.0
#: live sources whose reader thread has started and not yet ended
_READERS: "set[LiveSource]" = set()
#: set at interpreter exit: every live source stops reading
_EXITING = threading.Event()
_exit_hook_lock = threading.Lock()
_exit_hook_registered = False


def _register_exit_hook() -> None:
    """Register :func:`_join_readers_at_exit` once, when the first reader starts: exit hooks run
    last-registered first, so it runs before the hooks of the layers above (the pipeline's, which
    wait for the threads that consume these sources)."""
    global _exit_hook_registered
    with _exit_hook_lock:
        if not _exit_hook_registered:
            atexit.register(_join_readers_at_exit)
            _exit_hook_registered = True


def _join_readers_at_exit() -> None:
    """Stop every live source and wait for its reader thread before the interpreter finalises:
    a thread still inside an OpenCV call then aborts the process when the call returns (C++
    terminate). The wait ends with the call, at the latest after the source's read timeout."""
    _EXITING.set()
    for src in blocked_live_sources():
        log.warning("waiting up to %.0f s for %s to return from reading", src.call_bound,
                    src.info.name)
    for src in list(_READERS):
        while True:
            try:
                src._join_reader()
                break
            except KeyboardInterrupt:   # finalising now could abort: wait all the same
                continue


def blocked_live_sources() -> "list[LiveSource]":
    """Live sources whose reader thread is inside an OpenCV call (opening or reading) that
    cannot be interrupted: it ends within the source's :attr:`~LiveSource.call_bound`, and the
    interpreter must not finalise before it has."""
    return [src for src in list(_READERS) if src.in_opencv_call]


def _check_live_options(reconnect_attempts: int, backoff: float, backoff_max: float,
                        read_timeout: float, reset_frames: int) -> None:
    for name, value, lo, strict in (("reconnect_attempts", reconnect_attempts, 0, False),
                                    ("backoff", backoff, 0, False),
                                    ("backoff_max", backoff_max, 0, False),
                                    ("read_timeout", read_timeout, 0, True),
                                    ("reset_frames", reset_frames, 1, False)):
        ok = (isinstance(value, (int, float)) and not isinstance(value, bool)
              and math.isfinite(value) and (value > lo if strict else value >= lo))
        if not ok:
            rel = ">" if strict else ">="
            raise SourceError(f"live source {name} must be a finite number {rel} {lo}, "
                              f"got {value!r}")


class LiveSource(Source):
    """A camera (integer index) or network stream (rtsp/http URL).

    Failure budget: when reading fails (the stream ends, drops, or sends nothing for
    ``read_timeout`` seconds) the source reconnects, waiting ``backoff``, ``2*backoff``, ... (at
    most ``backoff_max``) seconds before each try. At most ``reconnect_attempts`` tries are made
    until the stream has delivered ``reset_frames`` frames in a row after a reconnection; only then
    do the count and the back-off start afresh. A stream that keeps failing, even one that comes
    back for a few frames each time, therefore fails (:class:`SourceError`) after
    ``reconnect_attempts`` reconnections.

    A stream whose length OpenCV knows (frame count > 0: a video file served over HTTP) is a file,
    not live: the end of the stream is the end of the source (before the announced length it is
    *truncated*), nothing reconnects, and frames carry ``index / fps`` timestamps. Live frames carry
    wall-clock timestamps, and the first frame after a reconnection a ``reconnect``
    :class:`~motiontrack.types.Discontinuity`: the stages reset what they learnt before the gap.

    Stopping: reading, reconnecting and the back-off waits run in a reader thread that reads one
    frame each time the consumer asks for one, while the consumer waits in slices of ``_POLL``
    seconds, so that iteration ends within one slice of :attr:`stop_requested` turning True,
    whatever the reader is doing. A reader left inside an OpenCV call releases its capture when
    the call returns (at most ``read_timeout`` seconds for streams), and interpreter exit waits
    for it.

    Parameters
    ----------
    target : camera index or stream URL.
    read_timeout : streams: longest wait (s) for a connection to open or for the next frame
        (OpenCV's FFmpeg open and read timeouts); cameras keep their backend's own limit.
    reset_frames : frames in a row after a reconnection that restore the failure budget.
    opener : ``opener(target)`` → a capture, instead of OpenCV's (tests).
    sleep : called with each back-off delay instead of waiting (tests).
    clock : wall-clock time, for the timestamps of live frames.
    """

    def __init__(self, target: int | str, start: int = 0, max_frames: int = 0,
                 reconnect_attempts: int = 5, backoff: float = 0.5, backoff_max: float = 8.0,
                 read_timeout: float = 5.0, reset_frames: int = 250,
                 opener: Callable[[Any], Any] | None = None,
                 sleep: Callable[[float], None] | None = None,
                 clock: Callable[[], float] = time.time) -> None:
        super().__init__(start, max_frames)
        _check_live_options(reconnect_attempts, backoff, backoff_max, read_timeout, reset_frames)
        self.target = target
        self.reconnect_attempts = reconnect_attempts
        self.backoff = backoff
        self.backoff_max = backoff_max
        self.read_timeout = read_timeout
        self.reset_frames = reset_frames
        self._opener = opener or self._capture
        self._sleep = sleep
        self._clock = clock
        self._what = f"camera {target}" if isinstance(target, int) else f"stream {target}"
        #: reconnections performed so far
        self.reconnects = 0
        #: set by the reader when it reconnected for the image it hands over next: that frame
        #: carries a ``reconnect`` :class:`~motiontrack.types.Discontinuity`
        self._reconnected = False
        self._attempts = 0       # reconnection attempts since the stream was last stable
        self._delay = backoff    # the next back-off wait (s)
        self._stable = 0         # frames read since the last reconnection
        self._read = 0           # frames read in all
        self._busy_until = 0.0   # monotonic time by which the current OpenCV call returns
        self._abandoned = threading.Event()
        self._requests: queue.Queue = queue.Queue(maxsize=1)
        self._replies: queue.Queue = queue.Queue(maxsize=1)
        self._reader: threading.Thread | None = None
        cap = self._open()
        if cap is None:
            raise SourceError(f"cannot open {self._what}")
        self._cap = cap
        ok, first = self._call(cap.read)
        if not ok or first is None:
            cap.release()
            raise SourceError(f"{self._what} opened but delivered no frame")
        self._first: np.ndarray | None = first
        self._read = 1
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        count = float(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0.0)
        #: frames a stream of known length announces (a video file over HTTP), else None
        self.length = int(count) if 0 < count < 2**31 else None
        self.info = SourceInfo(name=self._what, width=first.shape[1], height=first.shape[0],
                               fps=fps if 0 < fps < 1000 else None, frame_count=self.length,
                               live=self.length is None)

    # ---------------------------------------------------------------- the consumer's side
    def __iter__(self) -> Iterator[Frame]:
        index = 0
        produced = 0
        fps = self.info.fps or 25.0
        try:
            while not self.max_frames or produced < self.max_frames:
                img = self._next_image()
                if img is None:
                    if (produced == 0 and self.start > 0 and self.length is not None
                            and not self._stopping()):
                        raise _start_past_end(self.start, self._what, index)
                    return
                # the reader sets _reconnected before its reply and reads nothing until the
                # next request: the flag belongs to this image
                mark, self._reconnected = self._reconnected, False
                if index >= self.start:
                    stamp = self._clock() if self.info.live else index / fps
                    cut = (Discontinuity("reconnect") if mark and produced
                           else self.seek_mark(index) if produced == 0 else None)
                    yield Frame(index=index, image=img, timestamp=stamp, discontinuity=cut)
                    produced += 1
                index += 1
        finally:
            self.close()

    def _next_image(self) -> np.ndarray | None:
        """The next image from the reader thread; None at the end or on a stop request."""
        if self._first is not None:
            img, self._first = self._first, None
            return img
        if self._reader is None:
            _register_exit_hook()
            self._reader = threading.Thread(target=self._serve, name="motiontrack-live",
                                            daemon=True)
            _READERS.add(self)
            self._reader.start()
        self._requests.put(True)   # never blocks: every earlier request has had its reply
        while True:
            try:
                item = self._replies.get(timeout=_POLL)
            except queue.Empty:
                if self._stopping():
                    return None
                continue
            if isinstance(item, BaseException):
                raise item
            return item

    def _stopping(self) -> bool:
        return self._abandoned.is_set() or _EXITING.is_set() or bool(self.stop_requested())

    def close(self) -> None:
        """Stop reading. A reader thread inside an OpenCV call is not waited for: it releases the
        capture when the call returns."""
        if self._abandoned.is_set():
            return
        self._abandoned.set()
        if self._reader is None:
            cap, self._cap = getattr(self, "_cap", None), None
            if cap is not None:
                cap.release()
        elif not self.in_opencv_call:   # it notices within one slice
            self._reader.join(timeout=2 * _POLL)

    def _join_reader(self) -> None:
        """Wait until the reader thread has ended: as long as its current OpenCV call may last,
        and a second for it to notice the stop otherwise."""
        thread = self._reader
        deadline = time.monotonic() + 1.0
        while thread is not None and thread.is_alive():
            deadline = max(deadline, self._busy_until)
            left = deadline - time.monotonic()
            if left <= 0:
                return
            thread.join(timeout=min(left, _POLL))

    # ---------------------------------------------------------------- the reader thread
    def _serve(self) -> None:
        """The reader thread: one :meth:`_read_next` for each request of the consumer."""
        try:
            while not self._stopping():
                try:
                    self._requests.get(timeout=_POLL)
                except queue.Empty:
                    continue
                try:
                    item: Any = self._read_next()
                except BaseException as exc:  # handed to the consumer
                    item = exc
                self._replies.put(item)
                if not isinstance(item, np.ndarray):
                    return
        finally:
            if self._cap is not None:
                self._cap.release()
                self._cap = None
            _READERS.discard(self)

    def _read_next(self) -> np.ndarray | None:
        """The next image, reconnecting as far as the failure budget allows; None at the end of
        a stream of known length or on a stop request."""
        while True:
            if self._stopping():
                return None
            if self._cap is None and not self._reconnect():
                if self._stopping():
                    return None
                self.truncated = True
                raise SourceError(f"{self._what} failed after {self._read} frames and "
                                  f"{self._attempts} reconnection attempts (the attempts start "
                                  f"afresh after {self.reset_frames} frames in a row)")
            ok, img = self._call(self._cap.read)
            if ok and img is not None:
                self._read += 1
                self._stable += 1
                if self._stable >= self.reset_frames:
                    self._attempts, self._delay = 0, self.backoff
                return img
            self._cap.release()
            self._cap = None
            if self.length is not None:
                if self._read < self.length - 1:
                    self.truncated = True
                    log.warning("%s ended at frame %d of %d; keeping the frames read", self._what,
                                self._read, self.length)
                return None
            if self._stopping():
                return None

    def _reconnect(self) -> bool:
        """Open the stream again within the failure budget; False when it is spent or a stop
        came."""
        while self._attempts < self.reconnect_attempts:
            self._attempts += 1
            log.warning("%s dropped; reconnecting (attempt %d/%d) in %.1f s", self._what,
                        self._attempts, self.reconnect_attempts, self._delay)
            if self._wait(self._delay):
                return False
            self._delay = min(self._delay * 2, self.backoff_max)
            cap = self._open()
            if cap is not None:
                self._cap = cap
                self.reconnects += 1
                self._stable = 0
                self._reconnected = True
                return True
            if self._stopping():
                return False
        return False

    def _wait(self, delay: float) -> bool:
        """Wait ``delay`` seconds in slices of ``_POLL``; True when a stop came first."""
        if self._sleep is not None:
            self._sleep(delay)
            return self._stopping()
        end = time.monotonic() + delay
        while not self._stopping():
            left = end - time.monotonic()
            if left <= 0:
                return False
            self._abandoned.wait(min(left, _POLL))
        return True

    def _capture(self, target: int | str) -> cv2.VideoCapture:
        """OpenCV's capture of ``target``: streams through FFmpeg with the open and read
        timeouts, cameras as they are."""
        if isinstance(target, int):
            return cv2.VideoCapture(target)
        ms = max(1, int(round(self.read_timeout * 1000)))
        return cv2.VideoCapture(target, cv2.CAP_FFMPEG, [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, ms,
                                                         cv2.CAP_PROP_READ_TIMEOUT_MSEC, ms])

    def _open(self) -> Any:
        cap = self._call(self._opener, self.target)
        if not cap.isOpened():
            cap.release()
            return None
        return cap

    @property
    def call_bound(self) -> float:
        """The longest an OpenCV call of this source can block (s): the read timeout of a
        stream, the backend's own limit for a camera."""
        return _CAMERA_CALL_BOUND if isinstance(self.target, int) else self.read_timeout

    @property
    def in_opencv_call(self) -> bool:
        """Whether the reader thread is inside an OpenCV call (opening or reading)."""
        reader = self._reader
        return self._busy_until > 0 and reader is not None and reader.is_alive()

    def _call(self, fn: Callable[..., Any], *args: Any) -> Any:
        """``fn(*args)``, an OpenCV call that may block, with the time by which it returns in
        :attr:`_busy_until` meanwhile (for :meth:`_join_reader`)."""
        self._busy_until = time.monotonic() + self.call_bound + 1.0
        try:
            return fn(*args)
        finally:
            self._busy_until = 0.0


class ImageSequenceSource(_DecodedAhead):
    """Frames from an image folder or a glob pattern (e.g. ``input/*.jpg``), in natural order."""

    def __init__(self, pattern: str | Path, start: int = 0, max_frames: int = 0,
                 fps: float | None = None, max_pixels: int = DEFAULT_MAX_PIXELS) -> None:
        super().__init__(start, max_frames)
        self.max_pixels = max_pixels
        p = Path(pattern)
        if p.is_dir():
            files = [str(f) for f in p.iterdir() if f.suffix.lower() in IMAGE_EXTENSIONS]
            name = str(p)
        else:
            files = [f for f in glob.glob(str(pattern)) if Path(f).suffix.lower() in IMAGE_EXTENSIONS]
            name = str(pattern)
        if not files:
            raise SourceError(f"no images found in {name} (extensions: {', '.join(IMAGE_EXTENSIONS)})")
        self.files = sorted(files, key=natural_key)
        check_image(self.files[0], max_pixels)
        first = cv2.imread(self.files[0], cv2.IMREAD_COLOR)
        if first is None:
            raise SourceError(f"cannot read image {self.files[0]}")
        check_frame_size(self.files[0], first.shape[1], first.shape[0], max_pixels)
        self.info = SourceInfo(name=name, width=first.shape[1], height=first.shape[0],
                               fps=fps, frame_count=len(self.files))

    def _frames(self) -> Iterator[Frame]:
        fps = self.info.fps or 25.0
        end = len(self.files) if not self.max_frames else min(len(self.files), self.start + self.max_frames)
        for index in range(self.start, end):
            size = check_image(self.files[index], self.max_pixels)
            w, h = self.info.width, self.info.height   # a JPEG's EXIF may turn it a quarter
            if size is not None and size not in ((w, h), (h, w)):
                raise SourceError(f"image {self.files[index]} is {size[0]}x{size[1]}, expected "
                                  f"{self.info.width}x{self.info.height} like the first")
            img = cv2.imread(self.files[index], cv2.IMREAD_COLOR)
            if img is None:
                self.truncated = True
                log.warning("cannot read image %s; stopping after %d frames", self.files[index],
                            index - self.start)
                return
            if img.shape[:2] != (self.info.height, self.info.width):
                raise SourceError(f"image {self.files[index]} is {img.shape[1]}x{img.shape[0]}, "
                                  f"expected {self.info.width}x{self.info.height} like the first")
            yield Frame(index=index, image=img, timestamp=index / fps,
                        discontinuity=self.seek_mark(index))


class ArraySource(Source):
    """Frames from an in-memory sequence of images (tests, notebooks)."""

    def __init__(self, images, fps: float = 25.0, name: str = "<array>", start: int = 0,
                 max_frames: int = 0) -> None:
        super().__init__(start, max_frames)
        self.images = list(images)
        if not self.images:
            raise SourceError("no frames given")
        h, w = self.images[0].shape[:2]
        self.info = SourceInfo(name=name, width=w, height=h, fps=fps, frame_count=len(self.images))

    def __iter__(self) -> Iterator[Frame]:
        end = len(self.images) if not self.max_frames else min(len(self.images), self.start + self.max_frames)
        for i in range(self.start, end):
            yield Frame(index=i, image=np.asarray(self.images[i]),
                        timestamp=i / (self.info.fps or 25.0), discontinuity=self.seek_mark(i))


def open_source(spec: Any, start: int = 0, max_frames: int = 0,
                max_pixels: int = DEFAULT_MAX_PIXELS, **live_options: Any) -> Source:
    """Open ``spec``: a :class:`Source` (returned as is), a registered scheme (:data:`SCHEMES`,
    e.g. ``synth:NAME``), a camera index (``0`` or ``"0"``), a URL (``rtsp://``, ``http://``...),
    an image folder or glob, or a video file. An existing file is always the video file, even
    when its name holds glob characters (``*?[``).

    A ``start`` at or past the end of a source of known length is a
    :class:`~motiontrack.errors.ConfigError` here; a source whose length is found only by
    reading (a video file without a frame count, a stream of known length) raises it when the
    first read past ``start`` yields nothing. A picture (its header) or a video file (the
    frame size of its container) of more than ``max_pixels`` pixels is an
    :class:`~motiontrack.errors.InputError` before anything is decoded."""
    if isinstance(spec, Source):
        return spec
    src = _open(spec, start, max_frames, max_pixels, **live_options)
    n = src.info.frame_count
    if n is not None and start >= n and not src.info.live:
        src.close()
        raise _start_past_end(start, src.info.name, n)
    return src


def _open(spec: Any, start: int, max_frames: int, max_pixels: int,
          **live_options: Any) -> Source:
    if isinstance(spec, int) or (isinstance(spec, str) and spec.isdigit()):
        return LiveSource(int(spec), start, max_frames, **live_options)
    spec = os.fspath(spec)
    scheme, sep, _ = spec.partition(":")
    if sep and scheme in SCHEMES:
        return SCHEMES.get(scheme)(spec, start, max_frames)
    if _URL.match(spec) and not spec.startswith("file://"):
        return LiveSource(spec, start, max_frames, **live_options)
    if spec.startswith("file://"):
        spec = spec[len("file://"):]
    if Path(spec).is_file():   # whatever its name holds: `video[1080p].mp4` is no glob
        return VideoFileSource(spec, start, max_frames, max_pixels)
    if any(ch in spec for ch in "*?[") or Path(spec).is_dir():
        return ImageSequenceSource(spec, start, max_frames, max_pixels=max_pixels)
    return VideoFileSource(spec, start, max_frames, max_pixels)
