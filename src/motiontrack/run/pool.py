"""Many runs in a pool of local worker processes that stop when asked and die with their parent.

:func:`pool_map` calls ``fn(item, should_stop)`` for every item in a pool of spawned processes
(``concurrent.futures.ProcessPoolExecutor``, spawn start method, safe on every OS). Two things a
plain pool does not do:

* **a stop reaches the runs in progress.** The caller's ``should_stop`` is polled every
  :data:`POLL_S` seconds; once it says stop, a shared event tells every worker, whose ``fn``
  polls it after each frame (:meth:`~motiontrack.run.job.Job.run`'s ``should_stop``) and ends
  its run there. Runs not started are cancelled; runs that finish meanwhile still count. The
  workers ignore SIGINT, so that a Ctrl-C sent to the whole process group (a terminal) reaches
  them only through the parent, never in the middle of a frame.
* **the workers die with the parent.** A parent killed by SIGKILL (the OOM killer) cannot stop
  its pool; each worker asks the kernel for SIGKILL when its parent dies (Linux
  ``prctl(PR_SET_PDEATHSIG)``) and, on every system, a thread of its own checks
  ``os.getppid()`` every :data:`PARENT_POLL_S` seconds and ends the process when the parent is
  gone (a worker is re-parented to init or a subreaper, so its parent id changes).

The workers log as the parent does: the ``motiontrack`` logger's level and the formatter of its
first handler are handed to them, so that a warning of a run reads like one of the parent.
"""

from __future__ import annotations

import ctypes
import logging
import multiprocessing
import os
import pickle
import signal
import sys
import threading
import time
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any, Callable, Sequence

__all__ = ["pool_map", "die_with_parent", "POLL_S", "PARENT_POLL_S"]

#: how often the parent polls the caller's ``should_stop`` while the pool runs (seconds)
POLL_S = 0.1
#: how often a worker checks that its parent is alive (seconds)
PARENT_POLL_S = 0.5
#: ``prctl`` option of Linux: the signal sent to this process when its parent dies
_PR_SET_PDEATHSIG = 1

# the stop event of the pool this worker process belongs to (set by _init_worker)
_stop_event: Any = None


def die_with_parent(parent: int, poll_s: float = PARENT_POLL_S) -> None:
    """End this process as soon as the process ``parent`` (its parent's id) ends.

    On Linux the kernel sends SIGKILL when the parent dies (``PR_SET_PDEATHSIG``); everywhere a
    daemon thread compares ``os.getppid()`` with ``parent`` every ``poll_s`` seconds and calls
    ``os._exit`` when they differ. A parent that died before this call ends the process at once.
    """
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # no libc prctl: the thread below still watches
            pass
    if os.getppid() != parent:   # died before the request above took effect
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent, poll_s), daemon=True,
                     name="parent-watch").start()


def _watch_parent(parent: int, poll_s: float) -> None:
    while True:
        time.sleep(poll_s)
        if os.getppid() != parent:
            os._exit(1)


def _parent_logging() -> tuple[int, logging.Formatter | None]:
    """The level of the ``motiontrack`` logger and the formatter of its first handler (None
    when it has none, or one that cannot be handed to another process)."""
    root = logging.getLogger("motiontrack")
    fmt = next((h.formatter for h in root.handlers if h.formatter is not None), None)
    try:
        pickle.dumps(fmt)
    except Exception:   # noqa: BLE001 - any formatter may be installed; the default will do
        fmt = None
    return root.getEffectiveLevel(), fmt


def _log_as_parent(level: int, fmt: logging.Formatter | None) -> None:
    root = logging.getLogger("motiontrack")
    root.setLevel(level)
    if fmt is not None:
        handler = logging.StreamHandler(sys.stderr)
        handler.setFormatter(fmt)
        root.handlers[:] = [handler]
        root.propagate = False


def _init_worker(stop_event: Any, parent: int, init: Callable[[], None] | None,
                 log_setup: tuple[int, logging.Formatter | None] = (logging.WARNING, None)
                 ) -> None:
    """Initializer of a pool worker: the pool's stop event, SIGINT ignored (the parent asks for
    a stop through the event), death with the parent, logging as the parent's, then the
    caller's ``init``."""
    global _stop_event
    _stop_event = stop_event
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent(parent)
    _log_as_parent(*log_setup)
    if init is not None:
        init()


def _stop_requested() -> bool:
    return _stop_event is not None and _stop_event.is_set()


def _call(fn: Callable[[Any, Callable[[], bool]], Any], item: Any) -> Any:
    """``fn(item, should_stop)`` in a worker; a run taken from the queue after a stop was asked
    does not start."""
    if _stop_requested():
        raise KeyboardInterrupt
    return fn(item, _stop_requested)


def pool_map(fn: Callable[[Any, Callable[[], bool]], Any], items: Sequence[Any], jobs: int, *,
             on_result: Callable[[int, Any], None] | None = None,
             should_stop: Callable[[], bool] | None = None,
             init: Callable[[], None] | None = None) -> list[Any]:
    """``fn(item, should_stop)`` for every item in a pool of ``jobs`` spawned processes; the
    results in item order.

    ``fn`` and ``init`` must be picklable (module-level functions); ``init`` runs once in each
    worker. ``on_result(index, result)`` is called in the parent as each item finishes. An
    exception ``fn`` raises is raised here and cancels the items not started.

    When ``should_stop()`` turns true (polled every :data:`POLL_S` s), or on a
    ``KeyboardInterrupt`` in the parent, every worker is told to stop: the items in progress end
    after their current frame (``fn`` raises ``KeyboardInterrupt``; an item that finishes
    meanwhile is still passed to ``on_result``), the others are cancelled, the pool is shut down
    and ``KeyboardInterrupt`` is raised.
    """
    results: list[Any] = [None] * len(items)
    if not items:
        return results
    ctx = multiprocessing.get_context("spawn")
    stop = ctx.Event()
    pool = ProcessPoolExecutor(max_workers=min(jobs, len(items)), mp_context=ctx,
                               initializer=_init_worker,
                               initargs=(stop, os.getpid(), init, _parent_logging()))
    try:
        futures = {pool.submit(_call, fn, item): i for i, item in enumerate(items)}
        stopped = _collect(futures, results, on_result, should_stop, stop)
    except BaseException:   # a failed item, or an interrupt: nothing more starts
        stop.set()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()   # after a stop the workers are idle: this is quick
    if stopped:
        raise KeyboardInterrupt
    return results


def _collect(futures: dict[Future, int], results: list[Any],
             on_result: Callable[[int, Any], None] | None,
             should_stop: Callable[[], bool] | None, stop: Any) -> bool:
    """Wait for every future, passing results on as they come; whether a stop was asked."""
    pending = set(futures)
    stopping = False
    while pending:
        done, pending = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
        if not stopping and should_stop is not None and should_stop():
            stopping = True
            stop.set()
            for fut in pending:
                fut.cancel()   # those not handed to a worker yet
        for fut in sorted(done, key=futures.__getitem__):
            if fut.cancelled():
                continue
            exc = fut.exception()
            if exc is not None:
                if stopping:   # stopped part-way (or failed while stopping): not finished
                    continue
                raise exc
            i = futures[fut]
            results[i] = fut.result()
            if on_result is not None:
                on_result(i, results[i])
    return stopping
