"""``motiontrack events``: search the event store of a run, a batch or a ``serve`` output folder."""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from datetime import datetime


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "events", help="search the events a run, batch or serve stored (events.db)",
        description="List the events of an event store (events.db of a `track --scene`, `batch` "
                    "or `serve` output folder), newest first, filtered by camera, type, rule "
                    "(line or zone name), class and time. Times are ISO dates or times "
                    "(2026-12-01, 2026-12-01T18:00, with Z or +02:00, else local time) or a "
                    "time ago (30m, 24h, 7d).")
    p.add_argument("store", metavar="DB_OR_FOLDER",
                   help="an events.db file, or the folder holding one")
    p.add_argument("--camera", help="only this camera (a serve camera, or a batch video's name)")
    p.add_argument("--type", help="only this event type (line_cross, loiter, abandoned, ...)")
    p.add_argument("--rule", help="only events of this line or zone")
    p.add_argument("--class", dest="klass", metavar="CLASS", help="only objects of this class")
    p.add_argument("--since", metavar="TIME", help="only events at or after TIME")
    p.add_argument("--until", metavar="TIME", help="only events before TIME")
    p.add_argument("--limit", metavar="N", help="at most N events")
    p.add_argument("--offset", metavar="N", help="skip the first N events")
    p.add_argument("--oldest-first", action="store_true", help="oldest first")
    fmt = p.add_mutually_exclusive_group()
    fmt.add_argument("--json", action="store_true", help="one JSON object per line")
    fmt.add_argument("--csv", action="store_true", help="CSV with a header row")
    fmt.add_argument("--totals", choices=("hour", "day"),
                     help="counts per camera, type and hour or day (local time), and over every "
                          "camera, instead")
    p.set_defaults(func=cmd_events)


#: the camera column of the totals over every camera
ALL_CAMERAS = "(all)"
#: the columns of the table and the CSV
COLUMNS = ("id", "time", "camera", "type", "rule", "class", "track", "frame", "snapshot", "clip")


def local_time(epoch: float) -> str:
    """``epoch`` as local ISO time with its offset (``2026-12-01T18:00:05+01:00``)."""
    return datetime.fromtimestamp(epoch).astimezone().isoformat(timespec="seconds")


def cmd_events(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from ..io.event_store import EventStore, query_from

    params = {"camera": args.camera, "type": args.type, "rule": args.rule, "class": args.klass,
              "since": args.since, "until": args.until, "limit": args.limit,
              "offset": args.offset}
    query = replace(query_from(params, time.time()), oldest_first=args.oldest_first)
    with EventStore(args.store, readonly=True) as store:
        if args.totals:
            return _print_totals(store, query, 3600.0 if args.totals == "hour" else 86400.0)
        rows = store.search(query)
    if args.json:
        for e in rows:
            sys.stdout.write(json.dumps(e.as_dict()) + "\n")
        return 0
    table = [(e.id, local_time(e.end), e.camera, e.type, e.rule or "", e.klass or "",
              "" if e.track is None else e.track, "" if e.frame is None else e.frame,
              e.snapshot or "", e.clip or "") for e in rows]
    if args.csv:
        w = csv.writer(sys.stdout, lineterminator="\n")
        w.writerow(COLUMNS)
        w.writerows(table)
        return 0
    _print_table(COLUMNS[:8], [r[:8] for r in table])
    print(f"{len(rows)} event{'s' * (len(rows) != 1)}", file=sys.stderr)
    return 0


def _print_totals(store, query, bin_s: float) -> int:
    offset = datetime.now().astimezone().utcoffset()
    rows = store.totals(bin_s, query, utc_offset_s=offset.total_seconds() if offset else 0.0)
    table = [(c, local_time(start), t, n) for c, start, t, n in rows]
    if len({c for c, *_ in rows}) > 1:   # and over every camera
        every: dict[tuple[float, str], int] = {}
        for _, start, t, n in rows:
            every[start, t] = every.get((start, t), 0) + n
        table += [(ALL_CAMERAS, local_time(start), t, n) for (start, t), n in sorted(every.items())]
    _print_table(("camera", "from", "type", "count"), table)
    return 0


def _print_table(header, rows) -> None:
    from ..errors import printable

    text = [[printable(str(v)) for v in r] for r in [header, *rows]]
    widths = [max(len(r[k]) for r in text) for k in range(len(header))]
    for r in text:
        print("  ".join(v.ljust(w) for v, w in zip(r, widths)).rstrip())
