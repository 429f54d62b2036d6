"""``motion.knn.hold`` (the default): a tracked person who stops stays in the KNN mask and keeps
one track through the stop; the place they stood clears once they walk on; a pixel held too long
is learnt (``accept_s``); the hold leaves the mask of what moves as KNN makes it."""

from __future__ import annotations

import numpy as np

from helpers.stops import frames_by_track, stopping_person
from motiontrack.config import load_config
from motiontrack.motion.hold import Hold
from motiontrack.pipeline import Pipeline
from motiontrack.synth.sequence import SyntheticScene
from motiontrack.types import Frame

FPS = 25.0
WALK_TO = 80        # frame the person stops at
STAND = 250         # frames standing: 10 s, five times what KNN alone keeps them
N_FRAMES = WALK_TO + STAND + 80


def _scene() -> SyntheticScene:
    # walks right at 3 px/frame from the left edge, stands 10 s mid-image, walks on out of view
    return stopping_person((640, 480), FPS, WALK_TO, STAND, N_FRAMES - WALK_TO - STAND,
                           x0=-30.0, y0=400.0, speed=3.0, height=110.0, t0=5.0)


def test_person_who_stops_keeps_one_track_through_the_stop_by_default():
    seen = frames_by_track(load_config(None, []), _scene())
    assert list(seen) == [1]
    frames = np.array(seen[1])
    stop = (frames >= WALK_TO) & (frames < WALK_TO + STAND)
    assert stop.sum() == STAND                        # reported in every frame of the stop
    assert frames[-1] > WALK_TO + STAND + 40          # and after, as they walk on


def test_person_who_stops_is_lost_without_the_hold():
    seen = frames_by_track(load_config(None, ["motion.knn.hold=false"]), _scene())
    first = min(seen, key=lambda k: seen[k][0])
    assert seen[first][-1] < WALK_TO + STAND // 2     # learnt into KNN's background


def _masks(scene: SyntheticScene, overrides: list[str]) -> list[np.ndarray]:
    pipe = Pipeline(load_config(None, overrides), (scene.width, scene.height), fps=scene.fps)
    return [pipe.process(Frame(index=i, image=scene.frame(i), timestamp=i / scene.fps)).mask
            for i in range(scene.n_frames)]


def test_stopped_person_stays_in_the_mask_and_their_place_clears_when_they_leave():
    scene = _scene()
    masks = _masks(scene, [])
    gt = scene.ground_truth()
    stand_box = gt.boxes[gt.frames == WALK_TO + STAND - 1][0]
    scale = masks[0].shape[1] / scene.width
    x, y, w, h = (np.asarray(stand_box) * scale).round().astype(int)

    def covered(k: int) -> float:
        return float((masks[k][y:y + h, x:x + w] > 0).mean())

    # the last frame of the stop: the person fills most of their box
    assert covered(WALK_TO + STAND - 1) > 0.5
    # 2 s after they walked off (at 3 px a frame they are two widths away): no ghost there
    assert covered(WALK_TO + STAND + 50) < 0.05


def _car_frames(n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(0)
    out = []
    for _ in range(n):
        img = np.full((60, 80, 3), 120, np.uint8)
        img += rng.integers(0, 3, img.shape, dtype=np.uint8)
        img[20:40, 30:60] = (40, 40, 170)    # an object that never moves
        out.append(img)
    return out


def test_a_held_pixel_is_learnt_after_accept_s():
    # KNN has learnt the object (its raw output is background, 0); the boxes cover it; the
    # hold's background was started without it. 10 fps and accept_s 2: 20 frames held.
    hold = Hold(threshold=30, accept_s=2.0, fps=10.0)
    empty = np.full((60, 80, 3), 120, np.uint8)
    raw = np.zeros((60, 80), np.uint8)
    box = np.zeros((60, 80), bool)
    box[18:42, 28:62] = True
    hold.apply(empty, raw, None)
    held = [int((hold.apply(f, raw, box)[20:40, 30:60] > 0).sum()) for f in _car_frames(30)]
    assert held[0] == 20 * 30                 # the whole object is held at once
    assert held[18] == 20 * 30                # through its 19th frame
    assert held[20] == 0 and held[-1] == 0    # learnt at the 20th: background from there on


def test_without_boxes_the_mask_is_knns_own():
    hold = Hold()
    frames = _car_frames(12)
    raw = np.zeros((60, 80), np.uint8)
    raw[5:10, 5:10] = 255      # foreground
    raw[50:55, 5:10] = 127     # shadow: not foreground
    for f in frames:
        out = hold.apply(f, raw, None)
    expected = np.zeros_like(raw)
    expected[5:10, 5:10] = 255
    np.testing.assert_array_equal(out, expected)
