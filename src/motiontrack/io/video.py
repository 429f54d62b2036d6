"""Video sinks: browser-playable WebM (VP8/VP9) by default, H.264 MP4 and other codecs on request.

Files are written under a temporary name and renamed on :meth:`VideoSink.close`, so an interrupted
run leaves either a complete, playable video of everything processed so far or nothing. A video
never fills its device: it stops with :class:`~motiontrack.io.atomic.DiskFullError` when less
than :data:`DISK_RESERVE` is left (``cv2.VideoWriter`` would go on silently writing a broken
file), so the small outputs of the run still fit.

The encoder runs in a thread of its own behind a queue of a few frames
(:mod:`motiontrack.io.frame_queue`), so the run draws and tracks the next frames while it encodes.

WebM is encoded with PyAV (the ``video`` extra, ``pip install motiontrack[video]``) when it is
installed: it lets libvpx run in its real-time mode at a fixed speed (:data:`PYAV_OPTIONS`) on one
thread, several times faster than through ``cv2.VideoWriter``, which gives no access to the
encoder's speed settings (docs/benchmarks.md, "Speed alternatives"). H.264 (``h264``) is written
by PyAV too, with libx264 (or OpenH264) as yuv420p MP4 whose index comes first
(``movflags=+faststart``), so that browsers play it while it loads. Without PyAV, and for the
other codecs, OpenCV writes the file.

Which codecs this installation can encode is probed once per process
(:func:`encodable_codecs`: PyAV opens each encoder, OpenCV writes one tiny frame); a codec it
cannot encode is refused before the run with the list of those it can (:func:`check_codec`).
"""

from __future__ import annotations

import contextlib
import functools
import logging
import os
import tempfile
from fractions import Fraction
from pathlib import Path

import cv2
import numpy as np

from ..errors import InputError, MotionTrackError, printable
from .atomic import (DiskFullError, commit_temp, free_bytes, is_disk_full, output_error,
                     temp_path_for)
from .frame_queue import FrameQueue
from .native_logs import quiet as _quiet_native_logs

log = logging.getLogger(__name__)

_quiet_native_logs()   # before the first video is written (see io.native_logs)

#: codec name → (OpenCV fourcc, file extension, what it is)
CODECS = {
    "vp80": ("VP80", ".webm", "VP8 WebM, plays in browsers (the default)"),
    "vp90": ("VP90", ".webm", "VP9 WebM, plays in browsers"),
    "h264": ("avc1", ".mp4", "H.264 MP4 (yuv420p, faststart), plays in browsers"),
    "mp4v": ("mp4v", ".mp4", "MPEG-4 part 2 MP4 (browsers do not play it)"),
    "avc1": ("avc1", ".mp4", "H.264 MP4 through OpenCV's FFmpeg"),
    "mjpg": ("MJPG", ".avi", "Motion JPEG AVI"),
    "xvid": ("XVID", ".avi", "Xvid AVI"),
}


#: codec name → (container format, muxer options, PyAV encoders to try in turn)
PYAV_CODECS = {
    "vp80": ("webm", {}, ("libvpx",)),
    "vp90": ("webm", {}, ("libvpx-vp9",)),
    # the index (moov) first: a browser starts playing before the whole file has arrived
    "h264": ("mp4", {"movflags": "+faststart"}, ("libx264", "libopenh264", "h264")),
}
#: libvpx settings: real-time mode, constant quality (crf, lower = better; the bit rate is a cap),
#: blocks that barely change from the last frame (sum of absolute differences under
#: ``static-thresh`` over 16x16 pixels) kept as they are, which a still camera's scene mostly is.
#: VP8 reads a negative ``cpu-used`` as a fixed speed (-16 the fastest); a positive one lets it pick
#: its speed from the time it measures, to fill (16 - cpu-used) / 16 of the frame interval: at 10
#: fps, 50 ms a frame for cpu-used 8, and a file that depends on the machine's load. VP9's fastest
#: real-time speed is 8.
PYAV_OPTIONS = {"deadline": "realtime", "cpu-used": "-16", "crf": "16", "static-thresh": "1000"}
PYAV_MAX_BITRATE = 20_000_000
#: PyAV encoder → (its options, bit rate; 0 = the encoder's own rate control)
PYAV_ENCODER_OPTIONS = {
    "libvpx": (PYAV_OPTIONS, PYAV_MAX_BITRATE),
    "libvpx-vp9": ({**PYAV_OPTIONS, "cpu-used": "8", "row-mt": "1"}, PYAV_MAX_BITRATE),
    # the fastest preset: about as fast per frame as real-time libvpx, at a larger file (veryfast
    # writes a third of the size at twice the time); crf 23 is libx264's own default quality
    "libx264": ({"preset": "ultrafast", "crf": "23"}, 0),
    "libopenh264": ({}, 8_000_000),
}

#: bytes a video leaves free on its device for the other outputs of the run (tracks, summary)
DISK_RESERVE = 1 << 20


def encoder_threads() -> int:
    """Threads of an encoder: the cores the pipeline leaves (it keeps about two busy), at least 1
    and at most 8. libvpx's threads wait for each other by spinning, so on a machine without
    spare cores a second thread costs the pipeline CPU time instead of saving wall time."""
    return max(1, min(8, (os.cpu_count() or 1) - 2))


def extension_for(codec: str) -> str:
    return CODECS[codec][1]


def pyav_available() -> bool:
    try:
        import av  # noqa: F401
    except ImportError:
        return False
    return True


@functools.lru_cache(maxsize=None)
def pyav_encoder(codec: str) -> str | None:
    """The PyAV encoder that writes ``codec`` here (the first of :data:`PYAV_CODECS` that opens),
    or None: no PyAV, or none of its encoders."""
    if codec not in PYAV_CODECS or not pyav_available():
        return None
    import av

    available = av.codecs_available
    for name in PYAV_CODECS[codec][2]:
        if name not in available:
            continue
        try:
            ctx = av.CodecContext.create(name, "w")
            ctx.width, ctx.height, ctx.pix_fmt = 64, 48, "yuv420p"
            ctx.time_base = Fraction(1, 25)
            ctx.open()
            return ctx.codec.name
        except Exception as exc:   # e.g. a hardware encoder without its device
            log.debug("PyAV encoder %s does not open: %s", name, exc)
    return None


@contextlib.contextmanager
def _quiet_stderr():
    """Standard error closed at the file-descriptor level: FFmpeg inside OpenCV prints each
    encoder it fails to open there, which a probe is expected to do."""
    try:
        saved = os.dup(2)
    except OSError:  # pragma: no cover - no standard error at all
        yield
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)


@functools.lru_cache(maxsize=None)
def opencv_encodes(codec: str) -> bool:
    """Whether ``cv2.VideoWriter`` writes ``codec`` here: one 64x48 frame into a temporary file."""
    fourcc, ext = CODECS[codec][:2]
    with tempfile.TemporaryDirectory(prefix="motiontrack-codec-") as folder:
        path = os.path.join(folder, f"probe{ext}")
        with _quiet_stderr():
            writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*fourcc), 25.0, (64, 48))
            ok = writer.isOpened()
            if ok:
                writer.write(np.zeros((48, 64, 3), np.uint8))
            writer.release()
        return ok and os.path.isfile(path) and os.path.getsize(path) > 0


def encodable_codecs() -> dict[str, str]:
    """The codecs this installation can encode, in :data:`CODECS` order: name → what it is and
    what writes it (PyAV's encoder, else OpenCV)."""
    found = {}
    for name, (_, _, what) in CODECS.items():
        encoder = pyav_encoder(name)
        if encoder is not None:
            found[name] = f"{what}; PyAV {encoder}"
        elif opencv_encodes(name):
            found[name] = f"{what}; OpenCV"
    return found


def check_codec(codec: str) -> None:
    """Refuse a codec that is unknown or that this installation cannot encode, naming those it
    can (:class:`InputError`)."""
    if codec in CODECS and (pyav_encoder(codec) is not None or opencv_encodes(codec)):
        return
    can = ", ".join(encodable_codecs()) or "none"
    if codec not in CODECS:
        raise InputError(f"unknown codec {codec!r}; this installation can encode: {can}")
    hint = (" (it needs PyAV with libx264 or OpenH264: pip install motiontrack[video])"
            if codec in PYAV_CODECS else "")
    raise InputError(f"this installation cannot encode {codec} video{hint}; it can encode: {can}")


class _PyAVWriter:
    """libvpx or an H.264 encoder through PyAV; the ``write``/``release`` subset of
    ``cv2.VideoWriter`` used here.

    Frames of odd width or height are padded by one replicated pixel (4:2:0 needs even sizes).
    """

    def __init__(self, path: Path, codec: str, fps: float, size: tuple[int, int]) -> None:
        import av

        w, h = size
        self._pad = (h % 2, w % 2)
        container, muxer_options, _ = PYAV_CODECS[codec]
        encoder = pyav_encoder(codec)
        options, bit_rate = PYAV_ENCODER_OPTIONS.get(encoder, ({}, 0))
        self._out = av.open(str(path), "w", format=container, options=muxer_options)
        try:
            self._stream = self._out.add_stream(encoder,
                                                rate=Fraction(fps).limit_denominator(1001))
            self._stream.width, self._stream.height = w + self._pad[1], h + self._pad[0]
            self._stream.pix_fmt = "yuv420p"
            if bit_rate:
                self._stream.bit_rate = bit_rate
            self._stream.options = dict(options)
            self._stream.thread_count = encoder_threads()
        except BaseException:
            self._out.close()
            raise

    @property
    def buffer_shape(self) -> tuple[int, int]:
        """Shape of a frame as :meth:`fill` leaves it: I420, the planes one under the other."""
        return self._stream.height * 3 // 2, self._stream.width

    def fill(self, image: np.ndarray, buf: np.ndarray) -> None:
        """``image`` (BGR or gray, the video's size) into ``buf`` as I420 (in the run's thread:
        it replaces the copy a queued frame needs, and leaves the encoder's thread the encoding)."""
        if image.ndim == 2:
            image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
        if any(self._pad):
            image = cv2.copyMakeBorder(image, 0, self._pad[0], 0, self._pad[1], cv2.BORDER_REPLICATE)
        # OpenCV's BGR to I420 (BT.601, limited range, as FFmpeg's) takes a tenth of the time
        # of FFmpeg's own conversion from bgr24
        cv2.cvtColor(image, cv2.COLOR_BGR2YUV_I420, dst=buf)

    def write(self, yuv: np.ndarray) -> None:
        """Encode one frame that :meth:`fill` made."""
        import av

        frame = av.VideoFrame.from_ndarray(yuv, format="yuv420p")
        for packet in self._stream.encode(frame):
            self._out.mux(packet)

    def release(self) -> None:
        try:
            for packet in self._stream.encode():  # flush the encoder
                self._out.mux(packet)
        finally:
            self._out.close()


class EncoderError(MotionTrackError):
    """The encoder of a video failed while the run was writing it."""


class VideoSink:
    """Write frames to ``path`` with ``codec``; opened lazily at the first frame (size from it).

    ``backend``: ``"auto"`` (PyAV for WebM and H.264 when it has the encoder, else OpenCV),
    ``"pyav"`` or ``"opencv"``; :attr:`backend` tells which one is used.

    The encoder runs in a thread of its own (:class:`~motiontrack.io.frame_queue.FrameQueue`):
    :meth:`write` copies the frame (as I420 for PyAV) into one of at most ``slots`` buffers and
    returns, waiting
    only while every buffer is queued. An error of the encoder is raised, as one
    :class:`EncoderError` (or :class:`~motiontrack.io.atomic.DiskFullError`, or the
    :class:`OSError` of the device), by the next :meth:`write` or by :meth:`close`.
    :meth:`close` waits for every frame written and finishes the file.
    """

    def __init__(self, path: str | Path, fps: float, codec: str = "vp80", backend: str = "auto",
                 slots: int | None = None) -> None:
        if codec not in CODECS:
            raise InputError(f"unknown codec {codec!r}; valid: {', '.join(CODECS)}")
        if backend not in ("auto", "pyav", "opencv"):
            raise InputError(f"unknown video backend {backend!r}; valid: auto, pyav, opencv")
        if backend == "pyav" and pyav_encoder(codec) is None:
            raise InputError(f"the pyav backend needs PyAV (pip install av) with an encoder of "
                             f"{', '.join(PYAV_CODECS)}, got {codec!r}")
        if backend == "auto":
            backend = "pyav" if pyav_encoder(codec) is not None else "opencv"
        self.backend = backend
        self.path = Path(path)
        self.fps = float(fps) if fps and fps > 0 else 25.0
        self.codec = codec
        self.slots = slots
        self._writer: cv2.VideoWriter | _PyAVWriter | None = None
        self._queue: FrameQueue | None = None
        self._size = (0, 0)
        self._tmp: Path | None = None
        self.frames = 0

    def write(self, image: np.ndarray) -> None:
        """Queue one frame ((h, w, 3) BGR or (h, w) gray uint8); the first one sets the size."""
        h, w = image.shape[:2]
        if self._writer is None:
            self._writer = self._open(w, h)
            self._size = (w, h)
            if isinstance(self._writer, _PyAVWriter):
                shape, fill = self._writer.buffer_shape, self._writer.fill
            else:
                shape, fill = (h, w, 3), None
            self._queue = FrameQueue(self._encode, shape, self.slots, fill=fill,
                                     name=f"motiontrack-video-{self.path.name}")
        if (w, h) != self._size:
            raise EncoderError(f"cannot write {printable(self.path)}: frame of {w}x{h} pixels "
                               f"in a video of {self._size[0]}x{self._size[1]}")
        self._check_space()
        self._queue.put(image)
        self.frames += 1

    def _encode(self, image: np.ndarray) -> None:
        """One frame into the encoder (in the queue's thread): its errors as this sink's."""
        try:
            self._writer.write(image)
        except OSError as exc:  # PyAV reports a full device; cv2.VideoWriter reports nothing
            raise output_error(self.path, exc) from None
        except Exception as exc:
            raise EncoderError(f"cannot encode {self.codec} video to {printable(self.path)}: "
                               f"{printable(exc)}") from None

    def _check_space(self) -> None:
        """Stop before the device is full: less than :data:`DISK_RESERVE` is left."""
        free = free_bytes(self._tmp.parent)
        if free < DISK_RESERVE:
            raise DiskFullError(self.path, f"{free // 1024} KiB left on the device, less than the "
                                           f"{DISK_RESERVE // 1024} KiB a video leaves for the other "
                                           "outputs")

    def _open(self, w: int, h: int) -> "cv2.VideoWriter | _PyAVWriter":
        self._tmp = temp_path_for(self.path)
        if self.backend == "pyav":
            try:
                return _PyAVWriter(self._tmp, self.codec, self.fps, (w, h))
            except Exception as exc:
                self._tmp.unlink(missing_ok=True)
                if is_disk_full(exc):
                    raise output_error(self.path, exc) from None
                raise InputError(f"cannot encode {self.codec} video to {self.path} with PyAV: "
                                 f"{exc}") from None
        if self.codec in PYAV_CODECS:
            log.info("%s: %s is encoded by OpenCV, which gives the encoder no speed setting (about "
                     "ten times slower than with PyAV: pip install 'motiontrack[video]')",
                     self.path.name, self.codec)
        fourcc = cv2.VideoWriter_fourcc(*CODECS[self.codec][0])
        writer = cv2.VideoWriter(str(self._tmp), fourcc, self.fps, (w, h))
        if not writer.isOpened():
            self._tmp.unlink(missing_ok=True)
            raise InputError(f"this OpenCV build cannot encode {self.codec} video to {self.path}; "
                             f"this installation can encode: {', '.join(encodable_codecs())}")
        return writer

    def close(self) -> None:
        """Encode every frame written, finish the file and move it to its final name (nothing is
        written for 0 frames); when that fails, the temporary file is removed."""
        if self._writer is None:
            return
        try:
            if self._queue is not None:
                self._queue.close()   # every queued frame encoded, or the encoder's error
                self._queue = None
            writer, self._writer = self._writer, None
            writer.release()
            if self._tmp is not None:
                commit_temp(self._tmp, self.path)
                self._tmp = None
        except DiskFullError:
            self.discard()
            raise
        except OSError as exc:
            self.discard()
            raise output_error(self.path, exc) from None
        except BaseException:
            self.discard()
            raise

    def discard(self) -> None:
        """Stop writing (frames still queued are dropped) and remove the temporary file (nothing
        appears under :attr:`path`). Never fails: it is called while another error is on its
        way."""
        queue, self._queue = self._queue, None
        writer, self._writer = self._writer, None
        try:
            if queue is not None:
                queue.abort()
            if writer is not None:
                writer.release()
        except Exception as exc:  # e.g. the encoder cannot flush onto a full device
            log.debug("discarding %s: %s", self.path, exc)
        finally:
            if self._tmp is not None:
                self._tmp.unlink(missing_ok=True)
                self._tmp = None

    def __enter__(self) -> "VideoSink":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
