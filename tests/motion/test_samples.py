"""The sample-based background (``motion.method = vibe``): selective update under a protect
mask, the bounded protection, spatial diffusion blocked under the mask, re-learning on request,
ghosts re-learnt at once and shadows left out."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.config import ConfigError, load_config
from motiontrack.motion import DETECTORS, create_detector
from motiontrack.motion.samples import SampleBackground

H, W = 60, 80
BOX = (slice(20, 40), slice(30, 50))


def _ground(seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.integers(90, 110, (H, W, 3), dtype=np.uint8)


def _with_object(ground: np.ndarray, value=(20, 200, 240)) -> np.ndarray:
    img = ground.copy()
    img[BOX] = value
    # edges of its own: a dark stripe across the object
    img[BOX[0], 38:41] = (0, 0, 0)
    return img


def _protect() -> np.ndarray:
    p = np.zeros((H, W), bool)
    p[18:42, 28:52] = True
    return p


def _fg_in_box(mask: np.ndarray) -> float:
    return float((mask[BOX] > 0).mean())


def _fg_inside(mask: np.ndarray) -> float:
    """Foreground share of the box without its border ring (which the model's first samples,
    taken from each pixel's neighbours, may give the ground's values)."""
    return float((mask[22:38, 32:48] > 0).mean())


def _run(model: SampleBackground, frames: int, image: np.ndarray, protect=None) -> np.ndarray:
    mask = None
    for _ in range(frames):
        mask = model.apply(image, protect)
    return mask


def test_registered_and_configured():
    cfg = load_config(None, ["motion.method=vibe", "motion.vibe.n_samples=6",
                             "motion.vibe.accept_s=3"])
    det = create_detector(cfg.motion, fps=10.0)
    assert isinstance(det, SampleBackground) and "vibe" in DETECTORS.names()
    assert det.n == 6 and det._frames_of(det.accept_s) == 30 and det.protect and det.relearns


def test_min_matches_above_samples_is_a_config_error():
    with pytest.raises(ConfigError, match="min_matches"):
        load_config(None, ["motion.method=vibe", "motion.vibe.n_samples=2",
                           "motion.vibe.min_matches=3"])


def test_object_is_foreground_on_learnt_ground():
    model = SampleBackground(seed=1)
    ground = _ground()
    _run(model, 5, ground)
    mask = model.apply(_with_object(ground))
    assert _fg_in_box(mask) > 0.95
    assert (mask > 0).sum() <= (mask[BOX] > 0).sum() + 5   # the ground stays background


def test_stopped_object_is_learnt_after_absorb_s_unless_protected():
    ground = _ground()
    free, kept = (SampleBackground(absorb_s=2.0, accept_s=0.0, seed=2) for _ in range(2))
    for m in (free, kept):
        m.set_rate(10.0)                     # absorb_s: 20 frames
        _run(m, 3, ground)
    obj = _with_object(ground)
    assert _fg_in_box(_run(free, 19, obj)) > 0.95
    assert _fg_in_box(_run(free, 8, obj)) < 0.05
    assert _fg_inside(_run(kept, 200, obj, _protect())) == 1.0


def test_diffusion_is_blocked_under_the_protect_mask():
    # a ghost (ground where the model holds an object), with the ghost test off: with
    # subsampling 1 every background pixel diffuses each frame, which eats the ghost from its
    # border, except under the protect mask
    ground, obj = _ground(), _with_object(_ground())
    eaten, kept = (SampleBackground(subsampling=1, ghost_ratio=0.0, absorb_s=0.0, accept_s=0.0,
                                    seed=3) for _ in range(2))
    for m in (eaten, kept):
        _run(m, 3, obj)
    assert _fg_inside(_run(kept, 60, ground, _protect())) == 1.0
    assert _fg_in_box(_run(eaten, 60, ground)) < 0.5


def test_protection_ends_after_accept_s():
    ground = _ground()
    model = SampleBackground(accept_s=2.0, seed=3)
    model.set_rate(10.0)                     # 20 frames
    _run(model, 3, ground)
    obj = _with_object(ground)
    assert _fg_in_box(_run(model, 19, obj, _protect())) == 1.0
    # learnt at every frame once due: background within a few frames
    assert _fg_in_box(_run(model, 8, obj, _protect())) < 0.05


def test_relearn_whole_frame_and_pixels():
    ground = _ground()
    model = SampleBackground(ghost_ratio=0.0, seed=4)   # (a ghost test would re-learn it too)
    _run(model, 3, ground)
    obj = _with_object(ground)
    assert _fg_in_box(model.apply(obj)) > 0.95
    assert not model.apply(obj, relearn=True).any()
    assert _fg_inside(model.apply(ground)) == 1.0    # the object is the background now
    where = np.zeros((H, W), bool)
    where[BOX] = True
    assert _fg_in_box(model.apply(ground, relearn=where)) == 0.0


def test_ghost_is_relearnt_at_once_even_under_protection():
    ground = _ground()
    obj = _with_object(ground)
    ghosts, kept = SampleBackground(seed=5), SampleBackground(ghost_ratio=0.0, seed=5)
    for m in (ghosts, kept):
        _run(m, 5, obj)                      # the object stood there when the model started
    # it leaves: plain ground where the model holds it (protected: a tracker still follows it)
    masks = [ghosts.apply(ground, _protect()) for _ in range(SampleBackground.GHOST_EVERY)]
    assert _fg_in_box(masks[-1]) == 0.0 and ghosts.ghosts_dropped == 1
    assert _fg_inside(_run(kept, 20, ground, _protect())) == 1.0


def test_shadow_is_not_foreground():
    ground = _ground()
    # (a uniform shade also lowers the ground's contrast: the ghost test is off here)
    model = SampleBackground(ghost_ratio=0.0, seed=6)
    _run(model, 3, ground)
    shade = ground.copy()
    shade[BOX] = (ground[BOX] * 0.6).astype(np.uint8)
    assert _fg_in_box(model.apply(shade)) < 0.05
    plain = SampleBackground(shadows=False, ghost_ratio=0.0, seed=6)
    _run(plain, 3, ground)
    assert _fg_in_box(plain.apply(shade)) > 0.95


def test_same_seed_same_masks():
    rng = np.random.default_rng(7)
    frames = [rng.integers(0, 255, (H, W, 3), dtype=np.uint8) for _ in range(6)]
    a, b = SampleBackground(seed=9), SampleBackground(seed=9)
    for f in frames:
        assert np.array_equal(a.apply(f), b.apply(f))


def test_gray_input():
    model = SampleBackground(seed=8)
    ground = _ground()[..., 0]
    _run(model, 3, ground)
    img = ground.copy()
    img[BOX] = 250
    assert _fg_in_box(model.apply(img)) > 0.95
    assert model.background().shape == (H, W)


def test_track_refuses_min_matches_above_n_samples_in_one_line(tmp_path, capsys):
    from motiontrack.cli import main

    code = main(["track", "synth:walker?n_frames=2", "-o", str(tmp_path / "t"), "--no-video",
                 "--set", "motion.method=vibe", "--set", "motion.vibe.min_matches=9"])
    err = capsys.readouterr().err
    assert code == 2
    assert "motion.vibe.min_matches must be at most motion.vibe.n_samples (8), got 9" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "t").exists()
