"""``motion.keep_stopped``: a person who stops walking for several seconds keeps their track
(and id) through the stop when the dual background's static foreground is added to the mask;
without it the motion detector learns them into its background and the track is lost."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.stops import frames_by_track, stopping_person
from motiontrack.config import load_config
from motiontrack.synth.sequence import SyntheticScene

FPS = 25.0
WALK_TO = 80        # frame the person stops at
STAND = 100         # frames standing: 4 s
N_FRAMES = WALK_TO + STAND + 80


def _scene() -> SyntheticScene:
    # walks right at 3 px/frame from the left edge, stands 4 s mid-image, walks on out of view
    return stopping_person((640, 480), FPS, WALK_TO, STAND, N_FRAMES - WALK_TO - STAND,
                           x0=-30.0, y0=400.0, speed=3.0, height=110.0, t0=5.0)


def _frames_by_id(keep_stopped: bool) -> dict[int, list[int]]:
    # the KNN model alone (without its hold), so that what keeps the person is the dual background
    cfg = load_config(None, [f"motion.keep_stopped={str(keep_stopped).lower()}",
                             "motion.knn.hold=false"])
    return frames_by_track(cfg, _scene())


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
