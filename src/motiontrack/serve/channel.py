"""Camera process → server messages over bounded multiprocessing queues that never block the
camera.

Messages:

* ``("frame", jpeg_bytes, frame_index, fps, wall)`` — the latest annotated picture (``wall``:
  when its frame was read, epoch seconds, or None); dropped when the server has not taken the
  previous ones (a picture is worth showing only while it is new);
* ``("events", [event_json, ...])``, ``("counts", {...})``, ``("status", {...})`` — on a larger
  queue; when even that is full the message is dropped and counted (:attr:`Channel.dropped`),
  and the next status message reports the count.

A channel is made for one camera process: a process killed while writing can leave a queue's
pipe in a broken state, so a restarted camera gets a new channel.
"""

from __future__ import annotations

import queue
from typing import Any

__all__ = ["Channel"]

#: pictures waiting for the server: more only adds latency
FRAME_QUEUE = 2
#: events, counts and status messages waiting for the server
MESSAGE_QUEUE = 1000


class Channel:
    """Two bounded queues from one camera process to the server (picklable for "spawn")."""

    def __init__(self, ctx: Any) -> None:
        self.frames = ctx.Queue(FRAME_QUEUE)
        self.messages = ctx.Queue(MESSAGE_QUEUE)
        self.dropped = 0

    def frame(self, jpeg: bytes, index: int, fps: float, wall: float | None = None) -> bool:
        """Offer a picture; False when it was dropped."""
        try:
            self.frames.put_nowait(("frame", jpeg, int(index), float(fps), wall))
            return True
        except queue.Full:
            return False

    def _put(self, msg: tuple) -> None:
        try:
            self.messages.put_nowait(msg)
        except queue.Full:
            self.dropped += 1

    def events(self, events: list[dict]) -> None:
        if events:
            self._put(("events", list(events)))

    def counts(self, counts: dict) -> None:
        self._put(("counts", counts))

    def status(self, status: dict) -> None:
        self._put(("status", {**status, "dropped_messages": self.dropped}))

    def close(self) -> None:
        """The process is about to exit: the last messages (the final status) are written out;
        pictures not yet taken are not waited for."""
        self.frames.cancel_join_thread()
        self.frames.close()
        self.messages.close()
        self.messages.join_thread()
