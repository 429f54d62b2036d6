"""``study.json``, the file that describes a study: its JSON shape checked, and the settings
two of them share or differ in (``--resume`` continues only a study with the same settings).

Pure functions over the parsed JSON; :class:`~motiontrack.studies.sweep.Study` is what a valid
object stands for.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any, Mapping

from ..errors import InputError, printable

__all__ = ["STUDY_FILE", "SETTINGS", "study_meta_problem", "read_study_meta", "settings_key",
           "settings_differences"]

STUDY_FILE = "study.json"


# ------------------------------------------------------------------------------- JSON shape
def _json_type(v: Any) -> str:
    """The JSON type of a parsed value, for messages."""
    if v is None:
        return "null"
    for types, name in ((bool, "a boolean"), ((int, float), "a number"), (str, "a string"),
                        (list, "a list"), (dict, "an object")):
        if isinstance(v, types):
            return name
    return type(v).__name__  # pragma: no cover - json.loads gives only the types above


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def study_meta_problem(meta: Any) -> str | None:
    """What is wrong with the JSON shape of a ``study.json`` object, in one phrase, or None.

    Checked: the object, ``sequences`` (objects with string ``name`` and ``source``, string or
    null ``gt``, string ``group``), ``grid`` (``{"key": string, "values": [number | boolean |
    string, ...]}``), ``base_config`` and ``evaluation`` objects with a number ``xi`` (and a
    string ``scoring`` when present), and when
    present ``save`` (strings), ``versions`` (an object) and ``runs`` (a number). The values
    themselves are checked by :class:`Study`.
    """
    if not isinstance(meta, dict):
        return f"expected a JSON object, got {_json_type(meta)}"
    missing = [k for k in ("sequences", "grid", "base_config", "evaluation") if k not in meta]
    if missing:
        return "no " + ", ".join(f'"{k}"' for k in missing)
    seqs = meta["sequences"]
    if not isinstance(seqs, list) or not seqs:
        return f'"sequences" must be a non-empty list, got {_json_type(seqs)}'
    for i, s in enumerate(seqs, 1):
        if not isinstance(s, dict):
            return f"sequence {i} must be an object, got {_json_type(s)}"
        unknown = sorted(set(s) - {"name", "source", "gt", "group"})
        if unknown:
            return f"sequence {i}: unknown key(s) {', '.join(map(json.dumps, unknown))}"
        for key, ok, what in (("name", str, "a string"), ("source", str, "a string"),
                              ("gt", (str, type(None)), "a string or null"),
                              ("group", str, "a string")):
            if (key in s or key in ("name", "source")) and not isinstance(s.get(key), ok):
                return f'sequence {i}: "{key}" must be {what}, got {_json_type(s.get(key))}'
    grid = meta["grid"]
    if not isinstance(grid, list) or not grid:
        return f'"grid" must be a non-empty list, got {_json_type(grid)}'
    for i, g in enumerate(grid, 1):
        if not (isinstance(g, dict) and isinstance(g.get("key"), str)
                and isinstance(g.get("values"), list)):
            return f'grid entry {i} must be {{"key": string, "values": list}}'
        if not g["values"] or not all(isinstance(v, (str, bool)) or _is_number(v) for v in g["values"]):
            return (f'grid entry {i} ({json.dumps(g["key"])}): "values" must be a non-empty list '
                    "of numbers, booleans or strings")
    for key in ("base_config", "evaluation") + tuple(k for k in ("versions",) if k in meta):
        if not isinstance(meta[key], dict):
            return f'"{key}" must be an object, got {_json_type(meta[key])}'
    if not _is_number(meta["evaluation"].get("xi")):
        return f'"evaluation" needs a number "xi", got {_json_type(meta["evaluation"].get("xi"))}'
    if not isinstance(meta["evaluation"].get("scoring", ""), str):
        got = _json_type(meta["evaluation"]["scoring"])
        return f'"evaluation": "scoring" must be a string, got {got}'
    save = meta.get("save", [])
    if not isinstance(save, list) or not all(isinstance(x, str) for x in save):
        return '"save" must be a list of strings'
    if "runs" in meta and not _is_number(meta["runs"]):
        return f'"runs" must be a number, got {_json_type(meta["runs"])}'
    return None



def read_study_meta(folder: str | Path) -> dict[str, Any]:
    """The ``study.json`` object of a study folder, its JSON shape checked
    (:func:`study_meta_problem`); :class:`InputError` naming the file otherwise."""
    p = Path(folder) / STUDY_FILE
    if not p.is_file():
        raise InputError(f"no {STUDY_FILE} in {printable(folder)}: not a sweep output folder")
    try:
        meta = json.loads(p.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:
        raise InputError(f"malformed {printable(p)}: not UTF-8 text (byte {exc.start})") from None
    # JSONDecodeError, an integer of too many digits (both ValueError), nesting too deep
    except (ValueError, RecursionError) as exc:
        raise InputError(f"malformed {printable(p)}: {printable(exc)}") from None
    problem = study_meta_problem(meta)
    if problem:
        raise InputError(f"malformed {printable(p)}: {problem}")
    return meta


# ------------------------------------------------------------------------------- settings
#: the parts of study.json that decide a run's numbers (versions and run counts do not)
SETTINGS = ("format", "sequences", "grid", "base_config", "evaluation", "save")


def _settings(meta: Mapping[str, Any]) -> dict[str, Any]:
    """The settings of a study as plain JSON values (tuples become lists, as in study.json)."""
    return json.loads(json.dumps({k: meta.get(k) for k in SETTINGS}))


def _canonical(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"))


def settings_key(meta: Mapping[str, Any]) -> str:
    """SHA-256 of the settings of a ``study.json`` object: a run record made under other
    settings is not reused."""
    return hashlib.sha256(_canonical(_settings(meta)).encode("utf-8")).hexdigest()


def _flat_items(value: Any, prefix: str = "") -> dict[str, Any]:
    """The leaves of nested JSON objects by dotted key (``""`` for a value that is no object)."""
    if isinstance(value, dict) and value:
        out: dict[str, Any] = {}
        for k, v in value.items():
            out.update(_flat_items(v, f"{prefix}{k}."))
        return out
    return {prefix[:-1]: value}


def _value_diffs(label: str, old: Any, new: Any) -> list[str]:
    """``label key: OLD there, NEW now`` for every leaf that differs (values as JSON, so that
    control characters stay escaped)."""
    a, b = _flat_items(old), _flat_items(new)
    out = []
    for k in list(a) + [k for k in b if k not in a]:
        there = _canonical(a[k]) if k in a else "(absent)"
        now = _canonical(b[k]) if k in b else "(absent)"
        if there != now:
            out.append(f"{label}{' ' + printable(k) if k else ''}: {there} there, {now} now")
    return out


def settings_differences(old: Mapping[str, Any], new: Mapping[str, Any]) -> list[str]:
    """What differs between the settings of two ``study.json`` objects, one phrase each
    (empty when a study may be resumed)."""
    a, b = _settings(old), _settings(new)
    out: list[str] = []
    if _canonical(a["format"]) != _canonical(b["format"]):
        out += _value_diffs("study format", a["format"], b["format"])
    if _canonical(a["sequences"]) != _canonical(b["sequences"]):
        if len(a["sequences"]) != len(b["sequences"]):
            out.append(f"sequences: {len(a['sequences'])} there, {len(b['sequences'])} now")
        else:
            for i, (sa, sb) in enumerate(zip(a["sequences"], b["sequences"]), 1):
                out += _value_diffs(f"sequence {i}", sa, sb)
    ga = [(g["key"], g["values"]) for g in a["grid"]]
    gb = [(g["key"], g["values"]) for g in b["grid"]]
    if [k for k, _ in ga] != [k for k, _ in gb]:
        out.append(f"swept parameters: {printable(', '.join(k for k, _ in ga))} there, "
                   f"{printable(', '.join(k for k, _ in gb))} now")
    else:
        out += [f"values of {printable(k)}: {_canonical(va)} there, {_canonical(vb)} now"
                for (k, va), (_, vb) in zip(ga, gb) if _canonical(va) != _canonical(vb)]
    out += _value_diffs("base config", a["base_config"], b["base_config"])
    out += _value_diffs("evaluation", a["evaluation"], b["evaluation"])
    out += _value_diffs("--save", a["save"] or [], b["save"] or [])
    return out
