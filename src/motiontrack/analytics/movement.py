"""Per-track movement rules: stationary (stays within a radius) and speeding (over a window),
both on the tracks' smoothed trajectories (:mod:`.smoothing`).

* **Stationary**: a track's *stay* starts at a position; each later position within
  ``radius`` of the mean of the stay's positions extends it, the first one farther away ends it
  and starts a new stay there. ``stationary_start`` is emitted when a stay has lasted
  ``after_s``; from then on the stay holds positions up to ``release`` times the radius from its
  mean (hysteresis: a standing person who shifts their weight stays one stop). A stay ends only
  once the positions have been out of its reach for ``leave_s`` (a passer-by who hides the
  person for a moment, or merges with them into one box, ends nothing), and
  ``stationary_end`` is emitted then, with the time the stay lasted.
* **Speeding**: the speed is the straight distance between the smoothed positions at the two
  ends of the last ``window_s`` seconds over their time apart, measured once that span is at
  least half a window; its uncertainty is that distance's standard deviation (the two
  positions' covariances along the direction of motion) over the same time. ``speeding`` is
  emitted once the speed minus :data:`SIGMAS` standard deviations has exceeded the limit for
  ``min_s``; the track is armed again once its speed falls to :data:`REARM` of the limit, so a
  speed hovering at the limit is one event.
"""

from __future__ import annotations

import math

import numpy as np

from ..speed import WindowSpeed

__all__ = ["Stay", "SpeedWindow", "REARM", "SIGMAS"]

#: fraction of the limit a speeding track must slow down to before it can speed again
REARM = 0.9
#: standard deviations of its speed by which a track must exceed the limit (one-sided 97.7 %)
SIGMAS = 2.0


class Stay:
    """One track's current stay (positions in the rule's unit: pixels or metres)."""

    __slots__ = ("sx", "sy", "n", "first", "last", "stationary", "out_since")

    def __init__(self) -> None:
        self.n = 0
        self.stationary = False
        self.out_since: int | None = None

    def restart(self, p: tuple[float, float], frame: int) -> None:
        self.sx, self.sy, self.n = p[0], p[1], 1
        self.first = self.last = frame
        self.stationary = False
        self.out_since = None

    def step(self, p: tuple[float, float], frame: int, radius: float, after_frames: float,
             release: float = 1.0, leave_frames: float = 0.0) -> tuple[str | None, int]:
        """Add a position. Returns ``("start", 0)`` when the stay has just lasted
        ``after_frames``, ``("end", frames)`` when a stationary stay ended (``frames``: from
        its first to its last frame within reach), else ``(None, 0)``. A position out of the
        radius (once stationary, out of ``release`` times the radius) is not part of the stay;
        once positions have been out for ``leave_frames`` the stay ends and a new one starts
        there (a passer-by who hides the object for a moment ends nothing)."""
        reach = radius * release if self.stationary else radius
        if self.n and math.hypot(p[0] - self.sx / self.n, p[1] - self.sy / self.n) <= reach:
            self.sx += p[0]
            self.sy += p[1]
            self.n += 1
            self.last = frame
            self.out_since = None
            if not self.stationary and frame - self.first >= after_frames - 1e-9:
                self.stationary = True
                return "start", 0
            return None, 0
        if self.n:
            if self.out_since is None:
                self.out_since = frame
            if frame - self.out_since < leave_frames - 1e-9:
                return None, 0
        ended = self.stationary
        lasted = self.last - self.first if self.n else 0
        self.restart(p, frame)
        return ("end", lasted) if ended else (None, 0)


class SpeedWindow(WindowSpeed):
    """One track's speed over a trailing window of ``window_s`` seconds of its smoothed
    positions at ``fps`` frames a second (:meth:`add`, the window of
    :class:`~motiontrack.speed.WindowSpeed`), and its alarm state."""

    __slots__ = ("speeding", "over_since", "updates")

    def __init__(self, window_s: float, fps: float) -> None:
        super().__init__(window_s, fps)
        self.speeding = False
        #: the first frame of the current run of frames over the limit (None: not over it)
        self.over_since: int | None = None
        #: the smoother's measurements when last seen: fewer means it started again
        self.updates = 0

    def add(self, frame: int, p: np.ndarray,  # type: ignore[override]
            cov: np.ndarray) -> tuple[float, float] | None:
        """Add the smoothed position ``p`` (2,) with covariance ``cov`` (2, 2) at ``frame``;
        the speed over the window ending there (units per second) and its standard deviation,
        or None while the window spans less than half its length."""
        first = self.oldest((frame, p, cov))
        if first is None:
            return None
        f0, p0, cov0 = first
        span = frame - f0
        d = p - p0
        dist = math.hypot(d[0], d[1])
        c = cov + cov0
        # the two ends' covariances along the direction of motion (any direction at rest: the
        # largest); their correlation makes this an upper bound
        var = (float(d @ c @ d) / (dist * dist) if dist > 0
               else float(np.linalg.eigvalsh(c)[-1]))
        return dist * self.fps / span, math.sqrt(max(var, 0.0)) * self.fps / span
