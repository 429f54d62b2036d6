"""Config: defaults, TOML round trip, --set overrides, range and unknown-key errors."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.config import (MotionConfig, PipelineConfig, PreprocessConfig, RegionsConfig,
                                apply_overrides, load_config, save_config, to_dict)
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
    assert to_dict(PipelineConfig())["motion"]["method"] == "knn"


@pytest.mark.parametrize("size, scale", [
    ((768, 576), 0.5),      # PETS: half size, as always
    ((1920, 1080), 0.5),    # larger frames are never reduced below half size
    ((640, 480), 0.6),      # smaller frames keep about 384 x 288 pixels
    ((320, 240), 1.0),      # ... up to full size
    ((160, 120), 1.0),      # never enlarged
])
def test_automatic_processing_scale(size, scale):
    from motiontrack.preprocess import preprocess, resolve_scale

    assert resolve_scale(0.0, *size) == pytest.approx(scale)
    assert resolve_scale(0.3, *size) == 0.3  # an explicit scale is kept
    img = np.zeros((size[1], size[0], 3), np.uint8)
    out = preprocess(img, PreprocessConfig())
    assert out.shape[:2] == (round(size[1] * scale), round(size[0] * scale))
