"""Cold starts: KNN's first frames, and ghosts where an object that stood in the first frames left.

Synthetic scenes with an exact answer: a textured ground, and a person-sized textured block that
stands still in the first frames (so every background model learns it as background) and then
walks away; later a second block walks over the place it left.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiontrack.config import load_config
from motiontrack.motion import DETECTORS
from motiontrack.motion.ghosts import GhostFilter, outline_ratio
from motiontrack.pipeline import Pipeline
from motiontrack.types import Frame

W, H = 320, 240
START = (60, 80)          # where the first block stands (x, y of its top-left corner)
BW, BH = 24, 60           # block size


def _ground(seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    g = rng.integers(60, 200, (H // 8, W // 8, 3), dtype=np.uint8)
    return cv2.resize(g, (W, H), interpolation=cv2.INTER_CUBIC)   # smooth texture with edges


def _block(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    b = rng.integers(0, 60, (BH // 6, BW // 6, 3), dtype=np.uint8)   # dark clothing, some texture
    return cv2.resize(b, (BW, BH), interpolation=cv2.INTER_NEAREST)


def _scene(n: int = 100, stand: int = 30) -> tuple[list[np.ndarray], list[tuple[int, int] | None]]:
    """Frames, and the second block's top-left corner in each (None when off-screen).

    Block A stands at START for ``stand`` frames, then walks right at 4 px/frame. Block B enters
    from the left at frame 70 along the same row and crosses A's old place at frames 80-97."""
    ground, a, b = _ground(), _block(2), _block(3)
    frames, b_at = [], []
    for k in range(n):
        img = ground.copy()
        ax = START[0] + max(0, k - stand) * 4
        if ax + BW < W:
            img[START[1]:START[1] + BH, ax:ax + BW] = a
        bx = -BW + (k - 70) * 4 if k >= 70 else None
        if bx is not None and bx >= 0:
            img[START[1]:START[1] + BH, bx:bx + BW] = b
            b_at.append((bx, START[1]))
        else:
            b_at.append(None)
        frames.append(img)
    return frames, b_at


def _run(overrides: list[str]):
    frames, b_at = _scene()
    cfg = load_config(None, ["preprocess.scale=1", "regions.min_area=200", *overrides])
    pipe = Pipeline(cfg, (W, H), None, 25.0)
    out = list(pipe.results(Frame(index=k, timestamp=k / 25, image=f) for k, f in enumerate(frames)))
    return out, b_at


def _covers(box, x: float, y: float, w: float, h: float) -> bool:
    """The region's box overlaps the rectangle by more than half of the rectangle."""
    bx, by, bw, bh = box.as_array()
    ix = max(0.0, min(bx + bw, x + w) - max(bx, x))
    iy = max(0.0, min(by + bh, y + h) - max(by, y))
    return ix * iy > 0.5 * w * h


def _ghost_frames(results) -> list[int]:
    """Frames with a region over block A's starting place once A has left it (k >= 40) and
    before B comes near it (k < 78)."""
    return [r.index for r in results if 40 <= r.index < 78
            and any(_covers(reg.box, *START, BW, BH) for reg in r.regions)]


def test_outline_ratio_tells_an_object_from_the_place_it_left():
    flat = np.full((40, 40), 100, np.uint8)
    square = flat.copy()
    square[10:30, 10:30] = 30
    mask = np.zeros((40, 40), np.uint8)
    mask[10:30, 10:30] = 255
    assert outline_ratio(square, flat, mask) > 3     # the object is in the frame: edges there
    assert outline_ratio(flat, square, mask) < 0.3   # only the background has them: a ghost
    assert outline_ratio(flat, flat, mask) == pytest.approx(1.0)   # no evidence either way


def test_knn_reports_no_foreground_on_its_first_frame_and_motion_from_the_second():
    # without priming OpenCV's KNN calls every pixel foreground for the first four frames
    frames, _ = _scene(n=16, stand=0)
    det = DETECTORS.create("knn")
    first, second = det.apply(frames[0]), det.apply(frames[1])
    assert not first.any()
    assert (second > 0).mean() < 0.05                 # the ground is background at once ...
    assert (second[START[1]:START[1] + BH, START[0] + 4:START[0] + BW + 4] > 0).mean() > 0.15  # block
    unprimed = cv2.createBackgroundSubtractorKNN(500, 300.0, True)
    assert (unprimed.apply(frames[0]) > 0).mean() > 0.9  # (what priming is for)


def test_the_place_a_standing_object_left_is_not_a_region():
    # frame by frame: 0-29 A stands (learnt as background); from 30 A walks off to the right and
    # KNN holds the uncovered ground as foreground (a ghost) until about frame 55; with the
    # ghost filter (the default) that place is never a region, while A itself is found in every
    # frame as it walks away
    off, _ = _run(["motion.ghost_ratio=0"])
    on, _ = _run([])
    assert len(_ghost_frames(off)) >= 10            # the model really holds a ghost
    assert _ghost_frames(on) == []
    for r in on:
        ax = START[0] + max(0, r.index - 30) * 4
        if 36 <= r.index and ax + BW < W:
            assert any(_covers(reg.box, ax, START[1], BW, BH) for reg in r.regions), r.index


def test_an_object_walking_over_a_remembered_ghost_is_still_found():
    # B walks along A's row from frame 70 and crosses A's old place (x 60-84) at frames 80-97;
    # the ghost's pixels are hidden only where the frame still shows the uncovered ground.
    # A ghost that lasts until B arrives: A stands for 60 frames
    frames, b_at = _scene(n=130, stand=60)
    b_at = [None if k < 70 else (-BW + (k - 70) * 4, START[1]) for k in range(130)]
    cfg = load_config(None, ["preprocess.scale=1", "regions.min_area=200"])
    pipe = Pipeline(cfg, (W, H), None, 25.0)
    on = []
    for r in pipe.results(Frame(index=k, timestamp=k / 25, image=f) for k, f in enumerate(frames)):
        on.append(r)
        # the filter looks at its remembered pixels only inside a window: none lies outside it
        g = pipe.ghosts
        outside = g._ghost >= 0
        if g._win is not None:
            y1, y2, x1, x2 = g._win
            outside[y1:y2, x1:x2] = False
        assert not outside.any(), r.index
    assert pipe.ghosts.dropped > 0
    for r in on:
        at = b_at[r.index]
        if at is not None and 76 <= r.index <= 100:
            assert any(_covers(reg.box, at[0], at[1], BW, BH) for reg in r.regions), r.index


def test_ghost_filter_keeps_regions_until_it_has_a_background():
    f = GhostFilter(0.7)
    mask = np.zeros((20, 20), np.uint8)
    mask[5:15, 5:15] = 255
    from motiontrack.types import Box, Region

    reg = [Region(box=Box(5, 5, 10, 10), centroid=(10, 10), area=100)]
    out_mask, out = f.regions(np.zeros((20, 20), np.uint8), mask, lambda m: reg, 1.0)
    assert out == reg and out_mask is mask and f.dropped == 0


def _ghost_and_person(person: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First frame, later frame and detector mask, worked by hand: plain ground (gray 100); an
    object (gray 30) stands at columns 10-19 in the first frame; later that place shows the
    ground again (a ghost: the detector still reports it) and a person of gray ``person`` stands
    at columns 20-29, where the first frame showed ground. Rows 10-29; the mask covers both."""
    first = np.full((40, 40), 100, np.uint8)
    first[10:30, 10:20] = 30
    later = np.full((40, 40), 100, np.uint8)
    later[10:30, 20:30] = person
    mask = np.zeros((40, 40), np.uint8)
    mask[10:30, 10:30] = 255
    return first, later, mask


@pytest.mark.parametrize("person", [30, 108])   # dark, and only 8 gray levels off the ground
def test_a_ghost_attached_to_a_person_dissolves_pixel_by_pixel_and_the_person_stays(person):
    first, later, mask = _ghost_and_person(person)
    f = GhostFilter(0.0)          # ratio 0: the region-level test never fires, only the pixel one
    f.regions(first, np.zeros_like(mask), lambda m: [], 1.0)   # the background: the first frame
    out = []
    for _ in range(18):
        m, _ = f.regions(later, mask, lambda m: [], 1.0)
        out.append(m)
    # a run every 3rd frame (frames 3, 6, ...): the first only keeps the frame for the
    # stillness test; from frame 6 each run takes two rings of the ghost's border pixels that
    # look like the ground around them (gray 100) and not like the background held there (30)
    assert (out[3] == mask).all()                                 # frame 5: nothing taken yet
    taken = mask.astype(bool) & (out[5] == 0)                     # frame 6: the first run
    two_rings = np.zeros_like(taken)                              # the ghost's free sides: left,
    two_rings[10:30, 10:12] = two_rings[10:12, 10:20] = two_rings[28:30, 10:20] = True  # top, bottom
    assert (taken == two_rings).all()
    assert not out[-1][:, :20].any()                              # frame 18: the ghost is gone
    assert (out[-1] == np.where(np.arange(40)[None, :] >= 20, mask, 0)).all()   # the person stays


def test_pixels_that_keep_changing_are_never_taken_as_ghost():
    # the same ghost, but the frame flickers by 10 gray levels: nothing is still, nothing is taken
    first, later, mask = _ghost_and_person(30)
    f = GhostFilter(0.0)
    f.regions(first, np.zeros_like(mask), lambda m: [], 1.0)
    for k in range(18):
        m, _ = f.regions(later + (10 if k % 2 else 0), mask, lambda m: [], 1.0)
        assert (m == mask).all()
