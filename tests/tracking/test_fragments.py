"""One object, one track: the pieces of a tracked object's mask (a person who slows down and
breaks into head, torso and legs) start no track of their own, a track that formed on a piece
anyway ends inside the object's track, and a blob one track explains is not split."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiontrack.config import TrackerConfig
from motiontrack.tracking.merge import fragment_matrix, split_merged
from motiontrack.tracking.tracker import NEST_S, MultiObjectTracker

#: a person tracked at (100, 50), 40 x 100 px: expected box 52 x 130 around the centre (120, 100)
PERSON = np.array([[100.0, 50.0, 40.0, 100.0]])
REF = np.array([[40.0, 100.0]])


def test_pieces_of_a_tracked_object_are_found_in_its_expected_box():
    head, legs = [108.0, 50, 20, 22], [104.0, 95, 30, 55]
    far, whole = [300.0, 50, 40, 100], [100.0, 50, 40, 100]
    part, size = fragment_matrix(PERSON, np.array([True]), np.array([head, legs, far, whole]),
                                 REF)
    # expected box: 40 x 100 grown by 15 % a side, 52 x 130 around the prediction's centre;
    # the far box is outside it, the whole person no piece (as large as the track)
    assert part.tolist() == [[True, True, False, False]]
    np.testing.assert_allclose(size, [[52, 130]])
    # a tentative track has no pieces
    assert not fragment_matrix(PERSON, np.array([False]), np.array([head]), REF)[0].any()


def test_a_neighbours_own_box_is_a_piece_of_nobody_when_alone_is_asked():
    # a second track stands beside the first: its detection touches its own prediction
    pred = np.vstack([PERSON, [[140.0, 60, 30, 80]]])
    ref = np.vstack([REF, [[30.0, 80.0]]])
    neighbour = np.array([[138.0, 60, 12, 60]])
    assert not fragment_matrix(pred, np.array([True, True]), neighbour, ref)[0].any()
    # without alone, a piece of someone: it starts no track either way
    assert fragment_matrix(pred, np.array([True, True]), neighbour, ref, alone=False)[0].any()


def _tracker(**kw) -> MultiObjectTracker:
    return MultiObjectTracker(TrackerConfig(confirm_hits=3, **kw), image_size=(320, 240), fps=10.0)


def test_a_piece_beside_a_tracked_person_starts_no_track():
    trk = _tracker()
    for t in range(5):
        trk.update(np.array([[100.0 + t, 50, 40, 100]]))
    # the person's mask breaks: torso and a hand that reaches out of the box for 5 frames
    for t in range(5, 10):
        out = trk.update(np.array([[103.0 + t, 60, 40, 85], [98.0 + t, 120, 10, 12]]))
        assert [tr.id for tr in out] == [1]
    assert len(trk.meta) == 1
    off = _tracker(absorb_pieces=False)
    for t in range(5):
        off.update(np.array([[100.0 + t, 50, 40, 100]]))
    for t in range(5, 10):
        out = off.update(np.array([[103.0 + t, 60, 40, 85], [98.0 + t, 120, 10, 12]]))
    assert sorted(tr.id for tr in out) == [1, 2]       # the hand became a track


def test_a_track_inside_a_larger_one_for_half_a_second_ends_and_the_older_id_lives_on():
    trk = _tracker()
    torso, person = [110.0, 80, 20, 30], [100.0, 50, 40, 100]
    # frames 0-2: a torso (detected first: id 1) and the whole person around it (id 2), both
    # named at frame 2; nesting counts from the next frame, where both are named tracks
    named = []
    for t in range(10):
        out = trk.update(np.array([torso, person]))
        named.append(sorted(m.tid for m in trk.meta if m.tid))
    # nested for NEST_S = 0.5 s = 5 frames (3-7): the piece ends at frame 7, and the person's
    # track carries the older id, 1
    assert named[2:7] == [[1, 2]] * 5 and named[7] == [1]
    assert int(NEST_S * 10) == 5
    (tr,) = out
    assert tr.id == 1 and tr.box.h == pytest.approx(100, abs=1)


def test_a_blob_one_track_explains_is_not_split_between_pieces():
    # a person's track (centre in the blob, as large as it) and two small tracks on its torso
    # and legs: the blob is that person's, not three people merged
    pred = np.array([[100.0, 50, 40, 100], [108.0, 60, 20, 30], [106.0, 100, 24, 45]])
    det = np.array([[99.0, 49, 42, 102]])
    boxes, origin, owner = split_merged(pred, np.array([True, True, True]), det,
                                        ref=np.array([[40.0, 100], [20, 30], [24, 45]]))
    np.testing.assert_allclose(boxes, det)
    assert owner.tolist() == [-1]
    # without the person's track the two pieces do claim shares of it
    boxes, origin, owner = split_merged(pred[1:], np.array([True, True]), det)
    assert owner.tolist() == [0, 1]


@pytest.mark.data
@pytest.mark.slow
def test_on_the_sbi_office_people_are_not_shredded_into_tracks(data):
    """SBI HumanBody2: four people walk in and out, stand and talk. Without absorbing the
    pieces the tracker reports 27 tracks of at least a second, with it 21
    (benchmarks/still_people.py counts them with a scene)."""
    from motiontrack.config import load_config
    from motiontrack.pipeline import run

    counts = {}
    for group in (True, False):
        spans: dict[int, list[int]] = {}
        cfg = load_config(None, ["source.fps=25", f"tracker.absorb_pieces={str(group).lower()}"])
        with run(str(data("sbi", "HumanBody2") / "input" / "*.jpg"), cfg) as r:
            for res in r:
                for t in res.tracks:
                    spans.setdefault(t.id, [res.index, res.index])[1] = res.index
        counts[group] = sum(b - a + 1 >= 25 for a, b in spans.values())
    assert counts[True] <= 22 and counts[True] <= counts[False] - 5, counts
