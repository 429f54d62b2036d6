"""The first background (``motion.bootstrap_s``): after its first seconds the model starts again
from the median of frames kept over them, so someone standing in the first frame leaves no ghost
when they walk off."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.config import load_config
from motiontrack.motion import create_detector
from motiontrack.motion.stage import BOOT_SAMPLES, MotionStage

FPS = 10.0


def _frames(n: int = 60) -> list[np.ndarray]:
    """A textured ground (noise std 2); a dark block 12 x 20 px stands in frames 0-9 and leaves
    (the person of the first frame)."""
    rng = np.random.default_rng(0)
    ground = np.clip(rng.normal(120, 10, (60, 80, 3)), 0, 255).astype(np.uint8)
    out = []
    for i in range(n):
        f = np.clip(ground.astype(np.int16) + rng.normal(0, 2, ground.shape), 0, 255)
        f = f.astype(np.uint8)
        if i < 10:
            f[20:40, 30:42] = (30, 40, 50)
        out.append(f)
    return out


def _stage(bootstrap_s: float) -> MotionStage:
    cfg = load_config(None, [f"motion.bootstrap_s={bootstrap_s}", "stabilize.enabled=false"])
    return MotionStage(create_detector(cfg.motion, FPS), cfg.motion, cfg.stabilize, FPS)


def test_the_model_starts_again_from_what_the_first_seconds_showed_most():
    frames = _frames()
    stage = _stage(3.0)
    outs = [stage.apply(f) for f in frames]
    # frame 29 (3 s at 10 fps): the median of the frames kept shows the ground where the block
    # stood in frames 0-9 (a third of them) and the model's background is that median
    seed = outs[29].seed
    ground = frames[-1][22:38, 32:40].astype(int)
    assert np.abs(seed[22:38, 32:40].astype(int) - ground).max() < 12
    bg = stage.detector.background()
    assert np.abs(bg[22:38, 32:40].astype(int) - ground).max() < 12
    assert all((o.raw[22:38, 32:40] == 0).all() for o in outs[29:])


def test_the_frame_it_starts_again_carries_the_first_background():
    stage = _stage(2.0)
    outs = [stage.apply(f) for f in _frames(25)]
    seeded = [k for k, o in enumerate(outs) if o.seed is not None]
    assert seeded == [19] and outs[19].seed.shape == (60, 80, 3)
    assert not outs[19].relearned                   # no sudden change: no regions ignored
    assert len(stage._boot or []) == 0 and BOOT_SAMPLES == 11


def test_off_by_default_and_again_after_a_discontinuity():
    assert load_config().motion.bootstrap_s == 0.0
    off = _stage(0.0)
    assert all(off.apply(f).seed is None for f in _frames(30))
    stage = _stage(1.0)
    first = [stage.apply(f).seed is not None for f in _frames(15)]
    stage.reset(create_detector(load_config().motion, FPS))
    again = [stage.apply(f).seed is not None for f in _frames(15)]
    assert first.index(True) == 9 and again.index(True) == 9


def test_the_hold_keeps_the_background_it_knew_under_the_foreground():
    from motiontrack.motion.hold import Hold

    hold = Hold(30, 180.0, FPS)
    ground = np.full((10, 10, 3), 100, np.uint8)
    hold.apply(ground, np.zeros((10, 10), np.uint8), None)
    person = ground.copy()
    person[2:8, 4:6] = 20
    keep = np.zeros((10, 10), bool)
    keep[2:8, 4:6] = True
    hold.reseed(person, keep)               # the first background shows a person who stopped
    assert (hold._bg[2:8, 4:6] == 100).all()    # where the frame showed them: the ground kept
    hold.reseed(person)
    assert (hold._bg[2:8, 4:6] == 20).all()
    with pytest.raises(AssertionError):
        assert (hold._bg == 100).all()
