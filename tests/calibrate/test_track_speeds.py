"""Track speeds in ``summary.json`` of ``track --camera`` on PETS 2009 S2L1 (motiontrack.speed).

How ``--fps`` scales them: tests/io/test_source_options.py."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytestmark = pytest.mark.data


def test_pets_walkers_move_at_walking_speed(pets_camera_run):
    # frames 1-300 at the stored 10 fps; a frame-to-frame path length over the frame rate, box
    # jitter included, makes the median walker 1.83 m/s and the fastest 3.3 m/s
    m = json.loads((pets_camera_run / "summary.json").read_text())["measurements"]
    walkers = [v for v in m.values() if v["frames"] > 20]
    assert len(walkers) >= 8
    speeds = [v["mean_speed_mps"] for v in walkers]
    assert 1.0 <= np.median(speeds) <= 1.8
    assert max(speeds) < 2.5
    # the window and the frame rate of the number are written beside it
    assert {(v["speed_window_s"], v["speed_fps"]) for v in walkers} == {(1.0, 10.0)}
