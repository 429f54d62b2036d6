"""Playing a recorded source at its own frame rate: :class:`Pacer` and :class:`PacedSource`.

A file decodes far faster (or slower) than it was recorded; someone watching it (``serve``'s
cameras, ``track --show``) sees it at the rate it states. Frame ``n`` of a play is due ``n /
fps`` seconds after the first; a reader that falls more than :data:`BEHIND_S` behind (a slow
machine) carries on from where it is instead of racing to catch up. Live sources come at their
own pace and are never paced.
"""

from __future__ import annotations

import time
from typing import Any, Callable, Iterator

from ..types import Annotations, Frame
from .sources import Source

__all__ = ["Pacer", "PacedSource", "BEHIND_S"]

#: seconds behind the schedule after which the schedule moves instead
BEHIND_S = 1.0
#: longest wait (s) before a paced source looks at its stop request again
_SLICE = 0.05


def _sleep(seconds: float) -> bool:
    time.sleep(seconds)
    return False


class Pacer:
    """Waits until each frame of a play is due.

    Parameters
    ----------
    clock : monotonic seconds (tests give a clock of their own).
    sleep : ``sleep(seconds)`` waits and returns True when the wait was cut short by a stop
        request (``threading.Event.wait`` does exactly that); default: :func:`time.sleep`.
    """

    def __init__(self, clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], Any] | None = None) -> None:
        self.clock = clock
        self.sleep = sleep or _sleep
        self._t0: float | None = None

    def wait(self, n: int, fps: float) -> bool:
        """Wait until frame ``n`` (0-based, counted from the first frame paced) is due at
        ``fps``; True when a stop request ended the wait."""
        now = self.clock()
        if self._t0 is None:
            self._t0 = now
        delay = self._t0 + n / fps - now
        if delay < -BEHIND_S:   # fell behind: do not race to catch up
            self._t0 -= delay
            return False
        return delay > 0 and bool(self.sleep(delay))


class PacedSource(Source):
    """``source`` played at its frame rate (25 fps when it states none) by a :class:`Pacer`;
    a live source is passed through as it comes. Everything else is the source's own."""

    def __init__(self, source: Source, pacer: Pacer | None = None) -> None:
        super().__init__(source.start, source.max_frames)
        self.source = source
        self.info = source.info
        self.pacer = pacer or Pacer(sleep=self._sleep)

    def _sleep(self, seconds: float) -> bool:
        """Wait ``seconds`` in slices, True as soon as a stop is requested."""
        end = time.monotonic() + seconds
        while not self.stop_requested():
            left = end - time.monotonic()
            if left <= 0:
                return False
            time.sleep(min(left, _SLICE))
        return True

    def _paced(self, items: Iterator[Any]) -> Iterator[Any]:
        self.source.stop_requested = self.stop_requested
        try:
            if self.info.live:
                yield from items
                return
            fps = float(self.info.fps or 25.0)
            for n, item in enumerate(items):
                if self.pacer.wait(n, fps) or self.stop_requested():
                    return
                yield item
        finally:
            close = getattr(items, "close", None)
            if close is not None:   # stops a reading thread now
                close()

    def __iter__(self) -> Iterator[Frame]:
        return self._paced(iter(self.source))

    def prepared(self, prepare: Callable[[Frame], Any]) -> Iterator[tuple[Frame, Any]]:
        return self._paced(self.source.prepared(prepare))

    def ground_truth(self) -> Annotations | None:
        return self.source.ground_truth()

    def expected_frames(self) -> int | None:
        return self.source.expected_frames()

    @property
    def truncated(self) -> bool:   # type: ignore[override]
        return self.source.truncated

    @truncated.setter
    def truncated(self, value: bool) -> None:
        pass   # the wrapped source's own

    @property
    def reconnects(self) -> int:
        return int(getattr(self.source, "reconnects", 0))

    def close(self) -> None:
        self.source.close()
