"""Scene analytics with more tracks than the engine first makes room for, and tracks that
leave and whose place a new track takes: nothing of one track's state leaks to another."""

from __future__ import annotations

import numpy as np

from motiontrack.analytics import Analytics, parse_scene

SCENE = parse_scene({
    "forget_s": 1.0,
    "line": [{"name": "gate", "points": [[0, 100], [1000, 100]]}],
    "zone": [{"name": "pen", "polygon": [[0, 0], [1000, 0], [1000, 50], [0, 50]]}],
})


def _boxes(feet) -> np.ndarray:
    """10x20 boxes standing on the (N, 2) foot points."""
    f = np.asarray(feet, float).reshape(-1, 2)
    return np.column_stack([f[:, 0] - 5, f[:, 1] - 20, np.full(len(f), 10.0), np.full(len(f), 20.0)])


def test_forty_tracks_crossing_at_once_count_forty():
    an = Analytics(SCENE, 1.0)
    ids = np.arange(1, 41)
    x = 20.0 * ids
    an.step(1, ids, _boxes(np.column_stack([x, np.full(40, 80.0)])))   # above the gate
    frame = an.step(2, ids, _boxes(np.column_stack([x, np.full(40, 120.0)])))   # below: in
    assert frame.line_counts == {"gate": (40, 0)}
    assert sorted(e.track for e in frame.events) == ids.tolist()


def test_a_new_track_in_a_forgotten_tracks_place_starts_afresh():
    an = Analytics(SCENE, 1.0)
    # frames 1-2: 20 tracks in the pen (20 rows taken), track 1 also above the gate
    ids = np.arange(1, 21)
    for f in (1, 2):
        an.step(f, ids, _boxes(np.column_stack([10.0 * ids, np.full(20, 30.0)])))
    assert an.occupancy_by_zone() == {"pen": 20}
    # frame 4: all unseen for 2 s > forget_s: 20 zone exits; 20 new tracks below the gate
    # take their places and are neither in the pen nor on a side of the gate they never had
    new = np.arange(101, 121)
    frame = an.step(4, new, _boxes(np.column_stack([10.0 * ids, np.full(20, 300.0)])))
    assert [e.type for e in frame.events] == ["zone_exit"] * 20
    assert an.occupancy_by_zone() == {"pen": 0}
    # frame 5: the new tracks walk up past the gate: out, 20 times; nobody enters the pen
    frame = an.step(5, new, _boxes(np.column_stack([10.0 * ids, np.full(20, 70.0)])))
    assert frame.line_counts == {"gate": (0, 20)}
    assert {e.type for e in frame.events} == {"line_cross"}
