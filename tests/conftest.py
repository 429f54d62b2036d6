"""Fixtures shared by the test modules. Plain helpers live in the ``helpers`` package next to
this file (``from helpers import ann, tracks_of``); pytest puts tests/ on ``sys.path``."""

from __future__ import annotations

import pytest

from helpers.data import require


@pytest.fixture
def data():
    """``data("pets09-s2l1", "video.avi")`` → Path (skips or fails when absent)."""
    return require


@pytest.fixture(scope="session")
def scene_runs(tmp_path_factory):
    """``scene_runs(name, seed, *track_options)`` → :class:`helpers.SceneRun`, each run tracked
    once per session and shared by every test that asserts on it."""
    from helpers.runs import SceneRuns

    return SceneRuns(tmp_path_factory.mktemp("scene-runs"))
