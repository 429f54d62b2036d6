"""``motion.keep_stopped``: a person who stops walking for several seconds keeps their track
(and id) through the stop when the dual background's static foreground is added to the mask;
without it the motion detector learns them into its background and the track is lost."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.config import load_config
from motiontrack.pipeline import Pipeline
from motiontrack.synth.render import Person
from motiontrack.synth.sequence import SyntheticScene
from motiontrack.types import Frame

FPS = 25.0
WALK_TO = 80        # frame the person stops at
STAND = 100         # frames standing: 4 s
N_FRAMES = WALK_TO + STAND + 80


def _scene() -> SyntheticScene:
    # walks right at 3 px/frame from the left edge, stands 4 s mid-image, walks on out of view
    p = Person(id=1, x0=-30.0, y0=400.0, vx=3.0, vy=0.0, height=110.0, t0=5.0,
               turns=((float(WALK_TO), 0.0, 0.0), (float(WALK_TO + STAND), 3.0, 0.0)))
    return SyntheticScene("stop", 0, 640, 480, FPS, N_FRAMES, people=(p,))


def _frames_by_id(keep_stopped: bool) -> dict[int, list[int]]:
    scene = _scene()
    cfg = load_config(None, [f"motion.keep_stopped={str(keep_stopped).lower()}"])
    pipe = Pipeline(cfg, (scene.width, scene.height), fps=FPS)
    seen: dict[int, list[int]] = {}
    for i in range(scene.n_frames):
        r = pipe.process(Frame(index=i, image=scene.frame(i), timestamp=i / FPS))
        for t in r.tracks:
            seen.setdefault(t.id, []).append(i)
    return seen


def test_person_who_stops_keeps_one_track_with_keep_stopped():
    seen = _frames_by_id(True)
    assert list(seen) == [1]
    frames = np.array(seen[1])
    # reported through the whole stop, without a gap
    stop = (frames >= WALK_TO) & (frames < WALK_TO + STAND)
    assert stop.sum() == STAND
    assert frames[-1] > WALK_TO + STAND + 40


def test_person_who_stops_is_lost_and_renamed_without_keep_stopped():
    seen = _frames_by_id(False)
    first, *later = sorted(seen, key=lambda k: seen[k][0])
    # learnt into the background about 1.5 s into the stop; a new id once they walk on
    assert WALK_TO < seen[first][-1] < WALK_TO + STAND // 2
    assert later and seen[later[0]][0] > WALK_TO + STAND
