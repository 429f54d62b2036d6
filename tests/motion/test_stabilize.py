"""Camera-motion compensation and sudden-change handling of the motion stage: hand-built warps
whose transform is known exactly, short synthetic scenes shot by a shaking or panning camera,
and a light switched on."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from motiontrack.config import MotionConfig, PipelineConfig, StabilizeConfig, load_config
from motiontrack.motion import create_detector
from motiontrack.motion.stabilize import Stabilizer, corner_shift, estimate_transform
from motiontrack.motion.stage import MotionStage, sudden_change
from motiontrack.pipeline import Pipeline
from motiontrack.synth.camera import MovingCamera, shake_offsets, shift_annotations
from motiontrack.synth.scenes import make_scene
from motiontrack.synth.sequence import Lighting
from motiontrack.types import Annotations, Frame


@pytest.fixture(scope="module")
def textured() -> np.ndarray:
    """A 288x384 BGR frame of the synthetic street (textured ground, corners to follow)."""
    return make_scene("walker", 0, width=384, height=288, n_frames=2, noise=0.0).frame(0)


def _moved(image: np.ndarray, m: np.ndarray) -> np.ndarray:
    """``image`` as a camera moved by ``m`` (anchor → frame pixels) sees it."""
    h, w = image.shape[:2]
    return cv2.warpAffine(image, m, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


def _similarity(dx: float, dy: float, degrees: float = 0.0, centre=(192, 144)) -> np.ndarray:
    m = cv2.getRotationMatrix2D(centre, degrees, 1.0)
    m[:, 2] += (dx, dy)
    return m


@pytest.mark.parametrize("dx, dy, degrees", [
    (3.0, -2.0, 0.0),     # a whole-pixel shake
    (-4.0, 4.0, 0.0),     # the far corner of a +-4 px shake
    (2.5, 1.25, 0.0),     # sub-pixel
    (1.0, -3.0, 0.8),     # with a small roll
])
def test_estimated_transform_is_the_applied_warp(textured, dx, dy, degrees):
    stab = Stabilizer(StabilizeConfig())
    assert stab.apply(textured).transform is None          # the anchor
    m = _similarity(dx, dy, degrees)
    out = stab.apply(_moved(textured, m))
    assert out.transform is not None and not out.reanchored
    # the corners of the image land within a fifth of a pixel of where the warp put them
    assert corner_shift(np.vstack([out.transform - m + np.eye(2, 3)]), 384, 288) < 0.2


def test_warped_frame_lines_up_with_the_anchor(textured):
    stab = Stabilizer(StabilizeConfig())
    stab.apply(textured)
    out = stab.apply(_moved(textured, _similarity(4.0, -3.0)))
    inner = (slice(10, -10), slice(10, -10))
    diff = cv2.absdiff(out.image, textured)[inner].astype(float)
    before = cv2.absdiff(_moved(textured, _similarity(4.0, -3.0)), textured)[inner].astype(float)
    assert diff.mean() < 2.0 < before.mean()


def test_fixed_camera_frames_are_passed_on_unwarped(textured):
    stab = Stabilizer(StabilizeConfig(min_motion=0.5))
    stab.apply(textured)
    still = stab.apply(textured.copy())
    assert still.transform is None and still.image is not None
    assert np.array_equal(still.image, textured)
    # a 0.3 px drift is below min_motion: not warped either
    assert stab.apply(_moved(textured, _similarity(0.3, 0.0))).transform is None


def test_a_large_move_takes_the_frame_as_the_new_reference(textured):
    stab = Stabilizer(StabilizeConfig(reanchor=0.05))     # 0.05 * 288 = 14.4 px
    stab.apply(textured)
    out = stab.apply(_moved(textured, _similarity(20.0, 0.0)))
    assert out.reanchored and out.transform is None
    assert out.previous is not None and abs(out.previous[0, 2] - 20.0) < 0.3
    assert stab.anchors == 2


def test_unwarp_returns_the_mask_to_the_frame_and_blanks_what_the_anchor_missed():
    stab = Stabilizer(StabilizeConfig())
    mask = np.zeros((60, 80), np.uint8)
    mask[20:30, 30:40] = 255                               # anchor coordinates
    from motiontrack.motion.stabilize import StabilizedFrame
    frame = StabilizedFrame(mask, transform=np.array([[1.0, 0, 5], [0, 1.0, -3]]))
    out = stab.unwarp(mask, frame)
    # anchor pixel (x, y) is frame pixel (x + 5, y - 3)
    ys, xs = np.nonzero(out)
    assert (ys.min(), ys.max(), xs.min(), xs.max()) == (17, 26, 35, 44)
    full = stab.unwarp(np.full((60, 80), 255, np.uint8), frame)
    assert not full[:, :6].any() and not full[-4:, :].any()   # entered the view: never motion


def test_estimate_transform_needs_enough_agreeing_points():
    pts = np.random.default_rng(0).uniform(0, 100, (30, 2)).astype(np.float32)
    assert estimate_transform(pts[:5], pts[:5] + 1, min_inliers=12) is None
    m = estimate_transform(pts, pts + (2.0, -1.0), min_inliers=12)
    assert m is not None and np.allclose(m, [[1, 0, 2], [0, 1, -1]], atol=1e-3)


def _false_motion(frames, masks_of, cfg: PipelineConfig, size) -> float:
    """Mean fraction of each frame (after the first 10) that is motion more than 7 px from
    every object of the exact mask."""
    pipe = Pipeline(cfg, size, fps=25.0)
    out = []
    for f in frames:
        r = pipe.process(f)
        near = cv2.dilate((masks_of(f.index) > 0).astype(np.uint8), np.ones((15, 15), np.uint8))
        if f.index >= 10:
            out.append(float(((r.mask > 0) & (near == 0)).mean()))
    return float(np.mean(out))


def test_shaking_camera_mask_stays_empty_away_from_objects_with_compensation():
    cam = MovingCamera.shaking("walker", 4, seed=1, n_frames=40)
    frames = cam.frames()
    on = _false_motion(frames, cam.foreground_mask, PipelineConfig(), (cam.width, cam.height))
    off = _false_motion(frames, cam.foreground_mask,
                        load_config(None, ["stabilize.enabled=false"]), (cam.width, cam.height))
    assert on < 0.001          # the background model sees a steady scene
    assert off > 0.01          # without compensation every edge of the street lights up


def test_slow_pan_follows_the_reference_and_keeps_the_mask_clean():
    cam = MovingCamera.panning("walker", 1.0, seed=1, n_frames=60)
    pipe = Pipeline(PipelineConfig(), (cam.width, cam.height), fps=25.0)
    false = []
    for f in cam.frames():
        r = pipe.process(f)
        near = cv2.dilate((cam.foreground_mask(f.index) > 0).astype(np.uint8),
                          np.ones((15, 15), np.uint8))
        false.append(float(((r.mask > 0) & (near == 0)).mean()))
    # 60 px of pan: the reference moved on (every 0.1 * 240 = 24 px) and the model with it
    assert pipe.stage.stabilizer.anchors >= 3
    assert max(false[5:]) < 0.01


def test_tracks_on_a_shaking_camera_are_in_the_frame_the_user_sees():
    cam = MovingCamera.shaking("walker", 4, seed=2, n_frames=70)
    gt = cam.ground_truth()
    pipe = Pipeline(PipelineConfig(), (cam.width, cam.height), fps=25.0)
    ious = []
    for f in cam.frames():
        r = pipe.process(f)
        g = gt.boxes[gt.frames == f.index + 1]
        if len(r.tracks) == 1 and len(g) == 1:
            a, b = r.tracks[0].box.as_array(), g[0]
            x1, y1 = max(a[0], b[0]), max(a[1], b[1])
            x2, y2 = min(a[0] + a[2], b[0] + b[2]), min(a[1] + a[3], b[1] + b[3])
            inter = max(0, x2 - x1) * max(0, y2 - y1)
            ious.append(inter / (a[2] * a[3] + b[2] * b[3] - inter))
    assert len(ious) > 20 and np.median(ious) > 0.6


def _light_switch(factor: float, n: int = 80, at: int = 55):
    scene = make_scene("walker", 1, width=320, height=240, n_frames=n)
    return dataclasses.replace(scene, lighting=Lighting(n + 1, n + 2, 1.0, at, factor)), at


@pytest.mark.parametrize("factor", [1.25, 0.75])
def test_light_switched_on_or_off_starts_no_track_and_keeps_the_walker(factor):
    scene, at = _light_switch(factor)
    pipe = Pipeline(PipelineConfig(), (scene.width, scene.height), fps=25.0)
    ids, seen_after = set(), 0
    for i in range(scene.n_frames):
        r = pipe.process(Frame(index=i, image=scene.frame(i), timestamp=i / 25.0))
        ids |= {t.id for t in r.tracks}
        seen_after += i > at + 2 and len(r.tracks) == 1
    assert pipe.stage.relearned == 1
    assert ids == {1}                                  # the walker's track, and no other
    assert seen_after >= scene.n_frames - at - 5       # tracked on after the change


def test_sudden_change_thresholds_and_off_switches():
    cfg = MotionConfig()
    assert sudden_change(0.6, 0.0, cfg) and sudden_change(0.0, 25.0, cfg)
    assert not sudden_change(0.3, 5.0, cfg)
    off = MotionConfig(relearn_fraction=0.0, relearn_brightness=0.0)
    assert not sudden_change(1.0, 255.0, off)


@pytest.mark.parametrize("method", ["knn", "mog2", "frame_diff", "median", "farneback", "cnt"])
def test_relearn_starts_every_detector_from_the_given_background(method, textured):
    det = create_detector(MotionConfig(method=method))
    dark = (textured // 2).astype(np.uint8)
    for _ in range(5):
        det.apply(dark)
    det.relearn(textured)
    # the background it was given is no motion for the new model
    assert (det.apply(textured) > 0).mean() < 0.02


def test_motion_stage_relearn_is_the_detector_hook(textured):
    calls = []
    det = create_detector(MotionConfig())
    det.relearn = lambda image=None: calls.append(image)
    stage = MotionStage(det, MotionConfig(), StabilizeConfig())
    stage.relearn(textured)
    assert len(calls) == 1 and calls[0] is textured


def test_shift_annotations_moves_boxes_with_the_window():
    gt = Annotations.from_columns([1, 2, 2], [1, 1, 2], [[10, 10, 5, 5], [10, 10, 5, 5],
                                                         [200, 10, 5, 5]])
    offsets = np.array([[0, 0], [3, -2]])
    out = shift_annotations(gt, offsets, 100, 100, origin=(4, 4))
    assert out.boxes.tolist() == [[6, 6, 5, 5], [3, 8, 5, 5]]   # the box at x=200 left the view
    assert shake_offsets(50, 4, seed=3).min() >= -4 and shake_offsets(50, 4, seed=3).max() <= 4


def test_stabilizer_reports_the_camera_step_between_frames_only_while_it_moves(textured):
    stab = Stabilizer(StabilizeConfig())
    stab.apply(textured)
    assert stab.apply(textured.copy()).step is None            # fixed: no step
    first = stab.apply(_moved(textured, _similarity(3.0, 0.0)))
    second = stab.apply(_moved(textured, _similarity(3.0, -2.0)))
    # previous frame → this one: 3 px right, then 2 px up
    assert np.allclose(first.step, [[1, 0, 3], [0, 1, 0]], atol=0.2)
    assert np.allclose(second.step, [[1, 0, 0], [0, 1, -2]], atol=0.2)


def test_tracker_carries_its_tracks_with_the_camera():
    from motiontrack.tracking.tracker import MultiObjectTracker
    from motiontrack.types import Box, Region

    def region(x):
        return Region(box=Box(x, 50.0, 20.0, 40.0), centroid=(x + 10, 70.0), area=800.0)

    moved, still = MultiObjectTracker(image_size=(320, 240)), MultiObjectTracker(image_size=(320, 240))
    for k in range(6):                   # a standing object, seen by a steady camera
        moved.update([region(100.0)])
        still.update([region(100.0)])
    # the camera pans 30 px left: the object is 30 px further right in the next frame
    moved.camera_moved(np.array([[1.0, 0, 30], [0, 1.0, 0]]))
    (a,) = moved.update([region(130.0)])
    (b,) = still.update([region(130.0)])
    assert a.box.x == pytest.approx(130.0, abs=0.5)            # no velocity learnt from the pan
    assert abs(moved.x[0, 4]) < 0.5 < abs(still.x[0, 4])
    assert a.history[-2][0] == pytest.approx(140.0, abs=0.5)   # its trail moved with the view


def test_a_fixed_camera_is_measured_every_fourth_frame_until_it_moves(textured):
    stab = Stabilizer(StabilizeConfig())
    measured = []
    real = stab._measure
    stab._measure = lambda gray: (measured.append(1), real(gray))[1]
    for _ in range(41):
        assert stab.apply(textured).transform is None
    # frame 1 is the anchor; frames 2-26 measured (25 near the anchor: fixed), then 1 in 4
    assert len(measured) == 25 + 15 // 4
    shaken = _moved(textured, _similarity(3.0, -3.0))
    waited = next(k for k in range(1, 6) if stab.apply(shaken).transform is not None)
    assert waited <= 4
    before = len(measured)
    for _ in range(4):                                         # moving: every frame measured
        assert stab.apply(shaken).transform is not None
    assert len(measured) == before + 4


def test_a_moving_camera_has_its_small_shifts_compensated_too(textured):
    stab = Stabilizer(StabilizeConfig(min_motion=1.0))
    stab.apply(textured)
    # a fixed camera's 0.5 px is left alone ...
    assert stab.apply(_moved(textured, _similarity(0.5, 0.0))).transform is None
    # ... but once the camera has moved 3 px, a 0.5 px shift is warped as well
    assert stab.apply(_moved(textured, _similarity(3.0, 0.0))).transform is not None
    small = stab.apply(_moved(textured, _similarity(0.5, 0.0)))
    assert small.transform is not None and small.step is not None
