"""The event store of a whole batch: ``RESULTS/events.db``, every finished video's events.

Each video run with a scene keeps its events in its own ``events.db``
(:class:`~motiontrack.run.event_store_writer.EventStoreWriter`); at the end of the batch they
are gathered, with the video's name as their ``camera`` and ``segment``, into one store beside
the index, so ``motiontrack events RESULTS --type loiter`` searches every video at once. Only
finished videos (``done``, ``truncated``) are gathered; the file is written under a temporary
name and renamed into place, and removed when no finished video has events.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping, Sequence

from ..io.event_store import STORE_NAME, EventStore, remove_store
from ..run.folder import RunFolder
from .combined import FINISHED

__all__ = ["write_event_store"]


def write_event_store(results: Path, rows: Sequence[Mapping[str, Any]]) -> int | None:
    """Write ``RESULTS/events.db`` from the finished videos' stores; the number of events, or
    None when no finished video has a store (and an earlier batch's file is removed)."""
    results = Path(results)
    stores = [(str(r["name"]), RunFolder(results / str(r["name"])).event_store) for r in rows
              if r.get("status") in FINISHED]
    stores = [(name, db) for name, db in stores if db.is_file()]
    final = results / STORE_NAME
    if not stores:
        remove_store(final)
        return None
    tmp = results / f".{STORE_NAME}.{os.getpid()}.tmp"
    remove_store(tmp)
    n = 0
    try:
        out = EventStore(tmp)
        try:
            for name, db in stores:
                with EventStore(db, readonly=True) as video:
                    for e in video:
                        # media paths are relative to the store's folder: the video's, here
                        out.add(e.event, name, e.end, name, _under(name, e.snapshot),
                                _under(name, e.clip), e.clip_offset)
                        n += 1
        finally:
            out.close(finished=True)   # one self-contained file to rename into place
        os.replace(tmp, final)
    finally:
        remove_store(tmp)
    return n


def _under(folder: str, path: str | None) -> str | None:
    return None if path is None else f"{folder}/{path}"
