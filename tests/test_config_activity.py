"""Which config keys take effect (motiontrack.config_activity), the key descriptions every
command and docs/pipeline.md share (motiontrack.config_keys), and config errors that name keys as
users write them."""

from __future__ import annotations

import dataclasses
import typing

import pytest

from motiontrack.config import (KNNParams, MotionConfig, Not, PipelineConfig, PreprocessConfig,
                                RegionsConfig, apply_overrides, from_dict, load_config, presets)
from motiontrack.config_activity import (activity, check_study_keys, inactive_in_study,
                                         warn_inactive_overrides)
from motiontrack.config_keys import config_fields, flatten, key_docs, markdown_table
from motiontrack.errors import ConfigError
from motiontrack.studies.ablate import ROWS, row_settings

KEYS = [k for k, _, _ in config_fields()]


# ------------------------------------------------------------------------- one key, one config
@pytest.mark.parametrize("overrides, key, message", [
    # per-method sections: only the selected detector's keys take effect
    ([], "motion.mog2.var_threshold",
     "motion.mog2.var_threshold has no effect while motion.method = knn; "
     "add --set motion.method=mog2"),
    ([], "motion.median.threshold",
     "motion.median.threshold has no effect while motion.method = knn; "
     "add --set motion.method=median"),
    (["motion.method=mog2"], "motion.knn.dist2_threshold",
     "motion.knn.dist2_threshold has no effect while motion.method = mog2; "
     "add --set motion.method=knn"),
    # a switch of the section, and the section's method before it
    ([], "motion.knn.protect_threshold",
     "motion.knn.protect_threshold has no effect while motion.knn.protect = false; "
     "add --set motion.knn.protect=true"),
    ([], "motion.mog2.protect_threshold",
     "motion.mog2.protect_threshold has no effect while motion.method = knn and "
     "motion.mog2.protect = false; add --set motion.method=mog2 --set motion.mog2.protect=true"),
    # a switch that must differ from "off": the hint names a value that turns it on
    ([], "tracker.bridge_frames",
     "tracker.bridge_frames has no effect while tracker.bridge = none; add --set tracker.bridge=kcf"),
    (["tracker.cost=center"], "tracker.min_iou",
     "tracker.min_iou has no effect while tracker.cost = center; add --set tracker.cost=iou"),
    (["tracker.appearance_weight=0"], "tracker.appearance_gate",
     "tracker.appearance_gate has no effect while tracker.appearance_weight = 0.0; "
     "add --set tracker.appearance_weight=0.5"),
    (["cleanup.erode_kernel=0"], "cleanup.erode_iterations",
     "cleanup.erode_iterations has no effect while cleanup.erode_kernel = 0; "
     "add --set cleanup.erode_kernel=3"),
    (["preprocess.blur=none"], "preprocess.blur_kernel",
     "preprocess.blur_kernel has no effect while preprocess.blur = none; "
     "add --set preprocess.blur=gaussian"),
    (["motion.ghost_ratio=0"], "motion.ghost_pixels",
     "motion.ghost_pixels has no effect while motion.ghost_ratio = 0.0; "
     "add --set motion.ghost_ratio=0.7"),
    # the people stage: the stage's switch first, then the module's
    ([], "people.hog_every",
     "people.hog_every has no effect while people.enabled = false and people.hog = off; "
     "add --set people.enabled=true --set people.hog=regions"),
    ([], "people.refine_support",
     "people.refine_support has no effect while people.enabled = false and people.refine = false; "
     "add --set people.enabled=true --set people.refine=true"),
    # automatic head splitting runs only with the stage off
    (["people.enabled=true"], "people.upright_ratio",
     "people.upright_ratio has no effect while people.enabled = true; "
     "add --set people.enabled=false"),
    # ... and the hint never contradicts itself (people.enabled=true would switch it off again)
    (["people.auto_split=false"], "people.upright_ratio",
     "people.upright_ratio has no effect while people.auto_split = false; "
     "add --set people.auto_split=true"),
    (["people.auto_split=false"], "people.head_min_width",
     "people.head_min_width has no effect while people.enabled = false; "
     "add --set people.enabled=true"),
])
def test_an_inactive_key_names_what_keeps_it_off_and_how_to_turn_it_on(overrides, key, message):
    act = activity(load_config(None, overrides), key)
    assert not act.active
    assert act.message() == message


@pytest.mark.parametrize("overrides, key", [
    ([], "motion.knn.dist2_threshold"),                     # the default detector
    (["motion.method=mog2"], "motion.mog2.var_threshold"),
    (["motion.method=mog2", "motion.mog2.protect=true"], "motion.mog2.protect_threshold"),
    ([], "people.upright_ratio"),                           # automatic head splitting is on
    ([], "people.head_min_width"),                          # ... and uses the head detector
    (["people.enabled=true", "people.hog=alone"], "people.hog_every"),
    (["people.enabled=true", "people.refine=true"], "people.hypothesis_iou"),  # either switch
    (["people.enabled=true", "people.hypotheses=true"], "people.hypothesis_iou"),
    (["tracker.bridge=csrt"], "tracker.bridge_frames"),
    ([], "source.start"),                                   # keys without a switch
    ([], "regions.min_area"),
    ([], "motion.method"),
])
def test_an_active_key_needs_nothing(overrides, key):
    act = activity(load_config(None, overrides), key)
    assert act.active and act.needs == ()


def test_every_method_section_takes_effect_exactly_while_its_method_is_selected():
    sections = [f.name for f in dataclasses.fields(MotionConfig)
                if dataclasses.is_dataclass(typing.get_type_hints(MotionConfig)[f.name])]
    assert {"knn", "mog2", "median", "farneback"} <= set(sections)
    for method in sections:
        cfg = load_config(None, [f"motion.method={method}"])
        for key in KEYS:
            parts = key.split(".")
            if parts[0] == "motion" and len(parts) == 3 and parts[2] not in ("protect_threshold",):
                assert activity(cfg, key).active == (parts[1] == method), (method, key)


@pytest.mark.parametrize("base", [[], ["people.enabled=true"], ["motion.method=median"],
                                  ["people.auto_split=false", "people.heads=false"],
                                  ["tracker.cost=center", "tracker.appearance_weight=0",
                                   "motion.ghost_ratio=0", "cleanup.dilate_kernel=0"]]
                         + [[f"--preset={p}"] for p in presets()])
def test_the_settings_a_hint_names_turn_the_key_on(base):
    preset = base[0].split("=", 1)[1] if base and base[0].startswith("--preset") else None
    cfg = load_config(None, [] if preset else base, preset=preset)
    inactive = 0
    for key in KEYS:
        act = activity(cfg, key)
        if act.active:
            continue
        inactive += 1
        fixed = apply_overrides(cfg, act.settings)      # valid settings ...
        assert activity(fixed, key).active, (key, act.settings)   # ... that turn the key on
    assert inactive > 0


def test_every_when_names_a_sibling_switch_and_an_example_that_meets_it():
    sections: dict[str, list[str]] = {}
    for key in KEYS:
        section, _, name = key.rpartition(".")
        sections.setdefault(section, []).append(name)
    for key, f, _ in config_fields():
        section = key.rpartition(".")[0]
        for alt in f.metadata["when"]:
            for switch, cond in alt.items():
                assert switch in sections[section], (key, switch)
                if isinstance(cond, Not):
                    assert cond.example != cond.value, key
                    apply_overrides(PipelineConfig(), [f"{section}.{switch}={cond.example!r}"
                                                       .replace("'", '"')])


def test_an_unknown_key_is_a_config_error():
    with pytest.raises(ConfigError, match="unknown config key 'motion.nope'"):
        activity(PipelineConfig(), "motion.nope")


# ------------------------------------------------------------------------------------ studies
def test_a_study_that_varies_the_switch_activates_the_key():
    cfg = load_config(None)
    grid = {"motion.method": ["knn", "mog2"], "motion.mog2.var_threshold": [8, 40]}
    assert inactive_in_study(cfg, grid, grid) == []
    check_study_keys(cfg, grid)                       # no error


def test_a_study_no_point_of_which_activates_a_key_is_refused_naming_the_switch():
    cfg = load_config(None)
    with pytest.raises(ConfigError) as exc:
        check_study_keys(cfg, {"motion.mog2.var_threshold": [8, 40], "regions.min_area": [10, 20]})
    assert str(exc.value) == ("--param motion.mog2.var_threshold has no effect while motion.method "
                              "= knn; add --set motion.method=mog2 (or sweep motion.method)")
    # a method list that never names the section is refused too
    with pytest.raises(ConfigError, match="while motion.method = knn; add --set motion.method=mog2"):
        check_study_keys(cfg, {"motion.method": ["knn", "median"],
                               "motion.mog2.var_threshold": [8, 40]}, "search")


def test_a_tuning_range_stands_for_the_values_between_its_ends():
    cfg = load_config(None, ["motion.ghost_ratio=0"])
    assert inactive_in_study(cfg, ["motion.ghost_pixels"],
                             {"motion.ghost_ratio": (0.0, 1.0), "motion.ghost_pixels": (True, False)}
                             ) == []
    dead = inactive_in_study(cfg, ["motion.ghost_pixels"], {"motion.ghost_pixels": (True, False)})
    assert [a.key for a in dead] == ["motion.ghost_pixels"]


def test_an_ablation_row_that_switches_a_module_on_activates_its_keys():
    cfg = load_config(None)
    points = row_settings(ROWS)
    assert activity(cfg, "people.hog_every").active is False
    assert activity(cfg, "people.hog_every", points).active            # the HOG row
    assert activity(cfg, "people.hypothesis_coast", points).active     # the hypotheses row
    assert not activity(cfg, "people.refine_support", points).active   # no row refines


def test_overrides_of_inactive_keys_are_warned_about_once_each():
    cfg = load_config(None, ["motion.mog2.history=3", "motion.knn.history=3"])
    assert warn_inactive_overrides(cfg, ["motion.mog2.history=3", "motion.knn.history=3",
                                         "motion.mog2.history=4"]) == ["motion.mog2.history"]
    # in a study over motion.method, a --set motion.mog2.* key takes effect at some points
    assert warn_inactive_overrides(cfg, ["motion.mog2.history=3"],
                                   domains={"motion.method": ["knn", "mog2"]}) == []


# ------------------------------------------------------------------------------ key descriptions
def test_every_key_is_described_with_a_type_and_a_meaning():
    docs = key_docs()
    assert [d.key for d in docs] == KEYS
    assert len(KEYS) == len(flatten(PipelineConfig()))
    assert {d.type for d in docs} == {"int", "float", "bool", "str"}
    assert [d.key for d in docs if not d.meaning] == []
    knn = next(d for d in docs if d.key == "motion.knn.n_samples")
    assert (knn.type, knn.default, knn.allowed) == ("int", 7, "[1, 50]")
    kernel = next(d for d in docs if d.key == "preprocess.blur_kernel")
    assert kernel.allowed == "[0, 51] odd or 0"


def test_markdown_table_is_the_table_of_the_pipeline_doc():
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[1] / "docs" / "pipeline.md").read_text()
    assert markdown_table() in doc


# ------------------------------------------------------------------- errors name keys, not classes
def _sections():
    hints = typing.get_type_hints
    out = {}

    def walk(cls, prefix):
        for name, typ in hints(cls).items():
            if dataclasses.is_dataclass(typ):
                out[prefix + name] = typ
                walk(typ, f"{prefix}{name}.")

    walk(PipelineConfig, "")
    return out


def test_a_section_built_directly_names_its_keys_as_users_write_them():
    checked = 0
    for path, cls in _sections().items():
        for f in dataclasses.fields(cls):
            lo = f.metadata.get("lo")
            if lo is None or lo <= -(2**31):
                continue
            typ = typing.get_type_hints(cls)[f.name]
            with pytest.raises(ConfigError) as exc:
                cls(**{f.name: typ(lo) - 1})
            assert str(exc.value).startswith(f"{path}.{f.name} must be"), str(exc.value)
            checked += 1
    assert checked > 50


@pytest.mark.parametrize("make, message", [
    (lambda: KNNParams(history=0), "motion.knn.history must be in [1, 2147483647], got 0"),
    (lambda: RegionsConfig(max_size=2.0), "regions.max_size must be in [0.0, 1.0], got 2.0"),
    (lambda: PreprocessConfig(scale=0.01),
     "preprocess.scale must be 0 (automatic) or in [0.05, 1.0], got 0.01"),
    (lambda: KNNParams(n_samples=3, knn_samples=4),
     "motion.knn.knn_samples must be at most motion.knn.n_samples (3) and at least 1, got 4"),
    (lambda: load_config(None, ["motion.knn.knn_samples=9"]),
     "motion.knn.knn_samples must be at most motion.knn.n_samples (7) and at least 1, got 9"),
    (lambda: from_dict(KNNParams, {"nope": 1}),
     "unknown config key(s) motion.knn.nope; valid keys in motion.knn: accept_s, "
     "detect_shadows, dist2_threshold, history, hold, hold_speed, hold_threshold, "
     "knn_samples, learning_rate, n_samples, protect, protect_threshold, seed, "
     "shadow_inside, shadow_threshold, vehicle_shadow_threshold"),
    (lambda: from_dict(PipelineConfig, 3), "the config must be a table, got 3"),
])
def test_config_errors_name_the_key_never_the_class(make, message):
    with pytest.raises(ConfigError) as exc:
        make()
    assert str(exc.value) == message
    assert "Params" not in message and "Config" not in message
