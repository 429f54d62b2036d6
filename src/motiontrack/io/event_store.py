"""The event store: scene-analytics events in one SQLite file (``events.db``), searchable.

Beside the portable ``events.jsonl`` of each run, ``track --scene``, ``batch`` and ``serve``
keep their events in an SQLite database (the standard library's :mod:`sqlite3`) so that "every
loitering event at the gate last night" is one query (``motiontrack events``, ``serve``'s
``/api/events/search``). The file is in WAL mode: readers (a query, the browser) never block
the writer, and the writer commits at least once a second (:attr:`EventStore.commit_every_s`),
so a killed process loses at most the events of its last second and never leaves the file
inconsistent. Several processes may write one store (``serve``'s cameras and its retention):
each waits up to :data:`BUSY_TIMEOUT_MS` for another's write lock.

The schema is versioned with SQLite's ``user_version``: :data:`MIGRATIONS` lists the statements
that bring a file from one version to the next, applied in one transaction when a writer opens
an older file; a file of a newer version than this code knows is refused (a reader must not
guess at columns it does not know).

Columns of ``events``: ``id`` (order of arrival), ``camera`` (the camera, or the video of a
``track``/``batch`` run), ``segment`` (the run folder's name within the store's folder),
``type``, ``rule`` (the line or zone the event is about, when it has one), ``class`` (the
class of the event's track, its ``label``), ``track``, ``frame``, ``t`` (seconds into the
source), ``start``/``end`` (epoch seconds: ``end`` is when the event happened, ``start`` is
``end`` minus its ``dwell_s`` or ``duration_s``, else equal), ``x``, ``y``, ``snapshot``,
``clip`` (paths relative to the store's folder, or NULL), ``data`` (the event's JSON object as
in ``events.jsonl``) and ``clip_offset`` (seconds into the clip where the event's own seconds
start: events whose clips overlap share one).
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import sqlite3
import threading
import time
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

from ..errors import InputError
from .atomic import DiskFullError

__all__ = ["EventStore", "EventQuery", "StoredEvent", "STORE_NAME", "SCHEMA_VERSION",
           "MIGRATIONS", "store_path", "parse_time", "query_from", "remove_store"]

#: the store's file name in a run or serve output folder
STORE_NAME = "events.db"
#: how long a writer waits for another's write lock before it fails (milliseconds)
BUSY_TIMEOUT_MS = 60_000

#: ``MIGRATIONS[k]`` brings a file of version ``k`` to version ``k + 1``
MIGRATIONS: tuple[tuple[str, ...], ...] = (
    ("""CREATE TABLE events (
            id INTEGER PRIMARY KEY,
            camera TEXT NOT NULL,
            segment TEXT,
            type TEXT NOT NULL,
            rule TEXT,
            class TEXT,
            track INTEGER,
            frame INTEGER,
            t REAL,
            start REAL NOT NULL,
            "end" REAL NOT NULL,
            x REAL,
            y REAL,
            snapshot TEXT,
            clip TEXT,
            data TEXT NOT NULL)""",
     "CREATE INDEX events_camera_end ON events (camera, \"end\")",
     "CREATE INDEX events_type_end ON events (type, \"end\")",
     "CREATE INDEX events_rule_end ON events (rule, \"end\")",
     "CREATE INDEX events_end ON events (\"end\")"),
    # events whose clips overlap share one: where each event's own seconds start in it
    ("ALTER TABLE events ADD COLUMN clip_offset REAL",),
)
SCHEMA_VERSION = len(MIGRATIONS)

#: the event keys that name the rule's line or zone, in the order they are looked for
_RULE_KEYS = ("line", "zone", "rule")
#: the event keys that name the object's class (``label``: the class of the event's track)
_CLASS_KEYS = ("class", "label")
#: the event keys that say how long the event lasted before it was reported
_DURATION_KEYS = ("dwell_s", "duration_s")
_COLUMNS = ("id", "camera", "segment", "type", "rule", "class", "track", "frame", "t", "start",
            "end", "x", "y", "snapshot", "clip", "data", "clip_offset")


def store_path(path: str | Path) -> Path:
    """The database of ``path``: the file itself, or ``events.db`` of a folder."""
    p = Path(path)
    return p / STORE_NAME if p.is_dir() else p


def remove_store(path: str | Path, journal_only: bool = False) -> None:
    """Remove the store file ``path`` and its WAL journal beside it (``-wal``, ``-shm``), or
    the journal alone (a killed writer's, when its file is gone)."""
    for suffix in ("-wal", "-shm") if journal_only else ("", "-wal", "-shm"):
        with contextlib.suppress(FileNotFoundError):
            Path(f"{path}{suffix}").unlink()


@dataclass(frozen=True)
class EventQuery:
    """Which events a search returns: each given filter must hold (``None``: any); ``since``
    and ``until`` are epoch seconds bounding the event's ``end`` (``since`` <= end < ``until``);
    newest first unless ``oldest_first``; at most ``limit`` after skipping ``offset``."""

    camera: str | None = None
    type: str | None = None
    rule: str | None = None
    klass: str | None = None
    since: float | None = None
    until: float | None = None
    limit: int | None = None
    offset: int = 0
    oldest_first: bool = False

    def where(self) -> tuple[str, list[Any]]:
        """The SQL condition and its parameters."""
        parts, args = [], []
        for column, value in (("camera", self.camera), ("type", self.type), ("rule", self.rule),
                              ("class", self.klass)):
            if value is not None:
                parts.append(f'"{column}" = ?')
                args.append(value)
        if self.since is not None:
            parts.append('"end" >= ?')
            args.append(float(self.since))
        if self.until is not None:
            parts.append('"end" < ?')
            args.append(float(self.until))
        return (" WHERE " + " AND ".join(parts)) if parts else "", args


@dataclass(frozen=True)
class StoredEvent:
    """One row of the store (see the module docstring for the columns); ``event`` is the
    event's JSON object."""

    id: int
    camera: str
    segment: str | None
    type: str
    rule: str | None
    klass: str | None
    track: int | None
    frame: int | None
    t: float | None
    start: float
    end: float
    x: float | None
    y: float | None
    snapshot: str | None
    clip: str | None
    event: dict[str, Any]
    clip_offset: float | None = None

    def as_dict(self) -> dict[str, Any]:
        """The row as a JSON object (``class`` under its own name)."""
        return {"id": self.id, "camera": self.camera, "segment": self.segment, "type": self.type,
                "rule": self.rule, "class": self.klass, "track": self.track, "frame": self.frame,
                "t": self.t, "start": self.start, "end": self.end, "x": self.x, "y": self.y,
                "snapshot": self.snapshot, "clip": self.clip, "clip_offset": self.clip_offset,
                "event": self.event}


class EventStore:
    """An ``events.db`` opened for writing (``readonly=False``: created when missing, migrated
    when older) or for searching only.

    ``clock`` gives the seconds that pace the commits (:func:`time.monotonic`; tests inject
    their own). Use as a context manager or call :meth:`close`, which commits.
    """

    commit_every_s = 1.0

    def __init__(self, path: str | Path, readonly: bool = False,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.path = store_path(path)
        self.readonly = readonly
        self._clock = clock
        if readonly and not self.path.is_file():
            raise InputError(f"no event store at {self.path}")
        if not readonly and not self.path.exists():
            self._create()
        try:
            if readonly:
                self._db = sqlite3.connect(f"{self.path.resolve().as_uri()}?mode=ro", uri=True,
                                           check_same_thread=False)
            else:
                self._db = sqlite3.connect(self.path, check_same_thread=False)
            # several processes write one store (serve's cameras and its retention), each
            # holding the write lock for a few milliseconds: waiting is fine, failing is not
            self._db.execute(f"PRAGMA busy_timeout = {5000 if readonly else BUSY_TIMEOUT_MS}")
            version = self._db.execute("PRAGMA user_version").fetchone()[0]
        except sqlite3.DatabaseError as exc:
            raise InputError(f"{self.path}: not an event store ({exc})") from None
        if version > SCHEMA_VERSION:
            self._db.close()
            raise InputError(f"{self.path}: event store version {version} is newer than this "
                             f"motiontrack reads ({SCHEMA_VERSION}); upgrade motiontrack")
        if readonly and version < SCHEMA_VERSION:
            self._db.close()
            raise InputError(f"{self.path}: event store version {version}: open it for writing "
                             f"once (any run into its folder) to bring it to {SCHEMA_VERSION}")
        if not readonly:
            with self._full():
                self._db.execute("PRAGMA journal_mode = WAL")
                self._db.execute("PRAGMA synchronous = NORMAL")
                self._migrate(version)
        self._last_commit = clock()
        self._pending = 0

    def _create(self) -> None:
        """A new store appears whole: made under a temporary name, then linked into place (a
        reader never finds a file without its tables; when another writer made it first, its
        file is kept)."""
        tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.{threading.get_ident()}.new")
        tmp.unlink(missing_ok=True)
        try:
            db = sqlite3.connect(tmp)
            try:
                with self._full():
                    with db:
                        for steps in MIGRATIONS:
                            for statement in steps:
                                db.execute(statement)
                        db.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            finally:
                db.close()
            try:
                os.link(tmp, self.path)
            except FileExistsError:
                pass
        except sqlite3.OperationalError as exc:
            raise InputError(f"cannot create the event store {self.path}: {exc}") from None
        finally:
            tmp.unlink(missing_ok=True)

    def _migrate(self, version: int) -> None:
        if version == SCHEMA_VERSION:
            return
        with self._db:   # one transaction: a file is at one version or the next, never between
            for steps in MIGRATIONS[version:]:
                for statement in steps:
                    self._db.execute(statement)
            self._db.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")

    # ------------------------------------------------------------------ writing
    def add(self, event: dict[str, Any], camera: str, when: float, segment: str | None = None,
            snapshot: str | None = None, clip: str | None = None,
            clip_offset: float | None = None, commit: bool = True) -> int:
        """Store ``event`` (an ``events.jsonl`` object) of ``camera``, which happened at epoch
        second ``when``; returns its id. Committed within :attr:`commit_every_s`; with
        ``commit=False`` not before the caller's next :meth:`set_media` or :meth:`tick`, so
        that a snapshot named by the id is recorded with the event (no reader sees the
        event without it)."""
        duration = next((float(event[k]) for k in _DURATION_KEYS
                         if isinstance(event.get(k), (int, float))), 0.0)
        rule = next((str(event[k]) for k in _RULE_KEYS if event.get(k) is not None), None)
        klass = next((str(event[k]) for k in _CLASS_KEYS if event.get(k) is not None), None)
        with self._full():
            cur = self._db.execute(
                'INSERT INTO events (camera, segment, type, rule, class, track, frame, t, start, '
                '"end", x, y, snapshot, clip, data, clip_offset) '
                'VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)',
                (camera, segment, str(event.get("type")), rule, klass,
                 event.get("track"), event.get("frame"), event.get("t"), when - duration, when,
                 event.get("x"), event.get("y"), snapshot, clip, json.dumps(event),
                 clip_offset))
        self._pending += 1
        if commit:
            self.tick()
        return int(cur.lastrowid)

    def set_media(self, event_id: int, snapshot: str | None = None, clip: str | None = None,
                  clip_offset: float | None = None) -> None:
        """Record the snapshot and clip of an event once they are written (``clip_offset``:
        seconds into the clip where the event's own seconds start)."""
        with self._full():
            self._db.execute("UPDATE events SET snapshot = COALESCE(?, snapshot), "
                             "clip = COALESCE(?, clip), clip_offset = COALESCE(?, clip_offset) "
                             "WHERE id = ?", (snapshot, clip, clip_offset, event_id))
        self._pending += 1
        self.tick()

    def forget_segments(self, names: list[str]) -> int:
        """Remove the events of the segments ``names`` (their folders are gone); how many."""
        with self._full():
            n = 0
            for name in names:
                n += self._db.execute("DELETE FROM events WHERE segment = ?", (name,)).rowcount
            self._db.commit()
        return n

    @property
    def pending(self) -> int:
        """Changes made since the last commit."""
        return self._pending

    def tick(self) -> bool:
        """Commit when the last commit is :attr:`commit_every_s` old (call it every frame);
        whether it committed."""
        if self._pending and self._clock() - self._last_commit >= self.commit_every_s:
            self.commit()
            return True
        return False

    def commit(self) -> None:
        if not self.readonly:
            with self._full():
                self._db.commit()
        self._pending = 0
        self._last_commit = self._clock()

    def rollback(self) -> None:
        """Forget what was added since the last commit (after a :class:`DiskFullError`)."""
        self._db.rollback()
        self._pending = 0

    @contextlib.contextmanager
    def _full(self) -> Iterator[None]:
        """SQLite's "database or disk is full" as the :class:`DiskFullError` every output
        raises when its device fills."""
        try:
            yield
        except sqlite3.OperationalError as exc:
            text = str(exc)
            if "full" in text or "quota" in text or ("I/O error" in text and _nearly_full(self.path)):
                raise DiskFullError(self.path, text) from None   # its journal could not grow
            if "I/O error" in text or "readonly" in text or "unable to open" in text:
                raise InputError(f"cannot write the event store {self.path}: {text}") from None
            raise

    # ------------------------------------------------------------------ searching
    def search(self, query: EventQuery = EventQuery()) -> list[StoredEvent]:
        """The events ``query`` selects."""
        where, args = query.where()
        order = "ASC" if query.oldest_first else "DESC"
        sql = (f'SELECT {", ".join(_quoted(c) for c in _COLUMNS)} FROM events{where} '
               f'ORDER BY "end" {order}, id {order}')
        if query.limit is not None or query.offset:
            sql += " LIMIT ? OFFSET ?"
            args += [-1 if query.limit is None else int(query.limit), int(query.offset)]
        return [_row(r) for r in self._db.execute(sql, args)]

    def get(self, event_id: int) -> StoredEvent | None:
        """The event ``event_id``, or None."""
        row = self._db.execute(f'SELECT {", ".join(_quoted(c) for c in _COLUMNS)} FROM events '
                               'WHERE id = ?', (int(event_id),)).fetchone()
        return _row(row) if row is not None else None

    def count(self, query: EventQuery = EventQuery()) -> int:
        """How many events ``query`` selects, ignoring its limit and offset."""
        where, args = query.where()
        return int(self._db.execute(f"SELECT COUNT(*) FROM events{where}", args).fetchone()[0])

    def totals(self, bin_s: float = 3600.0, query: EventQuery = EventQuery(),
               utc_offset_s: float = 0.0) -> list[tuple[str, float, str, int]]:
        """``(camera, bin start, type, count)`` of the events ``query`` selects in bins of
        ``bin_s`` seconds (3600: hours, 86400: days, days starting at midnight of the time zone
        ``utc_offset_s`` east of UTC), ordered by camera, bin and type."""
        where, args = query.where()
        sql = (f'SELECT camera, CAST((("end" + ?) / ?) AS INTEGER) AS k, type, COUNT(*) '
               f'FROM events{where} GROUP BY camera, k, type ORDER BY camera, k, type')
        rows = self._db.execute(sql, [utc_offset_s, bin_s, *args])
        return [(c, k * bin_s - utc_offset_s, t, int(n)) for c, k, t, n in rows]

    def __iter__(self) -> Iterator[StoredEvent]:
        return iter(self.search(EventQuery(oldest_first=True)))

    def close(self, finished: bool = False) -> None:
        """Commit and close; ``finished``: no one writes to the file again (a run's own store
        at its end), so it leaves WAL mode and is one self-contained file, which readers open
        without creating a journal beside it."""
        if self._db is not None:
            self.commit()
            if finished and not self.readonly:
                with contextlib.suppress(sqlite3.OperationalError):   # another reader: stay WAL
                    self._db.execute("PRAGMA journal_mode = DELETE")
            self._db.close()
            self._db = None  # type: ignore[assignment]

    def __enter__(self) -> "EventStore":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


_AGO = re.compile(r"^(\d+(?:\.\d+)?)\s*([smhdw])$")
_UNIT_S = {"s": 1, "m": 60, "h": 3600, "d": 86400, "w": 7 * 86400}


def parse_time(text: str, now: float, what: str = "time") -> float:
    """Epoch seconds of ``text``: an ISO 8601 date or date and time (``2026-12-01``,
    ``2026-12-01T18:00``, with ``Z`` or ``+02:00`` or else in local time), or a time before
    ``now`` (``30m``, ``24h``, ``7d``, ``2w``)."""
    t = text.strip()
    ago = _AGO.match(t)
    if ago:
        return now - float(ago.group(1)) * _UNIT_S[ago.group(2)]
    try:
        when = datetime.fromisoformat(t.replace("Z", "+00:00").replace(" ", "T", 1))
    except ValueError:
        raise InputError(f"{what} must be an ISO date or time (2026-12-01, 2026-12-01T18:00, "
                         f"...Z or ...+02:00) or a time ago (30m, 24h, 7d), got {t[:40]!r}") from None
    return when.timestamp()   # a naive time is local time


#: the filters of a search, as the command line and the web API name them
QUERY_KEYS = ("camera", "type", "rule", "class", "since", "until", "limit", "offset")


def query_from(params: dict[str, str | None], now: float, max_limit: int | None = None
               ) -> EventQuery:
    """The :class:`EventQuery` of filters given as text (:data:`QUERY_KEYS`; missing or None:
    any); ``max_limit`` bounds ``limit`` (and is its default)."""
    unknown = sorted(set(k for k, v in params.items() if v is not None) - set(QUERY_KEYS))
    if unknown:
        raise InputError(f"unknown filter {unknown[0]!r}; filters: {', '.join(QUERY_KEYS)}")
    when = {k: parse_time(params[k], now, k) if params.get(k) is not None else None
            for k in ("since", "until")}
    return EventQuery(camera=params.get("camera"), type=params.get("type"),
                      rule=params.get("rule"), klass=params.get("class"), since=when["since"],
                      until=when["until"], limit=_whole(params, "limit", 1, max_limit, max_limit),
                      offset=_whole(params, "offset", 0, 0) or 0)


def _whole(params: dict[str, str | None], key: str, lo: int, default: int | None,
           most: int | None = None) -> int | None:
    """The whole number ``params[key]`` (at least ``lo``, at most ``most``), or ``default``."""
    v = params.get(key)
    if v is None:
        return default
    if not re.fullmatch(r"\d{1,9}", v.strip()):
        raise InputError(f"{key} must be a whole number >= {lo}, got {v[:40]!r}")
    n = int(v)
    if n < lo:
        raise InputError(f"{key} must be a whole number >= {lo}, got {n}")
    return n if most is None else min(n, most)


def _nearly_full(path: Path) -> bool:
    """Whether the device of ``path`` has under 1 MiB free (SQLite says "disk I/O error" when
    its shared-memory or journal file cannot grow)."""
    try:
        return shutil.disk_usage(path.parent).free < 1 << 20
    except OSError:
        return False


def _quoted(column: str) -> str:
    return f'"{column}"'


_DATA = _COLUMNS.index("data")


def _row(r: Iterable[Any]) -> StoredEvent:
    v = list(r)
    v[_DATA] = json.loads(v[_DATA])
    return StoredEvent(*v)
