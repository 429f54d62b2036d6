"""Job writers for tests of the run layer's failure handling."""

from __future__ import annotations

from motiontrack.run.job import Writer


class FailAt(Writer):
    """A writer whose ``write`` raises at one frame (0-based index), like an encoder that gives
    up."""

    def __init__(self, frame: int) -> None:
        self.paths = {}
        self.frame = frame

    def write(self, result) -> None:
        if result.index == self.frame:
            raise RuntimeError("encoder gave up")
