"""``serve``'s search over its event store: ``/api/events/search`` and ``/api/events/totals``."""

from __future__ import annotations

import asyncio
import time

import httpx
import pytest

from motiontrack.io.event_store import EventStore
from motiontrack.serve.app import create_app
from motiontrack.serve.hub import Hub
from motiontrack.serve.search import MAX_PAGE


def _get(app, *urls):
    async def go():
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url="http://127.0.0.1") as c:
            return [await c.get(u) for u in urls]

    return asyncio.run(go())


@pytest.fixture
def store(tmp_path):
    """A store of 1,200 events of two cameras over the last 20 minutes: every second one is
    the gate's line crossing, the others the bench's loitering."""
    now = time.time()
    db = tmp_path / "events.db"
    with EventStore(db) as s:
        for k in range(1200):
            event = ({"type": "line_cross", "frame": k + 1, "line": "gate", "direction": "in"}
                     if k % 2 == 0 else
                     {"type": "loiter", "frame": k + 1, "zone": "bench", "dwell_s": 5.0})
            s.add(event, "door" if k < 600 else "yard", now - 1200 + k, "cam/seg")
    return db


def test_search_filters_pages_and_counts(store):
    app = create_app(Hub([("door", False), ("yard", False)]), store=store)
    first, second, door, recent, capped = _get(
        app, "/api/events/search?type=loiter&limit=100",
        "/api/events/search?type=loiter&limit=100&offset=100",
        "/api/events/search?camera=door&rule=gate&limit=5",
        "/api/events/search?since=10m",
        "/api/events/search?limit=5000")
    a, b = first.json(), second.json()
    assert a["total"] == b["total"] == 600 and len(a["events"]) == len(b["events"]) == 100
    frames = [e["frame"] for e in a["events"] + b["events"]]
    assert frames == list(range(1200, 800, -2))          # newest first, pages in a row
    assert {e["rule"] for e in a["events"]} == {"bench"}
    d = door.json()
    assert d["total"] == 300 and [e["camera"] for e in d["events"]] == ["door"] * 5
    assert recent.json()["total"] in (599, 600, 601)      # the last 10 of 20 minutes
    assert capped.json()["limit"] == MAX_PAGE and len(capped.json()["events"]) == MAX_PAGE


def test_totals_per_hour_add_up_to_every_event(store):
    app = create_app(Hub([("door", False)]), store=store)
    (r,) = _get(app, "/api/events/totals?bin=hour&camera=yard")
    rows = r.json()["totals"]
    assert sum(t["count"] for t in rows) == 600 and {t["camera"] for t in rows} == {"yard"}
    assert all(t["start"] % 3600 == (-time.localtime().tm_gmtoff) % 3600 for t in rows)


def test_bad_filters_are_400_with_the_message_and_no_store_is_no_event(store, tmp_path):
    app = create_app(Hub([("door", False)]), store=store)
    since, unknown, bin_ = _get(app, "/api/events/search?since=yesterday",
                                "/api/events/search?colour=red", "/api/events/totals?bin=week")
    assert since.status_code == 400 and "since must be an ISO date" in since.json()["error"]
    assert unknown.status_code == 400 and "unknown filter 'colour'" in unknown.json()["error"]
    assert bin_.status_code == 400
    empty = create_app(Hub([("door", False)]), store=tmp_path / "none" / "events.db")
    (r,) = _get(empty, "/api/events/search")
    assert r.json() == {"events": [], "total": 0, "limit": MAX_PAGE, "offset": 0}


def test_an_events_snapshot_object_and_clip_are_served(tmp_path):
    import cv2
    import numpy as np

    from motiontrack.io.clips import write_mjpeg_clip

    db = tmp_path / "events.db"
    evidence = tmp_path / "cam" / "seg" / "evidence"
    evidence.mkdir(parents=True)
    picture = np.full((24, 32, 3), 90, np.uint8)
    cv2.imwrite(str(evidence / "1.jpg"), picture)
    cv2.imwrite(str(evidence / "1-object.jpg"), picture[:8, :8])
    jpegs = [cv2.imencode(".jpg", np.full((24, 32, 3), 10 * k, np.uint8))[1].tobytes()
             for k in range(5)]
    write_mjpeg_clip(evidence / "1.avi", jpegs, 50.0)
    with EventStore(db) as s:
        i = s.add({"type": "loiter", "frame": 3, "zone": "bench"}, "cam", time.time(), "cam/seg",
                   snapshot="cam/seg/evidence/1.jpg", clip="cam/seg/evidence/1.avi")
        s.add({"type": "loiter", "frame": 4, "zone": "bench"}, "cam", time.time(), "cam/seg",
              snapshot="../../etc/passwd")
    app = create_app(Hub([("cam", False)]), store=db)
    snap, obj, avi, mjpg, bad, none, kind = _get(
        app, f"/api/events/{i}/snapshot.jpg", f"/api/events/{i}/object.jpg",
        f"/api/events/{i}/clip.avi", f"/api/events/{i}/clip.mjpg", "/api/events/2/snapshot.jpg",
        "/api/events/99/clip.avi", f"/api/events/{i}/notes.txt")
    assert snap.headers["content-type"] == "image/jpeg"
    assert cv2.imdecode(np.frombuffer(snap.content, np.uint8), 1).shape == (24, 32, 3)
    assert cv2.imdecode(np.frombuffer(obj.content, np.uint8), 1).shape == (8, 8, 3)
    assert avi.content == (evidence / "1.avi").read_bytes()
    assert mjpg.headers["content-type"].startswith("multipart/x-mixed-replace")
    assert mjpg.content.count(b"Content-Type: image/jpeg") == 5      # every frame of the clip
    assert bad.status_code == none.status_code == kind.status_code == 404   # outside the folder


def test_the_token_in_the_query_is_not_taken_for_a_filter(store):
    app = create_app(Hub([("door", False)]), token="t0k", store=store)
    (r,) = _get(app, "/api/events/search?token=t0k&camera=door&limit=1")
    assert r.status_code == 200 and r.json()["total"] == 600
