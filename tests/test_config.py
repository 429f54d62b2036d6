"""Config: defaults, TOML round trip, --set overrides, range and unknown-key errors."""

from __future__ import annotations

import pytest

from motiontrack.config import (MotionConfig, PipelineConfig, RegionsConfig, apply_overrides,
                                load_config, save_config, to_dict)
from motiontrack.errors import ConfigError, InputError


def test_defaults_roundtrip(tmp_path):
    cfg = PipelineConfig()
    save_config(cfg, tmp_path / "c.toml")
    assert load_config(tmp_path / "c.toml") == cfg


@pytest.mark.parametrize("override, path, value", [
    ("motion.method=knn", ("motion", "method"), "knn"),
    ("motion.mog2.history=300", ("motion", "mog2", "history"), 300),
    ("motion.median.threshold=0.2", ("motion", "median", "threshold"), 0.2),
    ("preprocess.scale=1", ("preprocess", "scale"), 1.0),     # int accepted for a float
    ("output.video=false", ("output", "video"), False),
    ('output.codec="mjpg"', ("output", "codec"), "mjpg"),
    ("output.codec=mjpg", ("output", "codec"), "mjpg"),       # bare strings allowed
])
def test_overrides(override, path, value):
    cfg = apply_overrides(PipelineConfig(), [override])
    node = cfg
    for k in path:
        node = getattr(node, k)
    assert node == value


@pytest.mark.parametrize("override, message", [
    ("motion.median.threshold=1.5", "must be in [0.0, 1.0]"),
    ("preprocess.blur_kernel=4", "odd kernel size"),
    ("preprocess.blur=box", "must be one of"),
    ("motion.nope=1", "unknown config key 'motion.nope'"),
    ("nope.x=1", "unknown config key 'nope'"),
    ("motion.mog2.history=abc", "must be an integer"),
    ("output.video=3", "must be true or false"),
    ("novalue", "stage.param=value"),
])
def test_bad_overrides(override, message):
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("(", r"\(")):
        apply_overrides(PipelineConfig(), [override])


def test_unknown_key_in_file(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text("[regions]\nmin_areaa = 3\n")
    with pytest.raises(ConfigError, match="regions.min_areaa"):
        load_config(p)


@pytest.mark.parametrize("text", ["[regions\n", "a = = 1"])
def test_malformed_file(tmp_path, text):
    p = tmp_path / "c.toml"
    p.write_text(text)
    with pytest.raises(InputError, match="malformed config"):
        load_config(p)


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="not found"):
        load_config(tmp_path / "missing.toml")


def test_sections_validate_directly():
    with pytest.raises(ConfigError, match="RegionsConfig.max_size"):
        RegionsConfig(max_size=2.0)
    assert MotionConfig().params_for("mog2")["history"] == 500
    assert to_dict(PipelineConfig())["motion"]["method"] == "mog2"
