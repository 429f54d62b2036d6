"""``GET /metrics``: each camera's state and events in the Prometheus text format."""

from __future__ import annotations

import asyncio

import httpx
from prometheus_client.parser import text_string_to_metric_families

from motiontrack.serve.app import create_app
from motiontrack.serve.hub import Hub


def _scrape(app) -> tuple[httpx.Response, dict]:
    async def go():
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url="http://127.0.0.1") as c:
            return await c.get("/metrics")

    r = asyncio.run(go())
    samples = {(s.name, tuple(sorted(s.labels.items()))): s.value
               for fam in text_string_to_metric_families(r.text) for s in fam.samples}
    return r, samples


def test_metrics_report_each_cameras_state_and_events_by_type():
    hub = Hub([("gate", True), ("yard", False)])
    gate = hub.get("gate")
    gate.put_status({"status": "running", "fps": 24.5, "frames": 1200, "reconnects": 2,
                     "dropped_messages": 7})
    gate.restarts = 1
    gate.put_events([{"type": "line_cross"}, {"type": "line_cross"}, {"type": "loiter"},
                     {"type": "discontinuity", "reason": "loop", "frame": 9}])
    r, m = _scrape(create_app(hub))
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/plain")
    cam = (("camera", "gate"),)
    assert m["motiontrack_camera_up", cam] == 1.0
    assert m["motiontrack_camera_up", (("camera", "yard"),)] == 0.0   # still starting
    assert m["motiontrack_camera_frames", cam] == 1200.0
    assert m["motiontrack_camera_fps", cam] == 24.5
    assert m["motiontrack_camera_reconnects_total", cam] == 2.0
    assert m["motiontrack_camera_restarts_total", cam] == 1.0
    assert m["motiontrack_camera_dropped_messages_total", cam] == 7.0
    assert m["motiontrack_events_total", (("camera", "gate"), ("type", "line_cross"))] == 2.0
    assert m["motiontrack_events_total", (("camera", "gate"), ("type", "loiter"))] == 1.0
    # the source's discontinuity records are not events
    assert not [k for k in m if ("type", "discontinuity") in k[1]]


def test_metrics_need_the_token_like_every_route():
    hub = Hub([("gate", False)])

    async def go(headers):
        transport = httpx.ASGITransport(app=create_app(hub, token="s3cret"))
        async with httpx.AsyncClient(transport=transport, base_url="http://127.0.0.1") as c:
            return (await c.get("/metrics", headers=headers)).status_code

    assert asyncio.run(go({})) == 401
    assert asyncio.run(go({"Authorization": "Bearer s3cret"})) == 200
