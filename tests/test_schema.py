"""The file-schema mechanism: typed fields, nested tables, arrays of tables, messages, JSON
Schema."""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import pytest

from motiontrack.config import PipelineConfig
from motiontrack.errors import ConfigError
from motiontrack.schema import REQUIRED, Section, from_dict, json_schema, leaf_fields, param


@dataclass(frozen=True, kw_only=True)
class Zone(Section):
    name: str = param(REQUIRED, pattern=r"[a-z]{1,8}", pattern_doc="1 to 8 small letters")
    dwell_s: float = param(10.0, lo=0, lo_open=True, hi=3600, doc="seconds before an event")
    kind: str = param("zone", choices=("zone", "line"))


@dataclass(frozen=True, kw_only=True)
class Limits(Section):
    speed: float = param(2.0, lo=0.0, hi=100.0, doc="m/s")


@dataclass(frozen=True, kw_only=True)
class Scene(Section):
    zone: tuple[Zone, ...] = param((), doc="one table per zone")
    limits: Limits = field(default_factory=Limits)
    title: str | None = param(None, nonblank=True)


def test_nested_tables_and_arrays_of_tables_are_built():
    s = from_dict(Scene, {"zone": [{"name": "gate"}, {"name": "door", "dwell_s": 5}],
                          "limits": {"speed": 3}})
    assert s.zone == (Zone(name="gate"), Zone(name="door", dwell_s=5.0))
    assert s.limits.speed == 3.0 and isinstance(s.limits.speed, float) and s.title is None


@pytest.mark.parametrize("data, message", [
    ({"zone": [{"name": "gate", "dwel_s": 1}]},
     "unknown key(s) zone[1].dwel_s; valid keys in zone[1]: dwell_s, kind, name"),
    ({"zone": [{"name": "gate"}, {}]}, "zone[2].name is required"),
    ({"zone": [{"name": "Gate"}]}, "zone[1].name must be 1 to 8 small letters, got 'Gate'"),
    ({"zone": [{"name": "g", "dwell_s": 0}]}, "zone[1].dwell_s must be in (0, 3600], got 0.0"),
    ({"zone": [{"name": "g", "dwell_s": "long"}]}, "zone[1].dwell_s must be a number, got 'long'"),
    ({"zone": [{"name": "g", "kind": "area"}]},
     "zone[1].kind must be one of zone, line, got 'area'"),
    ({"limits": {"speed": 101}}, "limits.speed must be in [0.0, 100.0], got 101.0"),
    ({"limits": 3}, "limits must be a table, got 3"),
    ({"zone": {"name": "g"}}, "zone must be an array, got a table"),
    ({"title": "  "}, "title must be a non-empty string, got '  '"),
    ({"titel": "x"}, "unknown key(s) titel; valid keys: limits, title, zone"),
])
def test_a_problem_is_one_line_naming_the_key_as_written(data, message):
    with pytest.raises(ConfigError, match=re.escape(message)) as exc:
        from_dict(Scene, data)
    assert "\n" not in str(exc.value)


def test_a_section_built_directly_is_checked_too():
    with pytest.raises(ConfigError, match=re.escape("Limits.speed must be in [0.0, 100.0]")):
        Limits(speed=-1.0)


def test_json_schema_states_types_ranges_defaults_and_required_keys():
    s = json_schema(Scene, title="scene")
    assert s["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert s["additionalProperties"] is False and "required" not in s
    zone = s["properties"]["zone"]["items"]
    assert zone["required"] == ["name"]
    assert zone["properties"]["dwell_s"] == {"type": "number", "exclusiveMinimum": 0,
                                             "maximum": 3600, "description":
                                             "seconds before an event", "default": 10.0}
    assert zone["properties"]["kind"]["enum"] == ["zone", "line"]
    assert s["properties"]["limits"]["properties"]["speed"]["maximum"] == 100.0


def test_the_pipeline_config_exports_every_key_with_its_range():
    s = json_schema(PipelineConfig)
    knn = s["properties"]["motion"]["properties"]["knn"]["properties"]
    assert knn["n_samples"] == {"type": "integer", "minimum": 1, "maximum": 50, "default": 7,
                                "description": knn["n_samples"]["description"]}
    n_leaves = sum(1 for _ in leaf_fields(PipelineConfig))

    def count(obj):
        props = obj.get("properties")
        return 1 if props is None else sum(count(p) for p in props.values())

    assert count(s) == n_leaves


def test_a_mutable_default_is_refused():
    with pytest.raises(TypeError, match="immutable"):
        param([])


def test_the_cameras_file_schema_requires_a_camera_with_name_and_source():
    from motiontrack.serve.cameras import cameras_json_schema

    s = cameras_json_schema()
    assert s["required"] == ["camera"] and s["properties"]["camera"]["minItems"] == 1
    cam = s["properties"]["camera"]["items"]
    assert cam["required"] == ["name", "source"] and cam["additionalProperties"] is False
    assert cam["properties"]["fps"]["exclusiveMinimum"] == 0


def test_none_stands_for_an_absent_key_only_where_none_may_stand():
    assert from_dict(Scene, {"title": None}).title is None
    with pytest.raises(ConfigError, match=re.escape("zone[1].name is required")):
        from_dict(Scene, {"zone": [{"name": None}]})
    with pytest.raises(ConfigError, match=re.escape("limits.speed must be a number, got a NoneType")):
        from_dict(Scene, {"limits": {"speed": None}})


@dataclass(frozen=True, kw_only=True)
class Path2(Section):
    points: tuple[tuple[float, float], ...] = param(REQUIRED, lo=-10.0, hi=10.0)


@pytest.mark.parametrize("data, message", [
    ({"points": [[0, 0], [1]]}, r"points\[2\] must be \[x, y\]: an array of 2 numbers, got an array"),
    ({"points": [[0, 0], 3]}, r"points\[2\] must be \[x, y\]: an array of 2 numbers, got 3"),
    ({"points": "x"}, r"points must be an array of \[x, y\] points, got 'x'"),
    ({"points": [[0, "a"]]}, r"points\[1\]\[2\] must be a number, got 'a'"),
    ({"points": [[0, 11]]}, r"points\[1\]\[2\] must be in \[-10.0, 10.0\], got 11.0"),
    ({"points": [[float("nan"), 0]]}, r"points\[1\]\[1\] must be a finite number"),
])
def test_each_number_of_an_array_of_points_is_checked_and_named_by_its_place(data, message):
    with pytest.raises(ConfigError, match=message):
        from_dict(Path2, data)


def test_an_array_of_points_is_built_as_tuples_of_floats_and_exports_its_range():
    assert from_dict(Path2, {"points": [[1, 2], [3, 4.5]]}).points == ((1.0, 2.0), (3.0, 4.5))
    point = json_schema(Path2)["properties"]["points"]["items"]
    assert point["minItems"] == point["maxItems"] == 2 and point["items"] is False
    assert point["prefixItems"][0] == {"type": "number", "minimum": -10.0, "maximum": 10.0}
