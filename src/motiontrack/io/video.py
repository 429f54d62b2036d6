"""Video sinks: browser-playable WebM (VP8/VP9) by default, other codecs on request.

Files are written under a temporary name and renamed on :meth:`VideoSink.close`, so an interrupted
run leaves either a complete, playable video of everything processed so far or nothing.
"""

from __future__ import annotations

import logging
from pathlib import Path

import cv2
import numpy as np

from ..errors import InputError
from .atomic import commit_temp, temp_path_for

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


def extension_for(codec: str) -> str:
    return CODECS[codec][1]


class VideoSink:
    """Write frames to ``path`` with ``codec``; opened lazily at the first frame (size from it)."""

    def __init__(self, path: str | Path, fps: float, codec: str = "vp80") -> None:
        if codec not in CODECS:
            raise InputError(f"unknown codec {codec!r}; valid: {', '.join(CODECS)}")
        self.path = Path(path)
        self.fps = float(fps) if fps and fps > 0 else 25.0
        self.codec = codec
        self._writer: cv2.VideoWriter | None = None
        self._tmp: Path | None = None
        self.frames = 0

    def write(self, image: np.ndarray) -> None:
        if image.ndim == 2:
            image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
        if self._writer is None:
            h, w = image.shape[:2]
            self._tmp = temp_path_for(self.path)
            fourcc = cv2.VideoWriter_fourcc(*CODECS[self.codec][0])
            self._writer = cv2.VideoWriter(str(self._tmp), fourcc, self.fps, (w, h))
            if not self._writer.isOpened():
                self._tmp.unlink(missing_ok=True)
                raise InputError(f"this OpenCV build cannot encode {self.codec} video to {self.path}; "
                                 f"try --set output.codec=mjpg")
        self._writer.write(image)
        self.frames += 1

    def close(self) -> None:
        """Finish the file and move it to its final name (nothing is written for 0 frames)."""
        if self._writer is not None:
            self._writer.release()
            self._writer = None
            if self._tmp is not None:
                commit_temp(self._tmp, self.path)
                self._tmp = None

    def __enter__(self) -> "VideoSink":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
