"""The sample-based background in the pipeline: the previous frame's confirmed tracks are not
learnt (the pipeline passes them as the detector's ``protect`` mask), so a person who stops
keeps one track through the stop; without the mask the model learns them within ``absorb_s``."""

from __future__ import annotations

import numpy as np

from helpers.stops import frames_by_track, stopping_person
from motiontrack.config import load_config
from motiontrack.motion.base import MotionDetector
from motiontrack.pipeline import Pipeline
from motiontrack.synth.sequence import SyntheticScene
from motiontrack.types import Frame

FPS = 10.0
WALK_TO = 30        # frame the person stops at
STAND = 40          # frames standing: 4 s, twice absorb_s
N_FRAMES = WALK_TO + STAND + 25


def _scene() -> SyntheticScene:
    return stopping_person((320, 240), FPS, WALK_TO, STAND, N_FRAMES - WALK_TO - STAND,
                           x0=-15.0, y0=200.0, speed=4.0, height=70.0, t0=2.0)


def _frames_by_id(protect: bool) -> dict[int, list[int]]:
    cfg = load_config(None, ["motion.method=vibe", "motion.vibe.absorb_s=2",
                             f"motion.vibe.protect={str(protect).lower()}",
                             "preprocess.scale=1.0"])
    return frames_by_track(cfg, _scene())


def test_person_who_stops_keeps_one_track_under_the_protect_mask():
    seen = _frames_by_id(True)
    assert list(seen) == [1]
    frames = np.array(seen[1])
    stop = (frames >= WALK_TO) & (frames < WALK_TO + STAND)
    assert stop.sum() == STAND
    assert frames[-1] > WALK_TO + STAND + 10


def test_person_who_stops_is_learnt_without_the_protect_mask():
    seen = _frames_by_id(False)
    frames = np.concatenate([np.array(v) for v in seen.values()])
    stop = (frames >= WALK_TO) & (frames < WALK_TO + STAND)
    # learnt after absorb_s (2 s) standing: no box for the rest of the stop
    assert stop.sum() <= STAND - 15


class _Recorder(MotionDetector):
    """A detector that records what the pipeline passes it."""

    wants_color = False
    protect = True
    relearns = True
    protect_speed = None

    def __init__(self) -> None:
        self.calls: list[tuple] = []

    def apply(self, image, protect=None, relearn=None):
        self.calls.append((protect, relearn))
        return np.zeros(image.shape[:2], np.uint8)

    def background(self):
        return None

    def held(self):
        return None


def test_static_objects_a_track_brought_are_not_learnt():
    from motiontrack.types import Box, StaticFrame, StaticObject

    cfg = load_config(None, ["motion.method=vibe", "preprocess.scale=0.5"])
    pipe = Pipeline(cfg, (320, 240), fps=FPS, static=True)
    assert pipe._protect_mask((120, 160)) is None       # no track, no static object
    bag = StaticFrame((StaticObject(Box(100.0, 60.0, 40.0, 20.0), 800.0, 12, 2.0),),
                      np.zeros((120, 160), np.uint8))
    pipe._static_prev = bag
    # no track lies on it: a change of the background (the place someone stood at the start)
    assert pipe._protect_mask((120, 160)) is None
    pipe.tracker.named_boxes = lambda: np.array([[95.0, 50.0, 50.0, 40.0]])   # a track on it
    mask = pipe._protect_mask((120, 160))
    assert mask[30:40, 50:70].all() and mask.sum() == 200   # the box at half scale
    # the track walks off: the object it left stays kept (it overlaps the one kept before)
    pipe.tracker.named_boxes = lambda: np.zeros((0, 4))
    assert pipe._protect_mask((120, 160)).sum() == 200


def test_the_ghost_filters_ghost_pixels_reach_the_detector_with_the_next_frame():
    scene = _scene()
    cfg = load_config(None, ["motion.method=vibe", "preprocess.scale=1.0"])
    pipe = Pipeline(cfg, (scene.width, scene.height), fps=FPS)
    rec = _Recorder()
    pipe.stage.detector = rec
    ghost = np.zeros((scene.height, scene.width), bool)
    ghost[10:20, 10:20] = True
    pipe.ghosts.ghost_pixels = lambda shape: ghost       # as if a ghost was just found
    for i in range(3):
        pipe.process(Frame(index=i, image=scene.frame(i), timestamp=i / FPS))
    assert rec.calls[0][1] is None
    assert rec.calls[1][1] is ghost and rec.calls[2][1] is ghost


def _frames(scene, cut_at=None):
    from motiontrack.types import Discontinuity

    return [Frame(index=i, image=scene.frame(i), timestamp=i / FPS,
                  discontinuity=Discontinuity("seek") if i == cut_at else None)
            for i in range(scene.n_frames)]


def test_two_thread_order_keeps_the_stopped_person_and_repeats_exactly():
    # Pipeline.results runs the detector a frame ahead in a worker: its protect mask comes from
    # the tracks two frames back, made before the worker starts, so every run is the same
    scene = _scene()
    cfg = load_config(None, ["motion.method=vibe", "motion.vibe.absorb_s=2", "preprocess.scale=1.0"])
    runs = []
    for _ in range(2):
        pipe = Pipeline(cfg, (scene.width, scene.height), fps=FPS)
        runs.append([(r.index, t.id, tuple(t.box.as_array())) for r in pipe.results(_frames(scene))
                     for t in r.tracks])
    assert runs[0] == runs[1]
    ids = {i for _, i, _ in runs[0]}
    stopped = {k for k, _, _ in runs[0] if WALK_TO <= k < WALK_TO + STAND}
    assert ids == {1} and len(stopped) == STAND


def test_two_thread_order_gives_no_feedback_across_a_discontinuity(monkeypatch):
    from motiontrack.motion.ghosts import GhostFilter

    scene = SyntheticScene("short", 0, 64, 48, FPS, 6)
    pipe = Pipeline(load_config(None, ["motion.method=vibe", "preprocess.scale=1.0"]),
                    (64, 48), fps=FPS)
    rec = _Recorder()
    pipe.stage.detector = rec
    pipe.reset_motion = lambda: None                     # keep the recorder across the cut
    ghost = np.zeros((48, 64), bool)
    monkeypatch.setattr(GhostFilter, "ghost_pixels", lambda self, shape: ghost)  # (also anew)
    list(pipe.results(_frames(scene, cut_at=3)))
    relearn = [r is ghost for _, r in rec.calls]
    # frame 0: nothing found yet; frame 1: fed a frame ahead, before frame 0's regions;
    # frames 3 and 4: the cut and the frame fed while the state was still the old one's
    assert relearn == [False, False, True, False, False, True]
