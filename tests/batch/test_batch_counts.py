"""A batch's event counts: ``RESULTS/counts.csv`` (tidy, per video) and ``RESULTS/totals.json``."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from motiontrack.batch.counts import COUNTS_FILE, TOTALS_FILE, write_counts


def _summary(results: Path, name: str, analytics: dict | None) -> None:
    folder = results / name
    folder.mkdir(parents=True)
    doc = {"status": "complete", "frames": 10}
    if analytics is not None:
        doc["analytics"] = analytics
    (folder / "summary.json").write_text(json.dumps(doc), encoding="utf-8")


def _analytics(lines: dict, zones: dict, events: dict) -> dict:
    return {"lines": {k: {"in": i, "out": o} for k, (i, o) in lines.items()},
            "zones": {k: {"enters": e, "exits": x, "peak": 9, "mean_dwell_s": 1.5}
                      for k, (e, x) in zones.items()},
            "events": events}


def _counts(results: Path) -> list[tuple[str, ...]]:
    with open(results / COUNTS_FILE, newline="", encoding="utf-8") as fh:
        return [tuple(r) for r in csv.reader(fh)]


def test_counts_are_one_row_per_video_rule_and_measure_and_totals_sum_the_done_videos(tmp_path):
    # gate-a and gate-b share the line "gate"; plaza has its own scene; "plain" ran without
    # a scene and "broken" failed (a summary left from an earlier run does not count)
    _summary(tmp_path, "gate-a", _analytics({"gate": (3, 1)}, {"yard": (2, 2)},
                                            {"line_cross": 4, "zone_enter": 2}))
    _summary(tmp_path, "gate-b", _analytics({"gate": (5, 4), "side": (0, 1)}, {},
                                            {"line_cross": 10, "zone_enter": 0}))
    _summary(tmp_path, "plain", None)
    _summary(tmp_path, "broken", _analytics({"gate": (100, 100)}, {}, {"line_cross": 200}))
    rows = [{"name": "gate-a", "status": "done"}, {"name": "plain", "status": "done"},
            {"name": "broken", "status": "failed"}, {"name": "gate-b", "status": "done"}]
    totals = write_counts(tmp_path, rows)
    assert _counts(tmp_path) == [
        ("video", "kind", "name", "measure", "count"),
        ("gate-a", "line", "gate", "in", "3"), ("gate-a", "line", "gate", "out", "1"),
        ("gate-a", "zone", "yard", "enters", "2"), ("gate-a", "zone", "yard", "exits", "2"),
        ("gate-b", "line", "gate", "in", "5"), ("gate-b", "line", "gate", "out", "4"),
        ("gate-b", "line", "side", "in", "0"), ("gate-b", "line", "side", "out", "1"),
    ]
    assert totals == {"videos": ["gate-a", "gate-b"],
                      "lines": {"gate": {"in": 3 + 5, "out": 1 + 4}, "side": {"in": 0, "out": 1}},
                      "zones": {"yard": {"enters": 2, "exits": 2}},
                      "events": {"line_cross": 4 + 10, "zone_enter": 2 + 0}}
    assert json.loads((tmp_path / TOTALS_FILE).read_text(encoding="utf-8")) == totals


def test_a_batch_without_a_scene_writes_no_counts_and_removes_old_ones(tmp_path):
    (tmp_path / COUNTS_FILE).write_text("old\n", encoding="utf-8")
    (tmp_path / TOTALS_FILE).write_text("{}\n", encoding="utf-8")
    _summary(tmp_path, "plain", None)
    assert write_counts(tmp_path, [{"name": "plain", "status": "done"}]) is None
    assert not (tmp_path / COUNTS_FILE).exists() and not (tmp_path / TOTALS_FILE).exists()


def test_a_batch_with_a_scene_writes_each_videos_counts_beside_the_index(tmp_path,
                                                                          dask_session_client):
    pytest.importorskip("distributed")
    from motiontrack.batch import run_batch
    from motiontrack.config import PipelineConfig, apply_overrides

    scene = tmp_path / "scene.toml"   # a zone over the whole picture, a line down its middle
    scene.write_text('[[line]]\nname = "mid"\npoints = [[320, 0], [320, 480]]\n'
                     '[[zone]]\nname = "all"\n'
                     'polygon = [[0, 0], [4000, 0], [4000, 4000], [0, 4000]]\n', encoding="utf-8")
    rows = run_batch(["synth:walker?n_frames=40", "synth:walker?n_frames=30&seed=2"],
                     tmp_path / "results", apply_overrides(PipelineConfig(), ["output.video=false"]),
                     client=dask_session_client, scene=str(scene))
    assert [r["status"] for r in rows] == ["done", "done"]
    results = tmp_path / "results"
    counts = _counts(results)[1:]
    names = [r["name"] for r in rows]
    assert [c[:4] for c in counts] == [(n, *k) for n in names for k in (
        ("line", "mid", "in"), ("line", "mid", "out"), ("zone", "all", "enters"),
        ("zone", "all", "exits"))]
    for n in names:   # each row is what the video's own summary says
        a = json.loads((results / n / "summary.json").read_text(encoding="utf-8"))["analytics"]
        mine = {(c[1], c[3]): int(c[4]) for c in counts if c[0] == n}
        assert mine == {("line", "in"): a["lines"]["mid"]["in"],
                        ("line", "out"): a["lines"]["mid"]["out"],
                        ("zone", "enters"): a["zones"]["all"]["enters"],
                        ("zone", "exits"): a["zones"]["all"]["exits"]}
    totals = json.loads((results / TOTALS_FILE).read_text(encoding="utf-8"))
    assert totals["videos"] == names
    # every video's events in one store, the video's name as their camera
    from motiontrack.io.event_store import EventQuery, EventStore

    with EventStore(results, readonly=True) as store:
        for n in names:
            with EventStore(results / n, readonly=True) as own:
                mine = [e.event for e in own]
            assert [e.event for e in store.search(EventQuery(camera=n, oldest_first=True))] == mine
            assert mine and {e.segment for e in store.search(EventQuery(camera=n))} == {n}
    assert not list(results.glob("*.tmp")) and not (results / "events.db-wal").exists()
    assert totals["zones"]["all"]["enters"] == sum(
        int(c[4]) for c in counts if c[1:4] == ("zone", "all", "enters")) >= 2


def test_a_batch_without_events_leaves_no_store_and_removes_an_old_one(tmp_path):
    from motiontrack.batch.events import write_event_store

    (tmp_path / "events.db").write_bytes(b"old")
    _summary(tmp_path, "plain", None)
    assert write_event_store(tmp_path, [{"name": "plain", "status": "done"}]) is None
    assert not (tmp_path / "events.db").exists()
