"""`motiontrack config --json-schema FILE` exports the schemas of the files users write (config,
scene, cameras, manifest) as JSON Schema whose structure is sound and whose facts (required
keys, enums, bounds, no other keys, exactly one of two keys) known-good files satisfy; the
manifest's entries are checked by their schema."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from motiontrack.analytics.scene import parse_scene, scene_json_schema
from motiontrack.cli import main
from motiontrack.cli.config import JSON_SCHEMA_FILES, json_schema_of
from motiontrack.errors import InputError
from motiontrack.io.manifest import manifest_json_schema, read_manifest_entries

ROOT = Path(__file__).resolve().parents[1]
DRAFT = "https://json-schema.org/draft/2020-12/schema"
TYPES = {"object", "array", "string", "number", "integer", "boolean"}
PYTHON = {"object": dict, "array": list, "string": str, "boolean": bool,
          "number": (int, float), "integer": int}

SCENE = {
    "anchor": "center", "hysteresis_px": 3, "forget_s": 1.5,
    "line": [{"name": "gate", "points": [[0, 10], [100, 10]]},
             {"name": "m", "world": [[0, 0], [1, 0]]}],
    "zone": [{"name": "z", "polygon": [[0, 0], [9, 0], [9, 9]], "loiter_s": 4}],
    "stationary": {"after_s": 10, "radius_px": 15},
    "abandoned": {"after_s": 15, "distance_heights": 1.5},
    "speed": {"limit_mps": 3.0, "window_s": 1},
}
CAMERAS = {"camera": [{"name": "door", "source": "synth:crossing", "loop": True, "fps": 10}]}
MANIFEST = {"sequence": [{"name": "a", "source": "synth:crossing", "group": "g"},
                         {"source": "v.avi", "gt": "gt.txt", "scene": "s.toml"}]}


def well_formed(schema: dict, where: str = "#") -> None:
    """Hand checks of JSON Schema structure: known types, required keys among the properties,
    enums as lists, bounds as numbers in order, sub-schemas well formed in turn."""
    assert isinstance(schema, dict), where
    if "type" in schema:
        assert schema["type"] in TYPES, where
    if "enum" in schema:
        assert isinstance(schema["enum"], list) and schema["enum"], where
    bounds = [schema.get(k) for k in ("minimum", "exclusiveMinimum", "maximum")]
    for b in bounds:
        assert b is None or (isinstance(b, (int, float)) and not isinstance(b, bool)), where
    lo = schema.get("minimum", schema.get("exclusiveMinimum"))
    if lo is not None and schema.get("maximum") is not None:
        assert lo <= schema["maximum"], where
    if "properties" in schema:
        assert schema.get("type") == "object", where
        for name, sub in schema["properties"].items():
            well_formed(sub, f"{where}/{name}")
        assert set(schema.get("required", [])) <= set(schema["properties"]), where
    if isinstance(schema.get("items"), dict):
        well_formed(schema["items"], f"{where}/items")
    for i, sub in enumerate(schema.get("prefixItems", [])):
        well_formed(sub, f"{where}/{i}")
    for key in ("allOf", "oneOf"):
        for sub in schema.get(key, []):
            well_formed(sub, f"{where}/{key}")


def holds(schema: dict, data, where: str = "#") -> None:
    """The facts these tests rely on hold for ``data``: type, enum, bounds, required keys, no
    other keys, items, exactly one of a ``oneOf`` of required keys."""
    if "type" in schema:
        t = PYTHON[schema["type"]]
        assert isinstance(data, t) and not (isinstance(data, bool) and schema["type"] in (
            "number", "integer")), (where, data)
    if "enum" in schema:
        assert data in schema["enum"], where
    if isinstance(data, (int, float)) and not isinstance(data, bool):
        assert data >= schema.get("minimum", data), where
        assert data > schema.get("exclusiveMinimum", data - 1), where
        assert data <= schema.get("maximum", data), where
    if isinstance(data, dict):
        assert set(schema.get("required", [])) <= set(data), where
        props = schema.get("properties", {})
        if schema.get("additionalProperties") is False:
            assert set(data) <= set(props), (where, set(data) - set(props))
        for k, v in data.items():
            if k in props:
                holds(props[k], v, f"{where}/{k}")
        for group in schema.get("allOf", []):
            given = [alt for alt in group["oneOf"] if set(alt["required"]) <= set(data)]
            assert len(given) == 1, where
    if isinstance(data, list):
        assert len(data) >= schema.get("minItems", 0), where
        assert len(data) <= schema.get("maxItems", len(data)), where
        for i, v in enumerate(data):
            prefix = schema.get("prefixItems", [])
            sub = prefix[i] if i < len(prefix) else schema.get("items", {})
            if isinstance(sub, dict):
                holds(sub, v, f"{where}/{i}")


@pytest.mark.parametrize("file", JSON_SCHEMA_FILES)
def test_every_export_is_well_formed_json_schema(file):
    schema = json_schema_of(file)
    assert schema["$schema"] == DRAFT and schema["title"].startswith("motiontrack")
    well_formed(schema)
    json.dumps(schema)   # plain JSON


@pytest.mark.parametrize("file, data", [
    ("scene", SCENE),
    ("scene", tomllib.loads((ROOT / "examples" / "pets-s2l1-scene.toml").read_text())),
    ("config", tomllib.loads((ROOT / "src/motiontrack/data/presets/people.toml").read_text())),
    ("cameras", CAMERAS),
    ("manifest", MANIFEST),
])
def test_known_good_files_satisfy_their_exported_schema(file, data):
    holds(json_schema_of(file), data)


def test_scene_schema_knows_every_rules_table_and_its_facts():
    schema = scene_json_schema()
    props = schema["properties"]
    assert list(props) == ["anchor", "hysteresis_px", "forget_s", "evidence", "line", "zone",
                           "stationary", "abandoned", "speed"]
    assert props["evidence"]["properties"]["clip_s"]["default"] == [5.0, 10.0]
    # every rule's table may choose its own evidence
    assert {"snapshot", "clip_s"} <= set(props["zone"]["items"]["properties"])
    assert {"snapshot", "clip_s"} <= set(props["stationary"]["properties"])
    assert schema["additionalProperties"] is False
    assert props["anchor"]["enum"] == ["bottom_center", "center"]
    assert props["forget_s"]["exclusiveMinimum"] == 0.0
    line = props["line"]["items"]
    assert line["required"] == ["name"] and line["properties"]["points"]["items"]["maxItems"] == 2
    assert props["stationary"]["required"] == ["after_s"]
    assert props["speed"]["properties"]["window_s"]["default"] == 1.0


@pytest.mark.parametrize("data", [
    {"anchor": "head"},
    {"stationary": {"after_s": 0, "radius_px": 5}},
    {"stationary": {"after_s": 3, "radius_px": 5, "radius_m": 1}},
    {"line": [{"points": [[0, 0], [5, 5]]}]},
    {"zone": [{"name": "z", "polygon": [[0, 0, 0]]}]},
    {"speed": {"limit_px_s": 3, "colour": 1}},
])
def test_scenes_the_parser_refuses_break_a_fact_of_the_exported_schema(data):
    from motiontrack.errors import ConfigError

    with pytest.raises(ConfigError):
        parse_scene(data)
    with pytest.raises(AssertionError):
        holds(scene_json_schema(), data)


def test_manifest_schema_requires_one_sequence_with_a_source():
    schema = manifest_json_schema()
    seq = schema["properties"]["sequence"]
    assert schema["required"] == ["sequence"] and seq["minItems"] == 1
    assert seq["items"]["required"] == ["source"]
    assert set(seq["items"]["properties"]) == {"name", "source", "gt", "group", "scene", "camera"}


@pytest.mark.parametrize("body, message", [
    ('[[sequence]]\nname = "a"\n', r"sequence\[1\].source is required"),
    ('[[sequence]]\nsource = "synth:x"\n[[sequence]]\nsource = "v.avi"\ngt = 5\n',
     r"sequence\[2\].gt must be a string, got 5"),
    ('[[sequence]]\nsource = "synth:x"\ncolour = 1\n',
     r"unknown key\(s\) sequence\[1\].colour; valid keys in sequence\[1\]: group, gt, name, "
     r"source$"),
    ('[[sequence]]\nsource = "synth:x"\nscene = "s.toml"\n', r"unknown key\(s\) sequence\[1\].scene"),
    ('[[sequence]]\nsource = "  "\n', r"sequence\[1\].source must be a non-empty string"),
    ('sequence = [1]\n', r"sequence\[1\] must be a table, got 1"),
])
def test_manifest_problems_are_one_line_naming_the_file_and_key(tmp_path, body, message):
    path = tmp_path / "m.toml"
    path.write_text(body)
    with pytest.raises(InputError, match=message) as err:
        read_manifest_entries(path)
    assert str(err.value).startswith(str(path)) and "\n" not in str(err.value)


def test_batch_manifest_entries_may_name_their_scene_and_camera(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text('title = "kept for the reader"\n[[sequence]]\nsource = "synth:crossing"\n'
                    'scene = "s.toml"\n[[sequence]]\nsource = "clips/v.avi"\nname = ""\n')
    a, b = read_manifest_entries(path, files=("scene", "camera"))
    assert a == {"name": "crossing", "source": "synth:crossing", "gt": None, "group": "",
                 "scene": str((tmp_path / "s.toml").resolve())}
    assert b["name"] == "v" and b["source"] == str((tmp_path / "clips/v.avi").resolve())
    assert "scene" not in b


def test_config_json_schema_prints_the_named_file(capsys):
    assert main(["config", "--json-schema", "manifest"]) == 0
    assert json.loads(capsys.readouterr().out) == manifest_json_schema()
    assert main(["config", "--json-schema"]) == 0
    assert json.loads(capsys.readouterr().out)["title"] == "motiontrack pipeline config"
