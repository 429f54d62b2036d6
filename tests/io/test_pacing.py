"""A recorded source played at its own frame rate (:mod:`motiontrack.io.pacing`), on a clock of
the test's own: frame n is handed over n / fps seconds after the first, a reader that fell
behind carries on from where it is, a stop request ends the play, a live source is not paced."""

from __future__ import annotations

import numpy as np

from motiontrack.io.pacing import PacedSource, Pacer
from motiontrack.io.sources import ArraySource


class Clock:
    """Monotonic time that moves only when slept or told to (``work``)."""

    def __init__(self) -> None:
        self.now = 100.0
        self.slept: list[float] = []

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> bool:
        self.slept.append(round(seconds, 6))
        self.now += seconds
        return False


def _images(n: int) -> list[np.ndarray]:
    return [np.zeros((4, 4, 3), np.uint8)] * n


def test_frames_are_handed_over_at_the_sources_rate():
    clock = Clock()
    src = PacedSource(ArraySource(_images(5), fps=10.0), Pacer(clock, clock.sleep))
    times = []
    for frame in src:
        times.append(round(clock.now - 100.0, 6))
        clock.now += 0.02          # processing a frame takes 20 ms
    # frame k at k / 10 s: each wait is the 100 ms period less the 20 ms of processing
    assert times == [0.0, 0.1, 0.2, 0.3, 0.4]
    assert clock.slept == [0.08] * 4


def test_prepared_frames_are_paced_too():
    clock = Clock()
    src = PacedSource(ArraySource(_images(3), fps=4.0), Pacer(clock, clock.sleep))
    got = [(f.index, small) for f, small in src.prepared(lambda f: f.index * 2)]
    assert got == [(0, 0), (1, 2), (2, 4)] and clock.slept == [0.25, 0.25]


def test_a_reader_behind_by_more_than_a_second_carries_on_without_racing():
    clock = Clock()
    src = PacedSource(ArraySource(_images(4), fps=10.0), Pacer(clock, clock.sleep))
    for frame in src:
        if frame.index == 1:
            clock.now += 2.0       # a two-second stall after frame 1
    # frame 2 is 1.9 s late: the schedule moves, frame 3 is due 0.1 s after frame 2
    assert clock.slept == [0.1, 0.1]


def test_a_stop_request_ends_the_play():
    clock = Clock()
    src = PacedSource(ArraySource(_images(10), fps=10.0), Pacer(clock, clock.sleep))
    seen = []
    src.stop_requested = lambda: len(seen) >= 3
    for frame in src:
        seen.append(frame.index)
    assert seen == [0, 1, 2]


def test_a_live_source_is_not_paced():
    clock = Clock()
    inner = ArraySource(_images(5), fps=10.0)
    inner.info = type(inner.info)(**{**inner.info.__dict__, "live": True})
    src = PacedSource(inner, Pacer(clock, clock.sleep))
    assert len(list(src)) == 5 and clock.slept == []


def test_a_sleep_cut_short_by_a_stop_ends_the_play():
    clock = Clock()
    pacer = Pacer(clock, lambda s: True)   # every wait is ended by a stop request
    src = PacedSource(ArraySource(_images(5), fps=10.0), pacer)
    assert [f.index for f in src] == [0]
