"""The light test of the ghost filter: ground the sun or a lamp brightened is no region, an
object of the same brightness is."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiontrack.config import load_config
from motiontrack.motion.ghosts import GhostFilter, lit_share
from motiontrack.pipeline import Pipeline
from motiontrack.types import Box, Frame, Region

W, H = 160, 120
PATCH = (slice(40, 80), slice(60, 110))   # rows, columns of the brightened ground


def _ground() -> np.ndarray:
    rng = np.random.default_rng(4)
    g = rng.integers(90, 170, (H // 8, W // 8, 1), dtype=np.uint8)
    grey = cv2.resize(g, (W, H), interpolation=cv2.INTER_CUBIC)
    return cv2.merge([grey, grey, (grey * 0.9).astype(np.uint8)])


def test_the_share_counts_pixels_brightened_alike_in_every_channel():
    bg = np.full((2, 4, 3), 100, np.uint8)
    cur = bg.copy()
    cur[0, 0] = 106              # x1.06 in every channel: lit
    cur[0, 1] = (130, 130, 130)  # x1.3: brighter than the gain allows
    cur[0, 2] = (104, 105, 104)  # x1.04 within a hundredth between channels: lit
    cur[0, 3] = (101, 101, 101)  # x1.01: the ground as it was (a mask's rim), not lit
    cur[1, 0] = (95, 95, 95)     # darker: a shadow's business, not light's
    cur[1, 1] = (100, 115, 125)  # channels apart: a coloured object
    mask = np.full((2, 4), 255, np.uint8)
    mask[1, 2:] = 0              # left out of the count
    # six pixels counted; lit: [0, 0] and [0, 2], and [0, 1] once the gain allows x1.3
    assert lit_share(cur, bg, mask, 1.25) == pytest.approx(2 / 6)
    assert lit_share(cur, bg, mask, 1.35) == pytest.approx(3 / 6)
    held = np.zeros((2, 4), np.uint8)
    held[0, 0] = 255             # held: counted, never lit
    assert lit_share(cur, bg, mask, 1.25, held) == pytest.approx(1 / 6)
    assert lit_share(cur, bg, np.zeros((2, 4), np.uint8), 1.25) == 0.0


def _one_frame(lit: tuple[float, float], current: np.ndarray, held: np.ndarray | None = None,
               neighbour: tuple[slice, slice] | None = None):
    """The filter having learnt the plain ground, then one frame ``current`` whose PATCH is the
    mask's one region (and ``neighbour`` foreground that is no region)."""
    f = GhostFilter(0.7, pixels=False, lit=lit)
    mask = np.zeros((H, W), np.uint8)
    ground = _ground()
    f.regions(ground, mask, lambda m: [], 1.0)
    mask[PATCH] = 255
    if neighbour is not None:
        mask[neighbour] = 255
    region = Region(box=Box(60, 40, 50, 40), centroid=(85, 60), area=2000)
    return f, *f.regions(current, mask, lambda m: [region], 1.0, keep=held)


def test_brightened_ground_is_dropped_and_taken_out_of_the_mask():
    frame = _ground()
    frame[PATCH] = cv2.convertScaleAbs(frame[PATCH], alpha=1.08)
    f, mask, regions = _one_frame((0.5, 1.25), frame)
    assert regions == [] and not mask.any() and f.lit == 1
    # foreground just beside it, reaching into the margin of its window, stays
    beside = (slice(30, 90), slice(111, 113))
    f, mask, regions = _one_frame((0.5, 1.25), frame, neighbour=beside)
    assert regions == [] and f.lit == 1 and mask[beside].all() and not mask[PATCH].any()
    f, mask, regions = _one_frame((0.0, 1.25), frame)          # off
    assert len(regions) == 1 and mask[PATCH].all() and f.lit == 0


def test_an_object_as_bright_as_lit_ground_but_coloured_is_kept():
    frame = _ground()
    patch = frame[PATCH].astype(np.float32)
    patch *= np.array([0.85, 1.1, 1.35], np.float32)   # gray about 1.1 times the ground's
    frame[PATCH] = np.clip(patch, 0, 255).astype(np.uint8)
    f, mask, regions = _one_frame((0.5, 1.25), frame)
    assert len(regions) == 1 and mask[PATCH].all() and f.lit == 0


def test_pixels_held_for_a_stopped_object_count_as_not_lit():
    frame = _ground()
    frame[PATCH] = cv2.convertScaleAbs(frame[PATCH], alpha=1.08)
    held = np.zeros((H, W), np.uint8)
    held[40:80, 60:75] = 255           # three tenths of the region held
    f, _, regions = _one_frame((0.5, 1.25), frame, held)
    assert f.lit == 1 and regions == []
    held[40:80, 60:90] = 255           # three fifths held: the lit rest is no majority
    f, _, regions = _one_frame((0.5, 1.25), frame, held)
    assert f.lit == 0 and len(regions) == 1


def test_gray_frames_are_not_tested():
    gray = cv2.cvtColor(_ground(), cv2.COLOR_BGR2GRAY)
    frame = gray.copy()
    frame[PATCH] = cv2.convertScaleAbs(frame[PATCH], alpha=1.08)
    f = GhostFilter(0.7, pixels=False, lit=(0.5, 1.25))
    mask = np.zeros((H, W), np.uint8)
    f.regions(gray, mask, lambda m: [], 1.0)
    mask[PATCH] = 255
    region = Region(box=Box(60, 40, 50, 40), centroid=(85, 60), area=2000)
    _, regions = f.regions(frame, mask, lambda m: [region], 1.0)
    assert len(regions) == 1 and f.lit == 0


def _sunny_scene(n: int = 60):
    """Plain ground; from frame 30 on the sun comes out over PATCH within three frames (x1.08)."""
    ground = _ground()
    for k in range(n):
        img = ground.copy()
        gain = 1 + 0.08 * min(max(k - 29, 0), 3) / 3
        img[PATCH] = cv2.convertScaleAbs(ground[PATCH], alpha=gain)
        yield Frame(index=k, timestamp=k / 25, image=img)


@pytest.mark.parametrize("share, regions_expected", [(None, False), ("0", True)])
def test_the_sun_coming_out_over_part_of_the_scene_is_no_motion(share, regions_expected):
    """The default test (None), then none."""
    off = [] if share is None else [f"motion.light_share={share}"]
    cfg = load_config(None, ["preprocess.scale=1", "regions.min_area=100", *off])
    pipe = Pipeline(cfg, (W, H), None, 25.0)
    found = [r for r in pipe.results(_sunny_scene()) if r.index >= 30 and r.regions]
    assert bool(found) is regions_expected
