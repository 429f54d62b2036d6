"""Analytics rules are plug-ins: the built-in ones declare what types.py accepts, and a rule
defined here, registered by name, runs through `Analytics`, `analyze` and `track --scene` with
nothing else changed."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motiontrack.analytics import Analytics, parse_scene
from dataclasses import dataclass

from motiontrack.analytics.doc_tables import scene_keys_table
from motiontrack.analytics.rule import RULES, BaseRule, EventType, Rule
from motiontrack.analytics.scene import scene_json_schema
from motiontrack.analytics.specs import SceneSection
from motiontrack.cli import main
from motiontrack.errors import ConfigError
from motiontrack.schema import param
from motiontrack.types import EVENT_TYPES, Event, event_types


@dataclass(frozen=True)
class AppearedTable(SceneSection):
    """The ``[appeared]`` table."""

    min_height: float = param(0.0, lo=0.0, hi=10_000.0,
                              doc="only tracks whose box is at least this tall (pixels)")


class Appeared(BaseRule):
    """A track is seen for the first time: one ``appeared`` event in its first frame."""

    name = section = "appeared"
    schema = AppearedTable
    events = (EventType("appeared", meaning="a track is seen for the first time"),)

    def __init__(self, spec, context):
        super().__init__(spec, context)
        self.seen = 0

    def step(self, frame):
        new = np.flatnonzero(~frame.known & (frame.boxes[:, 3] >= self.spec.min_height))
        self.seen += len(new)
        return [frame.event("appeared", i) for i in new]

    def summary(self):
        return {"appeared": self.seen}


@pytest.fixture
def appeared():
    RULES.register(Appeared)
    yield Appeared
    RULES.unregister("appeared")


def test_builtin_rules_register_in_scene_order_and_declare_every_builtin_event_type():
    assert [r.name for r in RULES.ordered()] == ["line", "zone", "stationary", "abandoned", "speed"]
    assert tuple(e.name for e in RULES.event_types()) == EVENT_TYPES == event_types()
    scene = parse_scene({"stationary": {"after_s": 1, "radius_px": 5},
                         "abandoned": {"after_s": 1, "distance_heights": 1},
                         "speed": {"limit_px_s": 10}})
    an = Analytics(scene, fps=10.0)
    assert list(an.rules) == ["line", "zone", "stationary", "abandoned", "speed"]
    assert all(isinstance(rule, Rule) for rule in an.rules.values())


def test_a_frames_events_of_one_track_come_in_rule_then_frame_order():
    assert list(RULES.event_order()) == ["line_cross", "zone_exit", "zone_enter", "loiter",
                                         "stationary_end", "stationary_start", "abandoned",
                                         "speeding"]


def test_unknown_rule_name_lists_the_valid_ones():
    with pytest.raises(ConfigError, match="valid names: abandoned, line, speed, stationary, zone"):
        RULES.get("appeared")


def test_a_rule_cannot_take_a_section_or_event_type_another_rule_has(appeared):
    with pytest.raises(ValueError, match="scene section 'zone' already belongs to a rule"):
        RULES.register(type("Clash", (Appeared,), {"name": "clash", "section": "zone"}))
    twin = type("Twin", (Appeared,), {"name": "twin", "section": "twin"})
    with pytest.raises(ValueError, match="event type 'appeared' already belongs to a rule"):
        RULES.register(twin)
    assert "clash" not in RULES and "twin" not in RULES


def test_an_unregistered_rule_leaves_no_event_type_or_scene_key_behind(appeared):
    RULES.unregister("appeared")
    assert "appeared" not in event_types()
    with pytest.raises(ConfigError, match=r"unknown scene key\(s\) appeared"):
        parse_scene({"appeared": {}})
    RULES.register(Appeared)   # the fixture unregisters it again


def test_toy_rule_emits_through_analytics(appeared):
    an = Analytics(parse_scene({"appeared": {}}), fps=10.0)
    # frame 1: track 1 appears; frame 2: track 1 again, track 2 appears; frame 3: nobody
    f1 = an.step(1, [1], [(0, 0, 10, 20)])
    f2 = an.step(2, [1, 2], [(1, 0, 10, 20), (50, 50, 10, 20)])
    f3 = an.step(3, [], np.zeros((0, 4)))
    assert [(e.type, e.track, e.x, e.y) for e in f1.events] == [("appeared", 1, 5.0, 20.0)]
    assert [(e.type, e.track, e.t) for e in f2.events] == [("appeared", 2, 0.1)]
    assert f3.events == ()
    summary = an.summary()
    assert summary["events"]["appeared"] == 2 and summary["appeared"] == 2
    assert Event.from_json(f2.events[0].to_json()) == f2.events[0]


def test_toy_rule_without_its_table_does_not_run(appeared):
    an = Analytics(parse_scene({}), fps=10.0)
    assert an.step(1, [1], [(0, 0, 10, 20)]).events == ()
    assert "appeared" not in an.summary() and an.summary()["events"]["appeared"] == 0


def test_toy_rule_table_is_checked_by_its_schema(appeared):
    with pytest.raises(ConfigError, match=r"unknown scene key\(s\) appeared.x; valid keys in "
                                          r"appeared: min_height$"):
        parse_scene({"appeared": {"x": 1}})
    with pytest.raises(ConfigError, match=r"appeared.min_height must be in \[0.0, 10000.0\], "
                                          r"got -1.0"):
        parse_scene({"appeared": {"min_height": -1}})
    assert parse_scene({"appeared": {"min_height": 30}}).spec("appeared") == AppearedTable(30.0)


def test_toy_rule_schema_gives_its_docs_row_and_json_schema(appeared):
    assert ("| `appeared.min_height` | float in [0, 10000] | 0 | only tracks whose box is at "
            "least this tall (pixels) |") in scene_keys_table()
    table = scene_json_schema()["properties"]["appeared"]
    assert table["properties"]["min_height"] == {
        "type": "number", "minimum": 0.0, "maximum": 10_000.0, "default": 0.0,
        "description": "only tracks whose box is at least this tall (pixels)"}


def test_toy_rule_events_follow_its_table(appeared):
    an = Analytics(parse_scene({"appeared": {"min_height": 15}}), fps=10.0)
    f1 = an.step(1, [1, 2], [(0, 0, 10, 20), (50, 50, 10, 10)])
    assert [e.track for e in f1.events] == [1]


def test_toy_rule_emits_through_analyze(appeared, tmp_path):
    tracks = tmp_path / "tracks.txt"
    # track 7 in frames 1-3, track 8 from frame 2: one appeared each, at their first frame
    tracks.write_text("1,7,0,0,10,20,1,-1,-1,-1\n2,7,1,0,10,20,1,-1,-1,-1\n"
                      "2,8,40,0,10,20,1,-1,-1,-1\n3,7,2,0,10,20,1,-1,-1,-1\n")
    scene = tmp_path / "scene.toml"
    scene.write_text("[appeared]\n")
    out = tmp_path / "out"
    assert main(["analyze", str(tracks), "--scene", str(scene), "--fps", "5", "-o", str(out)]) == 0
    lines = (out / "events.jsonl").read_text().splitlines()[1:]
    assert [(e["type"], e["frame"], e["track"]) for e in map(json.loads, lines)] == [
        ("appeared", 1, 7), ("appeared", 2, 8)]
    summary = json.loads((out / "summary.json").read_text())["analytics"]
    assert summary["events"]["appeared"] == 2 and summary["appeared"] == 2


def test_toy_rule_emits_through_track_scene(appeared, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text("[appeared]\n")
    run = tmp_path / "run"
    assert main(["track", "synth:walker?n_frames=40", "--scene", str(scene), "--no-video",
                 "-o", str(run)]) == 0
    events = [json.loads(x) for x in (run / "events.jsonl").read_text().splitlines()[1:]]
    tracks = np.loadtxt(run / "tracks.txt", delimiter=",", ndmin=2)
    first = {int(i): int(tracks[tracks[:, 1] == i, 0].min()) for i in np.unique(tracks[:, 1])}
    assert events and all(e["type"] == "appeared" for e in events)
    assert {e["track"]: e["frame"] for e in events} == first


def test_toy_rule_events_are_scored_by_evaluate_events(appeared):
    from motiontrack.evaluate.events import evaluate_events

    def ev(frame, track):
        return Event.from_json({"type": "appeared", "frame": frame, "t": frame / 10.0,
                                "track": track, "x": 0.0, "y": 0.0})

    # ground truth: appearances at 1.0 s and 3.0 s; predicted: 1.1 s (within 0.5 s) and 5.0 s
    scored = evaluate_events([ev(10, 1), ev(30, 2)], [ev(11, 1), ev(50, 3)], tolerance_s=0.5)
    s = scored.by_type["appeared"]
    assert (s.tp, s.fp, s.fn) == (1, 1, 1)
