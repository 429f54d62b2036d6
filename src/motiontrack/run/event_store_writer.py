"""The writer that keeps each frame's scene-analytics events in an event store (``events.db``,
:mod:`motiontrack.io.event_store`) as they happen.

An event's time in the store is the frame's wall-clock time for a live source, and for a
recorded one the time the run started plus the event's ``t`` (a file's own recording time is
not known). With an evidence folder each event also gets its snapshot and clip
(:mod:`.evidence`), recorded in the store as they are written.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

from ..io.atomic import DiskFullError
from ..io.event_store import EventStore, remove_store
from ..types import FrameResult, frame_number
from .evidence import EvidenceKeeper
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
                 owned: bool = True, clock: Callable[[], float] = time.time,
                 evidence: Path | None = None) -> None:
        self.path = Path(path)
        self.paths = {"event_store": self.path} if owned else {}
        self.camera, self.segment = camera, segment
        self._clock = clock
        self._store: EventStore | None = None
        self._live = False
        self._started = 0.0
        self.count = 0
        #: the run folder whose ``evidence/`` gets each event's snapshot and clip (None: none)
        self.evidence_folder = evidence
        self._keeper: EvidenceKeeper | None = None
        self._ctx: JobContext | None = None
        #: events added since the last commit, and (once the device is full) every later one:
        #: written when the run ends, or the run fails with the device full
        self._uncommitted: list[tuple[dict, float]] = []
        self._full = False

    def start(self, ctx: JobContext) -> None:
        fresh = not self.path.exists()
        if self.paths and fresh:   # a killed run's journal of a file now removed
            remove_store(self.path, journal_only=True)
        self._store = EventStore(self.path)
        self._live = bool(ctx.info.live)
        self._started = self._clock()
        self._ctx = ctx
        analytics = getattr(ctx.processor, "analytics", None)
        if self.evidence_folder is not None and analytics is not None:
            self._keeper = EvidenceKeeper(self.evidence_folder, self.path.parent,
                                          analytics.scene.evidence, ctx.fps)
            if self.paths and fresh:   # an older run's evidence would be named as this run's
                self._keeper.clear()

    def write(self, result: FrameResult) -> None:
        if self._store is None:
            return
        scene, keeper, n = result.scene, self._keeper, frame_number(result.index)
        records = [(e.to_json(), result.timestamp if self._live else self._started + e.t)
                   for e in (scene.events if scene is not None else ())]
        picture = None
        pictured = result.frame is not None and result.frame.size > 0   # not a tracks file's
        if keeper is not None and pictured and (
                keeper.needs_picture(n) or any(keeper.snapshots(r) for r, _ in records)):
            picture = self._ctx.annotated(result)   # drawn only for a clip or a snapshot
        clips = keeper.frame(n, picture) if keeper is not None else []
        self.count += len(records)
        self._uncommitted += records
        if self._full:   # the device is full: kept for the end of the run
            return
        try:
            for record, when in records:
                # committed with its snapshot, not before it is written
                event_id = self._store.add(record, self.camera, when, self.segment,
                                           commit=keeper is None)
                if keeper is not None:
                    snapshot = keeper.event(event_id, record, result, picture)
                    if snapshot is not None:
                        self._store.set_media(event_id, snapshot=snapshot)
            self._media(clips)
            if not self.paths and (records or clips):
                # a store shared with other processes (serve's cameras, its retention): the
                # write lock is held for this frame's events only, never from one frame to
                # the next, so no writer waits on another for long
                self._store.commit()
            else:
                self._store.tick()
            if not self._store.pending:
                self._uncommitted.clear()
        except DiskFullError:
            self._store.rollback()   # what was not committed is in _uncommitted
            self._full = True
            raise

    def _media(self, clips: list[tuple[int, str, float]]) -> None:
        for event_id, path, offset in clips:
            self._store.set_media(event_id, clip=path, clip_offset=offset)

    def close(self, keep: bool) -> None:
        if self._store is not None and keep:
            if self._full:   # the run made room (its video went): the events kept meanwhile
                for record, when in self._uncommitted:
                    self._store.add(record, self.camera, when, self.segment)
            elif self._keeper is not None:
                self._media(self._keeper.close())   # the clips still open end with the run
        self._keeper = None
        if self._store is not None:
            self._store.close(finished=bool(self.paths))   # a run's own store is complete now
            self._store = None
        if not keep and self.paths:
            remove_store(self.path)

    def finish(self, summary: JobSummary) -> None:
        summary.extra["event_store"] = {"path": self.path.name if self.paths else str(self.path),
                                        "events": self.count}
