"""The writer that keeps each frame's scene-analytics events in an event store (``events.db``,
:mod:`motiontrack.io.event_store`) as they happen.

An event's time in the store is the frame's wall-clock time for a live source, and for a
recorded one the time the run started plus the event's ``t`` (a file's own recording time is
not known).
"""

from __future__ import annotations

import contextlib
import time
from pathlib import Path
from typing import Callable

from ..io.event_store import EventStore
from ..types import FrameResult
from .job import JobContext, JobSummary, Writer

__all__ = ["EventStoreWriter"]


class EventStoreWriter(Writer):
    """The events of every frame into the store ``path`` under ``camera`` (and ``segment``).

    ``owned``: the store is this run's own output (``track``: listed in :attr:`paths`, so an
    existing one is refused without ``--force`` and replaced with it, and removed when the run
    fails); otherwise it is shared with other runs (``serve``'s cameras) and only added to.
    ``clock`` gives wall-clock seconds (:func:`time.time`).
    """

    def __init__(self, path: str | Path, camera: str, segment: str | None = None,
                 owned: bool = True, clock: Callable[[], float] = time.time) -> None:
        self.path = Path(path)
        self.paths = {"event_store": self.path} if owned else {}
        self.camera, self.segment = camera, segment
        self._clock = clock
        self._store: EventStore | None = None
        self._live = False
        self._started = 0.0
        self.count = 0

    def start(self, ctx: JobContext) -> None:
        if self.paths and not self.path.exists():
            for stale in ("-wal", "-shm"):   # a killed run's journal of a file now removed
                with contextlib.suppress(FileNotFoundError):
                    Path(f"{self.path}{stale}").unlink()
        self._store = EventStore(self.path)
        self._live = bool(ctx.info.live)
        self._started = self._clock()

    def write(self, result: FrameResult) -> None:
        scene = result.scene
        if self._store is None or scene is None:
            return
        for e in scene.events:
            when = result.timestamp if self._live else self._started + e.t
            self._store.add(e.to_json(), self.camera, when, self.segment)
            self.count += 1
        self._store.tick()

    def close(self, keep: bool) -> None:
        if self._store is not None:
            self._store.close(finished=bool(self.paths))   # a run's own store is complete now
            self._store = None
        if not keep and self.paths:
            for suffix in ("", "-wal", "-shm"):
                with contextlib.suppress(FileNotFoundError):
                    Path(f"{self.path}{suffix}").unlink()

    def finish(self, summary: JobSummary) -> None:
        summary.extra["event_store"] = {"path": self.path.name if self.paths else str(self.path),
                                        "events": self.count}
