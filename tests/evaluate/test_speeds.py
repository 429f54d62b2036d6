"""Walking speeds of tracks against the ground truth's world positions (evaluate.speeds)."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.evaluate.speeds import majority_matches, speed_pairs
from motiontrack.io.mot import read_mot
from motiontrack.types import Annotations


def _walk(tid: int, x0: float, frames: range, speed_px: float, world_per_px: float = 0.02,
          jitter: float = 0.0, seed: int = 0) -> tuple[list, list]:
    """Rows (frame, id, box) and world positions of someone walking along y = 100, the box
    jittering ``jitter`` px across the way."""
    rng = np.random.default_rng(seed)
    rows, world = [], []
    for f in frames:
        x = x0 + speed_px * (f - frames[0])
        y = 100.0 + (rng.normal(0, jitter) if jitter else 0.0)
        rows.append((f, tid, x, y, 20.0, 50.0))
        world.append((x * world_per_px, y * world_per_px, 0.0))
    return rows, world


def _ann(rows, world) -> Annotations:
    a = np.array(rows, float)
    return Annotations.from_columns(a[:, 0], a[:, 1], a[:, 2:6], world=np.array(world, float))


def test_each_track_takes_the_person_it_matches_most():
    g1, w1 = _walk(7, 0, range(1, 31), 5)
    g2, w2 = _walk(8, 400, range(1, 31), -5)
    gt = _ann(g1 + g2, w1 + w2)
    # track 1 follows person 7 for frames 1-20, then jumps to person 8 for 21-25
    p = [r for r in g1 if r[0] <= 20] + [r for r in g2 if 21 <= r[0] <= 25]
    pred = _ann([(f, 1, x, y, w, h) for f, _, x, y, w, h in p], [(0, 0, 0)] * len(p))
    m = majority_matches(gt, pred)
    assert list(m) == [1] and m[1][0] == 7 and m[1][1].tolist() == list(range(1, 21))


def test_speeds_over_the_matched_frames_agree_when_jitter_is_smoothed():
    # person 3 walks 5 px = 0.1 m per frame: 1.0 m/s at 10 fps
    g, gw = _walk(3, 0, range(1, 61), 5)
    p, pw = _walk(1, 0, range(1, 61), 5, jitter=3.0, seed=1)
    gt, pred = _ann(g, gw), _ann(p, pw)
    raw = speed_pairs(gt, pred, 10.0, window_s=0.1)   # one frame apart
    smoothed = speed_pairs(gt, pred, 10.0)
    assert [(r["track"], r["gt"], r["frames"]) for r in smoothed] == [(1, 3, 60)]
    assert smoothed[0]["gt_speed_mps"] == pytest.approx(1.0)
    # jitter adds path that was never walked; over 1 s it is small against the walk
    assert raw[0]["diff_mps"] > 0.1
    assert abs(smoothed[0]["diff_mps"]) < 0.05


def test_tracks_matched_too_briefly_are_left_out():
    g, gw = _walk(3, 0, range(1, 9), 5)
    pred = _ann([(f, 1, x, y, w, h) for f, _, x, y, w, h in g], gw)
    assert speed_pairs(_ann(g, gw), pred, 10.0) == []             # 8 frames < 10
    assert len(speed_pairs(_ann(g, gw), pred, 10.0, min_frames=8)) == 1


@pytest.mark.slow
def test_pets_walking_speeds_match_the_ground_truth_within_015_mps(pets_camera_run, data):
    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")
    rows = speed_pairs(gt, read_mot(pets_camera_run / "tracks.txt"), 10.0)
    assert len(rows) >= 10
    assert np.median(np.abs([r["diff_mps"] for r in rows])) <= 0.15
