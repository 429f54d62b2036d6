"""The mean speed of a track: the measure of ``summary.json``'s track speeds and of the track
classes' pace.

A track's **speed at a frame** is the straight distance from its oldest position within the last
``window_s`` seconds to its position in that frame, over their time apart, measured once that
span is at least half a window (:class:`WindowSpeed`). Over a second, a walker's box jitter of a
few pixels moves the two ends a little while the walk moves them metres, so the jitter that a
frame-to-frame path length sums up (on PETS 2009 S2L1 about +0.5 m/s) mostly cancels.

A track's **mean speed** is the mean of its speeds at every frame where one is measured
(:func:`mean_speed`). Positions are in any unit (pixels, metres): speeds come out in that unit
per second. Frames are frame numbers; ``fps`` turns them into seconds, so footage stored at a
rate other than it was recorded at gives true speeds only with the true rate (``--fps``).

An alarm needs more than a mean: the scene rule ``[speed]`` measures the same window over the
track's smoothed trajectory, with its uncertainty (:mod:`motiontrack.analytics.smoothing`),
so one jittery second raises no alarm.

A module of the lowest layer: ``calibrate.measure`` and ``classify`` use it.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Iterable

__all__ = ["SPEED_WINDOW_S", "WindowSpeed", "mean_speed"]

#: the window of a speed when none is given (also the default of the scene's ``speed.window_s``)
SPEED_WINDOW_S = 1.0


class WindowSpeed:
    """One track's speed over a trailing window of ``window_s`` seconds at ``fps`` frames per
    second, one position at a time (:meth:`add`)."""

    __slots__ = ("samples", "window_frames", "fps")

    def __init__(self, window_s: float = SPEED_WINDOW_S, fps: float = 25.0) -> None:
        if not (window_s > 0 and math.isfinite(window_s)):
            raise ValueError(f"window_s must be > 0, got {window_s}")
        if not (fps > 0 and math.isfinite(fps)):
            raise ValueError(f"fps must be > 0, got {fps}")
        self.samples: deque[tuple[int, float, float]] = deque()
        self.window_frames = window_s * fps
        self.fps = fps

    def add(self, frame: int, x: float, y: float) -> float | None:
        """Add the position at ``frame`` (frames increasing); the speed (units per second) over
        the window ending there, or ``None`` while the window spans less than half its length."""
        first = self.oldest((frame, x, y))
        if first is None:
            return None
        f0, x0, y0 = first
        return math.hypot(x - x0, y - y0) * self.fps / (frame - f0)

    def oldest(self, sample: tuple) -> tuple | None:
        """Add ``sample`` (its frame first; frames increasing) and drop those older than the
        window; the oldest sample left, or None while the window spans less than half its
        length (or nothing)."""
        frame = sample[0]
        self.samples.append(sample)
        while self.samples and frame - self.samples[0][0] > self.window_frames + 1e-9:
            self.samples.popleft()
        first = self.samples[0]
        if frame - first[0] < self.window_frames / 2.0 or frame == first[0]:
            return None
        return first


def mean_speed(frames: Iterable[int], xy: Iterable[tuple[float, float]], fps: float,
               window_s: float = SPEED_WINDOW_S) -> float | None:
    """Mean of a track's speeds at its frames (:class:`WindowSpeed`), in units per second.

    Parameters
    ----------
    frames : frame numbers of the track's positions, increasing.
    xy : the positions, ``(x, y)`` each (non-finite ones are skipped).
    fps : frames per second (> 0).
    window_s : the window of each speed, seconds (> 0).

    Returns
    -------
    float, or None when no window spans half its length (a track shorter than half a window).
    """
    w = WindowSpeed(window_s, fps)
    speeds = []
    for f, (x, y) in zip(frames, xy):
        if math.isfinite(x) and math.isfinite(y):
            v = w.add(int(f), float(x), float(y))
            if v is not None:
                speeds.append(v)
    return math.fsum(speeds) / len(speeds) if speeds else None
