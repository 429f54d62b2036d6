"""Config: defaults, TOML round trip, --set overrides, range and unknown-key errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

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
    with pytest.raises(ConfigError, match="regions.max_size must be in"):
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
    # boxes come as tuples, NumPy rows of float64 and of int (the tracker's and the ghost
    # filter's): the same window
    assert pixel_window(np.array([10.5, 20, 7, 9]), 0.5, (100, 200)) == (5, 10, 9, 15)
    assert pixel_window(np.array([10, 20, 7, 9]), 0.5, (100, 200)) == (5, 10, 9, 15)
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


@pytest.mark.parametrize("override, message", [
    ("motion.knn.dist2_threshold=nan", "motion.knn.dist2_threshold must be a finite number"),
    ("motion.knn.dist2_threshold=inf", "must be a finite number in [0.0, inf], got inf"),
    ("tracker.fill_gaps_s=nan", "tracker.fill_gaps_s must be a finite number in [0.0, 3600.0]"),
    ("tracker.min_iou=-inf", "tracker.min_iou must be a finite number"),
    ("motion.knn.history=99999999999999999999", "motion.knn.history must be in [1, 2147483647]"),
    ("motion.knn.history=1e300", "an integer of 301 digits"),
    ("source.start=-inf", "source.start must be an integer"),
    ("motion.gsoc.n_samples=1000", "motion.gsoc.n_samples must be in [1, 50]"),
    ("motion.knn.history=" + "[" * 100_000, "nested too deeply"),
])
def test_numbers_are_finite_and_in_range(override, message):
    """NaN passes every "<" and ">" test, so a range check written as "lo <= v <= hi" let it in
    (and it was written to config.toml); integers past 64 bits reached OpenCV."""
    with pytest.raises(ConfigError) as err:
        apply_overrides(PipelineConfig(), [override])
    assert message in str(err.value)


def test_a_config_file_with_nan_is_refused_and_names_the_key(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text("[motion.knn]\ndist2_threshold = nan\n")
    with pytest.raises(ConfigError, match=r"^motion\.knn\.dist2_threshold must be a finite"):
        load_config(p)


def test_every_field_refuses_nan_inf_and_huge_integers():
    import dataclasses

    from motiontrack.config import INT_MAX, INT_MIN

    def leaves(cls, prefix=""):
        for f in dataclasses.fields(cls):
            default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
            if dataclasses.is_dataclass(default):
                yield from leaves(type(default), f"{prefix}{f.name}.")
            elif isinstance(default, (int, float)) and not isinstance(default, bool) \
                    and not f.metadata.get("choices"):
                yield f"{prefix}{f.name}", default, f.metadata

    checked = 0
    for key, default, meta in leaves(PipelineConfig):
        bad = ["nan", "inf", "-inf"]
        if isinstance(default, int):  # a float field may be large; an integer must fit a C int
            bad += [str(2**64), str(-(2**64)), str(INT_MAX + 1)]
            assert INT_MIN <= meta["lo"] and meta["hi"] <= INT_MAX, key
        for value in bad:
            with pytest.raises(ConfigError):
                apply_overrides(PipelineConfig(), [f"{key}={value}"])
        checked += 1
    assert checked > 80


@settings(max_examples=300, deadline=None, derandomize=True)
@given(value=st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                       st.integers(min_value=-(2**80), max_value=2**80)),
       key=st.sampled_from(["motion.knn.dist2_threshold", "motion.knn.history",
                            "tracker.fill_gaps_s", "tracker.min_iou", "regions.min_area",
                            "source.start", "motion.mog2.learning_rate", "people.samples"]))
def test_a_number_is_taken_only_when_finite_and_inside_its_range(key, value):
    try:
        cfg = apply_overrides(PipelineConfig(), [f"{key}={value!r}"])
    except ConfigError:
        return
    import dataclasses

    section, name = key.rsplit(".", 1)
    node = cfg
    for k in section.split("."):
        node = getattr(node, k)
    meta = {f.name: f.metadata for f in dataclasses.fields(node)}[name]
    v = getattr(node, name)
    assert np.isfinite(v) and meta["lo"] <= v
    assert meta["hi"] is None or v <= meta["hi"]
