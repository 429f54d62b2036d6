"""Event clips: JPEG frames already encoded, written as a Motion-JPEG AVI without re-encoding.

The frames of a clip come from a ring buffer of JPEG-encoded pictures (the pre-roll costs no
encoding when the event comes). With PyAV (the ``video`` extra) they are muxed into the AVI as
they are; without it OpenCV decodes and writes them again. The file is written a frame at a time
under a temporary name and renamed into place when it ends: a clip is complete or absent, and
one being gathered is on disk rather than in memory.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any, Sequence

import cv2
import numpy as np

from .atomic import temp_path_for

__all__ = ["write_mjpeg_clip", "ClipWriter", "read_clip", "clip_jpegs"]


def write_mjpeg_clip(path: str | Path, jpegs: Sequence[bytes], fps: float) -> Path:
    """Write ``jpegs`` (JPEG pictures of one size) as an MJPEG AVI at ``fps``."""
    if not jpegs:
        raise ValueError("a clip needs at least one frame")
    writer = ClipWriter(path, fps)
    try:
        for jpeg in jpegs:
            writer.add(jpeg)
    except BaseException:
        writer.abort()
        raise
    return writer.close()


class ClipWriter:
    """An MJPEG AVI written a frame at a time under a temporary name beside ``path``, so a clip
    being gathered holds no frames in memory; :meth:`close` renames it into place (complete or
    absent), :meth:`abort` removes it. The file is opened with the first frame, whose size
    every frame must have."""

    def __init__(self, path: str | Path, fps: float) -> None:
        self.path = Path(path)
        self.fps = float(fps)
        self.frames = 0
        self._tmp: Path | None = None
        self._out: Any = None

    def add(self, jpeg: bytes) -> None:
        if self._out is None:
            self._open(jpeg)
        self._out.add(jpeg, self.frames)
        self.frames += 1

    def _open(self, jpeg: bytes) -> None:
        first = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
        if first is None:
            raise ValueError("a clip's frame is not a JPEG picture")
        self._tmp = temp_path_for(self.path)
        size = (first.shape[1], first.shape[0])
        try:
            import av   # noqa: F401
        except ImportError:
            self._out = _Rewriter(self._tmp, self.fps, size)
        else:
            self._out = _Remuxer(self._tmp, self.fps, size)

    def close(self) -> Path:
        """Finish the file and give it its name; the path."""
        if self._out is None:
            raise ValueError("a clip needs at least one frame")
        try:
            self._out.close()
            self._tmp.replace(self.path)
        finally:
            self._out = None
            self._tmp.unlink(missing_ok=True)
        return self.path

    def abort(self) -> None:
        """Drop the clip: nothing is left of it."""
        out, self._out = self._out, None
        try:
            if out is not None:
                out.close()
        except Exception:   # noqa: BLE001 - the file goes anyway (a full disk, say)
            pass
        finally:
            if self._tmp is not None:
                self._tmp.unlink(missing_ok=True)


class _Remuxer:
    """JPEGs muxed as they are (PyAV)."""

    def __init__(self, path: Path, fps: float, size: tuple[int, int]) -> None:
        import av

        self.rate = Fraction(fps).limit_denominator(1000)
        self.box = av.open(str(path), "w", format="avi")
        self.stream = self.box.add_stream("mjpeg", rate=self.rate)
        self.stream.width, self.stream.height = size
        self.stream.pix_fmt = "yuvj420p"
        self.stream.time_base = 1 / self.rate

    def add(self, jpeg: bytes, index: int) -> None:
        import av

        packet = av.Packet(jpeg)
        packet.stream = self.stream
        packet.pts = packet.dts = index
        packet.time_base = 1 / self.rate
        self.box.mux(packet)

    def close(self) -> None:
        self.box.close()


class _Rewriter:
    """JPEGs decoded and written again (OpenCV), without PyAV."""

    def __init__(self, path: Path, fps: float, size: tuple[int, int]) -> None:
        self.writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, size)

    def add(self, jpeg: bytes, index: int) -> None:
        self.writer.write(cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR))

    def close(self) -> None:
        self.writer.release()


def read_clip(path: str | Path) -> tuple[list[np.ndarray], float]:
    """A clip's frames and frame rate (for tests and tools)."""
    cap = cv2.VideoCapture(str(path))
    frames = []
    try:
        while True:
            ok, frame = cap.read()
            if not ok:
                break
            frames.append(frame)
        return frames, float(cap.get(cv2.CAP_PROP_FPS))
    finally:
        cap.release()


def clip_jpegs(path: str | Path) -> tuple[list[bytes], float]:
    """A clip's frames as the JPEGs it holds and its frame rate: demuxed as they are with PyAV
    (a Motion-JPEG clip's packets are its pictures), encoded again from OpenCV's decoding
    without it."""
    try:
        import av
    except ImportError:
        frames, fps = read_clip(path)
        return [cv2.imencode(".jpg", f)[1].tobytes() for f in frames], fps
    with av.open(str(path)) as box:
        stream = box.streams.video[0]
        if stream.codec_context.name != "mjpeg":   # not one of ours: decode it
            frames, fps = read_clip(path)
            return [cv2.imencode(".jpg", f)[1].tobytes() for f in frames], fps
        fps = float(stream.average_rate or stream.base_rate or 0.0)
        return [bytes(p) for p in box.demux(stream) if p.size], fps
