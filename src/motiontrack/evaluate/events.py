"""Event-level evaluation: predicted scene-analytics events against ground-truth events.

Events are compared within *groups*: the same type and, where the type has them, the same line
and direction (``line_cross``) or zone (``zone_enter``, ``zone_exit``, ``loiter``); track ids are
never compared (a tracker's ids are not the ground truth's). In each group a predicted and a
ground-truth event may match when their times differ by at most the tolerance; the matching is
one-to-one and optimal: as many matches as possible, and among those the smallest total
``|Δt|`` (a linear assignment: dense for groups of up to 1,000 × 1,000 events, over the pairs
within the tolerance only for larger ones, so that memory grows with those pairs, not with the
product of the counts). Matched pairs are true positives (TP), unmatched predictions
false positives (FP), unmatched ground truth false negatives (FN); per group, per type and in
total:

* ``precision = TP / (TP + FP)``, ``recall = TP / (TP + FN)``,
  ``F1 = 2 TP / (2 TP + FP + FN)`` (``None`` where the denominator is 0);
* ``count_error = predicted − ground truth`` (what a counter gets wrong, whatever the times);
* ``mean_abs_dt_s``: mean ``|Δt|`` of the matches (``None`` without matches).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable, Sequence

import numpy as np

from ..assignment import linear_sum_assignment
from ..errors import ConfigError
from ..types import Event, event_types

__all__ = ["DEFAULT_TOLERANCE_S", "MAX_TOLERANCE_S", "MAX_PAIRS", "EventScore",
           "EventsEvaluation", "group_key", "match_times", "evaluate_events"]

#: default largest time difference of a match, seconds
DEFAULT_TOLERANCE_S = 1.0
#: largest tolerance, seconds (115 days: longer than any video)
MAX_TOLERANCE_S = 10_000_000.0
#: most pairs within the tolerance in one group (about 100 bytes each while matching)
MAX_PAIRS = 5_000_000
#: largest group (ground truth × predicted) matched on a dense matrix of every pair
_DENSE_MAX = 1_000_000
_EPS = 1e-9  # times are (frame - 1) / fps: equal differences may round a hair apart


def group_key(e: Event) -> tuple[str, str, str]:
    """``(type, line or zone or "", direction or "")``: events match only within one group."""
    return (e.type, e.line or e.zone or "", e.direction or "")


def match_times(gt: Sequence[float], pred: Sequence[float], tolerance_s: float,
                dense_max: int = _DENSE_MAX) -> list[tuple[int, int]]:
    """Optimal one-to-one matches ``(gt index, pred index)`` between two lists of times.

    A pair may match when ``|Δt| <= tolerance_s``; the result has as many pairs as possible
    and, among those, the smallest sum of ``|Δt|``. Groups of at most ``dense_max`` pairs are
    solved on the dense matrix of all pairs, larger ones on the pairs within the tolerance only
    (the same number of matches and the same sum of ``|Δt|``; among equally good matchings
    either may be chosen).

    Raises
    ------
    ConfigError
        More than :data:`MAX_PAIRS` pairs within the tolerance in a group too large for the
        dense matrix.
    """
    g = np.asarray(gt, dtype=np.float64).reshape(-1)
    p = np.asarray(pred, dtype=np.float64).reshape(-1)
    if g.size == 0 or p.size == 0:
        return []
    if g.size * p.size > dense_max:
        return _match_sparse(g, p, tolerance_s)
    # every allowed pair is worth `big` more than any sum of |Δt|, so the solver first maximises
    # the number of matches and then minimises their total time difference
    big = (tolerance_s + 1.0) * (min(g.size, p.size) + 1)
    dt = np.abs(g[:, None] - p[None, :])
    ok = dt <= tolerance_s + _EPS
    if not ok.any():
        return []
    rows, cols = linear_sum_assignment(np.where(ok, dt - big, 0.0))
    return [(int(r), int(c)) for r, c in zip(rows, cols) if ok[r, c]]


def _pairs_within(g: np.ndarray, p: np.ndarray, tolerance_s: float,
                  presorted: bool = False) -> tuple[np.ndarray, ...]:
    """``(gt index, pred index, |Δt|)`` of every pair within the tolerance, by ground truth
    then prediction (``presorted``: ``p`` is in time order), found on the sorted predicted
    times: memory grows with those pairs only."""
    order = np.arange(p.size) if presorted else np.argsort(p, kind="stable")
    ps = p[order]
    lo = np.searchsorted(ps, g - tolerance_s - 2 * _EPS, side="left")
    hi = np.searchsorted(ps, g + tolerance_s + 2 * _EPS, side="right")
    counts = hi - lo
    total = int(counts.sum())
    if total > MAX_PAIRS:
        raise ConfigError(f"{total:,} pairs of events are within the time tolerance in one "
                          f"group of {g.size:,} ground-truth and {p.size:,} predicted events, "
                          f"more than {MAX_PAIRS:,}: give a smaller tolerance")
    rows = np.repeat(np.arange(g.size), counts)
    cols = order[np.repeat(lo, counts) + np.arange(total) - np.repeat(np.cumsum(counts) - counts,
                                                                       counts)]
    dt = np.abs(g[rows] - p[cols])
    keep = dt <= tolerance_s + _EPS
    return rows[keep], cols[keep], dt[keep]


def _match_sparse(g: np.ndarray, p: np.ndarray, tolerance_s: float) -> list[tuple[int, int]]:
    """:func:`match_times` on the pairs within the tolerance, in time ``O(pairs)``.

    On a line, two matched pairs that cross (``g1 < g2`` but ``p1 > p2``) can be swapped to
    ``g1–p2, g2–p1`` without making either ``|Δt|`` longer than the longer of the two or the
    sum larger, so some optimal matching is monotone: the ground truth and the predictions it
    matches are in the same order. The best monotone matching is a longest chain of pairs
    increasing in both, scored ``(matches, −sum |Δt|)`` (compared exactly, not weighted by
    ``big``): one pass over the ground truth in time order, keeping per prediction the best
    chain ending there and one running best for the predictions no later event can reach.
    """
    og, op = np.argsort(g, kind="stable"), np.argsort(p, kind="stable")
    rows, cols, dt = _pairs_within(g[og], p[op], tolerance_s, presorted=True)
    if rows.size == 0:
        return []
    # per pair: (matches, -sum |Δt|, pair index) of the best chain ending with it, and the
    # chain's previous pair; `best_at[j]` the best chain of the rows done so far ending at j
    score: list[tuple[int, float, int]] = [(0, 0.0, -1)] * rows.size
    back = [-1] * rows.size
    best_at: list[tuple[int, float, int] | None] = [None] * p.size
    frozen, frontier = (0, 0.0, -1), 0
    starts = np.flatnonzero(np.r_[True, rows[1:] != rows[:-1]]).tolist() + [rows.size]
    cols_l, dt_l = cols.tolist(), dt.tolist()
    for s0, s1 in zip(starts[:-1], starts[1:]):
        lo = cols_l[s0]
        for j in range(frontier, lo):   # no later event reaches these predictions
            if best_at[j] is not None and best_at[j] > frozen:
                frozen = best_at[j]
        frontier = max(frontier, lo)
        running = frozen
        for e in range(s0, s1):
            j = cols_l[e]
            score[e] = (running[0] + 1, running[1] - dt_l[e], e)
            back[e] = running[2]
            if best_at[j] is not None and best_at[j] > running:
                running = best_at[j]
        for e in range(s0, s1):
            j = cols_l[e]
            if best_at[j] is None or score[e] > best_at[j]:
                best_at[j] = score[e]
    e = max(score)[2]
    out = []
    while e >= 0:
        out.append((int(og[rows[e]]), int(op[cols[e]])))
        e = back[e]
    return out[::-1]


@dataclass(frozen=True)
class EventScore:
    """Matching counts of one group (or a sum of groups)."""

    gt: int = 0
    pred: int = 0
    tp: int = 0
    abs_dt_sum: float = 0.0

    @property
    def fp(self) -> int:
        return self.pred - self.tp

    @property
    def fn(self) -> int:
        return self.gt - self.tp

    @property
    def precision(self) -> float | None:
        return self.tp / self.pred if self.pred else None

    @property
    def recall(self) -> float | None:
        return self.tp / self.gt if self.gt else None

    @property
    def f1(self) -> float | None:
        d = 2 * self.tp + self.fp + self.fn
        return 2 * self.tp / d if d else None

    @property
    def count_error(self) -> int:
        return self.pred - self.gt

    @property
    def mean_abs_dt_s(self) -> float | None:
        return self.abs_dt_sum / self.tp if self.tp else None

    def __add__(self, other: "EventScore") -> "EventScore":
        return EventScore(self.gt + other.gt, self.pred + other.pred, self.tp + other.tp,
                          self.abs_dt_sum + other.abs_dt_sum)

    def to_json(self) -> dict[str, Any]:
        """Counts and ratios (ratios rounded to 6 digits, ``None`` where undefined)."""
        def r(v: float | None) -> float | None:
            return None if v is None else round(v, 6)

        return {"gt": self.gt, "pred": self.pred, "tp": self.tp, "fp": self.fp, "fn": self.fn,
                "precision": r(self.precision), "recall": r(self.recall), "f1": r(self.f1),
                "count_error": self.count_error, "mean_abs_dt_s": r(self.mean_abs_dt_s)}


@dataclass(frozen=True)
class EventsEvaluation:
    """The scores of one comparison: per group, per type and in total."""

    tolerance_s: float
    groups: dict[tuple[str, str, str], EventScore]
    matches: dict[tuple[str, str, str], tuple[tuple[Event, Event], ...]]

    @property
    def by_type(self) -> dict[str, EventScore]:
        """Type → the sum of its groups (types in :func:`~motiontrack.types.event_types` order)."""
        out: dict[str, EventScore] = {}
        for (kind, _, _), s in self.groups.items():
            out[kind] = out.get(kind, EventScore()) + s
        return out

    @property
    def total(self) -> EventScore:
        return sum(self.groups.values(), EventScore())

    def to_json(self) -> dict[str, Any]:
        groups = []
        for (kind, target, direction), s in self.groups.items():
            g: dict[str, Any] = {"type": kind}
            if kind == "line_cross":
                g.update(line=target, direction=direction)
            elif target:
                g["zone"] = target
            groups.append({**g, **s.to_json()})
        return {"tolerance_s": self.tolerance_s, "groups": groups,
                "types": {k: s.to_json() for k, s in self.by_type.items()},
                "total": self.total.to_json()}


def _sort_key(key: tuple[str, str, str]) -> tuple[int, str, str]:
    # the live list: a plug-in rule's types sort after the built-in ones
    return (event_types().index(key[0]), key[1], key[2])


def evaluate_events(gt: Iterable[Event], pred: Iterable[Event],
                    tolerance_s: float = DEFAULT_TOLERANCE_S) -> EventsEvaluation:
    """Score predicted events against ground-truth events (see the module docstring).

    Parameters
    ----------
    gt, pred : iterables of Event
    tolerance_s : float
        Largest ``|Δt|`` of a match, seconds (>= 0).

    Returns
    -------
    EventsEvaluation
        Every group that has a ground-truth or a predicted event, ordered by type
        (:func:`~motiontrack.types.event_types`), line or zone name and direction.

    Raises
    ------
    ConfigError
        A tolerance that is negative, not finite or over :data:`MAX_TOLERANCE_S`; more than
        :data:`MAX_PAIRS` pairs within the tolerance in a large group.
    """
    if not (isinstance(tolerance_s, (int, float)) and np.isfinite(tolerance_s)
            and 0 <= tolerance_s <= MAX_TOLERANCE_S):
        raise ConfigError(f"the time tolerance must be a number of seconds in "
                          f"[0, {MAX_TOLERANCE_S:.0f}], got {tolerance_s!r}")
    by_gt: dict[tuple[str, str, str], list[Event]] = {}
    by_pred: dict[tuple[str, str, str], list[Event]] = {}
    for events, into in ((gt, by_gt), (pred, by_pred)):
        for e in events:
            into.setdefault(group_key(e), []).append(e)
    groups: dict[tuple[str, str, str], EventScore] = {}
    matches: dict[tuple[str, str, str], tuple[tuple[Event, Event], ...]] = {}
    for key in sorted(set(by_gt) | set(by_pred), key=_sort_key):
        g, p = by_gt.get(key, []), by_pred.get(key, [])
        pairs = match_times([e.t for e in g], [e.t for e in p], float(tolerance_s))
        matched = tuple((g[i], p[j]) for i, j in pairs)
        groups[key] = EventScore(len(g), len(p), len(pairs),
                                 float(sum(abs(a.t - b.t) for a, b in matched)))
        matches[key] = matched
    return EventsEvaluation(float(tolerance_s), groups, matches)
