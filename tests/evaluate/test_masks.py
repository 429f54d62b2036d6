"""CDnet 2014 mask metrics: hand-built scenarios, real highway data, the evaluate-masks command."""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.errors import InputError
from motiontrack.evaluate.masks import (
    MaskCounts, cdnet_video, compare_masks, evaluate_mask_folders, find_frames, mask_metrics,
    read_temporal_roi,
)

# labels: 0 static, 50 shadow, 85 outside ROI, 170 unknown, 255 motion
GT = np.array([[0, 50, 255, 255],
               [170, 85, 255, 0],
               [0, 0, 50, 255]], dtype=np.uint8)
PRED = np.array([[255, 255, 255, 0],
                 [255, 255, 0, 0],
                 [0, 127, 255, 255]], dtype=np.uint8)
NO_FIRST_COLUMN = np.array([[0, 1, 1, 1]] * 3, dtype=np.uint8)


@pytest.mark.parametrize("name, gt, pred, roi, expected", [
    # (0,0) FP; (0,1) shadow detected: FP + shadow error; (0,2) TP; (0,3) FN; (1,0) unknown and
    # (1,1) outside ROI: not counted; (1,2) FN; (1,3) TN; (2,0) TN; (2,1) 127 is not foreground: TN;
    # (2,2) shadow detected: FP + shadow error; (2,3) TP
    ("mixed", GT, PRED, None, dict(tp=2, fp=3, fn=2, tn=3, shadow_errors=2, shadow=2)),
    # the spatial ROI also drops (0,0) FP and (2,0) TN
    ("roi", GT, PRED, NO_FIRST_COLUMN, dict(tp=2, fp=3 - 1, fn=2, tn=3 - 1, shadow_errors=2,
                                            shadow=2)),
    # boolean prediction: True = foreground, so (2,1) 127 → True is now an FP
    ("bool", GT, PRED > 0, None, dict(tp=2, fp=3 + 1, fn=2, tn=3 - 1, shadow_errors=2, shadow=2)),
    ("all-unknown", np.full((2, 3), 170, np.uint8), np.full((2, 3), 255, np.uint8), None,
     dict(tp=0, fp=0, fn=0, tn=0, shadow_errors=0, shadow=0)),
    ("empty", np.zeros((0, 0), np.uint8), np.zeros((0, 0), np.uint8), None,
     dict(tp=0, fp=0, fn=0, tn=0, shadow_errors=0, shadow=0)),
])
def test_compare_masks_counts(name, gt, pred, roi, expected):
    c = compare_masks(gt, pred, roi)
    assert c == MaskCounts(**expected, frames=1)


def square(shift: int = 0) -> np.ndarray:
    """10×10 frame with a 4×5 moving block at rows 2..5, columns 2+shift..6+shift."""
    m = np.zeros((10, 10), np.uint8)
    m[2:6, 2 + shift:7 + shift] = 255
    return m


@pytest.mark.parametrize("name, pred, expected", [
    ("identical", square(), dict(tp=20, fp=0, fn=0, tn=100 - 20)),
    # shifted right by one column: one column lost (4 FN), one gained (4 FP)
    ("shift-1", square(1), dict(tp=4 * 4, fp=4, fn=4, tn=100 - 24)),
    # eroded with a 3×3 square: only the 2×3 interior survives
    ("eroded", cv2.erode(square(), np.ones((3, 3), np.uint8)), dict(tp=2 * 3, fp=0, fn=20 - 6,
                                                                     tn=100 - 20)),
    ("nothing", np.zeros((10, 10), np.uint8), dict(tp=0, fp=0, fn=20, tn=80)),
])
def test_square_scenarios(name, pred, expected):
    assert compare_masks(square(), pred) == MaskCounts(**expected, frames=1)


def test_metrics_formulas():
    m = mask_metrics(MaskCounts(tp=2, fp=3, fn=2, tn=3, shadow_errors=2, shadow=2))
    assert m["recall"] == pytest.approx(2 / (2 + 2))
    assert m["specificity"] == pytest.approx(3 / (3 + 3))
    assert m["fpr"] == pytest.approx(3 / (3 + 3))
    assert m["fnr"] == pytest.approx(2 / (2 + 2))
    assert m["pwc"] == pytest.approx(100 * (2 + 3) / (2 + 3 + 2 + 3))
    assert m["precision"] == pytest.approx(2 / (2 + 3))
    p, r = 2 / 5, 2 / 4
    assert m["f_measure"] == pytest.approx(2 * p * r / (p + r))
    assert m["fpr_shadow"] == pytest.approx(2 / 2)


def test_metrics_zero_denominators_are_nan():
    m = mask_metrics(MaskCounts())
    assert all(math.isnan(v) for v in m.values())
    m = mask_metrics(MaskCounts(tn=5))  # nothing moving, nothing detected
    assert m["specificity"] == 1 and m["fpr"] == 0 and m["pwc"] == 0
    assert math.isnan(m["recall"]) and math.isnan(m["precision"]) and math.isnan(m["f_measure"])


def test_stack_equals_sum_of_frames():
    rng = np.random.default_rng(7)
    labels = np.array([0, 50, 85, 170, 255], np.uint8)
    gt = rng.choice(labels, size=(5, 6, 7))
    pred = rng.choice(np.array([0, 127, 255], np.uint8), size=(5, 6, 7))
    roi = rng.random((6, 7)) > 0.2
    total = MaskCounts()
    for g, p in zip(gt, pred):
        total = total + compare_masks(g, p, roi)
    assert compare_masks(gt, pred, roi) == total
    assert total.frames == 5
    before = (gt.copy(), pred.copy())
    compare_masks(gt, pred, roi)
    np.testing.assert_array_equal(gt, before[0])
    np.testing.assert_array_equal(pred, before[1])


@pytest.mark.parametrize("gt, pred, roi, message", [
    (np.zeros((2, 2), np.uint8), np.zeros((2, 3), np.uint8), None, "same shape"),
    (np.zeros((2, 2), np.uint8), np.zeros((2, 2), np.uint8), np.ones((3, 3)), "ROI shape"),
    (np.zeros(4, np.uint8), np.zeros(4, np.uint8), None, r"\(H, W\)"),
])
def test_compare_masks_rejects_bad_shapes(gt, pred, roi, message):
    with pytest.raises(ValueError, match=message):
        compare_masks(gt, pred, roi)


def test_mask_counts_validate():
    with pytest.raises(ValueError, match="tp must be a non-negative integer"):
        MaskCounts(tp=-1)
    assert MaskCounts(tp=1, frames=1) + MaskCounts(fn=2, frames=1) == MaskCounts(tp=1, fn=2,
                                                                                 frames=2)


@pytest.mark.parametrize("text, expected", [("470 1000\n", (470, 1000)), ("1\t1", (1, 1))])
def test_read_temporal_roi(tmp_path, text, expected):
    (tmp_path / "t.txt").write_text(text)
    assert read_temporal_roi(tmp_path / "t.txt") == expected


@pytest.mark.parametrize("text", ["", "470", "a b", "10 5"])
def test_read_temporal_roi_malformed(tmp_path, text):
    (tmp_path / "t.txt").write_text(text)
    with pytest.raises(InputError, match="t.txt:1:"):
        read_temporal_roi(tmp_path / "t.txt")


def test_find_frames_by_number(tmp_path):
    for n in ("bin000470.png", "bin000471.png", "mask_12.png", "notes.txt", "nonumber.png"):
        (tmp_path / n).write_bytes(b"")
    assert sorted(find_frames(tmp_path)) == [12, 470, 471]
    assert sorted(find_frames(tmp_path, "bin")) == [470, 471]
    (tmp_path / "other000470.png").write_bytes(b"")
    with pytest.raises(InputError, match="two masks for frame 470"):
        find_frames(tmp_path)


# ------------------------------------------------------------------------------------ real data

HIGHWAY = "cdnet-highway"


def read_gt(data, f: int) -> np.ndarray:
    return cv2.imread(str(data(HIGHWAY, "groundtruth", f"gt{f:06d}.png")), cv2.IMREAD_GRAYSCALE)


def write_preds(folder, frames, make) -> None:
    folder.mkdir(exist_ok=True)
    for f in frames:
        cv2.imwrite(str(folder / f"bin{f:06d}.png"), make(f))


@pytest.mark.data
def test_highway_folder_layout(data):
    v = cdnet_video(data(HIGHWAY))
    assert len(v.inputs) == len(v.groundtruth) == 1000
    assert v.temporal_roi == (470, 1000)
    assert v.roi is not None and v.inputs[470].name == "in000470.jpg"


@pytest.mark.data
def test_highway_gt_against_itself_is_perfect(data, tmp_path):
    frames = range(470, 571)
    write_preds(tmp_path / "pred", frames,
                lambda f: np.where(read_gt(data, f) == 255, 255, 0).astype(np.uint8))
    r = evaluate_mask_folders(data(HIGHWAY, "groundtruth"), tmp_path / "pred", frames=(470, 570))
    gts = np.stack([read_gt(data, f) for f in frames])
    # independent count of the labels (ROI.bmp of highway is all white)
    assert r.counts == MaskCounts(tp=int((gts == 255).sum()), fp=0, fn=0,
                                  tn=int(((gts == 0) | (gts == 50)).sum()),
                                  shadow_errors=0, shadow=int((gts == 50).sum()), frames=101)
    # golden values for this subset of the data
    assert (r.counts.tp, r.counts.tn) == (21638, 7710957)
    assert r.metrics["recall"] == 1 and r.metrics["precision"] == 1 and r.metrics["pwc"] == 0
    assert r.metrics["f_measure"] == 1 and r.metrics["specificity"] == 1


@pytest.mark.data
def test_highway_shadow_detected_is_false_positive(data, tmp_path):
    """Frames 590..620 contain hard shadows: predicting shadow as motion adds them all to FP."""
    frames = range(590, 621)
    write_preds(tmp_path / "pred", frames,
                lambda f: np.where(np.isin(read_gt(data, f), (50, 255)), 255, 0).astype(np.uint8))
    r = evaluate_mask_folders(data(HIGHWAY), tmp_path / "pred", frames=(590, 620))
    gts = np.stack([read_gt(data, f) for f in frames])
    n_shadow = int((gts == 50).sum())
    assert n_shadow > 0
    assert r.counts == MaskCounts(tp=int((gts == 255).sum()), fp=n_shadow, fn=0,
                                  tn=int((gts == 0).sum()), shadow_errors=n_shadow,
                                  shadow=n_shadow, frames=31)
    assert r.metrics["fpr_shadow"] == 1


@pytest.mark.data
def test_highway_shifted_copy(data, tmp_path):
    """The ground truth's motion shifted 3 px right: counts equal an independent pixel count."""
    frames = range(470, 521)
    shifted = {f: np.roll(np.where(read_gt(data, f) == 255, 255, 0).astype(np.uint8), 3, axis=1)
               for f in frames}
    write_preds(tmp_path / "pred", frames, shifted.__getitem__)
    r = evaluate_mask_folders(data(HIGHWAY), tmp_path / "pred", frames=(470, 520))
    gts = np.stack([read_gt(data, f) for f in frames])
    pred = np.stack([shifted[f] for f in frames]) == 255
    valid = gts != 170
    pos = gts == 255
    assert r.counts.tp == int((valid & pos & pred).sum())
    assert r.counts.fp == int((valid & ~pos & pred).sum())
    assert r.counts.fn == int((valid & pos & ~pred).sum())
    assert r.counts.tn == int((valid & ~pos & ~pred).sum())
    assert 0 < r.counts.tp < int(pos.sum())
    assert 0 < r.metrics["recall"] < 1 and 0 < r.metrics["precision"] < 1


@pytest.mark.data
@pytest.mark.parametrize("frames", [(470, 650)])
def test_highway_mog2_smoke(data, tmp_path, frames):
    """OpenCV MOG2 (50 frames of warm-up) on a subset with shadows: a real, imperfect detector."""
    mog = cv2.createBackgroundSubtractorMOG2(history=500, varThreshold=16, detectShadows=True)
    out = tmp_path / "mog2"
    out.mkdir()
    for f in range(frames[0] - 50, frames[1] + 1):
        fg = mog.apply(cv2.imread(str(data(HIGHWAY, "input", f"in{f:06d}.jpg"))))
        if f >= frames[0]:
            cv2.imwrite(str(out / f"bin{f:06d}.png"), fg)  # 127 = MOG2 shadow → background
    r = evaluate_mask_folders(data(HIGHWAY), out, frames=frames)
    assert r.counts.frames == frames[1] - frames[0] + 1
    assert r.counts.shadow > 0
    m = r.metrics
    assert 0.5 < m["recall"] < 1 and 0.3 < m["precision"] < 1 and 0 < m["f_measure"] < 1
    assert 0 < m["pwc"] < 2 and m["specificity"] > 0.99


@pytest.mark.data
def test_missing_prediction_and_size_mismatch(data, tmp_path):
    write_preds(tmp_path / "p", range(470, 480), lambda f: np.zeros((240, 320), np.uint8))
    with pytest.raises(InputError, match=r"no predicted mask for 1 frame\(s\) in 470..480"):
        evaluate_mask_folders(data(HIGHWAY), tmp_path / "p", frames=(470, 480))
    write_preds(tmp_path / "q", [470], lambda f: np.zeros((10, 10), np.uint8))
    with pytest.raises(InputError, match="differs from the ground truth"):
        evaluate_mask_folders(data(HIGHWAY), tmp_path / "q", frames=(470, 470))
    with pytest.raises(InputError, match="no frames to evaluate"):
        evaluate_mask_folders(data(HIGHWAY), tmp_path / "p", frames=(1, 100))  # before 470
    with pytest.raises(InputError, match="mask folder not found"):
        evaluate_mask_folders(data(HIGHWAY), tmp_path / "missing", frames=(470, 470))


# ------------------------------------------------------------------------------------------ CLI


@pytest.mark.data
def test_cli_evaluate_masks(data, tmp_path, capsys):
    write_preds(tmp_path / "pred", range(470, 481),
                lambda f: np.where(read_gt(data, f) == 255, 255, 0).astype(np.uint8))
    code = main(["evaluate-masks", "--gt", str(data(HIGHWAY, "groundtruth")), "--pred",
                 str(tmp_path / "pred"), "--frames", "470:480", "--json", str(tmp_path / "m.json")])
    assert code == 0
    out = capsys.readouterr().out
    assert "Recall        1.000000" in out and "PWC (%)       0.000000" in out
    doc = json.loads((tmp_path / "m.json").read_text())
    assert doc["frames"] == 11 and doc["fp"] == 0 and doc["fn"] == 0 and doc["precision"] == 1
    assert doc["fpr_shadow"] is None  # nan → null


@pytest.mark.data
@pytest.mark.parametrize("extra, message", [
    ([], "no predicted mask for"),  # the default temporal ROI 470..1000 needs all frames
    (["--frames", "9"], "--frames must be A:B"),
])
def test_cli_evaluate_masks_errors(data, tmp_path, capsys, extra, message):
    write_preds(tmp_path / "pred", [470], lambda f: np.zeros((240, 320), np.uint8))
    code = main(["evaluate-masks", "--gt", str(data(HIGHWAY)), "--pred", str(tmp_path / "pred"),
                 *extra])
    assert code == 2
    err = capsys.readouterr().err
    assert err.startswith("motiontrack: error:") and message in err and "Traceback" not in err
