"""Many pipeline runs on Dask distributed: one function, ``map_tasks``, for every driver.

A task is one call ``fn(item)`` (one video: trackers carry state from frame to frame, so a video is
never split). ``dask_client`` opens the client: a local cluster of ``jobs`` worker processes, one
thread each (the runs are the parallelism), or an existing scheduler at ``cluster``.
``reusing_client`` lends one open client to every ``dask_client`` of a local cluster meanwhile,
so that many drivers in one process (a test session) share a cluster instead of each starting
its own.
"""

from __future__ import annotations

import contextlib
import logging
import uuid
from typing import Any, Callable, Iterator, Sequence

from ..errors import ConfigError, InputError, printable

log = logging.getLogger(__name__)

__all__ = ["dask_client", "map_tasks", "reusing_client"]

# the clients lent by reusing_client, innermost last
_lent: list[Any] = []


def _worker_init() -> None:
    """One OpenCV thread per worker process: the tasks are the parallelism."""
    import cv2

    cv2.setNumThreads(1)


@contextlib.contextmanager
def reusing_client(client: Any) -> Iterator[Any]:
    """While active, :func:`dask_client` without a ``cluster`` address yields ``client`` (left
    open on exit) instead of starting and stopping a local cluster of its own."""
    _lent.append(client)
    try:
        yield client
    finally:
        _lent.remove(client)


@contextlib.contextmanager
def dask_client(jobs: int = 1, cluster: str | None = None) -> Iterator[Any]:
    """A ``distributed.Client``: connected to the scheduler at ``cluster`` (``tcp://host:8786``),
    or to a local cluster of ``jobs`` worker processes started here and stopped on exit (or the
    client lent by :func:`reusing_client`)."""
    if jobs < 1:
        raise ConfigError(f"-j must be >= 1, got {jobs}")
    if not cluster and _lent:
        yield _lent[-1]
        return
    try:
        import dask
        from distributed import Client, LocalCluster
    except ImportError:
        raise ConfigError("running on Dask needs Dask distributed: "
                          "pip install 'dask[distributed]'") from None
    if cluster:
        try:
            client = Client(cluster, timeout=30)
        except (OSError, TimeoutError) as exc:
            raise InputError(f"cannot connect to the Dask scheduler at {printable(cluster)}: "
                             f"{printable(exc)}") from None
        local = None
    else:
        # a worker that dies fails its task at once (KilledWorker): map_tasks retries it and
        # counts the attempt, instead of the scheduler re-running it uncounted
        with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
            local = LocalCluster(n_workers=jobs, processes=True, threads_per_worker=1,
                                 dashboard_address=":0")   # never a busy fixed port
        client = Client(local)
    try:
        client.run(_worker_init)
        yield client
    finally:
        client.close()
        if local is not None:
            local.close()


def map_tasks(client: Any, fn: Callable[..., Any], items: Sequence[Any], *, retries: int = 0,
              on_result: Callable[[int, Any, int], None] | None = None,
              on_lost: Callable[[int, BaseException, int], Any] | None = None,
              key: str = "motiontrack", hard_timeout_s: float | None = None,
              on_timeout: Callable[[int, int], Any] | None = None) -> list[Any]:
    """``fn(item, attempt)`` for every item on ``client``'s workers; results in item order.

    ``on_result(index, result, attempts)`` is called as each task finishes (completion order).
    A task whose worker died (``KilledWorker``, a lost connection) is submitted again, up to
    ``retries`` more times; beyond that its result is ``on_lost(index, error, attempts)``, or
    the error is raised without ``on_lost``. Exceptions ``fn`` raises are
    raised here (a driver that must not stop catches them inside ``fn``). On any error or
    ``KeyboardInterrupt`` the tasks not finished are cancelled.

    With ``hard_timeout_s``, a task still executing that long after a worker started it (a
    thread cannot be stopped) is cancelled and its worker process restarted; its result is
    ``on_timeout(index, attempts)``.
    """
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    key = f"{key}-{uuid.uuid4().hex[:8]}"   # a client's finished keys are never re-used
    lost = (KilledWorker, OSError)   # CommClosedError is an OSError
    results: list[Any] = [None] * len(items)
    attempts = [1] * len(items)
    futures = {client.submit(fn, item, 1, key=f"{key}-{i}-1", pure=False): i
               for i, item in enumerate(items)}
    pending = as_completed(list(futures))
    timed_out: set[str] = set()
    watchdog = (_Watchdog(client, futures, hard_timeout_s, timed_out)
                if hard_timeout_s is not None else contextlib.nullcontext())
    try:
        with watchdog:
            _collect(client, fn, items, futures, pending, results, attempts, retries, lost,
                     on_result, on_lost, on_timeout, timed_out, key)
    except BaseException:
        client.cancel(list(futures))
        raise
    return results


def _collect(client, fn, items, futures, pending, results, attempts, retries, lost,
             on_result, on_lost, on_timeout, timed_out, key) -> None:
    """The loop of :func:`map_tasks` over the futures as they complete."""
    from distributed.client import FutureCancelledError

    for fut in pending:
        i = futures.pop(fut)
        try:
            if fut.key in timed_out:
                raise FutureCancelledError(fut.key, "timed out")
            res = fut.result()
        except FutureCancelledError:
            if fut.key not in timed_out or on_timeout is None:
                raise
            res = results[i] = on_timeout(i, attempts[i])
            if on_result is not None:
                on_result(i, res, attempts[i])
            continue
        except lost as exc:
            if attempts[i] > retries:
                if on_lost is None:
                    raise
                res = on_lost(i, exc, attempts[i])
                results[i] = res
                if on_result is not None:
                    on_result(i, res, attempts[i])
                continue
            attempts[i] += 1
            log.warning("task %d lost its worker (%s): attempt %d", i, printable(exc),
                        attempts[i])
            again = client.submit(fn, items[i], attempts[i], key=f"{key}-{i}-{attempts[i]}",
                                  pure=False)
            futures[again] = i
            pending.add(again)
            continue
        results[i] = res
        if on_result is not None:
            on_result(i, res, attempts[i])


class _Watchdog:
    """A thread that polls the tasks executing on the workers and, for one running longer than
    ``limit`` seconds, cancels its future and restarts its worker (the only way to stop it)."""

    def __init__(self, client: Any, futures: dict, limit: float, timed_out: set) -> None:
        import threading

        self.client, self.futures, self.limit, self.timed_out = client, futures, limit, timed_out
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._watch, daemon=True, name="task-watchdog")

    def __enter__(self) -> "_Watchdog":
        self.thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop.set()
        self.thread.join()

    def _watch(self) -> None:
        import time

        seen: dict[str, float] = {}
        while not self.stop.wait(0.5):
            try:
                stacks = self.client.call_stack()
            except Exception:   # noqa: BLE001 - a worker going away; poll again
                continue
            now = time.monotonic()
            for addr, running in stacks.items():
                for k in running:
                    started = seen.setdefault(k, now)
                    if now - started > self.limit and k not in self.timed_out:
                        try:
                            fut = next((f for f in list(self.futures) if f.key == k), None)
                        except RuntimeError:   # the dict changed meanwhile: next poll
                            continue
                        if fut is None:
                            continue
                        log.warning("task %s ran longer than %g s: restarting its worker",
                                    k, self.limit)
                        self.timed_out.add(k)
                        self.client.cancel([fut], force=True)
                        try:
                            self.client.restart_workers([addr])
                        except Exception as exc:   # noqa: BLE001 - it may be gone already
                            log.warning("could not restart worker %s: %s", addr, exc)
