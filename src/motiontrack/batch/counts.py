"""The event counts of a batch's videos run with a scene: ``counts.csv`` and ``totals.json``.

Each finished video run with a scene has the scene's totals in its ``summary.json``
(``"analytics"``: each line's ``in`` and ``out`` crossings, each zone's ``enters`` and
``exits``, the events of each type). They are gathered here into two files beside the index:

* ``RESULTS/counts.csv``, tidy, one row per video × rule × name × measure (scenes differ from
  video to video, so one column per line or zone would not fit them all):
  ``video,kind,name,measure,count`` with ``kind`` ``line`` (measures ``in``, ``out``) or
  ``zone`` (measures ``enters``, ``exits``), in the batch's video order, then the scene's order;
* ``RESULTS/totals.json``, the same counts summed over the finished videos by line and zone
  name, and the events of each type: ``{"videos": [names], "lines": {name: {"in", "out"}},
  "zones": {name: {"enters", "exits"}}, "events": {type: count}}``.

Only finished videos count (``done``, and ``truncated`` with the events up to where its source
ended); a batch without a video run with a scene writes neither file (and removes those of an
earlier batch into the same folder).
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any, Mapping, Sequence

from ..io.atomic import atomic_write_text
from ..run.folder import RunFolder
from .combined import FINISHED

__all__ = ["COUNTS_FILE", "TOTALS_FILE", "COUNT_COLUMNS", "MEASURES", "count_rows",
           "totals_of", "write_counts"]

COUNTS_FILE = "counts.csv"
TOTALS_FILE = "totals.json"
COUNT_COLUMNS = ("video", "kind", "name", "measure", "count")
#: the measures of each kind of rule, in the order of ``counts.csv``; all are sums over a video
MEASURES: dict[str, tuple[str, ...]] = {"line": ("in", "out"), "zone": ("enters", "exits")}
_SECTIONS = {"line": "lines", "zone": "zones"}


def _analytics(results: Path, row: Mapping[str, Any]) -> Mapping[str, Any] | None:
    """The ``analytics`` section of a finished (``done`` or ``truncated``: its events up to
    where the source ended) video's ``summary.json``, or None (no scene)."""
    if row.get("status") not in FINISHED:
        return None
    summary = RunFolder(Path(results) / str(row["name"])).summary()
    section = summary.get("analytics") if isinstance(summary, dict) else None
    return section if isinstance(section, dict) else None


def _count(value: Any) -> int:
    try:
        return int(value)
    except (TypeError, ValueError):
        return 0


def count_rows(results: Path, rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The rows of ``counts.csv`` for the finished (``done`` or ``truncated``) videos of ``rows`` run with a scene."""
    out: list[dict[str, Any]] = []
    for r in rows:
        section = _analytics(results, r)
        if section is None:
            continue
        for kind, measures in MEASURES.items():
            named = section.get(_SECTIONS[kind])
            for name, values in (named.items() if isinstance(named, dict) else ()):
                values = values if isinstance(values, dict) else {}
                out += [{"video": r["name"], "kind": kind, "name": name, "measure": m,
                         "count": _count(values.get(m))} for m in measures]
    return out


def totals_of(results: Path, rows: Sequence[Mapping[str, Any]]) -> dict[str, Any] | None:
    """``totals.json``: the counts of every finished video run with a scene summed by line and
    zone name, and its events by type; None when no video was run with a scene."""
    videos: list[str] = []
    totals: dict[str, dict[str, dict[str, int]]] = {"lines": {}, "zones": {}}
    events: dict[str, int] = {}
    for r in rows:
        section = _analytics(results, r)
        if section is None:
            continue
        videos.append(str(r["name"]))
        for t, n in (section.get("events") or {}).items():
            events[t] = events.get(t, 0) + _count(n)
    for c in count_rows(results, rows):
        named = totals[_SECTIONS[c["kind"]]].setdefault(
            c["name"], {m: 0 for m in MEASURES[c["kind"]]})
        named[c["measure"]] += c["count"]
    if not videos:
        return None
    return {"videos": videos, **totals, "events": events}


def write_counts(results: Path, rows: Sequence[Mapping[str, Any]]) -> dict[str, Any] | None:
    """Write ``RESULTS/counts.csv`` and ``RESULTS/totals.json`` (atomically; both removed when
    no finished video was run with a scene); returns the totals."""
    results = Path(results)
    totals = totals_of(results, rows)
    if totals is None:
        for name in (COUNTS_FILE, TOTALS_FILE):
            (results / name).unlink(missing_ok=True)
        return None
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COUNT_COLUMNS, lineterminator="\n")
    w.writeheader()
    w.writerows(count_rows(results, rows))
    atomic_write_text(results / COUNTS_FILE, buf.getvalue())
    atomic_write_text(results / TOTALS_FILE, json.dumps(totals, indent=2) + "\n")
    return totals
