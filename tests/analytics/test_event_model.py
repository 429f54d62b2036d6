"""The Event data model: self-validation and the events-file JSON round trip."""

from __future__ import annotations

import json

import pytest

from motiontrack.types import (
    EVENT_TYPES,
    EVENTS_SCHEMA,
    EVENTS_SCHEMA_VERSION,
    Event,
    event_types,
    events_header,
    register_event_type,
    unregister_event_type,
)

BASE = {"frame": 11, "t": 1.0, "track": 3, "x": 100.5, "y": 200.25}

#: one valid event of every type, with every field its type allows
VALID = [
    {"type": "line_cross", **BASE, "line": "gate", "direction": "in"},
    {"type": "line_cross", **BASE, "X": 1.5, "Y": -2.0, "line": "gate", "direction": "out"},
    {"type": "zone_enter", **BASE, "zone": "plaza"},
    {"type": "zone_exit", **BASE, "zone": "plaza", "dwell_s": 4.5},
    {"type": "loiter", **BASE, "zone": "plaza", "dwell_s": 20.0},
    {"type": "stationary_start", **BASE},
    {"type": "stationary_end", **BASE, "duration_s": 12.0},
    {"type": "abandoned", **BASE, "duration_s": 15.0, "owner": 2},
    {"type": "abandoned", **BASE, "duration_s": 15.0},
    {"type": "speeding", **BASE, "X": 0.0, "Y": 0.0, "speed_mps": 3.5},
    {"type": "speeding", **BASE, "speed_px_s": 250.0},
]


def test_every_event_type_has_a_valid_example():
    assert sorted({d["type"] for d in VALID}) == sorted(EVENT_TYPES)
    assert len(EVENT_TYPES) == 8


@pytest.mark.parametrize("obj", VALID, ids=lambda d: d["type"])
def test_event_json_round_trips_through_a_json_line(obj):
    event = Event.from_json(obj)
    assert event.to_json() == obj
    line = json.dumps(event.to_json())
    assert Event.from_json(json.loads(line)) == event


def test_to_json_keeps_schema_key_order_and_leaves_absent_keys_out():
    e = Event("zone_exit", 5, 0.4, 7, 1.0, 2.0, X=0.5, Y=0.25, zone="z", dwell_s=0.3)
    assert list(e.to_json()) == ["type", "frame", "t", "track", "x", "y", "X", "Y", "zone", "dwell_s"]


def test_from_json_accepts_whole_floats_for_integers_and_ints_for_floats():
    e = Event.from_json({"type": "stationary_start", "frame": 4.0, "t": 3, "track": 2.0, "x": 1, "y": 2})
    assert (e.frame, e.track) == (4, 2) and isinstance(e.frame, int)
    assert e.t == 3.0 and isinstance(e.t, float) and isinstance(e.to_json()["x"], float)


@pytest.mark.parametrize(
    "obj, message",
    [
        ({"type": "teleport", **BASE}, "event type must be one of line_cross"),
        ({**BASE}, "event type must be one of"),
        ({"type": "zone_enter", **BASE, "zone": "z", "colour": 1}, "unknown key 'colour'"),
        ({"type": "zone_enter", "frame": 1, "t": 0.0, "x": 1, "y": 1, "zone": "z"}, "needs track"),
        ({"type": "zone_enter", **BASE}, "zone_enter event needs zone"),
        ({"type": "zone_exit", **BASE, "zone": "z"}, "zone_exit event needs dwell_s"),
        ({"type": "line_cross", **BASE, "line": "g", "direction": "left"}, "'in' or 'out'"),
        ({"type": "line_cross", **BASE, "line": "g", "direction": "in", "zone": "z"}, "cannot have zone"),
        ({"type": "speeding", **BASE}, "exactly one of speed_mps and speed_px_s"),
        ({"type": "speeding", **BASE, "speed_mps": 1.0, "speed_px_s": 2.0}, "exactly one"),
        ({"type": "stationary_start", **BASE, "frame": 0}, "frame must be >= 1"),
        ({"type": "stationary_start", **BASE, "frame": 2.5}, "frame must be an integer"),
        ({"type": "stationary_start", **BASE, "t": -0.1}, "t must be >= 0"),
        ({"type": "stationary_start", **BASE, "x": float("nan")}, "x must be a finite number"),
        ({"type": "stationary_start", **BASE, "y": "12"}, "y must be a finite number"),
        ({"type": "stationary_start", **BASE, "track": True}, "track must be an integer"),
        ({"type": "stationary_start", **BASE, "X": 1.0}, "both X and Y or neither"),
        ({"type": "stationary_end", **BASE, "duration_s": -1.0}, "duration_s must be >= 0"),
        ({"type": "line_cross", **BASE, "line": "", "direction": "in"}, "line must be a non-empty"),
    ],
)
def test_bad_event_objects_are_refused_with_the_problem_named(obj, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        Event.from_json(obj)


def test_from_json_refuses_what_is_not_an_object():
    with pytest.raises(ValueError, match="must be a JSON object, got list"):
        Event.from_json([1, 2])


def test_events_are_frozen_and_hashable():
    e = Event.from_json(VALID[0])
    with pytest.raises(AttributeError):
        e.frame = 2  # type: ignore[misc]
    assert len({e, Event.from_json(VALID[0])}) == 1


def test_events_header_names_schema_version_and_frame_rate():
    h = events_header(25, source="video.avi", scene="scene.toml")
    assert h == {
        "schema": EVENTS_SCHEMA,
        "version": EVENTS_SCHEMA_VERSION,
        "fps": 25.0,
        "source": "video.avi",
        "scene": "scene.toml",
    }
    assert EVENTS_SCHEMA == "motiontrack.events" and EVENTS_SCHEMA_VERSION == 1


# ------------------------------------------------------------------ plug-in event types
@pytest.fixture
def counted():
    """A plug-in type ``counted`` that needs ``zone`` and may carry ``dwell_s``."""
    register_event_type("counted", ("zone",), ("dwell_s",))
    yield "counted"
    unregister_event_type("counted")


def test_a_registered_event_type_is_valid_with_its_fields_and_round_trips(counted):
    e = Event.from_json({"type": "counted", **BASE, "zone": "plaza", "dwell_s": 2.0})
    assert Event.from_json(e.to_json()) == e
    assert event_types() == EVENT_TYPES + ("counted",)


@pytest.mark.parametrize("extra, message", [
    ({}, "counted event needs zone"),
    ({"zone": "plaza", "line": "gate"}, "counted event cannot have line"),
])
def test_a_registered_event_type_checks_its_fields(counted, extra, message):
    with pytest.raises(ValueError, match=message):
        Event(type="counted", **BASE, **extra)


def test_an_unregistered_event_type_is_refused_again(counted):
    unregister_event_type("counted")
    with pytest.raises(ValueError, match="event type must be one of line_cross, .*speeding, got"):
        Event(type="counted", **BASE, zone="plaza")
    register_event_type("counted", ("zone",), ("dwell_s",))   # the fixture unregisters it


@pytest.mark.parametrize("name, required, optional, message", [
    ("zone_exit", ("zone",), (), "'zone_exit' is already registered with other fields"),
    ("counted2", ("colour",), (), "unknown field 'colour'"),
    ("two words", (), (), "letters, digits and _"),
])
def test_registering_an_event_type_refuses_clashes_and_unknown_fields(name, required, optional,
                                                                      message):
    with pytest.raises(ValueError, match=message):
        register_event_type(name, required, optional)


def test_registering_a_builtin_type_with_its_own_fields_changes_nothing():
    register_event_type("zone_exit", ("zone", "dwell_s"))
    assert event_types() == EVENT_TYPES
    with pytest.raises(ValueError, match="not a registered plug-in type"):
        unregister_event_type("zone_exit")
