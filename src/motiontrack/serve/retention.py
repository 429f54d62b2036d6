"""Retention: ``serve --keep-days D --keep-gb G`` removes the oldest output segments.

A segment (``OUT/CAMERA/YYYYmmdd-HHMMSS/``: tracks, events, counts, its ``evidence/``
snapshots and clips) goes when it ended more than ``keep_days`` days ago, and then, oldest
first, while all the segments together take more than ``keep_gb`` gigabytes. A segment a camera
is writing (and each camera's newest) is never removed, whatever its age or size. Each removal is logged with its size, and
the event store forgets the segment's events (their snapshots and clips went with it).

The server checks every :data:`CHECK_EVERY_S` seconds (:class:`RetentionThread`);
:func:`apply_retention` is the check itself, with the time and the segments in use given.
"""

from __future__ import annotations

import logging
import math
import shutil
import stat
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

from ..errors import ConfigError
from ..io.event_store import STORE_NAME, EventStore

log = logging.getLogger(__name__)

__all__ = ["Retention", "Segment", "segments", "apply_retention", "RetentionThread",
           "CHECK_EVERY_S"]

CHECK_EVERY_S = 60.0
_DAY = 86400.0


@dataclass(frozen=True)
class Retention:
    """How long and how much to keep (None: no bound)."""

    keep_days: float | None = None
    keep_gb: float | None = None

    def __post_init__(self) -> None:
        for flag, v in (("--keep-days", self.keep_days), ("--keep-gb", self.keep_gb)):
            if v is not None and not (math.isfinite(v) and v > 0):
                raise ConfigError(f"{flag} must be a number > 0, got {v}")

    @property
    def active(self) -> bool:
        return self.keep_days is not None or self.keep_gb is not None


@dataclass(frozen=True)
class Segment:
    """One segment folder: ``name`` is ``CAMERA/SEGMENT``, ``ended`` its newest file's time."""

    path: Path
    name: str
    ended: float
    bytes: int


def segments(out: Path) -> list[Segment]:
    """The segment folders of a ``serve`` output folder, oldest first."""
    found = []
    for cam in sorted(p for p in Path(out).iterdir() if p.is_dir()):
        for seg in sorted(p for p in cam.iterdir() if p.is_dir() and not p.name.startswith(".")):
            segment = _segment(seg, f"{cam.name}/{seg.name}")
            if segment is not None:
                found.append(segment)
    return sorted(found, key=lambda s: (s.ended, s.name))


def _segment(seg: Path, name: str) -> Segment | None:
    """The segment ``seg`` as it is now, or None when it is gone. A file may go while it is
    read (a writer renames its temporary files into place; a segment is removed): it is left
    out rather than failing the whole check."""
    try:
        ended, size = seg.stat().st_mtime, 0
        for f in seg.rglob("*"):
            try:
                st = f.stat()
            except FileNotFoundError:
                continue
            if stat.S_ISREG(st.st_mode):
                ended, size = max(ended, st.st_mtime), size + st.st_size
    except FileNotFoundError:
        return None
    return Segment(seg, name, ended, size)


def apply_retention(out: Path, retention: Retention, in_use: Iterable[str],
                    now: float) -> list[Segment]:
    """Remove the segments ``retention`` no longer keeps (never those ``in_use``, names
    ``CAMERA/SEGMENT``) and their events from the store; the segments removed."""
    if not retention.active or not Path(out).is_dir():
        return []
    everything = segments(out)
    newest = {s.name.split("/")[0]: s.name for s in everything}   # each camera's latest
    busy = set(in_use) | set(newest.values())   # a segment just started may not be reported yet
    found = [s for s in everything if s.name not in busy]
    doomed: list[Segment] = []
    if retention.keep_days is not None:
        doomed = [s for s in found if now - s.ended > retention.keep_days * _DAY]
    if retention.keep_gb is not None:
        total = sum(s.bytes for s in everything) - sum(s.bytes for s in doomed)
        for s in found:
            if total <= retention.keep_gb * 1e9:
                break
            if s not in doomed:
                doomed.append(s)
                total -= s.bytes
    # the store forgets the events first: a reader never finds an event whose snapshot or
    # clip is already gone (a segment that then cannot be removed is tried again next time)
    _forget(Path(out) / STORE_NAME, [s.name for s in doomed])
    removed = []
    for s in doomed:
        try:
            shutil.rmtree(s.path)
        except OSError as exc:
            log.warning("retention: cannot remove %s: %s", s.path, exc)
            continue
        log.info("retention: removed %s (%.1f MB, ended %s)", s.name, s.bytes / 1e6,
                 time.strftime("%Y-%m-%d %H:%M", time.localtime(s.ended)))
        removed.append(s)
    return removed


def _forget(store: Path, names: list[str]) -> None:
    if not names or not store.is_file():
        return
    with EventStore(store) as s:
        n = s.forget_segments(names)
    log.info("retention: %d events of %d segment(s) left the event store", n, len(names))


class RetentionThread:
    """:func:`apply_retention` every ``every_s`` seconds until :meth:`stop`; ``in_use`` gives
    the segments the cameras are writing, ``clock`` the time (:func:`time.time`)."""

    def __init__(self, out: Path, retention: Retention, in_use: Callable[[], Iterable[str]],
                 every_s: float = CHECK_EVERY_S, clock: Callable[[], float] = time.time) -> None:
        self.out, self.retention, self.in_use, self.every_s = out, retention, in_use, every_s
        self.clock = clock
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="retention", daemon=True)

    def start(self) -> None:
        if self.retention.active:
            self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.every_s):
            try:
                apply_retention(self.out, self.retention, self.in_use(), self.clock())
            except Exception as exc:   # noqa: BLE001 - the next check tries again
                log.warning("retention: %s", exc)

    def stop(self) -> None:
        """End the checks; a check under way finishes first (it removes whole folders)."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
