"""The options that stand for config keys: one table, the same key and type everywhere."""

from __future__ import annotations

import argparse

import pytest

from motiontrack.config import load_config
from motiontrack.config_flags import FLAGS, add_flag, flag, flag_overrides
from motiontrack.config_keys import config_fields


def test_every_flag_names_a_config_key_with_its_type():
    types = {key: typ for key, _, typ in config_fields()}
    for f in FLAGS:
        assert types[f.key] is f.type, f.option
        assert (f.switch is None) == (f.type is not bool), f.option


def test_flags_given_become_overrides_in_table_order_and_load():
    p = argparse.ArgumentParser()
    for f in FLAGS:
        add_flag(p, f.option)
    args = p.parse_args(["--fps", "12.5", "--start", "3", "--no-video", "--camera", 'a "b".xml',
                         "--codec", "mp4v"])
    overrides = flag_overrides(args)
    assert overrides == ["source.start=3", "source.fps=12.5", 'output.codec="mp4v"',
                         "output.video=false", 'measure.camera="a \\"b\\".xml"']
    cfg = load_config(None, overrides)
    assert (cfg.source.start, cfg.source.fps, cfg.output.video, cfg.measure.camera) == (
        3, 12.5, False, 'a "b".xml')


@pytest.mark.parametrize("values, expected", [
    ({}, []),
    ({"fps": None, "camera": ""}, []),
    ({"mask_video": False, "max_frames": 0}, ["source.max_frames=0"]),
    ({"fps": 10, "camera": "/c/View_001.xml"},
     ["source.fps=10.0", 'measure.camera="/c/View_001.xml"']),
])
def test_a_flag_not_given_adds_nothing(values, expected):
    assert flag_overrides(values) == expected


def test_a_flag_is_found_by_option_or_by_name():
    assert flag("--max-frames") is flag("max_frames") and flag("fps").key == "source.fps"


def test_dests_limit_the_flags_considered():
    assert flag_overrides({"start": 1, "camera": "x"}, ("start",)) == ["source.start=1"]
