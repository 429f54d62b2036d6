"""Per-track movement rules: stationary (stays within a radius) and speeding (over a window).

* **Stationary**: a track's *stay* starts at a position; each later position within
  ``radius`` of the mean of the stay's positions extends it, the first one farther away ends it
  and starts a new stay there. ``stationary_start`` is emitted when a stay has lasted
  ``after_s``; ``stationary_end`` when that stay ends, with the time it lasted.
* **Speeding**: the speed is :class:`motiontrack.speed.WindowSpeed`: the straight distance
  from the oldest position of the last ``window_s`` seconds to the current one over their time
  apart, measured once that span is at least half a window. ``speeding`` is emitted when it
  exceeds the limit; the track is armed
  again once its speed falls to 90 % of the limit, so a speed hovering at the limit is one event.
"""

from __future__ import annotations

import math

from ..speed import WindowSpeed

__all__ = ["Stay", "SpeedWindow", "REARM"]

#: fraction of the limit a speeding track must slow down to before it can speed again
REARM = 0.9


class Stay:
    """One track's current stay (positions in the rule's unit: pixels or metres)."""

    __slots__ = ("sx", "sy", "n", "first", "last", "stationary")

    def __init__(self) -> None:
        self.n = 0
        self.stationary = False

    def restart(self, p: tuple[float, float], frame: int) -> None:
        self.sx, self.sy, self.n = p[0], p[1], 1
        self.first = self.last = frame
        self.stationary = False

    def step(self, p: tuple[float, float], frame: int, radius: float,
             after_frames: float) -> tuple[str | None, int]:
        """Add a position. Returns ``("start", 0)`` when the stay has just lasted
        ``after_frames``, ``("end", frames)`` when a stationary stay ended (``frames``: from
        its first to its last frame), else ``(None, 0)``; a position out of the radius starts
        a new stay."""
        if self.n and math.hypot(p[0] - self.sx / self.n, p[1] - self.sy / self.n) <= radius:
            self.sx += p[0]
            self.sy += p[1]
            self.n += 1
            self.last = frame
            if not self.stationary and frame - self.first >= after_frames - 1e-9:
                self.stationary = True
                return "start", 0
            return None, 0
        ended = self.stationary
        lasted = self.last - self.first if self.n else 0
        self.restart(p, frame)
        return ("end", lasted) if ended else (None, 0)


class SpeedWindow(WindowSpeed):
    """One track's speed (:class:`~motiontrack.speed.WindowSpeed`, the definition
    ``summary.json``'s track speeds share) and whether it is speeding now."""

    __slots__ = ("speeding",)

    def __init__(self, window_s: float, fps: float) -> None:
        super().__init__(window_s, fps)
        self.speeding = False
