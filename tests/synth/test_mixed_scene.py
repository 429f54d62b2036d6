"""The synthetic scene of people and cars (``synth:mixed``): exact classes in its ground truth,
and a line with ``classes = ["person"]`` that counts exactly the people when tracked."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.synth import make_scene
from motiontrack.synth.vehicles import Vehicle, render_vehicle


def test_the_mixed_scene_has_people_and_vehicles_with_exact_classes() -> None:
    scene = make_scene("mixed", n_frames=300)
    gt = scene.ground_truth()
    assert scene.object_classes() == {1: "person", 2: "person", 3: "person",
                                      4: "vehicle", 5: "vehicle"}
    # MOTChallenge classes: 1 pedestrian, 3 car
    assert {int(i): int(k) for i, k in zip(gt.ids, gt.classes)} == {1: 1, 2: 1, 3: 1, 4: 3, 5: 3}
    cars = gt.boxes[gt.classes == 3]
    people = gt.boxes[gt.classes == 1]
    assert (cars[:, 3] / cars[:, 2]).max() < 0.6 < 1.5 < (people[:, 3] / people[:, 2]).min()
    lines = {ln["name"]: ln for ln in scene.scene_file["line"]}
    assert lines["crossing"]["classes"] == ["person"] and "classes" not in lines["gate"]
    crossed = {(e.line, e.track) for e in scene.ground_truth_events() if e.type == "line_cross"}
    # every object crosses the gate; only the people the line for people
    assert {t for ln, t in crossed if ln == "crossing"} == {1, 2, 3}
    assert {t for ln, t in crossed if ln == "gate"} == {1, 2, 4, 5}


def test_a_vehicle_sprite_spans_its_length_and_height() -> None:
    v = Vehicle(id=1, x0=100.0, y0=200.0, vx=10.0, length=120.0, height=40.0)
    box = render_vehicle(v, 2).bbox()              # bottom centre at x = 120 in frame 2
    assert box[0] == pytest.approx(60, abs=1) and box[2] == pytest.approx(121, abs=2)
    assert box[1] == pytest.approx(160, abs=1) and box[3] == pytest.approx(41, abs=2)
    with pytest.raises(ValueError, match="vehicle length and height"):
        Vehicle(id=1, x0=0, y0=0, vx=1, length=2, height=40)


@pytest.mark.slow   # the whole pipeline on the mixed scene
def test_a_line_for_people_counts_exactly_the_people_of_the_mixed_scene(scene_runs) -> None:
    run = scene_runs("mixed", 0)
    assert run.crossings("pred") == run.crossings("gt")
    assert sum(n for (line, _), n in run.crossings("pred").items() if line == "crossing") == 3
    labels = {e.label for e in run.pred if e.line == "crossing"}
    assert labels == {"person"}
    assert np.array_equal(sorted(run.summary["class_counts"].values()), [0, 2, 3])
