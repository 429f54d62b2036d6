"""The scene file's bounds: at most 1,000 points per zone polygon, 2 per line, 1,000 tables per
array; a polygon at the bound is checked in well under a second, and the per-frame zone test
works on many edges without a (edges × zones) array."""

from __future__ import annotations

import time

import numpy as np
import pytest

from motiontrack.analytics import parse_scene
from motiontrack.analytics.geometry import polygon_is_simple, segments_intersect
from motiontrack.analytics.scene import scene_json_schema
from motiontrack.analytics.specs import MAX_POLYGON_POINTS, MAX_TABLES, ZoneSpec
from motiontrack.analytics.zones import ZoneEdges
from motiontrack.errors import ConfigError


def star(k: int, wiggles: int = 37) -> list[list[float]]:
    """A simple polygon of ``k`` vertices: a circle of radius 1,000 px with a wavy border."""
    th = np.linspace(0, 2 * np.pi, k, endpoint=False)
    r = 1000 + 100 * np.sin(th * wiggles)
    return np.c_[2000 + r * np.cos(th), 2000 + r * np.sin(th)].round(3).tolist()


def test_a_zone_polygon_over_the_bound_is_refused_before_its_points_are_read():
    poly = [[0, 0]] * (MAX_POLYGON_POINTS + 1)
    with pytest.raises(ConfigError, match=r"^zone\[1\].polygon must have at most 1,000 \[x, y\] "
                                          r"points, got 1,001$"):
        parse_scene({"zone": [{"name": "z", "polygon": poly}]})


def test_six_hundred_thousand_points_are_refused_at_once():
    poly = [[0, 0]] * 600_000
    t = time.perf_counter()
    with pytest.raises(ConfigError, match="got 600,000"):
        parse_scene({"zone": [{"name": "z", "world": poly}]})
    assert time.perf_counter() - t < 5.0   # generous: the simplicity check took hours


def test_a_line_has_at_most_two_points():
    with pytest.raises(ConfigError, match=r"line\[1\].points must have at most 2 \[x, y\] points, "
                                          r"got 3"):
        parse_scene({"line": [{"name": "a", "points": [[0, 0], [5, 5], [9, 9]]}]})


def test_more_tables_than_the_bound_are_refused():
    zones = [{"name": f"z{i}", "polygon": [[0, 0], [9, 0], [0, 9]]} for i in range(MAX_TABLES + 1)]
    with pytest.raises(ConfigError, match=r"^zone must have at most 1,000 tables \(\[\[zone\]\]\), "
                                          r"got 1,001$"):
        parse_scene({"zone": zones})


def test_a_polygon_at_the_bound_validates_quickly_and_correctly():
    poly = star(MAX_POLYGON_POINTS)
    t = time.perf_counter()
    scene = parse_scene({"zone": [{"name": "z", "polygon": poly}]})
    # generous: the check takes about 0.1 s; the pairwise Python loop took over a second
    assert time.perf_counter() - t < 5.0
    assert len(scene.zones[0].polygon) == MAX_POLYGON_POINTS
    crossed = poly[:500] + poly[500:][::-1]   # the second half reversed: its edges cross
    with pytest.raises(ConfigError, match="simple polygon"):
        parse_scene({"zone": [{"name": "z", "polygon": crossed}]})


def _simple_by_pairs(v: np.ndarray) -> bool:
    """Every edge against every non-adjacent edge, one at a time."""
    k = len(v)
    w = np.roll(v, -1, axis=0)
    if np.any(np.all(v == w, axis=1)):
        return False
    for i in range(k):
        others = [j for j in range(k) if j != i and (j - i) % k not in (1, k - 1)]
        if others and np.any(segments_intersect(v[others], w[others], v[i], w[i])):
            return False
    return True


def test_the_simplicity_check_agrees_with_the_pairwise_definition():
    rng = np.random.default_rng(7)
    simple = 0
    for _ in range(400):   # small integer grids: touching, collinear and repeated points
        v = rng.integers(0, 4, (int(rng.integers(3, 8)), 2)).astype(float)
        expected = _simple_by_pairs(v)
        simple += expected
        assert polygon_is_simple(v) == expected, v.tolist()
    assert 20 < simple < 380   # both answers were exercised


def test_the_json_schema_states_the_bounds():
    schema = scene_json_schema()
    zone = schema["properties"]["zone"]
    assert zone["maxItems"] == MAX_TABLES
    assert zone["items"]["properties"]["polygon"]["maxItems"] == MAX_POLYGON_POINTS
    assert zone["items"]["properties"]["world"]["maxItems"] == MAX_POLYGON_POINTS
    assert schema["properties"]["line"]["items"]["properties"]["points"]["maxItems"] == 2


def test_zone_membership_of_many_zones_matches_each_zone_alone():
    # 100 zones of 1,000 points: a dense (edges x zones) array would take 800 MB
    base = np.asarray(star(MAX_POLYGON_POINTS))
    zones = tuple(ZoneSpec(f"z{i}", tuple(map(tuple, base + [10.0 * i, 0.0]))) for i in range(100))
    pts = np.array([[2000.0, 2000.0], [1010.0, 2000.0], [5000.0, 5000.0], [3995.0, 2000.0]])
    inside, dist = ZoneEdges(zones).classify(pts)
    assert inside.shape == dist.shape == (4, 100)
    for i in (0, 50, 99):
        alone_in, alone_d = ZoneEdges(zones[i:i + 1]).classify(pts)
        assert np.array_equal(inside[:, i], alone_in[:, 0])
        assert np.allclose(dist[:, i], alone_d[:, 0])
    assert inside[0].all() and not inside[2].any()   # shifted by at most 990 px
