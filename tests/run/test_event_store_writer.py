"""The writer of each frame's events into an event store: a store shared with other processes
(serve's cameras and its retention) is never left locked between frames."""

from __future__ import annotations

import sqlite3
from types import SimpleNamespace

import numpy as np

from motiontrack.io.event_store import STORE_NAME, EventStore
from motiontrack.run.event_store_writer import EventStoreWriter
from motiontrack.types import Event, FrameResult, SceneFrame


def _result(n: int, events: int) -> FrameResult:
    scene = SceneFrame(frame=n, events=tuple(
        Event(type="line_cross", frame=n, t=(n - 1) / 5, track=k + 1, x=1.0, y=2.0, line="gate",
              direction="in") for k in range(events)))
    return FrameResult(index=n - 1, timestamp=(n - 1) / 5, frame=np.zeros((8, 8, 3), np.uint8),
                       mask=None, regions=(), tracks=(), scene=scene)


def _ctx():
    return SimpleNamespace(info=SimpleNamespace(live=True), processor=None, fps=5.0)


def _lock_at_once(path) -> bool:
    """Whether another process could take the store's write lock without waiting."""
    db = sqlite3.connect(path, timeout=0)
    try:
        db.execute("BEGIN IMMEDIATE")
        db.rollback()
        return True
    except sqlite3.OperationalError:   # "database is locked"
        return False
    finally:
        db.close()


def test_a_shared_store_is_committed_with_each_frames_events(tmp_path):
    path = tmp_path / STORE_NAME
    writer = EventStoreWriter(path, "gate", "gate/seg-1", owned=False, clock=lambda: 1e9)
    writer.start(_ctx())
    for n in range(1, 4):
        writer.write(_result(n, events=2))
        assert _lock_at_once(path)                     # nothing held from frame to frame
        with EventStore(tmp_path, readonly=True) as reader:
            assert reader.count() == 2 * n             # and every event already readable
    writer.close(keep=True)
