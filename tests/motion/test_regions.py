"""Region extraction, filters and merging, table-driven (N = 0 included)."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.config import RegionsConfig
from motiontrack.motion.regions import (components, filter_regions, find_regions, merge_distance,
                                        merge_regions, silhouettes, smallest_region)
from motiontrack.types import Box, Region


def mask_with(*rects, shape=(100, 100)):
    m = np.zeros(shape, np.uint8)
    for x, y, w, h in rects:
        m[y:y + h, x:x + w] = 255
    return m


def reg(x, y, w, h, area=None):
    return Region(box=Box(x, y, w, h), centroid=(x + w / 2, y + h / 2), area=w * h if area is None else area)


def test_components_empty_mask():
    assert components(np.zeros((10, 10), np.uint8)) == []


def test_components_box_centroid_area():
    (r,) = components(mask_with((10, 20, 4, 6)))
    assert r.box == Box(10, 20, 4, 6)
    assert r.area == 4 * 6
    # pixel i covers [i, i+1): centre of columns 10..13 is 12.0, of rows 20..25 is 23.0
    assert r.centroid == pytest.approx((12.0, 23.0))


def test_components_scale_back_to_original_pixels():
    (r,) = components(mask_with((10, 20, 4, 6)), scale=0.5)
    assert r.box == Box(20, 40, 8, 12)
    assert r.area == 4 * 6 * 4
    assert r.centroid == pytest.approx((24.0, 46.0))


def test_components_connectivity():
    diag = np.zeros((5, 5), np.uint8)
    diag[1, 1] = diag[2, 2] = 255
    assert len(components(diag, 8)) == 1
    assert len(components(diag, 4)) == 2


@pytest.mark.parametrize("cfg, kept", [
    (RegionsConfig(min_area=0, max_size=0), [0, 1, 2, 3]),
    (RegionsConfig(min_area=50, max_size=0), [1, 2, 3]),           # 40 px region dropped
    (RegionsConfig(min_area=0, max_area=500, max_size=0), [0, 1, 3]),  # 800 px region dropped
    (RegionsConfig(min_area=0, min_size=0.01, max_size=0), [1, 2, 3]),   # 1% of 10000 = 100 px
    (RegionsConfig(min_area=0, max_size=0.05), [0, 1, 3]),          # 5% of 10000 = 500 px
    (RegionsConfig(min_area=0, max_size=0, min_hw_ratio=1.5), [1, 3]),  # h/w: 0.4, 2, 0.5, 4
    (RegionsConfig(min_area=0, max_size=0, max_hw_ratio=1.0), [0, 2]),
])
def test_filter_regions(cfg, kept):
    regions = [reg(0, 0, 10, 4), reg(0, 0, 10, 20), reg(0, 0, 40, 20), reg(0, 0, 5, 20)]
    out = filter_regions(regions, cfg, image_area=100 * 100)
    assert out == [regions[i] for i in kept]


def test_filter_regions_empty():
    assert filter_regions([], RegionsConfig(), 100.0) == []


@pytest.mark.parametrize("a, b, expected", [
    ((0, 0, 10, 10), (5, 5, 10, 10), 0.0),                    # overlap: no gap
    ((0, 0, 10, 10), (10, 0, 10, 10), 0.0),                   # touching edges
    ((0, 0, 10, 10), (15, 0, 10, 10), 5 / (10 + 10 + 1)),     # dx = 5
    ((0, 0, 10, 10), (15, 20, 10, 10), (5 + 10) / 21),        # dx = 5, dy = 10
    ((0, 0, 4, 20), (10, 0, 4, 8), 6 / (20 + 8 + 1)),         # max(W, H) per region
])
def test_merge_distance(a, b, expected):
    assert merge_distance(np.array([a]), np.array([b]))[0, 0] == pytest.approx(expected)
    assert merge_distance(np.array([b]), np.array([a]))[0, 0] == pytest.approx(expected)


def test_merge_distance_empty():
    assert merge_distance(np.zeros((0, 4)), np.zeros((3, 4))).shape == (0, 3)


def test_merge_regions_transitive_and_union():
    # a—b close, b—c close, a—c far: all three merge (single linkage); d stays alone
    a, b, c, d = reg(0, 0, 10, 10), reg(12, 0, 10, 10), reg(24, 0, 10, 10), reg(80, 80, 10, 10)
    out = merge_regions([a, b, c, d], threshold=0.2)
    assert len(out) == 2
    merged = next(r for r in out if r.area == 300)
    assert merged.box == Box(0, 0, 34, 10)
    assert merged.centroid == pytest.approx((17.0, 5.0))
    assert d in out


@pytest.mark.parametrize("threshold, n", [
    (0.0, 2),              # 0 switches merging off
    (2 / 21, 2),           # D = gap 2 / (10 + 10 + 1) is not below the threshold
    (2 / 21 + 1e-9, 1),    # just above: merged
])
def test_merge_threshold_is_strict(threshold, n):
    assert len(merge_regions([reg(0, 0, 10, 10), reg(12, 0, 10, 10)], threshold)) == n


def test_merge_regions_empty_and_single():
    assert merge_regions([], 1.0) == []
    r = reg(0, 0, 5, 5)
    assert merge_regions([r], 1.0) == [r]


def test_find_regions_drops_specks_then_merges():
    # a torso and legs split by a 2-px gap, plus one speck far away
    m = mask_with((40, 10, 10, 20), (40, 32, 10, 15), (90, 90, 1, 1))
    cfg = RegionsConfig(min_area=100, max_size=0, merge_threshold=0.1)
    (r,) = find_regions(m, cfg, scale=1.0, image_size=(100, 100))
    assert r.box == Box(40, 10, 10, 37)
    assert r.area == 10 * 20 + 10 * 15


def test_contour_and_labelled_components_agree():
    # two L-shapes whose boxes overlap (the contour path must not count the other's pixels),
    # a ring (hole) and scattered blobs; compared with full labelling
    from motiontrack.motion.regions import _components_labelled

    m = np.zeros((60, 80), np.uint8)
    m[5:30, 5:10] = 255
    m[25:30, 5:30] = 255                    # L one
    m[10:15, 12:35] = 255
    m[10:40, 30:35] = 255                   # L two, box overlaps L one's box
    m[40:55, 50:70] = 255
    m[45:50, 55:65] = 0                     # ring with a hole
    rng = np.random.default_rng(3)
    for _ in range(10):
        y, x = rng.integers(0, 55), rng.integers(40, 75)
        m[y:y + 3, x:x + 4] = 255
    def key(rs):
        return sorted((r.box.as_array().tolist(), r.area, r.centroid) for r in rs)
    for scale in (1.0, 0.5):
        a, b = key(components(m, 8, scale)), key(_components_labelled(m, 8, scale, 1))
        assert [x[0] for x in a] == [x[0] for x in b]
        assert np.allclose([x[1] for x in a], [x[1] for x in b])
        assert np.allclose([x[2] for x in a], [x[2] for x in b])


@pytest.mark.parametrize("args, message", [
    ((0, 0, 0, 5), "w > 0 and h > 0"),
    ((0, 0, 5, -1), "w > 0 and h > 0"),
    ((float("nan"), 0, 5, 5), "x must be finite"),
    ((0, float("inf"), 5, 5), "y must be finite"),
    ((0, 0, float("nan"), 5), "w must be finite"),
    ((0, 0, 5, float("inf")), "h must be finite"),
    ((1e308, 1e308, 5, 5), "too large"),
])
def test_box_rejects_bad_values(args, message):
    with pytest.raises(ValueError, match=message):
        Box(*args)
    assert Box(0.5, -3, 1e-3, 2).w == 1e-3   # tiny, negative corner: valid


def test_silhouettes_drop_specks_and_fill_the_holes_of_the_rest():
    m = mask_with((10, 10, 30, 30), (70, 70, 3, 3))   # an object and a 9-pixel speck
    m[20:27, 20:27] = 0                                # a hole in the object
    m[23, 23] = 255                                    # with a speck inside it
    out = silhouettes(m, 10)
    assert out[10:40, 10:40].all()                     # the hole filled, its speck with it
    assert not out[70:73, 70:73].any()                 # the speck outside gone
    assert int((out > 0).sum()) == 900
    assert (m[20:27, 20:27] == 0).sum() == 48          # the input is left as it was


def test_closed_silhouettes_join_parts_two_pixels_apart_and_keep_a_component_as_large_as_a_region():
    m = mask_with((10, 10, 10, 20), (22, 10, 10, 20), (50, 50, 3, 3))
    assert not silhouettes(m, 9)[10:30, 20:22].any()   # not closed unless asked
    out = silhouettes(m, 9, close=True)
    assert out[10:30, 20:22].all()                     # the gap closed
    assert out[50:53, 50:53].all()                     # nine pixels: a region may come from it
    assert not silhouettes(m, 10)[50:53, 50:53].any()
    assert silhouettes(np.zeros((20, 20), np.uint8), 10).sum() == 0


def test_a_thin_component_is_counted_by_its_pixels_not_its_box():
    m = mask_with((0, 0, 40, 1), (0, 0, 1, 40))        # an L: 79 pixels in a 40 x 40 box
    assert silhouettes(m, 80).sum() == 0
    assert np.array_equal(silhouettes(m, 79), m)


def test_the_smallest_region_follows_the_filters_and_merging():
    cfg = RegionsConfig(min_area=100, min_size=0.001)
    assert smallest_region(cfg, 0.5, (768, 576)) == pytest.approx(0.001 * 768 * 576 / 4)
    assert smallest_region(cfg, 1.0, (320, 240)) == pytest.approx(100)
    merging = RegionsConfig(min_area=100, min_size=0.0, merge_threshold=0.5)
    assert smallest_region(merging, 1.0, (320, 240)) == pytest.approx(25)
