"""BGSLibrary's models as ``motion.method = bgslibrary`` (through ``pybgs``, an optional extra),
with our shadow test and hold on their masks.

The tests that run a model need ``pybgs``: they skip without it, except under
``MOTIONTRACK_REQUIRE_DATA=1`` (.ci/run installs it), where its absence fails."""

from __future__ import annotations

import os
import sys

import cv2
import numpy as np
import pytest

from motiontrack.config import load_config
from motiontrack.errors import ConfigError
from motiontrack.motion import create_detector
from motiontrack.motion.shadows import FOREGROUND, SHADOW, shadow_test


def _pybgs():
    try:
        import pybgs
    except ImportError:
        if os.environ.get("MOTIONTRACK_REQUIRE_DATA") == "1":
            pytest.fail("pybgs (BGSLibrary) is not installed and MOTIONTRACK_REQUIRE_DATA=1")
        pytest.skip("pybgs (BGSLibrary) is not installed: pip install pybgs")
    return pybgs


def _cfg(*sets: str):
    return load_config(None, ["motion.method=bgslibrary", *sets])


# --------------------------------------------------------------------- the shadow test alone
def test_a_darker_copy_of_the_background_is_a_shadow_and_a_coloured_object_is_not():
    bg = np.full((4, 6, 3), (90, 120, 150), np.uint8)
    frame = bg.copy()
    frame[:, :2] = (45, 60, 75)          # half as bright, the same colour: a shadow
    frame[:, 2:4] = (30, 40, 160)        # as dark in blue and green, redder: an object
    frame[:, 4:] = (30, 40, 50)          # a third as bright: darker than the darkest shadow
    fg = np.full((4, 6), 255, np.uint8)
    out = shadow_test(frame, bg, fg, darkest=0.4)
    assert (out[:, :2] == SHADOW).all() and (out[:, 2:] == FOREGROUND).all()
    fg[0, 0] = 0                          # background stays background
    assert shadow_test(frame, bg, fg, darkest=0.4)[0, 0] == 0


def test_gray_frames_or_a_missing_background_have_no_shadows():
    fg = np.full((2, 2), 255, np.uint8)
    assert (shadow_test(np.zeros((2, 2), np.uint8), None, fg, 0.5) == FOREGROUND).all()
    assert (shadow_test(np.zeros((2, 2, 3), np.uint8), None, fg, 0.5) == FOREGROUND).all()


# ---------------------------------------------------------------- without pybgs: one message
def test_without_pybgs_the_method_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "pybgs", None)        # import pybgs raises ImportError
    with pytest.raises(ConfigError, match="needs BGSLibrary's Python binding pybgs"):
        create_detector(_cfg().motion)
    from motiontrack.motion.bgslibrary import algorithms

    assert algorithms() == ()


# ------------------------------------------------------------------------------- with pybgs
def test_an_unknown_model_lists_the_installed_ones():
    _pybgs()
    with pytest.raises(ConfigError, match=r"motion.bgslibrary.algorithm must be one of .*"
                                          r"SuBSENSE.*got 'Nope'"):
        create_detector(_cfg("motion.bgslibrary.algorithm='Nope'").motion)


def test_a_model_finds_a_moving_square_and_prints_nothing(capfd):
    _pybgs()
    det = create_detector(_cfg("motion.bgslibrary.algorithm='SigmaDelta'").motion)
    rng = np.random.default_rng(0)
    ground = rng.integers(80, 120, (60, 80, 3), dtype=np.uint8)
    for _ in range(40):
        det.apply(ground)
    masks = []
    for k in range(6):
        frame = ground.copy()
        frame[20:40, 10 + 5 * k:30 + 5 * k] = (20, 200, 40)
        masks.append(det.apply(frame))
    assert masks[-1][24:36, 40:50].mean() > 200 and masks[-1][:, :5].max() == 0
    det.relearn(ground)
    del det
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_the_pipeline_leaves_ghosts_to_the_model_and_holds_with_it():
    _pybgs()
    from motiontrack.pipeline import Pipeline

    pipe = Pipeline(_cfg(), (160, 120), fps=25.0)
    assert pipe.ghosts is None and pipe.detector.own_ghosts
    assert pipe.detector.protect and pipe.detector.relearns      # the hold takes the boxes
    assert pipe.pre_cfg.grayscale is False                         # SuBSENSE sees colour


@pytest.mark.data
@pytest.mark.slow
def test_subsense_on_the_sbi_office_with_our_stages(data):
    """SBI HumanBody2 frames 1-200 through SuBSENSE, our shadow test, hold and regions (F 0.55
    over these frames, where the man of the first frame walks off; 0.74 over all 740, where
    KNN's defaults reach 0.90: benchmarks/still_people.py)."""
    _pybgs()
    from motiontrack.evaluate.masks import MaskCounts, compare_masks, read_roi
    from motiontrack.pipeline import run

    folder = data("sbi", "HumanBody2")
    roi = read_roi(folder / "ROI.bmp")
    counts = MaskCounts()
    with run(str(folder / "input" / "*.jpg"), _cfg("source.max_frames=200")) as r:
        for res in r:
            gt = cv2.imread(str(folder / "groundtruth" / f"gt{res.index + 1:06d}.png"),
                            cv2.IMREAD_GRAYSCALE)
            counts = counts + compare_masks(gt, res.mask, roi)
    m = counts.metrics()
    assert m["recall"] >= 0.5 and m["f_measure"] >= 0.5, m
