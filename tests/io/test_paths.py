"""File arguments as paths or glob patterns (``motiontrack.io.paths.expand_paths``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from motiontrack.errors import InputError
from motiontrack.io.paths import expand_paths, is_pattern


def test_patterns_expand_in_natural_order_and_paths_stay_as_given(tmp_path):
    for rel in ("left1.jpg", "left2.jpg", "left10.jpg", "deep/left3.jpg", "video[1080p].mp4"):
        (tmp_path / rel).parent.mkdir(exist_ok=True)
        (tmp_path / rel).write_bytes(b"x")
    (tmp_path / "leftdir.jpg").mkdir()                 # a folder matching the pattern: no file
    got = expand_paths([tmp_path / "left*.jpg", tmp_path / "missing.jpg",
                        tmp_path / "video[1080p].mp4", str(tmp_path / "**" / "left3.jpg")])
    assert got == [tmp_path / "left1.jpg", tmp_path / "left2.jpg", tmp_path / "left10.jpg",
                   tmp_path / "missing.jpg",           # no pattern: the command reports it
                   tmp_path / "video[1080p].mp4",      # an existing name is never a pattern
                   tmp_path / "deep" / "left3.jpg"]    # ** crosses folders
    assert not is_pattern(tmp_path / "video[1080p].mp4") and is_pattern(tmp_path / "x*.jpg")
    assert all(isinstance(p, Path) for p in got)


def test_a_pattern_that_matches_nothing_names_what_was_looked_for(tmp_path):
    with pytest.raises(InputError, match=r"^no images match .*right\*\.jpg$"):
        expand_paths([tmp_path / "right*.jpg"], "images")
