"""Event matching of large groups: the pairs within the tolerance only, with the same number of
matches and the same total |Δt| as the dense assignment; bounded tolerance and pair count."""

from __future__ import annotations

import resource
import time

import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.errors import ConfigError
from motiontrack.evaluate import events as ev
from motiontrack.evaluate.events import evaluate_events, match_times
from motiontrack.io.events import write_events
from motiontrack.types import Event


def total_dt(gt, pred, pairs) -> float:
    return sum(abs(gt[i] - pred[j]) for i, j in pairs)


@pytest.mark.parametrize("gt, pred, tol, expected", [
    ([5.0], [6.0], 1.0, [(0, 0)]),
    ([5.0], [6.01], 1.0, []),
    ([0.1], [1.1], 1.0, [(0, 0)]),
    ([5.0], [4.5, 5.2], 1.0, [(0, 1)]),
    ([5.0, 6.0], [5.9], 1.0, [(1, 0)]),
    ([5.0, 6.5], [4.5, 5.6], 1.0, [(0, 0), (1, 1)]),
    ([1.0, 2.0], [1.9, 2.5], 1.0, [(0, 0), (1, 1)]),
    ([3.0], [3.0], 0.0, [(0, 0)]),
    ([1.0, 2.0, 3.0], [2.1, 0.2, 2.9, 9.0], 0.5, [(1, 0), (2, 2)]),
    ([7.0, 1.0], [1.0, 7.0], 0.0, [(0, 1), (1, 0)]),
])
def test_the_sparse_matching_gives_the_dense_matches(gt, pred, tol, expected):
    assert match_times(gt, pred, tol) == expected
    assert sorted(match_times(gt, pred, tol, dense_max=0)) == expected


def test_sparse_and_dense_agree_on_count_and_total_time_difference():
    rng = np.random.default_rng(3)
    for _ in range(1500):
        # times on a 0.1 s grid: many ties and many pairs exactly at the tolerance
        gt = (rng.integers(0, 40, rng.integers(0, 14)) / 10).tolist()
        pred = (rng.integers(0, 40, rng.integers(0, 14)) / 10).tolist()
        tol = float(rng.choice([0.0, 0.1, 0.3, 1.0]))
        dense, sparse = match_times(gt, pred, tol), match_times(gt, pred, tol, dense_max=0)
        assert len(sparse) == len(dense)
        assert total_dt(gt, pred, sparse) == pytest.approx(total_dt(gt, pred, dense), abs=1e-9)
        assert len({i for i, _ in sparse}) == len({j for _, j in sparse}) == len(sparse)
        assert all(abs(gt[i] - pred[j]) <= tol + 1e-9 for i, j in sparse)


def test_fifty_thousand_events_in_one_group_match_in_bounded_memory():
    n = 50_000
    rng = np.random.default_rng(5)
    gt = np.arange(n) * 0.4                      # a crossing every 0.4 s for 5.5 hours
    own = gt + rng.uniform(-0.3, 0.3, n)         # each found within 0.3 s ...
    keep = np.ones(n, bool)
    keep[::100] = False                          # ... but every 100th missed
    pred = own[keep]
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t = time.perf_counter()
    pairs = match_times(gt, pred, 1.0)
    elapsed = time.perf_counter() - t
    grown_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before
    assert len(pairs) == len(pred)               # every prediction matched
    assert len({i for i, _ in pairs}) == len(pairs)
    # at most the total of each prediction matched to its own event
    assert total_dt(gt, pred, pairs) <= float(np.abs(own - gt)[keep].sum()) + 1e-6
    assert grown_kib < 500 * 1024                # the dense matrix alone would be 20 GB
    assert elapsed < 20.0                        # generous: about 1 s; dense, over a minute


def test_too_many_pairs_within_the_tolerance_are_refused(monkeypatch):
    monkeypatch.setattr(ev, "MAX_PAIRS", 1000)
    with pytest.raises(ConfigError, match=r"^1,600 pairs of events are within the time "
                                          r"tolerance in one group of 40 ground-truth"):
        match_times(np.zeros(40), np.zeros(40), 1.0, dense_max=0)


@pytest.mark.parametrize("tol", [1e308, ev.MAX_TOLERANCE_S * 1.5])
def test_a_tolerance_beyond_the_bound_is_refused(tol):
    with pytest.raises(ConfigError, match=r"time tolerance must be a number of seconds in "
                                          r"\[0, 10000000\]"):
        evaluate_events([], [], tol)


@pytest.mark.parametrize("value", ["1e308", "inf", "nan", "-1"])
def test_evaluate_events_refuses_an_unbounded_tolerance_in_one_line(tmp_path, capsys, value):
    gt = tmp_path / "gt.jsonl"
    write_events(gt, [Event("line_cross", 11, 1.0, 1, 0.0, 0.0, line="g", direction="in")], 10.0)
    assert main(["evaluate-events", "--gt", str(gt), "--pred", str(gt),
                 f"--tolerance-s={value}"]) == 2
    err = capsys.readouterr().err
    assert "--tolerance-s must be a number of seconds in [0, 10000000]" in err
    assert err.count("\n") == 1 and "internal error" not in err
