"""Rules by class: a line with ``classes`` counts the crossings of those classes only."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.analytics import Analytics, parse_scene
from motiontrack.errors import ConfigError

FPS = 10.0
GATE = {"name": "gate", "points": [[100, 0], [100, 200]]}


def _cross(an: Analytics, labels: list[str] | None) -> list:
    """Two tracks walk left to right across x = 100 (anchors at the boxes' bottom centre)
    over frames 1-6; ``labels`` their classes."""
    events = []
    for f in range(1, 7):
        x = 60.0 + 15 * f            # anchor x: 75, 90, 105, 120, 135, 150
        boxes = [[x - 5, 50, 10, 30], [x - 5, 120, 10, 30]]
        events += an.step(f, [1, 2], boxes, labels=labels).events
    return events


def test_a_line_with_classes_counts_only_those_classes() -> None:
    scene = parse_scene({"line": [{**GATE, "classes": ["person"]},
                                  {**GATE, "name": "all"}]})
    events = _cross(an := Analytics(scene, FPS), ["person", "vehicle"])
    crossings = sorted((e.line, e.track, e.label) for e in events)
    # the person (track 1) crosses both lines; the vehicle (track 2) only the one for all
    assert crossings == [("all", 1, "person"), ("all", 2, "vehicle"), ("gate", 1, "person")]
    # left to right across a line drawn downwards is "out"
    assert an.counts_by_line() == {"gate": (0, 1), "all": (0, 2)}
    assert an.summary()["lines_by_class"] == {
        "gate": {"person": {"in": 0, "out": 1}},
        "all": {"person": {"in": 0, "out": 1}, "vehicle": {"in": 0, "out": 1}}}


def test_a_line_with_classes_counts_nothing_of_unclassified_tracks() -> None:
    scene = parse_scene({"line": [{**GATE, "classes": ["person"]}]})
    events = _cross(an := Analytics(scene, FPS), None)
    assert events == [] and an.counts_by_line() == {"gate": (0, 0)}
    assert "lines_by_class" not in an.summary()


def test_events_of_classified_tracks_carry_their_class() -> None:
    events = _cross(Analytics(parse_scene({"line": [GATE]}), FPS), ["other", "person"])
    assert [(e.track, e.label) for e in events] == [(1, "other"), (2, "person")]
    assert events[0].to_json()["label"] == "other"


@pytest.mark.parametrize("classes, message", [
    (["cat"], "line[1].classes[1] must be one of person, vehicle, other"),
    ("person", "classes"),
])
def test_an_unknown_class_is_refused_naming_the_key(classes, message) -> None:
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
        parse_scene({"line": [{**GATE, "classes": classes}]})


PLAZA = {"name": "plaza", "polygon": [[50, 0], [150, 0], [150, 200], [50, 200]]}


def _enter_and_stay(an: Analytics, labels: list[str], frames: int = 6) -> list:
    """Tracks 1 and 2 step into the plaza at frame 2 (anchors x 40 → 80) and stand there."""
    events = []
    for f in range(1, frames + 1):
        x = 40.0 if f == 1 else 80.0
        boxes = [[x - 5, 50, 10, 30], [x - 5, 120, 10, 30]]
        events += an.step(f, [1, 2], boxes, labels=labels).events
    return events


def test_a_zone_with_classes_holds_only_those_classes() -> None:
    scene = parse_scene({"zone": [{**PLAZA, "classes": ["vehicle"], "loiter_s": 0.3}]})
    events = _enter_and_stay(an := Analytics(scene, FPS), ["person", "vehicle"])
    # frame 2: the vehicle enters; frame 5 (0.3 s = 3 frames later) it loiters; the person
    # is never inside
    assert [(e.type, e.frame, e.track, e.label) for e in events] == [
        ("zone_enter", 2, 2, "vehicle"), ("loiter", 5, 2, "vehicle")]
    assert an.occupancy_by_zone() == {"plaza": 1}


def test_stationary_with_classes_reports_only_those_classes() -> None:
    scene = parse_scene({"stationary": {"after_s": 0.3, "radius_px": 5, "leave_s": 0,
                                        "classes": ["person"]}})
    # the 40 px step at frame 2 gives the young track a speed of 400 px/s; standing at x = 80
    # from then on, frames 3-5 are outliers to it until the third starts the smoothed
    # trajectory again at frame 5, where the stay starts; stationary 3 frames later
    events = _enter_and_stay(Analytics(scene, FPS), ["person", "vehicle"], frames=8)
    assert [(e.type, e.frame, e.track) for e in events] == [("stationary_start", 8, 1)]
    with pytest.raises(ConfigError, match=r"stationary.classes\[2\] must be one of"):
        parse_scene({"stationary": {"after_s": 1, "radius_px": 5,
                                    "classes": ["person", "dog"]}})


def test_a_tracks_files_class_column_drives_the_rules_of_analyze_and_evaluate_events() -> None:
    from motiontrack.io.mot import parse_mot
    from motiontrack.run.analyze import analysed_events

    # tracks.txt rows with the class column: track 1 a person, track 2 a vehicle, both walking
    # left to right across x = 100 (anchor x = left + 5)
    rows = "".join(f"{f},{tid},{55 + 15 * f},{y},10,30,1,-1,-1,-1,{k}\n"
                   for f in range(1, 7) for tid, y, k in ((1, 50, 1), (2, 120, 3)))
    scene = parse_scene({"line": [{**GATE, "classes": ["person"]}]})
    events = analysed_events(parse_mot(rows), scene, FPS)
    assert [(e.track, e.line, e.label) for e in events] == [(1, "gate", "person")]


def test_counts_and_heat_maps_split_by_class(tmp_path) -> None:
    import csv

    from motiontrack.io.mot import parse_mot
    from motiontrack.run.analyze import analyze_job

    rows = "".join(f"{f},{tid},{55 + 15 * f},{y},10,30,1,-1,-1,-1,{k}\n"
                   for f in range(1, 7) for tid, y, k in ((1, 50, 1), (2, 120, 3)))
    scene = parse_scene({"line": [GATE]})
    job = analyze_job(parse_mot(rows), scene, FPS, tmp_path, size=(200, 200), by_class=True)
    summary = job.run()
    with open(tmp_path / "counts.csv") as fh:
        (row,) = list(csv.DictReader(fh))
    # both tracks cross "out"; the class columns split them
    assert (row["line:gate:out"], row["line:gate:person:out"], row["line:gate:vehicle:out"],
            row["line:gate:other:out"]) == ("2", "1", "1", "0")
    # 6 frames of each track: each class's map counts its own rows only
    assert summary.extra["heatmap"]["visits"] == 12
    assert [summary.extra[f"heatmap_{c}"]["visits"] for c in ("person", "vehicle", "other")] \
        == [6, 6, 0]
    assert all((tmp_path / f"heatmap_{c}.png").is_file() for c in ("person", "vehicle", "other"))


def _left_object(classes: list[str] | None, owner_label: str) -> list:
    """A track (100 px tall) stands at x 100-140 until frame 10, then walks right at 10 px a
    frame out of view after frame 40; from frame 11 a still object lies beside where it stood
    (the hand-built scene of tests/analytics/test_abandoned.py)."""
    from motiontrack.types import Box, StaticFrame, StaticObject

    rule = {"after_s": 2.0, "distance_heights": 1.5}
    if classes is not None:
        rule["classes"] = classes
    an = Analytics(parse_scene({"abandoned": rule}), FPS)
    events = []
    for f in range(1, 71):
        x = 100 + 10 * max(0, f - 10)
        ids, boxes = ([1], [(x, 100, 40, 100)]) if f <= 40 else ([], [])
        static = StaticFrame()
        if f >= 11:
            static = StaticFrame((StaticObject(Box(145, 180, 20, 20), 400, f - 10, 1.0),))
        labels = [owner_label] * len(ids)
        events += [e for e in an.step(f, ids, boxes, static, labels=labels).events
                   if e.type == "abandoned"]
    return events


def test_abandoned_with_classes_reports_objects_left_by_tracks_of_those_classes() -> None:
    assert [(e.frame, e.owner) for e in _left_object(None, "vehicle")] == [(49, 1)]
    assert [(e.frame, e.owner) for e in _left_object(["person"], "person")] == [(49, 1)]
    # a parked car's "object" (its owner a vehicle) is not abandoned luggage
    assert _left_object(["person"], "vehicle") == []
