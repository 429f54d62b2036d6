"""Single-object trackers (track/single.py) and ``motiontrack follow``."""

from __future__ import annotations

import json
from functools import lru_cache

import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.errors import ConfigError
from motiontrack.synth import make_scene
from motiontrack.tracking.association import iou_matrix
from motiontrack.tracking.single import (
    SINGLE_TRACKERS,
    background_weights,
    clip_box,
    create_single_tracker,
    follow,
    follow_accuracy,
    parse_box,
)
from motiontrack.types import Annotations, Box

OPENCV = ["csrt", "kcf", "mil", "mosse", "medianflow"]
OURS = ["meanshift", "camshift"]


# ----------------------------------------------------------------------------- small pure parts
@pytest.mark.parametrize("text, expected", [
    ("10,20,30,40", Box(10, 20, 30, 40)),
    (" 1.5, 2 ,3,4 ", Box(1.5, 2, 3, 4)),
    ("-5,-5,10,10", Box(-5, -5, 10, 10)),  # partly outside the image is allowed
])
def test_parse_box(text, expected):
    assert parse_box(text) == expected


@pytest.mark.parametrize("text", ["1,2,3", "1,2,3,4,5", "a,b,c,d", "1,2,0,4", "1,2,3,-4", "",
                                  "1,2,nan,4"])
def test_parse_box_rejects(text):
    with pytest.raises(ConfigError):
        parse_box(text)


@pytest.mark.parametrize("box, expected", [
    (Box(10, 10, 20, 20), Box(10, 10, 20, 20)),          # inside: unchanged
    (Box(-5, -5, 20, 20), Box(0, 0, 15, 15)),            # top-left corner cut
    (Box(90, 40, 20, 20), Box(90, 40, 100 - 90, 50 - 40)),  # bottom-right cut at 100x50
    (Box(200, 10, 5, 5), None),                         # entirely outside
    (Box(99.5, 10, 5, 5), None),                        # less than one pixel inside
])
def test_clip_box(box, expected):
    assert clip_box(box, 100, 50) == expected


@pytest.mark.parametrize("obj, bg, expected", [
    # o* = 2 (smallest non-zero background bin): v = min(1, 2 / o_u), v = 1 where o_u = 0
    ([4, 4, 4, 4], [0, 2, 4, 8], [4 * 1, 4 * 1, 4 * 2 / 4, 4 * 2 / 8]),
    ([1, 0, 3], [0, 0, 0], [1, 0, 3]),  # empty background: unchanged
    ([], [], []),
])
def test_background_weights(obj, bg, expected):
    np.testing.assert_allclose(background_weights(np.array(obj, float), np.array(bg, float)),
                               expected)


def test_registry_lists_every_tracker():
    assert set(OPENCV + OURS + ["nano", "vit"]) == set(SINGLE_TRACKERS.names())


@pytest.mark.parametrize("name, params, needle", [
    ("nano", {}, "backbone"),
    ("nano", {"backbone": "/nonexistent/backbone.onnx", "neckhead": "x"}, "not found"),
    ("vit", {}, "net=PATH"),
    ("vit", {"net": "/nonexistent/vit.onnx"}, "not found"),
    ("nope", {}, "valid names"),
    ("kcf", {"detect_thresh": 2.0}, "detect_thresh"),
    ("meanshift", {"bins": 1}, "bins"),
    ("camshift", {"max_growth": 0.5}, "max_growth"),
    ("csrt", {"unknown": 1}, "bad parameters"),
])
def test_bad_tracker_configuration(name, params, needle):
    with pytest.raises(ConfigError, match=needle):
        create_single_tracker(name, **params)


@pytest.mark.parametrize("name", OPENCV + OURS)
def test_init_box_outside_image_is_an_error(name):
    img = np.zeros((40, 60, 3), np.uint8)
    with pytest.raises(ConfigError, match="4x4 pixels"):
        create_single_tracker(name).init(img, Box(100, 100, 10, 10))


# -------------------------------------------------------------- hand-built moving rigid patch
def _rigid_scene(n=25, step=(3, 1), seed=0):
    """A textured, coloured 40x40 patch moving ``step`` px per frame over a grey noisy floor.

    (MOSSE and MIL lose targets of about 24 px in a 160x120 image; 40 px is comfortable.)"""
    rng = np.random.default_rng(seed)
    coarse = rng.integers(0, 256, (5, 5, 3), dtype=np.uint8)
    patch = np.repeat(np.repeat(coarse, 8, axis=0), 8, axis=1)  # 8x8-pixel blocks
    patch[..., 2] = np.maximum(patch[..., 2], 160)  # reddish, saturated enough for a hue model
    patch[..., 0] = patch[..., 0] // 4
    frames, boxes = [], []
    for i in range(n):
        img = np.full((180, 240, 3), 110, np.uint8)
        img += rng.integers(0, 8, img.shape, dtype=np.uint8)
        x, y = 20 + step[0] * i, 40 + step[1] * i
        img[y:y + 40, x:x + 40] = patch
        frames.append(img)
        boxes.append(Box(x, y, 40, 40))
    return frames, boxes


@pytest.mark.parametrize("name", OPENCV + OURS)
def test_rigid_patch_followed_by_every_tracker(name):
    # Frame 0: init on the true box. Frames 1..24: the patch moves (3, 1) px per frame; every
    # tracker must keep IoU >= 0.5 on every frame (a rigid, textured target is the easy case).
    frames, boxes = _rigid_scene()
    # MIL draws its samples from a generator OpenCV seeds by itself, so a run can lose the
    # patch (roughly one run in five to one in three here): it must follow it in one of six runs
    for _attempt in range(6 if name == "mil" else 1):
        out = list(follow(frames, create_single_tracker(name), boxes[0]))
        assert out[0][2] and out[0][3] == boxes[0]
        ious = [iou_matrix(b.as_array(), t.as_array())[0, 0] if ok else 0.0
                for (_, _, ok, b, _), t in zip(out, boxes)]
        assert len(ious) == 25
        if min(ious) >= 0.5:
            break
    assert min(ious) >= 0.5, np.round(ious, 2)


# ------------------------------------------------------------------ synthetic people (walker/runner)
@lru_cache(maxsize=None)
def _scene_frames(name: str, n: int):
    """Frames from the first frame whose gt box is fully visible and inside the image."""
    s = make_scene(name)
    gt = s.ground_truth()
    b = gt.boxes
    inside = ((b[:, 0] >= 0) & (b[:, 1] >= 0) & (b[:, 0] + b[:, 2] <= s.width)
              & (b[:, 1] + b[:, 3] <= s.height) & (gt.visibility >= 0.99))
    f0 = int(gt.frames[np.flatnonzero(inside)[0]])
    frames = tuple(s.frame(f - 1) for f in range(f0, f0 + n))
    return f0, frames, gt


# Thresholds measured on seed 0 (docs/flow_and_single.md) with a small margin: fraction of the
# frames after the init frame with IoU >= 0.5 ("iou") or with the box centre inside the gt box
# ("centre"). The walker's gt box width swings 24..47 px with the legs, so fixed-size boxes peak
# near IoU 0.55 at full stride. Weak pairs are stated, not hidden: mil on the runner (0.17), MOSSE
# on both (0.23 / 0.0: its PSR test declares failure on the deforming person), medianflow on the
# runner (0.4), camshift's box locks onto the trousers' colour (IoU ~0.45, centre always inside).
SYNTH_CASES = [
    ("walker", "csrt", 40, "iou", 0.9),
    ("walker", "kcf", 60, "iou", 0.9),
    ("walker", "mil", 40, "iou", 0.9),
    ("walker", "medianflow", 60, "iou", 0.7),
    ("walker", "meanshift", 60, "iou", 0.5),
    ("walker", "meanshift", 60, "centre", 0.95),
    ("walker", "camshift", 60, "centre", 0.95),
    ("walker", "medianflow", 60, "centre", 0.95),
    ("runner", "csrt", 40, "iou", 0.9),
    ("runner", "kcf", 60, "iou", 0.9),
    ("runner", "meanshift", 60, "iou", 0.9),
    ("runner", "camshift", 60, "centre", 0.95),
]


@pytest.mark.parametrize("scene, name, n, criterion, minimum", SYNTH_CASES)
@pytest.mark.slow
def test_synthetic_person_followed(scene, name, n, criterion, minimum):
    f0, frames, gt = _scene_frames(scene, 61)

    def share_followed() -> float:
        out = list(follow(frames[:n + 1], create_single_tracker(name), Box(*gt.at(f0).boxes[0])))
        good = []
        for k, (_, _, ok, b, _) in enumerate(out[1:], start=1):
            g = gt.at(f0 + k).boxes[0]
            if criterion == "iou":
                good.append(ok and iou_matrix(b.as_array(), g)[0, 0] >= 0.5)
            else:
                cx, cy = b.center if ok else (-1, -1)
                good.append(g[0] <= cx <= g[0] + g[2] and g[1] <= cy <= g[1] + g[3])
        assert len(good) == n
        return float(np.mean(good))

    # MIL draws its samples from a generator inside OpenCV that cv2.setRNGSeed does not reach,
    # so one run depends on the MIL runs before it in the process: the median of three runs
    share = float(np.median([share_followed() for _ in range(3 if name == "mil" else 1)]))
    assert share >= minimum, f"{name} on {scene}: {share:.3f} < {minimum}"


# --------------------------------------------------------------------------------- accuracy
def _ann(frames, boxes, ids=None, meta=None):
    return Annotations.from_columns(frames, ids if ids is not None else np.ones(len(frames)),
                                    np.array(boxes, float).reshape(-1, 4), meta=meta)


def test_follow_accuracy_arithmetic():
    gt = _ann([1, 2, 3, 4, 1], [[0, 0, 10, 10], [0, 0, 10, 10], [0, 0, 10, 10], [0, 0, 10, 10],
                                [50, 50, 10, 10]], ids=[7, 7, 7, 7, 8])
    # frame 1 exact (IoU 1), frame 2 shifted by half (IoU 50 / 150), frame 3 missing, frame 4 far
    pred = _ann([1, 2, 4], [[0, 0, 10, 10], [5, 0, 10, 10], [30, 30, 10, 10]])
    acc = follow_accuracy(gt, pred)
    assert acc["gt_id"] == 7  # chosen by IoU with the first predicted box
    assert acc["frames"] == 4
    assert acc["lost"] == 1
    assert acc["mean_iou"] == pytest.approx((1 + 50 / 150 + 0 + 0) / 4)
    assert acc["iou50"] == pytest.approx(1 / 4)
    # the processed range can end after the last prediction: lost frames still count
    acc = follow_accuracy(gt, _ann([1], [[0, 0, 10, 10]], meta={"last_frame": 4}), gt_id=7)
    assert (acc["frames"], acc["lost"], acc["mean_iou"]) == (4, 3, pytest.approx(1 / 4))


def test_follow_accuracy_empty():
    assert follow_accuracy(_ann([1], [[0, 0, 1, 1]]), Annotations.empty())["frames"] == 0
    # a box that overlaps no gt object is matched to none (not to an arbitrary one)
    acc = follow_accuracy(_ann([1, 2], [[0, 0, 1, 1]] * 2), _ann([1, 2], [[50, 50, 5, 5]] * 2))
    assert acc["gt_id"] == -1 and acc["frames"] == 0


def test_follow_handles_no_frames():
    assert list(follow([], create_single_tracker("mosse"), Box(0, 0, 5, 5))) == []


# -------------------------------------------------------------------------------------- CLI
@pytest.mark.parametrize("argv, needle", [
    (["--box", "1,2,3", "--tracker", "csrt"], "x,y,w,h"),
    (["--box", "a,b,c,d"], "x,y,w,h"),
    (["--box", "1,2,30,40", "--tracker", "nope"], "valid names"),
    (["--box", "1,2,30,40", "--tracker", "nano"], "backbone"),
    (["--box", "700,2,30,40", "--tracker", "kcf", "--max-frames", "2", "--no-video"], "4x4"),
    (["--box", "1,2,30,40", "--param", "novalue"], "KEY=VALUE"),
])
def test_follow_cli_errors(argv, needle, tmp_path, capsys):
    code = main(["follow", "synth:walker", "-o", str(tmp_path / "o"), *argv])
    err = capsys.readouterr().err
    errors = [ln for ln in err.splitlines() if ln.startswith("motiontrack: error:")]
    assert code != 0 and "Traceback" not in err
    assert len(errors) == 1 and needle in errors[0]


def test_follow_cli_missing_video(tmp_path, capsys):
    code = main(["follow", str(tmp_path / "missing.avi"), "--box", "1,2,3,4", "-o", str(tmp_path)])
    err = capsys.readouterr().err
    assert code != 0 and "not found" in err and "Traceback" not in err


@pytest.mark.slow
def test_follow_cli_outputs(tmp_path, capsys):
    out = tmp_path / "o"
    # walker frame index 30 (frame 31) gt box is 613,300,27,91 (first fully visible frame)
    argv = ["follow", "synth:walker", "--box", "613,300,27,91", "--tracker", "kcf", "--start", "30",
            "--max-frames", "20", "--codec", "mjpg", "-o", str(out)]
    assert main(argv) == 0
    rows = np.loadtxt(out / "tracks.txt", delimiter=",", ndmin=2)
    assert rows[0, :6].tolist() == [31, 1, 613, 300, 27, 91]
    assert set(rows[:, 1]) == {1} and len(rows) == 20
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 20 and summary["tracker"] == "kcf"
    assert summary["accuracy"]["gt_id"] == 1 and summary["accuracy"]["iou50"] >= 0.9
    assert (out / "annotated.avi").stat().st_size > 0
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no temporary leftovers
    assert main(argv) != 0  # outputs exist: refuse without --force
    assert "--force" in capsys.readouterr().err
    assert main(argv + ["--force", "--no-video"]) == 0


@pytest.mark.data
@pytest.mark.slow
def test_follow_pets_person(data, tmp_path):
    # PETS 2009 S2L1 view 1, person 9 (gt_mot15.txt, frame 1 box 499,158,31,75), frames 1-60
    # with CSRT. Measured: mean IoU 0.77, IoU >= 0.5 on 92 % of frames 1-100.
    video = data("pets09-s2l1", "video.avi")
    gt = data("pets09-s2l1", "gt_mot15.txt")
    out = tmp_path / "pets"
    code = main(["follow", str(video), "--box", "499,158,31.03,75.17", "--tracker", "csrt",
                 "--max-frames", "60", "--no-video", "--gt", str(gt), "-o", str(out)])
    assert code == 0
    acc = json.loads((out / "summary.json").read_text())["accuracy"]
    assert acc["gt_id"] == 9 and acc["frames"] == 60
    assert acc["iou50"] >= 0.85 and acc["mean_iou"] >= 0.65, acc
