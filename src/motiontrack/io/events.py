"""Events files (``events.jsonl``): a header object, then one scene-analytics event per line.

The header is :func:`motiontrack.types.events_header` (``schema``, ``version``, ``fps``,
``source``, ``scene``); each further non-empty line is one :meth:`Event.to_json` object
(``docs/analytics.md``), or a ``{"type": "discontinuity", "reason", "frame"}`` record where the
source jumped (:class:`~motiontrack.types.Discontinuity`). Reading checks the schema name and version and every event, and names
the file and line of the first problem in one :class:`~motiontrack.errors.InputError`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping

from ..errors import InputError, excerpt, location
from ..types import EVENTS_SCHEMA, EVENTS_SCHEMA_VERSION, Discontinuity, Event, events_header
from .atomic import atomic_write_text
from .textfile import read_text

__all__ = ["EventsFile", "is_events_file", "read_events", "write_events", "format_events",
           "MAX_EVENTS_BYTES"]

#: largest events file read (a day of a busy camera is a few MB)
MAX_EVENTS_BYTES = 512 * 2**20


@dataclass(frozen=True)
class EventsFile:
    """An events file's header and events (in file order), and its discontinuity records as
    ``(frame, Discontinuity)``."""

    header: Mapping = field(default_factory=dict)
    events: tuple[Event, ...] = ()
    discontinuities: tuple[tuple[int, Discontinuity], ...] = ()

    @property
    def fps(self) -> float:
        return float(self.header.get("fps", 0.0))


def _no_constants(token: str) -> None:
    raise ValueError(f"{token} is not a number JSON allows")


def _parse_line(line: str, where: str) -> object:
    try:
        return json.loads(line, parse_constant=_no_constants)
    except (json.JSONDecodeError, ValueError, RecursionError) as exc:
        msg = exc.msg if isinstance(exc, json.JSONDecodeError) else str(exc) or "too deeply nested"
        raise InputError(f"{where}: not a JSON object ({msg})") from None


def _check_header(obj: object, where: str) -> dict:
    if not isinstance(obj, dict) or obj.get("schema") != EVENTS_SCHEMA:
        raise InputError(f"{where}: not an events file: the first line must be the header "
                         f'{{"schema": "{EVENTS_SCHEMA}", "version": ...}}')
    version = obj.get("version")
    if isinstance(version, bool) or not isinstance(version, int):
        raise InputError(f"{where}: header version must be an integer, got {excerpt(version)}")
    if version > EVENTS_SCHEMA_VERSION or version < 1:
        raise InputError(f"{where}: events schema version {version}; this motiontrack reads "
                         f"version {EVENTS_SCHEMA_VERSION}")
    fps = obj.get("fps")
    if fps is not None and (isinstance(fps, bool) or not isinstance(fps, (int, float))
                            or not math.isfinite(fps) or fps <= 0):
        raise InputError(f"{where}: header fps must be a number > 0, got {excerpt(fps)}")
    return obj


def is_events_file(path: str | Path) -> bool:
    """Whether ``path`` is a file whose first non-empty line is a JSON object naming the events
    schema (other files, tracks files for instance, are not; a missing file neither)."""
    try:
        with open(path, "rb") as fh:
            for raw in fh:
                if raw.strip():
                    break
            else:
                return False
    except OSError:
        return False
    try:
        obj = json.loads(raw[:1_000_000].decode("utf-8-sig"))
    except (ValueError, UnicodeDecodeError, RecursionError):
        return False
    return isinstance(obj, dict) and obj.get("schema") == EVENTS_SCHEMA


def read_events(path: str | Path) -> EventsFile:
    """Read an events file.

    Raises
    ------
    InputError
        Missing or unreadable file, no header or another schema, a newer schema version, a
        line that is not JSON or not an event of this schema (named by file and line).
    """
    p = Path(path)
    text = read_text(p, "events file", MAX_EVENTS_BYTES, encoding="utf-8")
    header: dict | None = None
    events: list[Event] = []
    cuts: list[tuple[int, Discontinuity]] = []
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        where = location(p, number)
        obj = _parse_line(line, where)
        if header is None:
            header = _check_header(obj, where)
            continue
        try:
            if isinstance(obj, dict) and obj.get("type") == "discontinuity":
                cuts.append(_discontinuity(obj))
            else:
                events.append(Event.from_json(obj))
        except (ValueError, TypeError) as exc:
            raise InputError(f"{where}: {exc}") from None
    if header is None:
        raise InputError(f"events file {location(p)} is empty: it needs at least the header line")
    return EventsFile(header, tuple(events), tuple(cuts))


def _discontinuity(obj: dict) -> tuple[int, Discontinuity]:
    """A discontinuity record: ``{"type": "discontinuity", "reason": ..., "frame": N}``."""
    extra = sorted(set(obj) - {"type", "reason", "frame"})
    if extra:
        raise ValueError(f"discontinuity record has unknown keys {', '.join(extra)}")
    frame = obj.get("frame")
    if isinstance(frame, bool) or not isinstance(frame, int) or frame < 1:
        raise ValueError(f"discontinuity frame must be an integer >= 1, got {frame!r}")
    return frame, Discontinuity(obj.get("reason"))


def format_events(events: Iterable[Event], header: Mapping) -> str:
    """The text of an events file: ``header`` on the first line, then one event per line."""
    lines = [json.dumps(dict(header))] + [json.dumps(e.to_json()) for e in events]
    return "\n".join(lines) + "\n"


def write_events(path: str | Path, events: Iterable[Event], fps: float, source: str = "",
                 scene: str = "") -> None:
    """Write an events file atomically (header from :func:`events_header`)."""
    atomic_write_text(path, format_events(events, events_header(fps, source, scene)))
