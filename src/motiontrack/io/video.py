"""Video sinks: browser-playable WebM (VP8/VP9) by default, other codecs on request.

Files are written under a temporary name and renamed on :meth:`VideoSink.close`, so an interrupted
run leaves either a complete, playable video of everything processed so far or nothing. A video
never fills its device: it stops with :class:`~motiontrack.io.atomic.DiskFullError` when less
than :data:`DISK_RESERVE` is left (``cv2.VideoWriter`` would go on silently writing a broken
file), so the small outputs of the run still fit.

WebM is encoded with PyAV (the ``video`` extra, ``pip install motiontrack[video]``) when it is
installed: it lets libvpx run in its real-time mode (``deadline=realtime``, ``cpu-used=8``,
constant quality ``crf``), about 4–8 ms per 768x576 frame against 32 ms (VP8) and 175 ms (VP9)
through ``cv2.VideoWriter``, which gives no access to the encoder's speed settings. Without PyAV,
and for the other codecs, OpenCV writes the file.
"""

from __future__ import annotations

import logging
import os
from fractions import Fraction
from pathlib import Path

import cv2
import numpy as np

from ..errors import InputError
from .atomic import (DiskFullError, commit_temp, free_bytes, is_disk_full, output_error,
                     temp_path_for)

log = logging.getLogger(__name__)

#: codec name → (fourcc, file extension)
CODECS = {
    "vp80": ("VP80", ".webm"),
    "vp90": ("VP90", ".webm"),
    "mp4v": ("mp4v", ".mp4"),
    "avc1": ("avc1", ".mp4"),
    "mjpg": ("MJPG", ".avi"),
    "xvid": ("XVID", ".avi"),
}


#: codec name → libvpx encoder used through PyAV
PYAV_ENCODERS = {"vp80": "libvpx", "vp90": "libvpx-vp9"}
#: libvpx settings: real-time speed, constant quality (crf, lower = better; the bit rate is a cap)
PYAV_OPTIONS = {"deadline": "realtime", "cpu-used": "8", "crf": "10"}
PYAV_MAX_BITRATE = 20_000_000

#: bytes a video leaves free on its device for the other outputs of the run (tracks, summary)
DISK_RESERVE = 1 << 20


def extension_for(codec: str) -> str:
    return CODECS[codec][1]


def pyav_available() -> bool:
    try:
        import av  # noqa: F401
    except ImportError:
        return False
    return True


class _PyAVWriter:
    """libvpx through PyAV; the ``write``/``release`` subset of ``cv2.VideoWriter`` used here.

    Frames of odd width or height are padded by one replicated pixel (4:2:0 needs even sizes).
    """

    def __init__(self, path: Path, codec: str, fps: float, size: tuple[int, int]) -> None:
        import av

        w, h = size
        self._pad = (h % 2, w % 2)
        self._out = av.open(str(path), "w", format="webm")
        try:
            self._stream = self._out.add_stream(PYAV_ENCODERS[codec],
                                                rate=Fraction(fps).limit_denominator(1001))
            self._stream.width, self._stream.height = w + self._pad[1], h + self._pad[0]
            self._stream.pix_fmt = "yuv420p"
            self._stream.bit_rate = PYAV_MAX_BITRATE
            self._stream.options = dict(PYAV_OPTIONS, **({"row-mt": "1"} if codec == "vp90" else {}))
            self._stream.thread_count = max(1, min(8, os.cpu_count() or 1))
        except BaseException:
            self._out.close()
            raise

    def write(self, image: np.ndarray) -> None:
        import av

        if any(self._pad):
            image = cv2.copyMakeBorder(image, 0, self._pad[0], 0, self._pad[1], cv2.BORDER_REPLICATE)
        frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(image), format="bgr24")
        for packet in self._stream.encode(frame):
            self._out.mux(packet)

    def release(self) -> None:
        try:
            for packet in self._stream.encode():  # flush the encoder
                self._out.mux(packet)
        finally:
            self._out.close()


class VideoSink:
    """Write frames to ``path`` with ``codec``; opened lazily at the first frame (size from it).

    ``backend``: ``"auto"`` (PyAV for WebM when installed, else OpenCV), ``"pyav"`` or
    ``"opencv"``; :attr:`backend` tells which one is used.
    """

    def __init__(self, path: str | Path, fps: float, codec: str = "vp80", backend: str = "auto") -> None:
        if codec not in CODECS:
            raise InputError(f"unknown codec {codec!r}; valid: {', '.join(CODECS)}")
        if backend not in ("auto", "pyav", "opencv"):
            raise InputError(f"unknown video backend {backend!r}; valid: auto, pyav, opencv")
        if backend == "pyav" and (codec not in PYAV_ENCODERS or not pyav_available()):
            raise InputError(f"the pyav backend needs PyAV (pip install av) and a WebM codec "
                             f"({', '.join(PYAV_ENCODERS)}), got {codec!r}")
        if backend == "auto":
            backend = "pyav" if codec in PYAV_ENCODERS and pyav_available() else "opencv"
        self.backend = backend
        self.path = Path(path)
        self.fps = float(fps) if fps and fps > 0 else 25.0
        self.codec = codec
        self._writer: cv2.VideoWriter | _PyAVWriter | None = None
        self._tmp: Path | None = None
        self.frames = 0

    def write(self, image: np.ndarray) -> None:
        if image.ndim == 2:
            image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
        if self._writer is None:
            self._writer = self._open(image.shape[1], image.shape[0])
        self._check_space()
        try:
            self._writer.write(image)
        except OSError as exc:  # PyAV reports a full device; cv2.VideoWriter reports nothing
            raise output_error(self.path, exc) from None
        self.frames += 1

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
        fourcc = cv2.VideoWriter_fourcc(*CODECS[self.codec][0])
        writer = cv2.VideoWriter(str(self._tmp), fourcc, self.fps, (w, h))
        if not writer.isOpened():
            self._tmp.unlink(missing_ok=True)
            raise InputError(f"this OpenCV build cannot encode {self.codec} video to {self.path}; "
                             f"try --set output.codec=mjpg")
        return writer

    def close(self) -> None:
        """Finish the file and move it to its final name (nothing is written for 0 frames);
        when that fails, the temporary file is removed."""
        if self._writer is not None:
            writer, self._writer = self._writer, None
            try:
                writer.release()
                if self._tmp is not None:
                    commit_temp(self._tmp, self.path)
                    self._tmp = None
            except OSError as exc:
                self.discard()
                raise output_error(self.path, exc) from None
            except BaseException:
                self.discard()
                raise

    def discard(self) -> None:
        """Stop writing and remove the temporary file (nothing appears under :attr:`path`).
        Never fails: it is called while another error is on its way."""
        writer, self._writer = self._writer, None
        try:
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
