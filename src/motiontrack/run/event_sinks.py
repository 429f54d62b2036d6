"""The writer that sends each frame's scene-analytics events to webhooks and MQTT brokers.

Like :class:`~motiontrack.run.analytics_writers.EventsWriter` it reads the
:class:`~motiontrack.types.SceneFrame` of each frame, as a writer of the
:class:`~motiontrack.run.job.Job` of ``track --scene`` or ``analyze``. The sending happens in
the background threads of :mod:`motiontrack.io.sinks`; the pipeline only queues, so a slow or
absent receiver never slows a run down, and at the end a run waits at most ``flush_s`` for them.
"""

from __future__ import annotations

import logging
import time
from typing import Any, Sequence

from ..io.sinks import (FLUSH_S, Delivery, MqttDelivery, MqttTarget, SinkSettings,
                        WebhookDelivery, WebhookTarget, check_camera_name, encode)
from ..types import FrameResult
from .job import JobContext, JobSummary, Writer

log = logging.getLogger(__name__)

__all__ = ["EventSinksWriter", "deliveries", "sinks_writer"]

Target = WebhookTarget | MqttTarget


def deliveries(targets: Sequence[Target], camera: str,
               settings: SinkSettings | None = None) -> list[Delivery]:
    """One delivery per target, sending as ``settings`` say (default :class:`SinkSettings`)."""
    st = settings or SinkSettings()
    out: list[Delivery] = []
    for t in targets:
        if isinstance(t, WebhookTarget):
            out.append(WebhookDelivery(t, queue_size=st.queue_size, timeout_s=st.timeout_s,
                                       retries=st.retries))
        else:
            out.append(MqttDelivery(t, camera, queue_size=st.queue_size,
                                    connect_timeout_s=st.timeout_s))
    return out


def sinks_writer(targets: Sequence[Target], camera: str,
                 settings: SinkSettings | None = None) -> "EventSinksWriter":
    """The writer sending every event to ``targets`` and waiting for them at the end of the
    run, as ``settings`` say (default :class:`SinkSettings`)."""
    st = settings or SinkSettings()
    return EventSinksWriter(deliveries(targets, camera, st), camera, st.flush_s)


class EventSinksWriter(Writer):
    """Every event as ``{**event.to_json(), "camera": camera}`` to each delivery, in frame order;
    a frame after a discontinuity of the source is preceded by its ``{"type": "discontinuity",
    "reason", "frame", "camera"}`` record (counted among the sink's ``events``).

    ``summary.json`` gains ``sinks``: per sink its ``events``, ``delivered``, ``failed``,
    ``dropped`` and ``retries`` (:meth:`Delivery.stats`). The writer owns no file.
    """

    def __init__(self, sinks: Sequence[Delivery], camera: str, flush_s: float = FLUSH_S) -> None:
        self.paths = {}
        self.camera = check_camera_name(camera)
        self.sinks = list(sinks)
        self.flush_s = float(flush_s)
        self._open = False
        self._stats: list[dict[str, Any]] | None = None

    def start(self, ctx: JobContext) -> None:
        for s in self.sinks:
            s.start()
        self._open = True

    def write(self, result: FrameResult) -> None:
        scene = result.scene
        if scene is None:
            return
        records = [e.to_json() for e in scene.events]
        if scene.discontinuity is not None:   # as events.jsonl: the jump before the frame's events
            records.insert(0, scene.discontinuity.to_json(scene.frame))
        for record in records:
            body = encode({**record, "camera": self.camera})
            for s in self.sinks:
                s.offer(body)

    def close(self, keep: bool) -> None:
        """With ``keep`` (the run ended, however), send what is queued for at most ``flush_s``
        seconds, all sinks together; without it (the run failed), stop at once."""
        if not self._open:
            return
        self._open = False
        deadline = time.monotonic() + self.flush_s if keep else None
        stats = []
        for s in self.sinks:
            try:
                stats.append(s.close(deadline))
            except KeyboardInterrupt:
                # a second Ctrl-C while the sinks drain: stop waiting, but keep the run's
                # outputs (letting it escape would remove them as a failed run's)
                log.warning("not waiting for the event sinks any longer")
                deadline = None
                stats.append(s.close(None))
        self._stats = stats

    def stats(self) -> list[dict[str, Any]]:
        return self._stats if self._stats is not None else [s.stats() for s in self.sinks]

    def finish(self, summary: JobSummary) -> None:
        summary.extra["sinks"] = self.stats()
