"""Ground-truth statistics (thesis eqs. 4.27–4.30) against hand computations."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from motiontrack.errors import ConfigError
from motiontrack.evaluate.gtstats import gt_statistics, parse_image_size
from motiontrack.types import Annotations

MU = "area_mean_fraction_of_image (mu, eq. 4.27)"
SIGMA = "area_std_fraction_of_image (sigma, eq. 4.28)"
MIN = "MIN_REGION_SIZE_fraction_of_image (mu - sigma, eq. 4.29)"
MAX = "MAX_REGION_SIZE_fraction_of_image (mu + sigma, eq. 4.30)"


def ann(boxes, consider=None, frames=None):
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    n = len(boxes)
    return Annotations.from_columns(frames if frames is not None else np.arange(1, n + 1),
                                    np.arange(1, n + 1), boxes, consider=consider)


# image 100 x 50 = 5000 px²
# box A 10 x 10: area 100 = 0.02 of the image, h/w = 1
# box B 10 x 30: area 300 = 0.06 of the image, h/w = 3
# box C 40 x 40 (consider = 0): ignored
TWO = ann([[0, 0, 10, 10], [5, 5, 10, 30], [0, 0, 40, 40]], consider=[True, True, False])


@pytest.mark.parametrize("key, expected", [
    ("n_boxes", 2),
    ("image_area_px2", 100 * 50),
    ("area_mean_px2", (100 + 300) / 2),
    ("area_std_px2", math.sqrt(((100 - 200) ** 2 + (300 - 200) ** 2) / 2)),
    (MU, (0.02 + 0.06) / 2),
    (SIGMA, math.sqrt(((0.02 - 0.04) ** 2 + (0.06 - 0.04) ** 2) / 2)),   # = 0.02
    (MIN, 0.04 - 0.02),
    (MAX, 0.04 + 0.02),
    ("MIN_REGION_SIZE_px2", (0.04 - 0.02) * 5000),
    ("MAX_REGION_SIZE_px2", (0.04 + 0.02) * 5000),
    ("height_to_width_mean", (1 + 3) / 2),
    ("height_to_width_std", 1.0),
    ("MIN_HEIGHT_TO_WIDTH (mean - std)", 2 - 1),
    ("MAX_HEIGHT_TO_WIDTH (mean + std)", 2 + 1),
    ("height_to_width_observed_min", 1.0),
    ("height_to_width_observed_max", 3.0),
])
def test_hand_computed(key, expected):
    st = gt_statistics([TWO], (100, 50))
    assert st[key] == pytest.approx(expected, rel=1e-12)


def test_sample_std_and_overrides():
    st = gt_statistics([TWO], (100, 50), ddof=1)
    assert st[SIGMA] == pytest.approx(math.sqrt(((0.02 - 0.04) ** 2 + (0.06 - 0.04) ** 2) / (2 - 1)))
    st0 = gt_statistics([TWO], (100, 50))
    assert st0["recommended_overrides"] == ["regions.min_size=0.02", "regions.max_size=0.06",
                                            "regions.min_hw_ratio=1", "regions.max_hw_ratio=3"]


def test_pooling_several_files_equals_one():
    a = ann([[0, 0, 10, 10]])
    b = ann([[5, 5, 10, 30]])
    both = ann([[0, 0, 10, 10], [5, 5, 10, 30]])
    assert gt_statistics([a, b], (100, 50)) == gt_statistics([both], (100, 50))


def test_min_is_clamped_at_zero():
    # areas 10, 10, 1000 px²: mu = 340, sigma = sqrt((330² + 330² + 660²) / 3) = 466.7 > mu,
    # so mu - sigma < 0 is clamped to 0 (a region cannot be smaller than nothing)
    st = gt_statistics([ann([[0, 0, 1, 10], [0, 0, 2, 5], [0, 0, 10, 100]])], (100, 50))
    assert st[MIN] == 0.0
    assert st[MAX] == pytest.approx((340 + math.sqrt(((10 - 340) ** 2 * 2 + 660 ** 2) / 3)) / 5000)


def test_empty_ground_truth_gives_none_not_errors():
    st = gt_statistics([Annotations.empty()], (100, 50))
    assert st["n_boxes"] == 0
    assert st[MU] is None and st[MIN] is None
    assert st["recommended_overrides"] == []
    json.dumps(st)  # JSON-safe (no nan)


@pytest.mark.parametrize("text, expected", [("768x576", (768, 576)), ("640X480", (640, 480))])
def test_parse_image_size(text, expected):
    assert parse_image_size(text) == expected


@pytest.mark.parametrize("text", ["768", "0x10", "axb", "10x-5", "1x2x3"])
def test_parse_image_size_rejects(text):
    with pytest.raises(ConfigError):
        parse_image_size(text)


def test_cli_json(tmp_path, capsys):
    from motiontrack.cli import main

    gt = tmp_path / "gt.txt"
    # MOT15 layout: 7th column is the consider flag; the 40x40 row is ignored
    gt.write_text("1,1,0,0,10,10,1,-1,-1,-1\n1,2,5,5,10,30,1,-1,-1,-1\n2,3,0,0,40,40,0,-1,-1,-1\n")
    out = tmp_path / "stats.json"
    assert main(["gt-stats", str(gt), "--image-size", "100x50", "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert d[MIN] == pytest.approx(0.02) and d[MAX] == pytest.approx(0.06)
    assert "--set regions.min_size=0.02" in capsys.readouterr().out


@pytest.mark.data
def test_pets_ground_truth(data):
    from motiontrack.io.annotations import read_annotations

    gt = read_annotations(data("pets09-s2l1", "gt_mot15.txt"), mot_kind="gt")
    st = gt_statistics([gt], (768, 576))
    keep = gt.boxes[gt.consider]
    rel = keep[:, 2] * keep[:, 3] / (768 * 576)
    assert st["n_boxes"] == len(keep)
    assert st[MIN] == pytest.approx(rel.mean() - rel.std())
    assert st[MAX] == pytest.approx(rel.mean() + rel.std())
    assert 0 < st[MIN] < st[MU] < st[MAX] < 0.05      # pedestrians are small in this view
    assert 1.5 < st["height_to_width_mean"] < 4        # and upright
