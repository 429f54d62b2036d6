"""Ground-truth statistics: the thesis' size model (eqs. 4.27–4.30) and the recommended region
limits against hand computations, and the recommendation applied to tracking PETS 2009."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from motiontrack.errors import ConfigError
from motiontrack.evaluate.gtstats import gt_statistics, parse_image_size, recommend_regions, touching_groups
from motiontrack.types import Annotations

MU = "area_mean_fraction_of_image (mu, eq. 4.27)"
SIGMA = "area_std_fraction_of_image (sigma, eq. 4.28)"
MIN = "thesis_model_MIN_REGION_SIZE_fraction_of_image (mu - sigma, eq. 4.29)"
MAX = "thesis_model_MAX_REGION_SIZE_fraction_of_image (mu + sigma, eq. 4.30)"


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
    ("thesis_model_MIN_REGION_SIZE_px2", (0.04 - 0.02) * 5000),
    ("thesis_model_MAX_REGION_SIZE_px2", (0.04 + 0.02) * 5000),
    ("height_to_width_mean", (1 + 3) / 2),
    ("height_to_width_std", 1.0),
    ("thesis_model_MIN_HEIGHT_TO_WIDTH (mean - std)", 2 - 1),
    ("thesis_model_MAX_HEIGHT_TO_WIDTH (mean + std)", 2 + 1),
    ("height_to_width_observed_min", 1.0),
    ("height_to_width_observed_max", 3.0),
])
def test_hand_computed(key, expected):
    st = gt_statistics([TWO], (100, 50))
    assert st[key] == pytest.approx(expected, rel=1e-12)


def test_sample_std_and_thesis_model_overrides():
    st = gt_statistics([TWO], (100, 50), ddof=1)
    assert st[SIGMA] == pytest.approx(math.sqrt(((0.02 - 0.04) ** 2 + (0.06 - 0.04) ** 2) / (2 - 1)))
    st0 = gt_statistics([TWO], (100, 50))
    assert st0["thesis_model_overrides"] == ["regions.min_size=0.02", "regions.max_size=0.06",
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
    assert st["recommended_overrides"] == [] and st["thesis_model_overrides"] == []
    assert st["recommended_regions.min_size"] is None and st["n_groups"] == 0
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
    printed = capsys.readouterr().out
    assert "thesis_model_overrides" in printed and "--set regions.min_size=0.02" in printed
    # recommended: percentile 5 of the areas 100, 300 is 110 px², a quarter of it over 5000 px²
    assert d["recommended_regions.min_size"] == pytest.approx(0.25 * 110 / 5000)
    assert f"--set regions.min_size={0.25 * 110 / 5000:.6g}" in printed


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


# --- the recommendation: percentiles of people and groups, widened for segmentation noise ---------

def test_touching_groups_by_frame():
    frames = np.array([1, 1, 1, 2, 2, 2, 3])
    boxes = np.array([
        [0, 0, 10, 30], [10, 0, 10, 30],     # frame 1: touch at x = 10 -> one group (0, 0, 20, 30)
        [50, 0, 10, 30],                     # frame 1: alone, no group
        [0, 0, 10, 30], [5, 5, 10, 30],      # frame 2: overlap, and the third box overlaps the
        [14, 20, 10, 10],                    #   second: a chain of three, union (0, 0, 24, 35)
        [20, 0, 10, 30],                     # frame 3: would touch frame 1's second box, but alone
    ], float)
    g = touching_groups(frames, boxes)
    assert sorted(map(tuple, g.tolist())) == [(0, 0, 20, 30, 2), (0, 0, 24, 35, 3)]
    assert touching_groups(np.zeros(0), np.zeros((0, 4))).shape == (0, 5)


def test_recommendation_of_no_boxes_is_none():
    rec = recommend_regions(np.zeros((0, 4)), np.zeros((0, 5)), (100, 100))
    assert set(rec.values()) == {None}


def test_recommendation_of_one_box():
    # one person 10 x 30 px (area 300, h/w 3) in a 100 x 100 image, no groups: every percentile is
    # that box
    rec = recommend_regions(np.array([[0, 0, 10, 30]]), np.zeros((0, 5)), (100, 100))
    assert rec["regions.min_size"] == pytest.approx(0.5 * 0.5 * 300 / 10000)  # fill x half a person
    assert rec["regions.max_size"] == pytest.approx(2 * 300 / 10000)          # shadow, dilation
    assert rec["regions.min_hw_ratio"] == pytest.approx(0.5 * 3)               # top half
    assert rec["regions.max_hw_ratio"] == pytest.approx(3 / 0.5)               # left half
    assert rec["group_area_high_px2"] is None


def test_one_mistaken_annotation_moves_nothing():
    # 20 people 10 x 30 plus a 1 x 1 and a 20 x 100 annotation error: sorted areas
    # [1, 300 x 20, 2000] and ratios [1, 3 x 20, 5]; percentile 5 at rank 0.05 * 21 = 1.05 and
    # 95 at 19.95 both fall on 300 and 3, so the recommendation is that of the clean boxes ...
    clean = np.tile([0, 0, 10, 30], (20, 1)).astype(float)
    dirty = np.vstack([clean, [[0, 0, 1, 1], [0, 0, 20, 100]]])
    no_groups = np.zeros((0, 5))
    assert recommend_regions(dirty, no_groups, (100, 100)) == \
        recommend_regions(clean, no_groups, (100, 100))
    # ... while the thesis' mu - sigma falls from 300 px² (sigma = 0) to about 1 px²
    areas = np.r_[[300.0] * 20, 1, 2000]
    st = gt_statistics([ann(dirty)], (100, 100))
    assert st[MIN] * 10000 == pytest.approx(areas.mean() - areas.std()) and st[MIN] * 10000 < 2
    assert st["recommended_regions.min_size"] == pytest.approx(0.25 * 300 / 10000)


def test_groups_widen_the_size_and_shape_limits():
    # people 10 x 30 (h/w 3); groups of three side by side 30 x 30 (h/w 1, area 900): a
    # percentile over everything would drop them, so they count as their own population
    people = np.tile([0, 0, 10, 30], (21, 1)).astype(float)
    groups = np.tile([0, 0, 30, 30, 3], (2, 1)).astype(float)
    rec = recommend_regions(people, groups, (100, 100))
    assert rec["regions.max_size"] == pytest.approx(2 * 900 / 10000)
    assert rec["regions.min_hw_ratio"] == pytest.approx(0.5 * 1)
    assert rec["regions.max_hw_ratio"] == pytest.approx(3 / 0.5)
    assert rec["regions.min_size"] == pytest.approx(0.25 * 300 / 10000)   # from the people alone


def test_max_size_is_at_most_the_image():
    rec = recommend_regions(np.array([[0, 0, 90, 90]]), np.zeros((0, 5)), (100, 100))
    assert rec["regions.max_size"] == 1.0


@pytest.mark.parametrize("q", [50, 70, -1, float("nan")])
def test_percentile_out_of_range_is_refused(q):
    with pytest.raises(ConfigError, match="--percentile"):
        recommend_regions(np.array([[0, 0, 10, 30]]), np.zeros((0, 5)), (100, 100), q)


def test_cli_write_config_is_a_track_config(tmp_path, capsys):
    from motiontrack.cli import main
    from motiontrack.config import load_config

    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,0,0,10,30,1,-1,-1,-1\n")
    cfg = tmp_path / "rec.toml"
    args = ["gt-stats", str(gt), "--image-size", "100x100", "--write-config", str(cfg)]
    assert main(args) == 0
    r = load_config(cfg).regions
    assert (r.min_size, r.max_size, r.min_hw_ratio, r.max_hw_ratio) == \
        pytest.approx((0.25 * 300 / 10000, 2 * 300 / 10000, 1.5, 6))
    assert load_config(cfg).motion == load_config(None).motion     # nothing else changes
    capsys.readouterr()
    assert main(args) == 2                                           # exists: needs --force
    assert "--force" in capsys.readouterr().err
    assert main(args + ["--force"]) == 0


def test_cli_write_config_refuses_ground_truth_without_boxes(tmp_path, capsys):
    from motiontrack.cli import main

    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,0,0,10,30,0,-1,-1,-1\n")      # consider = 0: nothing counts
    cfg = tmp_path / "rec.toml"
    assert main(["gt-stats", str(gt), "--image-size", "100x100", "--write-config", str(cfg)]) == 2
    assert "no boxes" in capsys.readouterr().err and not cfg.exists()


@pytest.mark.data
@pytest.mark.slow
def test_pets_recommendation_keeps_the_people_the_thesis_model_drops(data, tmp_path, capsys):
    import motiontrack
    from motiontrack.cli import main
    from motiontrack.config import load_config
    from motiontrack.evaluate.mot import evaluate_tracking
    from motiontrack.io.mot import read_mot

    from helpers import tracks_of

    video = data("pets09-s2l1", "video.avi")
    gt_path = data("pets09-s2l1", "gt_mot15.txt")
    cfg, js = tmp_path / "rec.toml", tmp_path / "stats.json"
    assert main(["gt-stats", str(gt_path), "--image-size", "768x576", "--write-config", str(cfg),
                 "--json", str(js)]) == 0
    stats = json.loads(js.read_text())
    printed = capsys.readouterr().out
    # the thesis model is still reported, under its own name
    assert stats[MIN] == pytest.approx(stats[MU] - stats[SIGMA])
    assert stats[MAX] == pytest.approx(stats[MU] + stats[SIGMA])
    assert "thesis_model_overrides" in printed and MIN in printed
    gt = read_mot(gt_path, kind="gt")

    def score(config):
        r = evaluate_tracking(gt, tracks_of(motiontrack.track(str(video), config)),
                              ignore_zero_marked=True)
        return r["HOTA"], r["TP"] / (r["TP"] + r["FN"])

    hota_default, recall_default = score(load_config(None))
    hota_rec, recall_rec = score(load_config(cfg))
    hota_thesis, recall_thesis = score(load_config(None, stats["thesis_model_overrides"]))
    assert hota_rec >= hota_default - 0.02
    assert recall_rec >= recall_default - 0.005
    assert recall_thesis < 0.5 * recall_default and hota_thesis < 0.5 * hota_default


def test_cli_pools_the_files_a_quoted_glob_matches(tmp_path, capsys):
    from motiontrack.cli import main

    (tmp_path / "gt").mkdir()
    (tmp_path / "gt" / "a.txt").write_text("1,1,0,0,10,10,1,-1,-1,-1\n")
    (tmp_path / "gt" / "b.txt").write_text("1,2,5,5,10,30,1,-1,-1,-1\n")
    listed, pattern = tmp_path / "listed.json", tmp_path / "pattern.json"
    assert main(["gt-stats", str(tmp_path / "gt" / "a.txt"), str(tmp_path / "gt" / "b.txt"),
                 "--image-size", "100x50", "--json", str(listed)]) == 0
    assert main(["gt-stats", str(tmp_path / "gt" / "*.txt"), "--image-size", "100x50",
                 "--json", str(pattern)]) == 0
    assert json.loads(pattern.read_text()) == json.loads(listed.read_text())
    assert json.loads(pattern.read_text())["n_boxes"] == 2
    capsys.readouterr()
    assert main(["gt-stats", str(tmp_path / "gt" / "*.xml"), "--image-size", "100x50"]) == 2
    assert capsys.readouterr().err.strip() == (f"motiontrack: error: no ground-truth files "
                                               f"match {tmp_path / 'gt' / '*.xml'}")
