"""Event clips: JPEG frames already encoded, written as a Motion-JPEG AVI without re-encoding.

The frames of a clip come from a ring buffer of JPEG-encoded pictures (the pre-roll costs no
encoding when the event comes). With PyAV (the ``video`` extra) they are muxed into the AVI as
they are; without it OpenCV decodes and writes them again. The file is written under a temporary
name and renamed into place: a clip is complete or absent.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Sequence

import cv2
import numpy as np

from .atomic import temp_path_for

__all__ = ["write_mjpeg_clip", "read_clip", "clip_jpegs"]


def write_mjpeg_clip(path: str | Path, jpegs: Sequence[bytes], fps: float) -> Path:
    """Write ``jpegs`` (JPEG pictures of one size) as an MJPEG AVI at ``fps``."""
    path = Path(path)
    if not jpegs:
        raise ValueError("a clip needs at least one frame")
    first = cv2.imdecode(np.frombuffer(jpegs[0], np.uint8), cv2.IMREAD_COLOR)
    h, w = first.shape[:2]
    tmp = temp_path_for(path)
    try:
        try:
            import av   # noqa: F401
        except ImportError:
            _rewrite(tmp, jpegs, fps, (w, h))
        else:
            _remux(tmp, jpegs, fps, (w, h))
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def _remux(path: Path, jpegs: Sequence[bytes], fps: float, size: tuple[int, int]) -> None:
    import av

    rate = Fraction(fps).limit_denominator(1000)
    with av.open(str(path), "w", format="avi") as out:
        stream = out.add_stream("mjpeg", rate=rate)
        stream.width, stream.height = size
        stream.pix_fmt = "yuvj420p"
        stream.time_base = 1 / rate
        for i, jpeg in enumerate(jpegs):
            packet = av.Packet(jpeg)
            packet.stream = stream
            packet.pts = packet.dts = i
            packet.time_base = 1 / rate
            out.mux(packet)


def _rewrite(path: Path, jpegs: Sequence[bytes], fps: float, size: tuple[int, int]) -> None:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, size)
    try:
        for jpeg in jpegs:
            writer.write(cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR))
    finally:
        writer.release()


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
