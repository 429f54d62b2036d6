"""Server-side state of every camera, and fan-out to the viewers.

Reader threads (:meth:`Hub.attach`) take each camera's messages off its
:class:`~.channel.Channel` and update a :class:`CameraState`: the latest JPEG, the status, the
last :data:`EVENTS_KEPT` events each with a per-camera ``seq`` (1, 2, ...), and the counts. Each
viewer (an MJPEG stream, an event stream) subscribes with a bounded asyncio queue of its own;
when it is full the oldest item is dropped, so a slow or vanished viewer only loses its own
pictures and never holds up a camera or another viewer. An event stream can start where an
earlier one ended (:meth:`Hub.subscribe_events` with a :class:`Cursor`): the kept events it
missed come first.
"""

from __future__ import annotations

import asyncio
import collections
import itertools
import queue
import re
import secrets
import threading
from dataclasses import dataclass, field
from typing import Any, Iterable

__all__ = ["Hub", "CameraState", "Subscriber", "Cursor", "EVENTS_KEPT"]

#: events kept in memory per camera for ``?since=`` and resumed event streams (about 1 KB
#: each): enough to bridge a dropped connection; every event is in the store, which
#: ``/api/events/search`` reads, so a wall of cameras does not hold its history in memory
EVENTS_KEPT = 1_000


class Subscriber:
    """One viewer's bounded queue on its event loop; items are offered from any thread."""

    def __init__(self, loop: asyncio.AbstractEventLoop, size: int) -> None:
        self.loop = loop
        self.queue: asyncio.Queue = asyncio.Queue(size)
        self.dropped = 0

    def offer(self, item: Any) -> None:
        try:
            self.loop.call_soon_threadsafe(self._put, item)
        except RuntimeError:   # the loop is closed: the viewer is gone
            pass

    def _put(self, item: Any) -> None:
        if self.queue.full():
            self.queue.get_nowait()
            self.dropped += 1
        self.queue.put_nowait(item)


_CURSOR = re.compile(r"(?P<boot>[0-9a-f]+)\.(?P<seqs>(?:[A-Za-z0-9_-]+=\d+(?:,|$))*)")


@dataclass
class Cursor:
    """How far an event stream has gone: each camera's last ``seq`` sent, in the run of the
    server ``boot`` (a restarted server numbers its events from 1 again). Written as the event
    stream's ``id`` (``boot.gate=12,lobby=40``), which a browser's ``EventSource`` sends back
    as ``Last-Event-ID`` when it reconnects."""

    boot: str
    seqs: dict[str, int] = field(default_factory=dict)

    def __str__(self) -> str:
        return f"{self.boot}." + ",".join(f"{n}={q}" for n, q in self.seqs.items())

    @classmethod
    def parse(cls, text: str | None) -> "Cursor | None":
        """The cursor ``text`` writes, or None when it is not one."""
        m = _CURSOR.fullmatch(text or "")
        if m is None:
            return None
        pairs = (kv.split("=") for kv in m["seqs"].split(",") if kv)
        return cls(m["boot"], {n: int(q) for n, q in pairs})


class CameraState:
    """What the server knows about one camera."""

    def __init__(self, name: str, has_scene: bool) -> None:
        self.name = name
        self.has_scene = has_scene
        self.lock = threading.Lock()
        self.jpeg: bytes | None = None
        self.frame_index = 0
        #: when the latest picture's frame was read (epoch seconds), or None
        self.wall: float | None = None
        self.status: dict[str, Any] = {"status": "starting", "fps": 0.0, "frames": 0,
                                       "reconnects": 0}
        self.events: collections.deque = collections.deque(maxlen=EVENTS_KEPT)
        self.seq = 0
        #: events by type since the server started (``/metrics``)
        self.event_types: collections.Counter = collections.Counter()
        self.counts: dict[str, Any] = {"lines": {}, "zones": {}}
        self.restarts = 0
        self.frame_subs: set[Subscriber] = set()
        self.event_subs: set[Subscriber] = set()

    # -------------------------------------------------------------------- updates
    def put_frame(self, jpeg: bytes, index: int, wall: float | None = None) -> None:
        with self.lock:
            self.jpeg, self.frame_index, self.wall = jpeg, index, wall
            subs = list(self.frame_subs)
        for s in subs:
            s.offer((jpeg, wall))

    def put_events(self, events: Iterable[dict]) -> list[dict]:
        out = []
        with self.lock:
            for e in events:
                self.seq += 1
                if e.get("type") != "discontinuity":   # a record of the source, not an event
                    self.event_types[str(e.get("type"))] += 1
                item = {**e, "seq": self.seq}
                self.events.append(item)
                out.append(item)
            subs = list(self.event_subs)
        for s in subs:
            for item in out:
                s.offer({"camera": self.name, **item})
        return out

    def put_status(self, status: dict) -> None:
        with self.lock:
            self.status = {**self.status, **status}

    def set_status(self, status: str) -> None:
        """A status the supervisor knows better than the camera (``restarting``, ``failed``)."""
        with self.lock:
            self.status = {**self.status, "status": status}

    def put_counts(self, counts: dict) -> None:
        with self.lock:
            self.counts = counts

    # ---------------------------------------------------------------------- reads
    def events_since(self, since: int, limit: int = EVENTS_KEPT) -> list[dict]:
        with self.lock:
            return self._events_after(since, limit)

    def _events_after(self, since: int, limit: int) -> list[dict]:
        """The kept events with ``seq`` above ``since``, at most ``limit`` (hold the lock)."""
        if not self.events or since >= self.seq:
            return []
        first = self.events[0]["seq"]
        start = max(0, since + 1 - first)
        return list(itertools.islice(self.events, start, start + limit))

    def describe(self) -> dict[str, Any]:
        with self.lock:
            s = self.status
            return {"name": self.name, "status": s.get("status", "starting"),
                    "fps": s.get("fps", 0.0), "frames": s.get("frames", 0),
                    "reconnects": s.get("reconnects", 0), "scene": self.has_scene,
                    "pid": s.get("pid"), "restarts": self.restarts,
                    "segment": s.get("segment", ""), "scene_error": s.get("scene_error"),
                    "tracks": s.get("tracks", [])}


class Hub:
    """Every camera's :class:`CameraState`, by name, in the cameras file's order."""

    def __init__(self, cameras: Iterable[tuple[str, bool]]) -> None:
        self.cameras: dict[str, CameraState] = {n: CameraState(n, s) for n, s in cameras}
        self._stop = threading.Event()
        #: this run of the server, in event-stream cursors
        self.boot = secrets.token_hex(4)

    def get(self, name: str) -> CameraState | None:
        return self.cameras.get(name)

    # ------------------------------------------------------------------- readers
    def attach(self, name: str, channel: Any) -> list[threading.Thread]:
        """Start the threads that read one camera process's channel (until :meth:`close` or
        the returned threads' ``done`` event is set)."""
        cam = self.cameras[name]
        done = threading.Event()

        def frames() -> None:
            while not (self._stop.is_set() or done.is_set()):
                try:
                    msg = channel.frames.get(timeout=0.25)
                except queue.Empty:
                    continue
                except (EOFError, OSError, ValueError):
                    return
                cam.put_frame(msg[1], msg[2], msg[4])

        def messages() -> None:
            while not (self._stop.is_set() or done.is_set()):
                try:
                    msg = channel.messages.get(timeout=0.25)
                except queue.Empty:
                    continue
                except (EOFError, OSError, ValueError):
                    return
                kind = msg[0]
                if kind == "events":
                    cam.put_events(msg[1])
                elif kind == "counts":
                    cam.put_counts(msg[1])
                elif kind == "status":
                    cam.put_status(msg[1])

        threads = [threading.Thread(target=f, name=f"hub-{name}-{f.__name__}", daemon=True)
                   for f in (frames, messages)]
        for t in threads:
            t.done = done   # type: ignore[attr-defined]
            t.start()
        return threads

    def close(self) -> None:
        self._stop.set()

    # --------------------------------------------------------------- subscribers
    def subscribe_frames(self, cam: CameraState, size: int = 2) -> Subscriber:
        sub = Subscriber(asyncio.get_running_loop(), size)
        with cam.lock:
            cam.frame_subs.add(sub)
        return sub

    def unsubscribe_frames(self, cam: CameraState, sub: Subscriber) -> None:
        with cam.lock:
            cam.frame_subs.discard(sub)

    def subscribe_events(self, size: int = 1000, after: Cursor | None = None
                         ) -> tuple[Subscriber, Cursor, list[dict]]:
        """Every camera's events from now on, through the returned subscriber, after the
        events it missed: ``(subscriber, start, missed)``. When ``after`` is a cursor of this
        server, ``start`` is it (for the cameras it names) and ``missed`` the kept events after
        it (``camera`` added, each camera's in order), which the subscriber does not receive:
        sent first, they continue the earlier stream with no gap and no repeat (but events no
        longer kept). Otherwise, and for a camera ``after`` does not name, the stream starts
        now: ``start`` is each camera's last ``seq`` and nothing is missed."""
        sub = Subscriber(asyncio.get_running_loop(), size)
        mine = after is not None and after.boot == self.boot
        start = Cursor(self.boot)
        missed: list[dict] = []
        for cam in self.cameras.values():
            with cam.lock:
                cam.event_subs.add(sub)
                seq = after.seqs.get(cam.name, cam.seq) if mine else cam.seq
                start.seqs[cam.name] = min(seq, cam.seq)
                missed += [{"camera": cam.name, **e}
                           for e in cam._events_after(start.seqs[cam.name], EVENTS_KEPT)]
        return sub, start, missed

    def unsubscribe_events(self, sub: Subscriber) -> None:
        for cam in self.cameras.values():
            with cam.lock:
                cam.event_subs.discard(sub)
