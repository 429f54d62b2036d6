"""Frames handed to a consumer (a video encoder) running in a thread of its own.

The frame that a run draws is copied into one of a fixed set of buffers and queued; a worker
thread gives each queued frame, in order, to ``consume`` and returns its buffer. So the drawing
thread never waits for the encoder while a buffer is free, memory stays at ``slots`` frames
however far the encoder falls behind (``put`` waits for a free buffer: back-pressure), and no
full-size image is allocated per frame. Encoders (PyAV's, ``cv2.VideoWriter``) release the GIL
while they encode, so the worker runs beside the pipeline's own threads.

An error of ``consume`` is kept and raised, once, by the next :meth:`FrameQueue.put` or by
:meth:`FrameQueue.close`; frames queued after it are dropped, so the thread never blocks a run
that is about to fail.
"""

from __future__ import annotations

import queue
import threading
from typing import Callable

import cv2
import numpy as np

__all__ = ["FrameQueue", "QUEUE_BYTES", "MAX_SLOTS", "slots_for", "copy_frame"]

#: memory the queued frames of one video may take (at least 2 frames are queued whatever the size)
QUEUE_BYTES = 32 << 20
#: most frames queued for one video: a few frames absorb the encoder's uneven pace (key frames)
MAX_SLOTS = 4


def slots_for(shape: tuple[int, ...]) -> int:
    """Buffers of a queue of frames of ``shape`` (uint8): :data:`MAX_SLOTS`, fewer for large
    frames so that they take at most :data:`QUEUE_BYTES`, never fewer than 2."""
    nbytes = int(np.prod(shape))
    return max(2, min(MAX_SLOTS, QUEUE_BYTES // max(1, nbytes)))


def copy_frame(image: np.ndarray, buf: np.ndarray) -> None:
    """``image`` ((h, w, 3) BGR or (h, w) gray uint8) into the (h, w, 3) buffer ``buf``."""
    if image.shape[:2] != buf.shape[:2]:
        raise ValueError(f"frame of {image.shape[1]}x{image.shape[0]} pixels into a buffer of "
                         f"{buf.shape[1]}x{buf.shape[0]}")
    if image.ndim == 2:
        cv2.cvtColor(image, cv2.COLOR_GRAY2BGR, dst=buf)
    else:
        np.copyto(buf, image, casting="unsafe")


class FrameQueue:
    """``consume(frame)`` for every :meth:`put` frame, in order, in a worker thread.

    Parameters
    ----------
    consume : called in the worker with each frame, a uint8 buffer of ``shape`` that is reused
        once it returns (it must not keep a reference to it).
    shape : shape of the buffers, (h, w, 3) for BGR frames.
    slots : buffers, i.e. the most frames queued or being consumed at once (default
        :func:`slots_for`).
    name : the worker thread's name.
    fill : ``fill(image, buffer)`` puts a frame given to :meth:`put` into a buffer, in the
        caller's thread (e.g. converted for the encoder); default :func:`copy_frame`.
    """

    def __init__(self, consume: Callable[[np.ndarray], None], shape: tuple[int, ...],
                 slots: int | None = None, name: str = "motiontrack-encoder",
                 fill: Callable[[np.ndarray, np.ndarray], None] | None = None) -> None:
        self.shape = tuple(int(s) for s in shape)
        self.slots = slots_for(self.shape) if slots is None else int(slots)
        if self.slots < 1:
            raise ValueError(f"slots must be >= 1, got {self.slots}")
        self._consume = consume
        self._fill = fill or copy_frame
        self._free: queue.SimpleQueue[np.ndarray] = queue.SimpleQueue()
        for _ in range(self.slots):
            self._free.put(np.empty(self.shape, np.uint8))
        self._work: queue.SimpleQueue[np.ndarray | None] = queue.SimpleQueue()
        self._error: BaseException | None = None
        self._reported = False
        self._drop = False
        self._closed = False
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    @property
    def error(self) -> BaseException | None:
        """The error ``consume`` raised, if it did."""
        return self._error

    def put(self, image: np.ndarray) -> None:
        """Queue ``image``, copied into a buffer by ``fill``; waits while every buffer is in use.
        Raises the worker's error once it has one."""
        self._raise()
        if self._closed:
            raise ValueError("frame queue is closed")
        buf = self._free.get()   # blocks while the worker holds every buffer
        try:
            self._fill(image, buf)
        except BaseException:
            self._free.put(buf)
            raise
        self._work.put(buf)

    def close(self) -> None:
        """Wait until every queued frame is consumed and stop the worker; raises its error
        (unless :meth:`put` has raised it already)."""
        self._stop()
        self._raise()

    def abort(self) -> None:
        """Drop the frames not consumed yet, wait for the one being consumed, stop the worker.
        Never raises: it is called while another error is on its way."""
        self._drop = True
        self._stop()

    @property
    def pending(self) -> int:
        """Frames queued or being consumed."""
        return self.slots - self._free.qsize()

    def _stop(self) -> None:
        if not self._closed:
            self._closed = True
            self._work.put(None)
        self._thread.join()

    def _raise(self) -> None:
        if self._error is not None and not self._reported:
            self._reported = True
            raise self._error

    def _run(self) -> None:
        while True:
            buf = self._work.get()
            if buf is None:
                return
            try:
                if self._error is None and not self._drop:
                    self._consume(buf)
            except BaseException as exc:   # kept for the run's thread, which raises it
                self._error = exc
            finally:
                self._free.put(buf)
