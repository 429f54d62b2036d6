"""The SQLite event store: what is stored, how it is searched, committed and migrated."""

from __future__ import annotations

import sqlite3
import subprocess
import sys
import textwrap

import pytest

from motiontrack.errors import InputError
from motiontrack.io.event_store import (SCHEMA_VERSION, EventQuery, EventStore, STORE_NAME,
                                        store_path)

T0 = 1_764_700_000.0   # an epoch second (2025-12-02 18:26:40 UTC)


def _cross(frame, line="gate", direction="in", track=1):
    return {"type": "line_cross", "frame": frame, "t": (frame - 1) / 25, "track": track,
            "x": 10.0, "y": 20.0, "line": line, "direction": direction}


def _loiter(frame, zone="bench", dwell=30.0, track=2):
    return {"type": "loiter", "frame": frame, "t": (frame - 1) / 25, "track": track,
            "x": 1.0, "y": 2.0, "zone": zone, "dwell_s": dwell}


@pytest.fixture
def store(tmp_path):
    clock = [0.0]
    s = EventStore(tmp_path, clock=lambda: clock[0])
    s.clock = clock
    yield s
    s.close()


def test_events_are_found_by_camera_type_rule_and_time(store):
    ids = [store.add(_cross(10), "door", T0 + 10),
           store.add(_loiter(50), "door", T0 + 50, segment="20251202-182640"),
           store.add(_cross(70, line="exit", direction="out"), "yard", T0 + 70),
           store.add({**_loiter(90, zone="gate"), "class": "person"}, "yard", T0 + 90)]
    assert ids == [1, 2, 3, 4]
    found = lambda **q: [e.id for e in store.search(EventQuery(**q))]   # noqa: E731
    assert found() == [4, 3, 2, 1]                      # newest first
    assert found(oldest_first=True) == [1, 2, 3, 4]
    assert found(camera="door") == [2, 1]
    assert found(type="loiter") == [4, 2]
    assert found(rule="gate") == [4, 1]                 # a line and a zone of that name
    assert found(klass="person") == [4]
    assert found(since=T0 + 50, until=T0 + 90) == [3, 2]   # since <= end < until
    assert found(limit=2, offset=1) == [3, 2]
    assert store.count(EventQuery(camera="yard")) == 2
    loiter = store.search(EventQuery(camera="door", type="loiter"))[0]
    # a loiter reported after 30 s in the zone started 30 s before it was reported
    assert (loiter.start, loiter.end, loiter.rule, loiter.segment) == (
        T0 + 20, T0 + 50, "bench", "20251202-182640")
    assert loiter.event == _loiter(50) and loiter.as_dict()["class"] is None


def test_events_are_committed_within_a_second_of_being_added(store, tmp_path):
    store.add(_cross(1), "door", T0)
    reader = EventStore(tmp_path, readonly=True)
    assert reader.count() == 0                          # not committed yet
    store.clock[0] = 0.99
    store.add(_cross(2), "door", T0 + 1)
    assert reader.count() == 0
    store.clock[0] = 1.0
    store.tick()
    assert reader.count() == 2
    reader.close()


def test_a_killed_writer_loses_at_most_its_last_second_and_leaves_the_file_whole(tmp_path):
    script = textwrap.dedent(f"""
        import os
        from motiontrack.io.event_store import EventStore
        clock = [0.0]
        s = EventStore({str(tmp_path)!r}, clock=lambda: clock[0])
        for k in range(5):
            s.add({{"type": "line_cross", "frame": k + 1, "line": "gate"}}, "door", k)
        clock[0] = 1.0
        s.tick()                      # the first five are a second old: committed
        s.add({{"type": "line_cross", "frame": 6, "line": "gate"}}, "door", 6)
        os._exit(9)                   # killed before the sixth is committed
    """)
    assert subprocess.run([sys.executable, "-c", script]).returncode == 9
    with EventStore(tmp_path, readonly=True) as s:
        assert [e.frame for e in s] == [1, 2, 3, 4, 5]
    with sqlite3.connect(tmp_path / STORE_NAME) as db:
        assert db.execute("PRAGMA integrity_check").fetchone() == ("ok",)
        assert db.execute("PRAGMA journal_mode").fetchone() == ("wal",)


def test_hourly_and_daily_totals_per_camera_and_type(store):
    for k in range(3):
        store.add(_cross(k + 1), "door", 7200.0 + 60 * k)      # 02:00-02:02 UTC
    store.add(_loiter(9), "door", 3 * 3600.0 + 5)               # 03:00
    store.add(_cross(9), "yard", 86400.0 + 1)                    # the next day
    assert store.totals(3600) == [("door", 7200.0, "line_cross", 3),
                                  ("door", 10800.0, "loiter", 1),
                                  ("yard", 86400.0, "line_cross", 1)]
    # days from local midnight, two hours east of UTC: 02:00 UTC is 04:00 on the first day
    assert store.totals(86400, utc_offset_s=7200) == [("door", -7200.0, "line_cross", 3),
                                                      ("door", -7200.0, "loiter", 1),
                                                      ("yard", 79200.0, "line_cross", 1)]
    assert store.totals(86400, EventQuery(type="loiter")) == [("door", 0.0, "loiter", 1)]


def test_media_paths_are_recorded_once_written(store):
    i = store.add(_cross(1), "door", T0)
    store.set_media(i, snapshot="door/1.jpg")
    store.set_media(i, clip="door/1.mp4")
    (e,) = store.search()
    assert (e.snapshot, e.clip) == ("door/1.jpg", "door/1.mp4")


def test_an_event_added_without_commit_is_first_seen_with_its_snapshot(store, tmp_path):
    store.commit_every_s = 0.0                          # every tick commits
    reader = EventStore(tmp_path, readonly=True)
    i = store.add(_cross(1), "door", T0, commit=False)
    assert reader.count() == 0                          # its snapshot is not written yet
    store.set_media(i, snapshot=f"evidence/{i}.jpg")
    (e,) = reader.search()
    assert e.snapshot == f"evidence/{i}.jpg"
    store.add(_cross(2), "door", T0 + 1)                # the default commits at once here
    assert reader.count() == 2
    reader.close()


def test_an_older_file_is_migrated_and_a_newer_or_foreign_one_refused(tmp_path):
    db = tmp_path / "old.db"
    sqlite3.connect(db).close()                          # version 0: an empty database
    with EventStore(db) as s:
        s.add(_cross(1), "door", T0)
    with sqlite3.connect(db) as c:
        assert c.execute("PRAGMA user_version").fetchone() == (SCHEMA_VERSION,)
        c.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
    with pytest.raises(InputError, match=r"newer than this motiontrack reads"):
        EventStore(db, readonly=True)
    junk = tmp_path / "junk.db"
    junk.write_bytes(b"not a database" * 100)
    with pytest.raises(InputError, match=r"junk.db: not an event store"):
        EventStore(junk)
    with pytest.raises(InputError, match=r"no event store at .*missing.db"):
        EventStore(tmp_path / "missing.db", readonly=True)
    assert store_path(tmp_path) == tmp_path / STORE_NAME and store_path(db) == db


def test_a_new_store_appears_with_its_tables(tmp_path, monkeypatch):
    """A reader polling for a run's store never finds a file without its tables."""
    seen = []
    real_link = __import__("os").link

    def link(src, dst):
        with sqlite3.connect(src) as db:   # what the file holds when it takes its name
            seen.append(db.execute("PRAGMA user_version").fetchone()[0])
        return real_link(src, dst)

    monkeypatch.setattr("motiontrack.io.event_store.os.link", link)
    with EventStore(tmp_path) as s:
        s.add(_cross(1), "door", T0)
    assert seen == [SCHEMA_VERSION]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["events.db"]   # no temporary file
    with EventStore(tmp_path) as again:          # an existing store is opened, not replaced
        assert again.count() == 1


def test_a_store_of_the_first_version_gains_the_clip_offset_and_keeps_its_events(tmp_path):
    from motiontrack.io.event_store import MIGRATIONS

    db = tmp_path / "events.db"
    with sqlite3.connect(db) as c:   # what the first version made
        for statement in MIGRATIONS[0]:
            c.execute(statement)
        c.execute("INSERT INTO events (camera, type, start, \"end\", data) "
                  "VALUES ('door', 'loiter', 1.0, 2.0, '{\"type\": \"loiter\"}')")
        c.execute("PRAGMA user_version = 1")
    with pytest.raises(InputError, match="version 1: open it for writing once"):
        EventStore(db, readonly=True)
    with EventStore(db) as s:
        s.set_media(1, clip="evidence/1.avi", clip_offset=4.5)
    with EventStore(db, readonly=True) as s:
        (e,) = list(s)
    assert (e.camera, e.clip, e.clip_offset) == ("door", "evidence/1.avi", 4.5)
