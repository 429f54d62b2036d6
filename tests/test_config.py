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
    from motiontrack.imaging import resolve_scale
    from motiontrack.preprocess import preprocess

    assert resolve_scale(0.0, *size) == pytest.approx(scale)
    assert resolve_scale(0.3, *size) == 0.3  # an explicit scale is kept
    img = np.zeros((size[1], size[0], 3), np.uint8)
    out = preprocess(img, PreprocessConfig())
    assert out.shape[:2] == (round(size[1] * scale), round(size[0] * scale))


def test_pixel_window_scales_widens_and_cuts_a_box():
    from motiontrack.imaging import pixel_window

    # (10.5, 20, 7, 9) at scale 0.5 is x 5.25..8.75, y 10..14.5: whole pixels 5..9, 10..15
    assert pixel_window((10.5, 20, 7, 9), 0.5, (100, 200)) == (5, 10, 9, 15)
    assert pixel_window((10.5, 20, 7, 9), 0.5, (100, 200, 3), margin=2) == (3, 8, 11, 17)
    # cut to the image; a box outside it is an empty window
    assert pixel_window((-4, 190, 10, 30), 1.0, (200, 100)) == (0, 190, 6, 200)
    x1, y1, x2, y2 = pixel_window((150, 10, 5, 5), 1.0, (200, 100))
    assert x2 <= x1


def test_to_gray_converts_colour_and_passes_gray_through():
    from motiontrack.imaging import to_gray

    bgr = np.zeros((4, 5, 3), np.uint8)
    bgr[..., 2] = 200                      # pure red
    g = to_gray(bgr)
    assert g.shape == (4, 5) and int(g[0, 0]) == round(0.299 * 200)
    gray = np.full((4, 5), 7, np.uint8)
    assert to_gray(gray) is gray
