"""Head detector (thesis 4.3) on hand-built masks, and splitting merged regions by heads."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiontrack.people.heads import (
    detect_heads, detect_heads_many, height_profile, split_region_by_heads,
)
from motiontrack.types import Box, Region


def _person(mask: np.ndarray, cx: int, foot: int, height: int = 90, head_r: int = 6,
            body_w: int = 24) -> None:
    """A round head on a rectangular body, feet at row ``foot``."""
    top = foot - height
    cv2.circle(mask, (cx, top + head_r), head_r, 255, -1)
    cv2.rectangle(mask, (cx - body_w // 2, top + 2 * head_r - 1), (cx + body_w // 2, foot), 255, -1)


def _region(mask: np.ndarray) -> Region:
    ys, xs = np.nonzero(mask)
    box = Box.from_xyxy(xs.min(), ys.min(), xs.max() + 1, ys.max() + 1)
    return Region(box=box, centroid=(xs.mean(), ys.mean()), area=float(len(xs)))


# (head x positions, foot rows, heights): one, two and three people, side by side or merged.
# A head must stand above the neighbouring shoulders: a much shorter person whose head is level
# with a neighbour's shoulder is not separable by the height profile (a limitation of the method).
CASES = [
    pytest.param([50], [110], [90], id="one"),
    pytest.param([40, 70], [110, 110], [90, 90], id="two-touching"),
    pytest.param([40, 64], [110, 112], [90, 86], id="two-merged-different-heights"),
    pytest.param([30, 58, 90], [110, 110, 110], [90, 90, 90], id="three"),
    pytest.param([30, 52, 80], [110, 108, 112], [88, 92, 90], id="three-merged"),
]


@pytest.mark.parametrize("xs, feet, heights", CASES)
def test_heads_found_at_exact_x(xs, feet, heights):
    mask = np.zeros((130, 130), np.uint8)
    for x, f, h in zip(xs, feet, heights):
        _person(mask, x, f, h)
    heads = detect_heads(mask)
    assert [round(h.x) for h in heads] == pytest.approx(xs, abs=1)
    for h, f, ht in zip(heads, feet, heights):
        # y: mean top of the head interval + half its width, close to the circle centre
        assert h.y == pytest.approx(f - ht + 6, abs=2)
        assert 6 <= h.width <= 13


@pytest.mark.parametrize("scale", [0.5, 0.25])
def test_heads_on_a_downscaled_mask_are_reported_in_original_pixels(scale):
    mask = np.zeros((240, 260), np.uint8)
    for x in (80, 140, 200):
        _person(mask, x, 220, height=180, head_r=12, body_w=48)
    small = cv2.resize(mask, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    small = np.where(small > 127, 255, 0).astype(np.uint8)
    heads = detect_heads(small, _region(mask).box, scale=scale)
    assert [h.x for h in heads] == pytest.approx([80, 140, 200], abs=2 / scale)


def test_flat_top_and_empty_mask_give_no_heads():
    box_only = np.zeros((60, 60), np.uint8)
    box_only[10:50, 10:50] = 255  # flat top, 40 px wide: wider than any head
    assert detect_heads(box_only, max_width=30) == []
    assert detect_heads(np.zeros((30, 30), np.uint8)) == []
    assert detect_heads(np.zeros((0, 0), np.uint8)) == []


def test_height_profile():
    m = np.zeros((5, 4), np.uint8)
    m[2:, 0] = 1
    m[0:, 2] = 1
    assert height_profile(m).tolist() == [2.0, 5.0, 0.0, 5.0]


@pytest.mark.parametrize("xs", [[40, 70], [30, 58, 90]])
def test_split_merged_region_between_heads(xs):
    mask = np.zeros((130, 130), np.uint8)
    for x in xs:
        _person(mask, x, 110)
    region = _region(mask)
    parts = split_region_by_heads(region, mask)
    assert len(parts) == len(xs)
    for p, x in zip(parts, xs):
        assert p.box.x <= x <= p.box.x2
        assert p.box.h == pytest.approx(91, abs=1)
        assert p.score == region.score
    assert sum(p.area for p in parts) == pytest.approx(region.area)


def test_split_keeps_a_single_person():
    mask = np.zeros((130, 130), np.uint8)
    _person(mask, 60, 110)
    region = _region(mask)
    assert split_region_by_heads(region, mask) == [region]


def test_detect_heads_many_equals_one_region_at_a_time():
    # The batched detector lays all profiles end to end with inf gaps; on random masks, scales,
    # boxes (partly outside the mask, empty) and parameters it must give exactly what
    # detect_heads gives region by region.
    rng = np.random.default_rng(7)
    found = 0
    for _ in range(1500):
        H, W = (int(v) for v in rng.integers(5, 60, 2))
        mask = np.zeros((H, W), np.uint8)
        for _k in range(int(rng.integers(0, 6))):
            x, w, y = int(rng.integers(0, W)), int(rng.integers(1, 15)), int(rng.integers(0, H))
            mask[y:, x:x + w] = 255
        mask[rng.random((H, W)) < 0.05] = 0
        scale = float(rng.choice([0.25, 0.5, 1.0]))
        boxes = [Box(float(rng.uniform(-5, W / scale)), float(rng.uniform(-5, H / scale)),
                     float(rng.uniform(1, W / scale)), float(rng.uniform(1, H / scale)))
                 for _b in range(int(rng.integers(0, 5)))]
        params = dict(min_width=float(rng.uniform(1, 10)), tolerance=float(rng.uniform(0, 5)),
                      min_drop=float(rng.uniform(0, 8)))
        one = [detect_heads(mask, b, scale, **params) for b in boxes]
        assert detect_heads_many(mask, boxes, scale, **params) == one
        found += sum(map(len, one))
    assert found > 500  # the comparison covered many actual heads, not just empty lists


@pytest.mark.parametrize("xs, feet, heights", CASES)
def test_detect_heads_many_on_the_hand_built_people(xs, feet, heights):
    mask = np.zeros((130, 140), np.uint8)
    for x, f, h in zip(xs, feet, heights):
        _person(mask, x, f, h)
    box = _region(mask).box
    heads = detect_heads_many(mask, [box, Box(0, 0, 5, 5), box])
    assert [h.x for h in heads[0]] == pytest.approx(xs, abs=1.0)
    assert heads[1] == [] and heads[2] == heads[0]


@pytest.mark.parametrize("scale", [0.4, 0.5, 0.55, 0.6, 0.75, 1.0])
@pytest.mark.slow
def test_heads_found_at_any_processing_scale(scale):
    # min_drop (4 px) is a fraction of a mask row at most scales; it is rounded to whole rows, so
    # the walker's head is found whatever the scale (unrounded, the head's 2-row flank would
    # fall short of a 2.2 / 2.4-row drop at 0.55 and 0.6 and no head would be found).
    from motiontrack.config import load_config
    from motiontrack.pipeline import run

    cfg = load_config(None, ["people.enabled=true", "people.shapes=false",
                             f"preprocess.scale={scale}"])
    with_region = with_head = 0
    for r in run("synth:walker?n_frames=100", cfg):
        inside = [g for g in r.regions if 40 < g.box.x and g.box.x2 < 600]  # fully in view
        if len(inside) == 1:
            with_region += 1
            with_head += r.people is not None and len(r.people.heads) == 1
    assert with_region > 30
    assert with_head >= 0.9 * with_region


# ------------------------------------------------ people.auto_split (the default pipeline)
def _auto_split(mask: np.ndarray, settings: list[str] = ()) -> list[list[Region]]:
    """Regions of ``mask`` after the pipeline's automatic head splitting, over 30 frames of
    the same mask (the scene gate is a running mean over frames)."""
    from motiontrack.config import load_config
    from motiontrack.pipeline import Pipeline
    from motiontrack.motion.regions import find_regions

    cfg = load_config(None, list(settings))
    pipe = Pipeline(cfg, (mask.shape[1], mask.shape[0]))
    assert pipe.scale == 1.0
    regions = find_regions(mask, cfg.regions, 1.0, (mask.shape[1], mask.shape[0]))
    return [pipe._split_upright(mask, list(regions))[0] for _ in range(30)]


def _street(people: bool) -> np.ndarray:
    """Three lone people and a merged pair (upright scene), or the same four as cars: wide
    blobs, one of them with two roof bumps that look like heads to the height profile."""
    mask = np.zeros((240, 320), np.uint8)
    if people:
        for x in (30, 80, 130):
            _person(mask, x, 110)
        _person(mask, 200, 220)
        _person(mask, 222, 220)            # merged with the previous one
    else:
        for x in (10, 90, 170):
            cv2.rectangle(mask, (x, 70), (x + 60, 110), 255, -1)
        cv2.rectangle(mask, (170, 180), (290, 220), 255, -1)
        cv2.rectangle(mask, (180, 168), (200, 180), 255, -1)   # two bumps on a wide blob
        cv2.rectangle(mask, (250, 168), (270, 180), 255, -1)
    return mask


def test_auto_split_separates_a_merged_pair_in_an_upright_scene():
    frames = _auto_split(_street(people=True))
    # every frame: the three lone people untouched (upright: no head search) and the pair split
    for regions in frames:
        assert len(regions) == 5
        pair = sorted(r.centroid[0] for r in regions if r.box.y > 120)
        assert pair == [pytest.approx(200, abs=4), pytest.approx(222, abs=4)]


def test_auto_split_leaves_a_scene_of_wide_objects_alone():
    mask = _street(people=False)
    from motiontrack.people.heads import detect_heads

    big = _region(np.where(np.arange(240)[:, None] > 150, mask, 0))
    assert len(detect_heads(mask, big.box)) == 2    # the detector alone would split the car
    for regions in _auto_split(mask):
        assert len(regions) == 4


def test_auto_split_can_be_switched_off():
    for settings in (["people.auto_split=false"], ["people.split=false"], ["people.heads=false"]):
        assert all(len(r) == 4 for r in _auto_split(_street(people=True), settings))


def test_running_highest_top_is_the_minimum_over_the_window_with_the_edges_open():
    from motiontrack.people.heads import _running_max_top

    top = np.array([5.0, 3.0, 9.0, 9.0, 1.0, 7.0, 8.0])
    assert _running_max_top(top, 1).tolist() == [3, 3, 3, 1, 1, 1, 7]
    assert _running_max_top(top, 2).tolist() == [3, 3, 1, 1, 1, 1, 1]
    assert _running_max_top(top, 10).tolist() == [1] * 7
    assert _running_max_top(top, 0).tolist() == top.tolist()
    assert _running_max_top(np.zeros(0), 3).tolist() == []
