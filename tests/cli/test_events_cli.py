"""``track --scene`` keeps its events in ``events.db``; ``motiontrack events`` searches it."""

from __future__ import annotations

import csv
import io
import json
import time

import pytest

from helpers.cli_errors import user_error
from motiontrack.cli import main
from motiontrack.io.event_store import EventStore, parse_time


@pytest.fixture
def utc(monkeypatch):
    """Local time is UTC while the test runs."""
    monkeypatch.setenv("TZ", "UTC")
    time.tzset()
    yield
    monkeypatch.undo()
    time.tzset()


def test_the_store_of_a_run_holds_the_events_of_its_events_file(scene_runs):
    r = scene_runs("runner", 0)
    with EventStore(r.run_dir, readonly=True) as store:
        rows = list(store)
    assert [e.event for e in rows] == [e.to_json() for e in r.pred] and rows
    assert {e.camera for e in rows} == {"synth-runner"} and {e.segment for e in rows} == {None}
    # a recorded source: the run's start plus the event's time in the video
    started = rows[0].end - rows[0].t
    assert all(abs(e.end - (started + e.t)) < 1e-6 for e in rows)
    assert r.summary["event_store"] == {"path": "events.db", "events": len(rows)}
    # a finished run's store is one file: reading it leaves no journal beside it
    assert sorted(p.name for p in r.run_dir.glob("events.db*")) == ["events.db"]


def test_events_are_listed_filtered_and_exported(scene_runs, capsys, utc):
    r = scene_runs("runner", 0)
    capsys.readouterr()   # what the shared run printed, when this test started it
    crossings = [e.to_json() for e in r.pred if e.type == "line_cross"]
    assert main(["events", str(r.run_dir), "--type", "line_cross", "--json",
                 "--oldest-first"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [json.loads(x)["event"] for x in lines] == crossings
    assert main(["events", str(r.run_dir / "events.db"), "--rule", "gate", "--csv"]) == 0
    table = list(csv.reader(io.StringIO(capsys.readouterr().out)))
    assert table[0] == ["id", "time", "camera", "type", "rule", "class", "track", "frame",
                        "snapshot", "clip"]
    assert len(table) - 1 == sum(e.line == "gate" or e.zone == "gate" for e in r.pred)
    assert main(["events", str(r.run_dir), "--limit", "1"]) == 0
    out, err = capsys.readouterr()
    assert out.splitlines()[0].split()[:3] == ["id", "time", "camera"]
    assert len(out.splitlines()) == 2 and err == "1 event\n"
    assert main(["events", str(r.run_dir), "--until", "2000-01-01"]) == 0
    assert capsys.readouterr().out.splitlines()[1:] == []


def test_totals_count_each_type_per_hour(scene_runs, capsys, utc):
    r = scene_runs("runner", 0)
    capsys.readouterr()
    assert main(["events", str(r.run_dir), "--totals", "hour"]) == 0
    rows = [ln.split() for ln in capsys.readouterr().out.splitlines()[1:]]
    counted = {}
    for camera, start, kind, n in rows:
        assert camera == "synth-runner" and start.endswith(":00:00+00:00")
        counted[kind] = counted.get(kind, 0) + int(n)
    assert counted == {t: sum(e.type == t for e in r.pred) for t in {e.type for e in r.pred}}


def test_times_are_iso_dates_and_times_or_a_time_ago(utc):
    now = 1_764_700_000.0
    assert parse_time("2026-12-01", now) == 1_796_083_200.0
    assert parse_time("2026-12-01T18:00+02:00", now) == 1_796_083_200.0 + 16 * 3600
    assert parse_time("2026-12-01 18:00Z", now) == 1_796_083_200.0 + 18 * 3600
    assert parse_time("24h", now) == now - 86400 and parse_time("30m", now) == now - 1800


@pytest.mark.parametrize("args, words", [
    (["--since", "yesterday"], ("since must be an ISO date",)),
    (["--limit", "0"], ("limit must be a whole number >= 1, got 0",)),
    (["--offset", "-3"], ("offset must be a whole number >= 0",)),
])
def test_a_bad_filter_is_one_line(scene_runs, capsys, args, words):
    r = scene_runs("runner", 0)
    capsys.readouterr()
    user_error(main(["events", str(r.run_dir), *args]), capsys.readouterr().err, *words)


def test_a_folder_without_a_store_is_one_line(tmp_path, capsys):
    user_error(main(["events", str(tmp_path)]), capsys.readouterr().err,
               "no event store at", "events.db")


def test_totals_of_several_cameras_are_also_given_over_every_camera(tmp_path, capsys, utc):
    with EventStore(tmp_path) as store:
        for camera, when in (("gate", 3600.0), ("gate", 3700.0), ("yard", 3800.0),
                             ("yard", 7300.0)):
            store.add({"type": "loiter", "frame": 1, "zone": "z"}, camera, when)
    assert main(["events", str(tmp_path), "--totals", "hour"]) == 0
    rows = [ln.split() for ln in capsys.readouterr().out.splitlines()[1:]]
    assert rows == [["gate", "1970-01-01T01:00:00+00:00", "loiter", "2"],
                    ["yard", "1970-01-01T01:00:00+00:00", "loiter", "1"],
                    ["yard", "1970-01-01T02:00:00+00:00", "loiter", "1"],
                    ["(all)", "1970-01-01T01:00:00+00:00", "loiter", "3"],
                    ["(all)", "1970-01-01T02:00:00+00:00", "loiter", "1"]]
