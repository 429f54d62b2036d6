"""``serve --keep-days/--keep-gb``: the oldest segments go, never one being written, and the
event store forgets their events."""

from __future__ import annotations

import logging
import os

import pytest

from motiontrack.errors import ConfigError
from motiontrack.io.event_store import EventQuery, EventStore
from motiontrack.serve.retention import Retention, apply_retention, segments

DAY = 86400.0
NOW = 1_800_000_000.0


def _segment(out, name: str, ended: float, size: int) -> None:
    """A segment folder ``CAMERA/SEGMENT`` whose files end at ``ended``, ``size`` bytes."""
    seg = out / name
    (seg / "evidence").mkdir(parents=True)
    for f, n in ((seg / "tracks.txt", size // 2), (seg / "evidence" / "1.avi", size - size // 2)):
        f.write_bytes(b"x" * n)
        os.utime(f, (ended, ended))
    os.utime(seg, (ended, ended))


@pytest.fixture
def out(tmp_path):
    """gate: 3 segments ended 9, 5 and 1 days ago and one being written; yard: 2 segments."""
    for name, age, size in (("gate/a", 9, 400), ("gate/b", 5, 300), ("gate/c", 1, 200),
                            ("gate/d", 0, 100), ("yard/a", 8, 1000), ("yard/b", 0.1, 50)):
        _segment(tmp_path, name, NOW - age * DAY, size)
    with EventStore(tmp_path) as store:
        for seg in ("gate/a", "gate/b", "gate/c", "gate/d", "yard/a", "yard/b"):
            store.add({"type": "loiter", "frame": 1}, seg.split("/")[0], NOW, seg)
    return tmp_path


def _left(out):
    return [s.name for s in segments(out)]


def test_segments_older_than_the_days_kept_go_and_their_events_with_them(out, caplog):
    caplog.set_level(logging.INFO)
    removed = apply_retention(out, Retention(keep_days=6), in_use=["gate/d"], now=NOW)
    assert [s.name for s in removed] == ["gate/a", "yard/a"]        # oldest first
    assert _left(out) == ["gate/b", "gate/c", "yard/b", "gate/d"]
    with EventStore(out, readonly=True) as store:
        assert sorted(e.segment for e in store) == ["gate/b", "gate/c", "gate/d", "yard/b"]
    assert "retention: removed gate/a (0.0 MB" in caplog.text


def test_a_segments_events_leave_the_store_before_its_files_go(out, monkeypatch):
    import shutil

    import motiontrack.serve.retention as retention

    seen, remove = [], shutil.rmtree

    def rmtree(path, *a, **kw):   # what a reader of the store sees as the files go
        with EventStore(out, readonly=True) as store:
            seen.append((path.relative_to(out).as_posix(),
                         sorted(e.segment for e in store if (out / e.segment) == path)))
        remove(path, *a, **kw)

    monkeypatch.setattr(retention.shutil, "rmtree", rmtree)
    apply_retention(out, Retention(keep_days=6), in_use=["gate/d"], now=NOW)
    assert seen == [("gate/a", []), ("yard/a", [])]


def test_the_oldest_go_until_all_fit_in_the_size_kept(out):
    # 2,050 bytes in all; keep 1,000: gate/a (400), yard/a (1000) go → 650 left
    removed = apply_retention(out, Retention(keep_gb=1000 / 1e9), in_use=[], now=NOW)
    assert [s.name for s in removed] == ["gate/a", "yard/a"]
    # keep 100: everything goes but what the cameras write and each camera's newest
    apply_retention(out, Retention(keep_gb=100 / 1e9), in_use=["gate/c"], now=NOW)
    assert _left(out) == ["gate/c", "yard/b", "gate/d"]
    with EventStore(out, readonly=True) as store:
        assert store.count(EventQuery(camera="gate")) == 2


def test_a_segment_being_written_is_never_removed_whatever_its_age(out):
    apply_retention(out, Retention(keep_days=0.01), in_use=["gate/b", "yard/b"], now=NOW)
    assert _left(out) == ["gate/b", "yard/b", "gate/d"]


@pytest.mark.parametrize("kw, flag", [({"keep_days": 0}, "--keep-days"),
                                      ({"keep_gb": -1}, "--keep-gb"),
                                      ({"keep_days": float("nan")}, "--keep-days")])
def test_bounds_must_be_positive(kw, flag):
    with pytest.raises(ConfigError, match=f"{flag} must be a number > 0"):
        Retention(**kw)


def test_the_servers_thread_applies_retention_until_stopped(out):
    import time

    from motiontrack.serve.retention import RetentionThread

    seen = []

    def in_use():
        seen.append(1)
        return ["gate/d"]

    t = RetentionThread(out, Retention(keep_days=6), in_use, every_s=0.02, clock=lambda: NOW)
    t.start()
    kept = ["gate/b", "gate/c", "yard/b", "gate/d"]
    end = time.monotonic() + 10
    while _left(out) != kept and time.monotonic() < end:   # a check removes one at a time
        time.sleep(0.02)
    t.stop()
    assert _left(out) == kept and seen
    assert not t._thread.is_alive()                       # stopped: no check runs after it
    idle = RetentionThread(out, Retention(), in_use)   # nothing to keep: no thread at all
    idle.start()
    assert not idle._thread.is_alive()


def test_files_and_segments_that_go_while_they_are_read_are_left_out(out, monkeypatch):
    """A camera renames its temporary files into place, and a segment may be removed, while
    the check reads the folders: what is gone is left out, the check goes on."""
    from pathlib import Path

    real = Path.rglob

    def racing(self, pattern):
        if self.name == "b":                        # gate/b: a file renamed meanwhile
            yield self / ".tracks.txt.x1.part"
        if self.name == "a" and self.parent.name == "yard":
            raise FileNotFoundError(self)             # yard/a: removed meanwhile
        yield from real(self, pattern)

    monkeypatch.setattr(Path, "rglob", racing)
    found = {s.name: s.bytes for s in segments(out)}
    assert found == {"gate/a": 400, "gate/b": 300, "gate/c": 200, "gate/d": 100, "yard/b": 50}
