"""Scene analytics end to end: ``synth-events`` writes a synthetic scene's scene file and exact
events, ``track --scene`` runs the whole pipeline on the rendered video with it, and the events
the tracker's tracks give are compared with the ground truth's.

Each scene runs at one seed, tracked once per session (the ``scene_runs`` fixture) and shared by
every assertion about it. Only ``runner`` (150 frames) runs in the fast suite. The same checks
over seeds 0-9 of every scene are ``benchmarks/seed_sweeps.py events`` (a non-zero exit when a
seed misses), and ``benchmarks/scene_events.py`` prints the comparison as a table.
"""

from __future__ import annotations

import pytest

from motiontrack.evaluate.events import evaluate_events

CROSSING_DIRECTIONS = (("gate", "in"), ("gate", "out"))


@pytest.fixture
def tracked(scene_runs):
    """``tracked(name, seed)``: the scene's ground truth and the tracked run, each run once per
    session (tests/helpers/runs.py)."""
    return scene_runs


# ----------------------------------------------------- one or two people: everything exact
# walker, runner and loiter: one person; crossing: two who pass each other in front of the line
EXACT = [pytest.param(name, 0, marks=[] if name == "runner" else pytest.mark.slow)
         for name in ("walker", "runner", "crossing", "loiter")]


@pytest.mark.parametrize("name, seed", EXACT)
def test_line_counts_per_direction_equal_the_ground_truth(tracked, name, seed):
    r = tracked(name, seed)
    gt, pred = r.crossings("gt"), r.crossings("pred")
    assert {k: pred[k] for k in CROSSING_DIRECTIONS} == {k: gt[k] for k in CROSSING_DIRECTIONS}
    # and the totals a user reads in summary.json say the same
    lines = r.summary["analytics"]["lines"]["gate"]
    assert (lines["in"], lines["out"]) == (gt["gate", "in"], gt["gate", "out"])
    if name == "crossing":
        assert gt["gate", "in"] == gt["gate", "out"] == 1
    elif name != "loiter":  # the loiter walker may leave back across the line
        assert sum(gt.values()) == 1


@pytest.mark.parametrize("name, seed", EXACT)
def test_zone_entries_and_exits_equal_the_ground_truth(tracked, name, seed):
    r = tracked(name, seed)
    for kind in ("zone_enter", "zone_exit"):
        assert r.count("pred", kind) == r.count("gt", kind), kind
    zone = r.summary["analytics"]["zones"]["plaza"]
    assert (zone["enters"], zone["exits"]) == (r.count("gt", "zone_enter"),
                                              r.count("gt", "zone_exit"))


@pytest.mark.parametrize("name, seed", EXACT)
def test_every_event_is_found_within_a_second(tracked, name, seed):
    r = tracked(name, seed)
    total = evaluate_events(r.gt, r.pred, tolerance_s=1.0).total
    assert (total.tp, total.fp, total.fn) == (len(r.gt), 0, 0)


# ----------------------------------------------------------------------------------- crowd
@pytest.mark.slow
@pytest.mark.parametrize("seed", [0])
def test_crowd_line_counts_within_one_of_the_ground_truth(tracked, seed):
    r = tracked("crowd", seed)
    gt, pred = r.crossings("gt"), r.crossings("pred")
    for key in CROSSING_DIRECTIONS:
        assert abs(pred[key] - gt[key]) <= 1, (key, pred[key], gt[key])


# ------------------------------------------------------------------------------------ loiter
@pytest.mark.slow
@pytest.mark.parametrize("seed", [0])
def test_loiter_fires_within_half_a_second_of_the_ground_truth(tracked, seed):
    r = tracked("loiter", seed)
    (gt,) = [e for e in r.gt if e.type == "loiter"]
    (pred,) = [e for e in r.pred if e.type == "loiter"]
    assert pred.zone == gt.zone == "plaza"
    assert abs(pred.t - gt.t) <= 0.5


@pytest.mark.parametrize("name, seed", EXACT)
def test_no_event_carries_other_because_its_track_is_young(tracked, name, seed):
    """A person's first event (often a zone_enter at the edge of the view) already says person:
    the track's tentative frames voted for its class when it was confirmed."""
    r = tracked(name, seed)
    assert r.pred and {e.label for e in r.pred} == {"person"}
