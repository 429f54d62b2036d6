"""A source of frames without pictures: the frame count, size and rate of a sequence whose
detections are all a run needs (``motiontrack track --detections det.txt`` without a video).

Each frame carries an empty image (``(0, 0) uint8``): the pipeline with external detections
never reads pixels, and the stages that could (the detection tracker's appearance term) take an
empty image as "no picture".
"""

from __future__ import annotations

from typing import Iterator

import numpy as np

from ..errors import ConfigError
from ..types import Frame
from .sources import Source, SourceInfo

__all__ = ["PicturelessSource", "NO_PICTURE"]

#: the image of every frame of a :class:`PicturelessSource`
NO_PICTURE = np.zeros((0, 0), np.uint8)
NO_PICTURE.flags.writeable = False


class PicturelessSource(Source):
    """``frames`` frames of ``width`` x ``height`` at ``fps`` (None: unknown, 25 where a rate is
    needed), named ``name``, with no pictures; ``start`` and ``max_frames`` as every source."""

    def __init__(self, name: str, width: int, height: int, fps: float | None, frames: int,
                 start: int = 0, max_frames: int = 0) -> None:
        super().__init__(start, max_frames)
        if width < 1 or height < 1:
            raise ConfigError(f"{name}: frame size must be at least 1x1, got {width}x{height}")
        if frames < 1:
            raise ConfigError(f"{name}: a sequence needs at least one frame, got {frames}")
        if start >= frames:
            raise ConfigError(f"--start {start} is at or past the end of {name} ({frames} frames)")
        self.info = SourceInfo(name, int(width), int(height), fps, int(frames))

    def __iter__(self) -> Iterator[Frame]:
        end = self.info.frame_count
        if self.max_frames:
            end = min(end, self.start + self.max_frames)
        period = 1.0 / (self.info.fps or 25.0)
        for i in range(self.start, end):
            if self.stop_requested():
                return
            yield Frame(i, NO_PICTURE, i * period, self.seek_mark(i))
