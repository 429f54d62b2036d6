"""Scene analytics end to end: ``synth-events`` writes a synthetic scene's scene file and exact
events, ``track --scene`` runs the whole pipeline on the rendered video with it, and the events
the tracker's tracks give are compared with the ground truth's.

Each (scene, seed) is tracked once per module (the ``tracked`` fixture) and shared by every
assertion about it. Only ``runner`` seed 0 (150 frames) runs in the fast suite; the seed
sweeps are slow (5-13 s per run, the whole module about 5 minutes on a 2-core machine).
``benchmarks/scene_events.py`` prints the same comparison as a table.
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import pytest

from motiontrack.cli import main
from motiontrack.evaluate.events import evaluate_events
from motiontrack.io.events import read_events
from motiontrack.types import Event

SEEDS = range(10)
CROSSING_DIRECTIONS = (("gate", "in"), ("gate", "out"))


@dataclass(frozen=True)
class Tracked:
    gt: list[Event]          # synth-events: the scene's exact events
    pred: list[Event]        # track --scene on the rendered video
    summary: dict            # the run's summary.json

    def crossings(self, which: str) -> Counter:
        """``(line, direction)`` -> crossings, of ``"gt"`` or ``"pred"``."""
        events = self.gt if which == "gt" else self.pred
        return Counter((e.line, e.direction) for e in events if e.type == "line_cross")

    def count(self, which: str, kind: str) -> int:
        return sum(e.type == kind for e in (self.gt if which == "gt" else self.pred))


@pytest.fixture(scope="module")
def tracked(tmp_path_factory):
    """``tracked(name, seed)``: the scene's ground truth and the tracked run, each run once."""
    runs: dict[tuple[str, int], Tracked] = {}

    def run(name: str, seed: int) -> Tracked:
        if (name, seed) not in runs:
            spec = f"synth:{name}?seed={seed}"
            d: Path = tmp_path_factory.mktemp(f"{name}-{seed}")
            assert main(["synth-events", spec, "-o", str(d / "gt")]) == 0
            assert main(["track", spec, "--scene", str(d / "gt" / "scene.toml"), "--no-video",
                         "-o", str(d / "run")]) == 0
            runs[name, seed] = Tracked(
                read_events(d / "gt" / "events.jsonl").events,
                read_events(d / "run" / "events.jsonl").events,
                json.loads((d / "run" / "summary.json").read_text()))
        return runs[name, seed]

    return run


# ----------------------------------------------------- one or two people: everything exact
# walker, runner and loiter: one person; crossing: two who pass each other in front of the line
EXACT = [pytest.param(name, seed, marks=[] if (name, seed) == ("runner", 0) else pytest.mark.slow)
         for name in ("walker", "runner", "crossing", "loiter") for seed in SEEDS]


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
@pytest.mark.parametrize("seed", SEEDS)
def test_crowd_line_counts_within_one_of_the_ground_truth(tracked, seed):
    r = tracked("crowd", seed)
    gt, pred = r.crossings("gt"), r.crossings("pred")
    for key in CROSSING_DIRECTIONS:
        assert abs(pred[key] - gt[key]) <= 1, (key, pred[key], gt[key])


# ------------------------------------------------------------------------------------ loiter
@pytest.mark.slow
@pytest.mark.parametrize("seed", SEEDS)
def test_loiter_fires_within_half_a_second_of_the_ground_truth(tracked, seed):
    r = tracked("loiter", seed)
    (gt,) = [e for e in r.gt if e.type == "loiter"]
    (pred,) = [e for e in r.pred if e.type == "loiter"]
    assert pred.zone == gt.zone == "plaza"
    assert abs(pred.t - gt.t) <= 0.5
