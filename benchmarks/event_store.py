"""The event store's search: filtered queries over 10,000 stored events.

A store of ``--events`` events (default 10,000) of 4 cameras over one week (line crossings,
zone entries and exits, loitering, stationary and abandoned objects, 6 lines and zones) is
written with :class:`motiontrack.io.event_store.EventStore`; then each query below runs
``--rounds`` times on a fresh read-only connection, as ``motiontrack events`` and serve's
``/api/events/search`` open it, and its wall time (open, search of one page of 100, count,
close) is reported as median and maximum, beside the target of 50 ms.

Run: .venv/bin/python benchmarks/event_store.py [--events 10000] [--rounds 21]
"""

from __future__ import annotations

import argparse
import random
import statistics
import tempfile
import time
from pathlib import Path

from motiontrack.io.event_store import EventQuery, EventStore

TARGET_MS = 50.0
WEEK = 7 * 86400.0
TYPES = ("line_cross", "zone_enter", "zone_exit", "loiter", "stationary_start", "abandoned")
RULES = ("gate", "door", "bench", "yard", "lot", "lobby")
CAMERAS = ("gate", "lobby", "yard", "lot")


def fill(path: Path, n: int, now: float, seed: int = 0) -> None:
    rng = random.Random(seed)
    with EventStore(path) as store:
        for k in range(n):
            kind = rng.choice(TYPES)
            rule = rng.choice(RULES)
            event = {"type": kind, "frame": k + 1, "t": k * 0.04, "track": rng.randrange(500),
                     "x": rng.uniform(0, 640), "y": rng.uniform(0, 480),
                     ("line" if kind == "line_cross" else "zone"): rule}
            if kind in ("zone_exit", "loiter"):
                event["dwell_s"] = round(rng.uniform(1, 120), 2)
            store.add(event, rng.choice(CAMERAS), now - WEEK + WEEK * k / n, "seg")
        store.close(finished=True)


def queries(now: float) -> list[tuple[str, EventQuery]]:
    night = now - 86400.0
    return [
        ("newest 100", EventQuery(limit=100)),
        ("one camera", EventQuery(camera="gate", limit=100)),
        ("loiter at the gate last night", EventQuery(camera="gate", type="loiter",
                                                     since=night - 12 * 3600, until=night,
                                                     limit=100)),
        ("one rule, a day", EventQuery(rule="bench", since=night, limit=100)),
        ("page 11 of one type", EventQuery(type="line_cross", limit=100, offset=1000)),
    ]


def time_query(path: Path, query: EventQuery) -> float:
    t0 = time.perf_counter()
    with EventStore(path, readonly=True) as store:
        store.search(query)
        store.count(query)
    return (time.perf_counter() - t0) * 1000.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--events", type=int, default=10_000)
    ap.add_argument("--rounds", type=int, default=21)
    args = ap.parse_args()
    now = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "events.db"
        t0 = time.perf_counter()
        fill(db, args.events, now)
        wrote = time.perf_counter() - t0
        print(f"{args.events} events written in {wrote:.2f} s "
              f"({args.events / wrote:,.0f} events/s, committed each second)")
        print(f"{'query':<32} {'matches':>8} {'median ms':>10} {'max ms':>8} {'target ms':>10}")
        worst = 0.0
        for name, q in queries(now):
            with EventStore(db, readonly=True) as store:
                matches = store.count(q)
            times = [time_query(db, q) for _ in range(args.rounds)]
            med = statistics.median(times)
            worst = max(worst, med)
            print(f"{name:<32} {matches:>8} {med:>10.2f} {max(times):>8.2f} {TARGET_MS:>10.0f}")
    return 0 if worst < TARGET_MS else 1


if __name__ == "__main__":
    raise SystemExit(main())
