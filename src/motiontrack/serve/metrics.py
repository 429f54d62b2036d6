"""``GET /metrics``: the server's cameras in the Prometheus text format (``prometheus_client``,
in the ``serve`` extra).

Read from the :class:`~.hub.Hub` at each scrape (a collector, no state of its own):

* ``motiontrack_camera_up`` — 1 while the camera runs, else 0;
* ``motiontrack_camera_frames`` — frames its current process has processed (a gauge: a
  restarted camera counts from 0 again);
* ``motiontrack_camera_fps`` — its processing rate;
* ``motiontrack_camera_reconnects_total`` — reconnections of its live source;
* ``motiontrack_camera_restarts_total`` — restarts of its process by the server;
* ``motiontrack_camera_dropped_messages_total`` — pictures and messages the camera dropped
  because the server had not taken the previous ones;
* ``motiontrack_events_total`` — events by camera and type since the server started.

Every metric has the label ``camera``; ``motiontrack_events_total`` also ``type``.
"""

from __future__ import annotations

from typing import Any, Iterator

import anyio
from starlette.requests import Request
from starlette.responses import Response
from starlette.routing import Route

from .hub import Hub

__all__ = ["metrics_routes", "render_metrics"]


class _HubCollector:
    def __init__(self, hub: Hub) -> None:
        self.hub = hub

    def collect(self) -> Iterator[Any]:
        from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily

        up = GaugeMetricFamily("motiontrack_camera_up", "1 while the camera runs", labels=["camera"])
        frames = GaugeMetricFamily("motiontrack_camera_frames",
                                   "frames processed by the camera's current process",
                                   labels=["camera"])
        fps = GaugeMetricFamily("motiontrack_camera_fps", "frames processed per second",
                                labels=["camera"])
        reconnects = CounterMetricFamily("motiontrack_camera_reconnects",
                                         "reconnections of the camera's live source",
                                         labels=["camera"])
        restarts = CounterMetricFamily("motiontrack_camera_restarts",
                                       "restarts of the camera's process", labels=["camera"])
        dropped = CounterMetricFamily("motiontrack_camera_dropped_messages",
                                      "pictures and messages dropped before the server took them",
                                      labels=["camera"])
        events = CounterMetricFamily("motiontrack_events", "events since the server started",
                                     labels=["camera", "type"])
        for name, cam in self.hub.cameras.items():
            with cam.lock:
                s, n_restarts, by_type = dict(cam.status), cam.restarts, dict(cam.event_types)
            up.add_metric([name], 1.0 if s.get("status") == "running" else 0.0)
            frames.add_metric([name], float(s.get("frames", 0) or 0))
            fps.add_metric([name], float(s.get("fps", 0.0) or 0.0))
            reconnects.add_metric([name], float(s.get("reconnects", 0) or 0))
            restarts.add_metric([name], float(n_restarts))
            dropped.add_metric([name], float(s.get("dropped_messages", 0) or 0))
            for kind, n in sorted(by_type.items()):
                events.add_metric([name, kind], float(n))
        yield from (up, frames, fps, reconnects, restarts, dropped, events)


def render_metrics(hub: Hub) -> tuple[bytes, str]:
    """The exposition of ``hub``'s metrics and its content type."""
    from prometheus_client import CONTENT_TYPE_LATEST, CollectorRegistry, generate_latest

    registry = CollectorRegistry(auto_describe=False)
    registry.register(_HubCollector(hub))
    return generate_latest(registry), CONTENT_TYPE_LATEST


def metrics_routes(hub: Hub) -> list[Route]:
    async def metrics(request: Request) -> Response:
        try:
            body, kind = await anyio.to_thread.run_sync(render_metrics, hub)
        except ImportError:
            return Response("/metrics needs prometheus_client: pip install "
                            "'motiontrack[serve]'\n", status_code=501, media_type="text/plain")
        return Response(body, media_type=kind)

    return [Route("/metrics", metrics)]
