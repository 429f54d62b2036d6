"""Framewise metrics (thesis §4.1, ViPER-PE): worked examples, edge cases, ViPER-PE's own output."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from motiontrack.errors import ConfigError
from motiontrack.evaluate.framewise import METRIC_KEYS, evaluate_framewise, frame_measures
from motiontrack.io.viper import read_viper
from motiontrack.types import Annotations

from helpers import ann


# ---------------------------------------------------------------------------------------------
# The thesis' worked example (§4.1), rebuilt as one frame:
#
#   target  T  = (x=2, y=0, w=6, h=3)  -> [2, 8) x [0, 3), area 18
#   cand    c1 = (x=1, y=0, w=5, h=5)  -> [1, 6) x [0, 5), area 25, overlaps T on [2, 6) x [0, 3) = 12
#   cand    c2 = (x=7, y=0, w=2, h=5)  -> [7, 9) x [0, 5), area 10, overlaps T on [7, 8) x [0, 3) = 3
#
#   c1 and c2 are disjoint, so |UC| = 35, matched = 12 + 3 = 15, false = 20, missed = 3
#   (the column [6, 7) x [0, 3) of T is not covered). T is split into 2 fragments.
# ---------------------------------------------------------------------------------------------
THESIS_GT = [(1, 1, 2, 0, 6, 3)]
THESIS_PRED = [(1, 1, 1, 0, 5, 5), (1, 2, 7, 0, 2, 5)]
THESIS_EXPECTED = {
    "pixel_precision": 1 - 20 / 35,
    "pixel_recall": 15 / 18,
    "fragmentation": 1 / (1 + math.log10(2)),
    "object_area_precision": (12 / 25 + 3 / 10) / 2,
    "box_area_precision": (12 / 25 + 3 / 10) / 2,
    "object_area_recall": (12 + 3) / 18,
    "localized_object_precision": 0.0,  # 12/25 = 0.48 and 3/10 = 0.3 are both < 0.75
    "localized_object_recall": 1.0,  # 15/18 = 0.833 >= 0.75
    "matched_pixels": 15.0,
    "missed_pixels": 3.0,
    "false_pixels": 20.0,
    "detection_accuracy": 2 * 1 / (1 + 2),
    "object_count_recall": 1.0,
    "object_count_precision": 1 / 2,
    # dice distance: T against UC, then c1 and c2 against UT, averaged
    "dice_distance": ((1 - 2 * 15 / (18 + 35)) + (1 - 2 * 12 / (25 + 18)) + (1 - 2 * 3 / (10 + 18)))
    / 3,
    "dice": 1
    - ((1 - 2 * 15 / (18 + 35)) + (1 - 2 * 12 / (25 + 18)) + (1 - 2 * 3 / (10 + 18))) / 3,
    "n_gt": 1.0,
    "n_pred": 2.0,
}


@pytest.mark.parametrize("key", sorted(THESIS_EXPECTED))
def test_thesis_worked_example(key):
    overall, per_frame = evaluate_framewise(ann(THESIS_GT), ann(THESIS_PRED), xi=0.75)
    assert overall[key] == pytest.approx(THESIS_EXPECTED[key], abs=1e-12)
    # one frame: the per-frame numbers are the overall numbers
    assert len(per_frame) == 1 and per_frame[0]["frame"] == 1
    assert per_frame[0][key] == pytest.approx(THESIS_EXPECTED[key], abs=1e-12)


def test_keys_present():
    overall, per_frame = evaluate_framewise(ann(THESIS_GT), ann(THESIS_PRED))
    required = {
        "pixel_precision", "pixel_recall", "object_area_precision", "object_area_recall",
        "fragmentation", "localized_object_precision", "localized_object_recall", "dice",
        "matched_pixels", "missed_pixels", "false_pixels",
    }
    assert required <= set(overall) == set(METRIC_KEYS)
    assert set(per_frame[0]) == set(METRIC_KEYS) | {"frame"}


# ---------------------------------------------------------------------------------------------
# Small scenes: (gt rows, pred rows, xi, expected subset)
# ---------------------------------------------------------------------------------------------
NAN = math.nan
SCENES = {
    # exact match: everything perfect
    "identical": (
        [(1, 1, 0, 0, 4, 4)], [(1, 7, 0, 0, 4, 4)], 0.75,
        {"pixel_precision": 1.0, "pixel_recall": 1.0, "fragmentation": 1.0, "dice": 1.0,
         "object_area_recall": 1.0, "object_area_precision": 1.0, "matched_pixels": 16.0,
         "localized_object_recall": 1.0, "localized_object_precision": 1.0},
    ),
    # only ground truth: everything missed; precision undefined (ViPER: "undefined")
    "gt only": (
        [(1, 1, 0, 0, 4, 4)], [], 0.75,
        {"pixel_recall": 0.0, "pixel_precision": NAN, "missed_pixels": 16.0, "false_pixels": 0.0,
         "object_area_recall": 0.0, "object_area_precision": NAN, "fragmentation": NAN,
         "localized_object_recall": 0.0, "localized_object_precision": NAN,
         "detection_accuracy": 0.0, "object_count_recall": 0.0, "object_count_precision": NAN,
         "dice_distance": 1.0},
    ),
    # only results: everything false (ViPER frames 93-100 of the sample)
    "pred only": (
        [], [(1, 1, 0, 0, 4, 4)], 0.75,
        {"pixel_recall": NAN, "pixel_precision": 0.0, "false_pixels": 16.0,
         "object_area_recall": NAN, "object_area_precision": 0.0, "fragmentation": NAN,
         "localized_object_precision": 0.0, "detection_accuracy": 0.0,
         "object_count_recall": NAN, "object_count_precision": 0.0, "dice_distance": 1.0},
    ),
    # disjoint boxes: counts are right (DA 1) but nothing overlaps (ViPER sample frame 92)
    "disjoint": (
        [(1, 1, 0, 0, 2, 2)], [(1, 1, 10, 10, 2, 2)], 0.75,
        {"matched_pixels": 0.0, "missed_pixels": 4.0, "false_pixels": 4.0,
         "detection_accuracy": 1.0, "fragmentation": NAN, "object_area_recall": 0.0,
         "dice_distance": 1.0},
    ),
    # two overlapping targets: their union (4x2 + 4x2 - 2x2 = 12) is counted once
    "overlapping targets": (
        [(1, 1, 0, 0, 4, 2), (1, 2, 2, 0, 4, 2)], [(1, 1, 0, 0, 6, 2)], 0.75,
        {"matched_pixels": 12.0, "missed_pixels": 0.0, "false_pixels": 0.0,
         "object_area_recall": 1.0, "fragmentation": 1.0, "object_count_precision": 1.0,
         "object_count_recall": 1 / 2},
    ),
    # a target split into 3 candidate pieces
    "three fragments": (
        [(1, 1, 0, 0, 9, 1)], [(1, 1, 0, 0, 3, 1), (1, 2, 3, 0, 3, 1), (1, 3, 6, 0, 3, 1)], 0.75,
        {"fragmentation": 1 / (1 + math.log10(3)), "object_area_recall": 1.0,
         "pixel_precision": 1.0},
    ),
    # fractional boxes are measured exactly (no rasterisation): half of the target is matched
    "fractional": (
        [(1, 1, 0.0, 0.0, 1.0, 1.0)], [(1, 1, 0.5, 0.0, 1.0, 1.0)], 0.5,
        {"matched_pixels": 0.5, "missed_pixels": 0.5, "pixel_recall": 0.5,
         "localized_object_recall": 1.0},  # 0.5 >= xi = 0.5: the threshold is inclusive
    ),
    # just under the threshold
    "below xi": (
        [(1, 1, 0, 0, 4, 1)], [(1, 1, 0, 0, 3, 1)], 0.76,
        {"object_area_recall": 3 / 4, "localized_object_recall": 0.0,
         "localized_object_precision": 1.0},
    ),
}


@pytest.mark.parametrize("name", list(SCENES))
def test_scenes(name):
    gt, pred, xi, expected = SCENES[name]
    overall, _ = evaluate_framewise(ann(gt), ann(pred), xi=xi)
    for key, value in expected.items():
        if math.isnan(value):
            assert math.isnan(overall[key]), (key, overall[key])
        else:
            assert overall[key] == pytest.approx(value, abs=1e-12), key


def test_overall_weighting_is_per_object_not_per_frame():
    # frame 1: one target fully found (area recall 1)
    # frame 2: three targets, none found (area recall 0 each); a candidate elsewhere
    gt = ann([(1, 1, 0, 0, 2, 2),
              (2, 1, 0, 0, 2, 2), (2, 2, 5, 0, 2, 2), (2, 3, 10, 0, 2, 2)])
    pred = ann([(1, 1, 0, 0, 2, 2), (2, 1, 50, 50, 2, 2)])
    overall, per_frame = evaluate_framewise(gt, pred)
    assert [d["object_area_recall"] for d in per_frame] == [1.0, 0.0]
    assert overall["object_area_recall"] == pytest.approx((1 + 0 + 0 + 0) / 4)  # not (1 + 0) / 2
    assert overall["localized_object_recall"] == pytest.approx(1 / 4)
    assert overall["matched_pixels"] == 4.0
    assert overall["missed_pixels"] == 12.0
    assert overall["false_pixels"] == 4.0
    assert overall["pixel_recall"] == pytest.approx(4 / 16)
    # counts are pooled: 4 targets, 2 candidates
    assert overall["detection_accuracy"] == pytest.approx(2 * 2 / (4 + 2))
    assert overall["object_count_recall"] == pytest.approx(2 / 4)


def test_empty_frames_are_skipped_and_frames_filter():
    gt = ann([(1, 1, 0, 0, 2, 2), (5, 1, 0, 0, 2, 2)])
    pred = ann([(3, 1, 0, 0, 2, 2)])
    _, per_frame = evaluate_framewise(gt, pred)
    assert [d["frame"] for d in per_frame] == [1, 3, 5]  # frames 2 and 4 have nothing
    overall, per_frame = evaluate_framewise(gt, pred, frames=(3, 5))
    assert [d["frame"] for d in per_frame] == [3, 5]
    assert overall["missed_pixels"] == 4.0 and overall["false_pixels"] == 4.0


@pytest.mark.parametrize(
    "gt, pred",
    [([], []), ([(1, 1, 0, 0, 2, 2)], []), ([], [(1, 1, 0, 0, 2, 2)])],
    ids=["both empty", "no pred", "no gt"],
)
def test_n_zero(gt, pred):
    overall, per_frame = evaluate_framewise(ann(gt), ann(pred))
    assert set(overall) == set(METRIC_KEYS)
    assert len(per_frame) == (0 if not gt and not pred else 1)
    if not gt and not pred:
        assert overall["matched_pixels"] == 0.0 and overall["missed_pixels"] == 0.0
        assert all(math.isnan(overall[k]) for k in (
            "pixel_precision", "pixel_recall", "object_area_recall", "fragmentation",
            "detection_accuracy", "localized_object_recall", "dice"))


def test_frame_measures_empty():
    fm = frame_measures(np.zeros((0, 4)), np.zeros((0, 4)))
    assert fm.n_gt == 0 and fm.matched == 0.0 and len(fm.dice_distance) == 0


def test_consider_false_gt_rows_are_dropped():
    gt = ann([(1, 1, 0, 0, 2, 2), (1, 2, 10, 10, 2, 2)], consider=[True, False])
    overall, _ = evaluate_framewise(gt, ann([(1, 1, 0, 0, 2, 2)]))
    assert overall["pixel_recall"] == 1.0 and overall["n_gt"] == 1.0


def test_clipping_to_frame_size():
    # target half outside a 10 x 10 frame: only [6, 10) x [0, 2) counts (area 8)
    gt = ann([(1, 1, 6, 0, 8, 2)])
    pred = ann([(1, 1, 6, 0, 4, 2)])
    clipped, _ = evaluate_framewise(gt, pred, frame_size=(10, 10))
    assert clipped["missed_pixels"] == 0.0 and clipped["object_area_recall"] == 1.0
    unclipped, _ = evaluate_framewise(gt, pred)
    assert unclipped["missed_pixels"] == 8.0 and unclipped["object_area_recall"] == 8 / 16


@pytest.mark.parametrize("xi", [-0.1, 1.5, float("nan")])
def test_bad_xi(xi):
    with pytest.raises(ConfigError, match="xi"):
        evaluate_framewise(ann(THESIS_GT), ann(THESIS_PRED), xi=xi)


def test_inputs_not_mutated():
    gt, pred = ann(THESIS_GT), ann(THESIS_PRED)
    before = (gt.boxes.copy(), pred.boxes.copy())
    evaluate_framewise(gt, pred, frame_size=(4, 4))
    assert np.array_equal(gt.boxes, before[0]) and np.array_equal(pred.boxes, before[1])


def _raster(boxes, size):
    m = np.zeros(size, dtype=bool)
    for x, y, w, h in boxes.astype(int):
        m[y:y + h, x:x + w] = True
    return m


@pytest.mark.parametrize("seed", range(5))
def test_against_brute_force_raster(seed):
    """Analytic areas equal pixel counting on a rasterised canvas (integer boxes)."""
    rng = np.random.default_rng(seed)
    n, m = rng.integers(0, 6, size=2)
    g = np.c_[rng.integers(0, 30, (n, 2)), rng.integers(1, 15, (n, 2))].astype(float)
    p = np.c_[rng.integers(0, 30, (m, 2)), rng.integers(1, 15, (m, 2))].astype(float)
    fm = frame_measures(g, p)
    ut, uc = _raster(g, (50, 50)), _raster(p, (50, 50))
    assert fm.matched == (ut & uc).sum()
    assert fm.gt_area == ut.sum() and fm.pred_area == uc.sum()
    for i in range(n):
        t = _raster(g[i:i + 1], (50, 50))
        if uc.any():
            assert fm.area_recall[i] == pytest.approx((t & uc).sum() / t.sum())
    for j in range(m):
        c = _raster(p[j:j + 1], (50, 50))
        if ut.any():
            assert fm.area_precision[j] == pytest.approx((c & ut).sum() / c.sum())


def test_800_frames_10_objects_runs_vectorised():
    # the speed target (< 1 s) is measured in benchmarks/framewise.py, not here
    rng = np.random.default_rng(0)
    frames = np.repeat(np.arange(1, 801), 10)
    ids = np.tile(np.arange(1, 11), 800)
    boxes = np.c_[rng.uniform(0, 700, (8000, 2)), rng.uniform(10, 120, (8000, 2))]
    gt = Annotations.from_columns(frames, ids, boxes)
    pred = Annotations.from_columns(frames, ids, boxes + rng.normal(0, 3, boxes.shape))
    overall, per_frame = evaluate_framewise(gt, pred)
    assert len(per_frame) == 800
    assert 0.5 < overall["pixel_recall"] <= 1.0


# ---------------------------------------------------------------------------------------------
# ViPER-PE's own output for viper-sample-001: every frame, every metric, to 1e-9
# ---------------------------------------------------------------------------------------------
VIPER_LABELS = {
    "Detection Accuracy": "detection_accuracy",
    "Object Count Recall": "object_count_recall",
    "Object Count Precision": "object_count_precision",
    "Dice coefficient": "dice_distance",  # ViPER prints the dice *distance* under this label
    "Pixels matched": "matched_pixels",
    "Pixels missed": "missed_pixels",
    "Pixels falsely detected": "false_pixels",
    "Fragmentation metric": "fragmentation",
    "Object Area Recall": "object_area_recall",
    "Box Area Precision": "box_area_precision",
    "Localized Object Area Recall": "localized_object_area_recall",
    "Localized Box Area Precision": "localized_box_area_precision",
}
COUNT_KEYS = {"matched_pixels", "missed_pixels", "false_pixels"}


def parse_viper_pe_pixel_results(text: str) -> dict:
    """The PIXEL RESULTS section of a ViPER-PE output: {frame or "total": {key: value}}."""
    section = text.split("PIXEL RESULTS", 1)[1].split("\n", 2)[2].split("\n*****", 1)[0]
    blocks: dict = {}
    current = None
    for line in section.splitlines():
        m = re.match(r"For frame (\d+)$", line.strip())
        if m:
            current = blocks.setdefault(int(m.group(1)), {})
            continue
        if line.startswith("Total for all frames"):
            current = blocks.setdefault("total", {})
            continue
        if current is not None and ":" in line:
            label, value = (s.strip() for s in line.split(":", 1))
            current[VIPER_LABELS[label]] = math.nan if value == "undefined" else float(value)
    return blocks


@pytest.mark.data
def test_reproduces_viper_pe_output(data):
    folder = data("viper-sample-001")
    expected = parse_viper_pe_pixel_results((folder / "output.txt").read_text())
    assert len(expected) == 101 and "total" in expected  # frames 1..100 + total
    gt = read_viper(folder / "test-truth.xml")
    pred = read_viper(folder / "test-candidate.xml")
    # the sample's object-Person.epf asks for [arearecall 0.7] [areaprecision 0.7]
    overall, per_frame = evaluate_framewise(gt, pred, xi=0.7)
    ours = {d["frame"]: d for d in per_frame}
    ours["total"] = overall
    assert set(ours) == set(expected)
    checked = 0
    for frame, values in expected.items():
        assert len(values) == 12, frame
        for key, value in values.items():
            got = ours[frame][key]
            if math.isnan(value):
                assert math.isnan(got), (frame, key, got)
            elif key in COUNT_KEYS:
                assert got == value, (frame, key, got, value)
            else:
                assert got == pytest.approx(value, abs=1e-9, rel=0), (frame, key, got, value)
            checked += 1
    assert checked == 101 * 12
