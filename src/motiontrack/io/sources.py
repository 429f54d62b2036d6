"""Video sources: files, cameras, streams, image folders/globs and synthetic scenes.

Every source is an iterable of :class:`~motiontrack.types.Frame` with known (or ``None``) size, fps
and frame count. Opening problems raise :class:`~motiontrack.errors.SourceError` with one clear
message; a file that stops decoding early (truncated) ends with a warning and keeps what decoded.
Live sources (cameras, streams) reconnect with bounded exponential back-off and stamp frames with
wall-clock time.
"""

from __future__ import annotations

import glob
import logging
import os
import queue
import re
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator

import cv2
import numpy as np

from ..errors import SourceError
from ..registry import Registry
from ..types import Annotations, Frame

log = logging.getLogger(__name__)

__all__ = ["SourceInfo", "Source", "VideoFileSource", "LiveSource", "ImageSequenceSource",
           "ArraySource", "SCHEMES", "open_source", "IMAGE_EXTENSIONS"]

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

    def describe(self) -> str:
        fps = f"{self.fps:g} fps" if self.fps else "fps unknown"
        n = f"{self.frame_count} frames" if self.frame_count is not None else "length unknown"
        return f"{self.name}: {self.width}x{self.height}, {fps}, {n}"


class Source:
    """Base class: ``info`` plus iteration over frames from ``start`` for ``max_frames`` frames."""

    info: SourceInfo

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


class VideoFileSource(_DecodedAhead):
    """A video file decoded with OpenCV (FFmpeg backend)."""

    def __init__(self, path: str | Path, start: int = 0, max_frames: int = 0) -> None:
        super().__init__(start, max_frames)
        self.path = Path(path)
        if not self.path.exists():
            raise SourceError(f"video file not found: {self.path}")
        if self.path.is_dir():
            raise SourceError(f"{self.path} is a folder with no images")
        if self.path.stat().st_size == 0:
            raise SourceError(f"video file is empty: {self.path}")
        cap = _open_capture(str(self.path), f"{self.path} as a video (not a video file, or an "
                            "unsupported codec)")
        ok, first = cap.read()
        if not ok or first is None:
            cap.release()
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
                    log.warning("%s has only %d frames; --start %d is past the end",
                                self.path, index, self.start)
                    return
                index += 1
            produced = 0
            while not self.max_frames or produced < self.max_frames:
                ok, img = cap.read()
                if not ok or img is None:
                    break
                yield Frame(index=index, image=img, timestamp=index / fps)
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


class LiveSource(Source):
    """A camera (integer index) or network stream (rtsp/http URL).

    When reading fails the source reconnects up to ``reconnect_attempts`` times, waiting
    ``backoff``, ``2*backoff``, ... (at most ``backoff_max``) seconds between tries. Frames carry
    wall-clock timestamps so a tracker can see the gap.
    """

    def __init__(self, target: int | str, start: int = 0, max_frames: int = 0,
                 reconnect_attempts: int = 5, backoff: float = 0.5, backoff_max: float = 8.0,
                 opener: Callable[[Any], Any] | None = None, sleep: Callable[[float], None] = time.sleep,
                 clock: Callable[[], float] = time.time) -> None:
        super().__init__(start, max_frames)
        self.target = target
        self.reconnect_attempts = reconnect_attempts
        self.backoff = backoff
        self.backoff_max = backoff_max
        self._opener = opener or cv2.VideoCapture
        self._sleep = sleep
        self._clock = clock
        what = f"camera {target}" if isinstance(target, int) else f"stream {target}"
        self._what = what
        cap = self._open()
        if cap is None:
            raise SourceError(f"cannot open {what}")
        self._cap = cap
        ok, first = cap.read()
        if not ok or first is None:
            cap.release()
            raise SourceError(f"{what} opened but delivered no frame")
        self._first = first
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        self.info = SourceInfo(name=what, width=first.shape[1], height=first.shape[0],
                               fps=fps if 0 < fps < 1000 else None, frame_count=None, live=True)
        #: reconnections performed so far
        self.reconnects = 0

    def _open(self) -> Any:
        cap = self._opener(self.target)
        if not cap.isOpened():
            cap.release()
            return None
        return cap

    def _reconnect(self) -> bool:
        delay = self.backoff
        for attempt in range(1, self.reconnect_attempts + 1):
            log.warning("%s dropped; reconnecting (attempt %d/%d) in %.1f s", self._what, attempt,
                        self.reconnect_attempts, delay)
            self._sleep(delay)
            cap = self._open()
            if cap is not None:
                self._cap = cap
                self.reconnects += 1
                return True
            delay = min(delay * 2, self.backoff_max)
        return False

    def __iter__(self) -> Iterator[Frame]:
        index = 0
        produced = 0
        pending = self._first
        try:
            while not self.max_frames or produced < self.max_frames:
                if pending is not None:
                    img, pending = pending, None
                else:
                    ok, img = self._cap.read()
                    if not ok or img is None:
                        self._cap.release()
                        if not self._reconnect():
                            self.truncated = True
                            raise SourceError(f"{self._what} failed after {index} frames and "
                                              f"{self.reconnect_attempts} reconnection attempts")
                        continue
                if index >= self.start:
                    yield Frame(index=index, image=img, timestamp=self._clock())
                    produced += 1
                index += 1
        finally:
            self.close()

    def close(self) -> None:
        cap = getattr(self, "_cap", None)
        if cap is not None:
            cap.release()


def _natural_key(s: str) -> list[Any]:
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]


class ImageSequenceSource(_DecodedAhead):
    """Frames from an image folder or a glob pattern (e.g. ``input/*.jpg``), in natural order."""

    def __init__(self, pattern: str | Path, start: int = 0, max_frames: int = 0,
                 fps: float | None = None) -> None:
        super().__init__(start, max_frames)
        p = Path(pattern)
        if p.is_dir():
            files = [str(f) for f in p.iterdir() if f.suffix.lower() in IMAGE_EXTENSIONS]
            name = str(p)
        else:
            files = [f for f in glob.glob(str(pattern)) if Path(f).suffix.lower() in IMAGE_EXTENSIONS]
            name = str(pattern)
        if not files:
            raise SourceError(f"no images found in {name} (extensions: {', '.join(IMAGE_EXTENSIONS)})")
        self.files = sorted(files, key=_natural_key)
        first = cv2.imread(self.files[0], cv2.IMREAD_COLOR)
        if first is None:
            raise SourceError(f"cannot read image {self.files[0]}")
        self.info = SourceInfo(name=name, width=first.shape[1], height=first.shape[0],
                               fps=fps, frame_count=len(self.files))

    def _frames(self) -> Iterator[Frame]:
        fps = self.info.fps or 25.0
        end = len(self.files) if not self.max_frames else min(len(self.files), self.start + self.max_frames)
        for index in range(self.start, end):
            img = cv2.imread(self.files[index], cv2.IMREAD_COLOR)
            if img is None:
                self.truncated = True
                log.warning("cannot read image %s; stopping after %d frames", self.files[index],
                            index - self.start)
                return
            if img.shape[:2] != (self.info.height, self.info.width):
                raise SourceError(f"image {self.files[index]} is {img.shape[1]}x{img.shape[0]}, "
                                  f"expected {self.info.width}x{self.info.height} like the first")
            yield Frame(index=index, image=img, timestamp=index / fps)


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
            yield Frame(index=i, image=np.asarray(self.images[i]), timestamp=i / (self.info.fps or 25.0))


def open_source(spec: Any, start: int = 0, max_frames: int = 0, **live_options: Any) -> Source:
    """Open ``spec``: a :class:`Source` (returned as is), a registered scheme (:data:`SCHEMES`,
    e.g. ``synth:NAME``), a camera index (``0`` or ``"0"``), a URL (``rtsp://``, ``http://``...),
    an image folder or glob, or a video file."""
    if isinstance(spec, Source):
        return spec
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
    if any(ch in spec for ch in "*?[") or Path(spec).is_dir():
        return ImageSequenceSource(spec, start, max_frames)
    return VideoFileSource(spec, start, max_frames)
