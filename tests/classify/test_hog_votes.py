"""HOG people evidence in the track classifier (classes.hog): which tracks HOG looks at, the
votes its people cast, and people walking side by side in PETS 2009 told from a vehicle."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.classify import TrackClassifier
from motiontrack.config import ClassesConfig
from motiontrack.types import Box, Region, Track, TrackState

FPS = 10.0
IMAGE = np.zeros((480, 640, 3), np.uint8)


class _StubHOG:
    """Finds the people ``found(box)`` says in every box it is shown; logs ``(frame, x)``."""

    def __init__(self, found) -> None:
        self.found, self.looks, self.frame = found, [], 0

    def people_in_box(self, image, box, scale=1.0) -> list[Region]:
        self.looks.append((self.frame, float(box[0])))
        return [Region(box=b, centroid=b.center, area=b.area) for b in self.found(box)]


def _classifier(found, **cfg) -> tuple[TrackClassifier, _StubHOG]:
    clf = TrackClassifier(ClassesConfig(**cfg), FPS)
    clf.hog = stub = _StubHOG(found)
    return clf, stub


def _frames(clf: TrackClassifier, stub: _StubHOG, frames: int, boxes, step: float = 1.0,
            image=IMAGE, scale: float = 1.0) -> list[Track]:
    """Tracks ``1..len(boxes)``, each box ``(x, y, w, h)`` moving ``step`` px a frame; the last
    frame's snapshots."""
    for k in range(frames):
        stub.frame = k
        tracks = [Track(id=i + 1, box=Box(x + step * k, y, w, h), state=TrackState.CONFIRMED)
                  for i, (x, y, w, h) in enumerate(boxes)]
        out = clf.update(tracks, image=image, scale=scale)
    return out


def _person_in(box) -> list[Box]:
    x, y, w, h = box
    return [Box(x + w / 4, y, w / 2, h)]


def _two_in(box) -> list[Box]:
    x, y, w, h = box
    return [Box(x, y, w / 2, h), Box(x + w / 2, y, w / 2, h)]


def _beside(box) -> list[Box]:
    x, y, w, h = box
    return [Box(x + w, y, w / 2, h)]    # its centre is right of the box


@pytest.mark.parametrize("found, person, label", [
    (_person_in, 3 * 10, ("person", round(30 / 46, 3))),
    (_two_in, 3 * 2 * 10, ("person", round(60 / 76, 3))),   # a merged pair: 10 votes each
    (_beside, 0, ("vehicle", 1.0)),                         # centred outside the box
    (lambda box: [], 0, ("vehicle", 1.0)),                  # a miss is no evidence
])
def test_each_person_hog_finds_centred_in_the_box_casts_hog_vote_votes(found, person, label):
    clf, stub = _classifier(found, hog_vote=10, hog_every=5)
    # a square 60x60 box, 1 px a frame (0.17 heights a second): a vehicle vote every frame.
    # Frames 0-4: its speed is not known yet (half a second of window), so HOG waits;
    # frame 5: first look; then every 5 measured frames: frames 10 and 15
    (t,) = _frames(clf, stub, 16, [(100, 100, 60, 60)])
    assert [f for f, _ in stub.looks] == [5, 10, 15]
    assert clf._tracks[1].votes.tolist() == [person, 16, 0]
    assert (t.label, t.label_score) == label


def test_hog_never_looks_at_a_fast_track_an_upright_person_or_a_tiny_box():
    # 60x60 moving 40 px a frame = 400 px/s = 6.7 heights a second, faster than a person
    clf, stub = _classifier(_person_in)
    _frames(clf, stub, 12, [(0, 0, 60, 60)], step=40.0)
    assert stub.looks == []
    # at processing scale 0.5: 30x90 at aspect 3 and 0.1 heights a second, a person by its
    # own votes every frame; 24x30, 15 px tall there, under the 16 px HOG can see; and the
    # slow square, looked at in frames 5 and 10
    clf, stub = _classifier(_person_in)
    _frames(clf, stub, 12, [(0, 0, 30, 90), (200, 0, 60, 60), (400, 0, 24, 30)], scale=0.5)
    assert stub.looks == [(5, 205.0), (10, 210.0)]


def test_at_most_hog_per_frame_looks_a_frame_vehicle_like_tracks_first():
    clf, stub = _classifier(lambda box: [], hog_per_frame=2, hog_every=5)
    # tracks 1-3 square (vehicle votes), track 4 aspect 1.4 (other votes), all slow
    boxes = [(0, 0, 60, 60), (100, 0, 60, 60), (200, 0, 60, 60), (300, 0, 40, 56)]
    _frames(clf, stub, 12, boxes)
    by_frame: dict[int, list[int]] = {}
    for f, x in stub.looks:
        by_frame.setdefault(f, []).append(int(x - f) // 100 + 1)
    # frame 5: all four due, vehicles first by id; frame 6: the last vehicle, then the other;
    # frames 10 and 11: each again 5 measured frames after its look
    assert by_frame == {5: [1, 2], 6: [3, 4], 10: [1, 2], 11: [3, 4]}


def test_without_a_frame_or_with_hog_off_there_is_no_hog_evidence():
    clf, stub = _classifier(_person_in)
    _frames(clf, stub, 12, [(0, 0, 60, 60)], image=None)
    assert stub.looks == [] and clf.label(1) == ("vehicle", 1.0)
    assert TrackClassifier(ClassesConfig(hog="off"), FPS).hog is None


def _side_by_side(data, first: int, last: int):
    """PETS frames ``first..last`` (0-based) at processing scale 0.5 and the union of the
    ground-truth boxes of people 11 and 12, who walk side by side from frame 21 on."""
    import cv2

    from motiontrack.config import PreprocessConfig
    from motiontrack.io.mot import read_mot
    from motiontrack.preprocess import preprocess

    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")
    cap = cv2.VideoCapture(str(data("pets09-s2l1", "video.avi")))
    cap.set(cv2.CAP_PROP_POS_FRAMES, first)
    out = []
    for f in range(first, last + 1):
        ok, image = cap.read()
        assert ok
        g = gt.at(f + 1)
        b = g.boxes[np.isin(g.ids, [11, 12])]
        assert len(b) == 2
        x1, y1 = b[:, :2].min(axis=0)
        x2, y2 = (b[:, :2] + b[:, 2:]).max(axis=0)
        out.append((preprocess(image, PreprocessConfig(scale=0.5)),
                    Box(x1, y1, x2 - x1, y2 - y1)))
    cap.release()
    return out


@pytest.mark.data
@pytest.mark.parametrize("hog, label", [("daimler", "person"), ("default", "person"),
                                        ("off", "other")])
def test_two_pets_people_walking_side_by_side_as_one_blob_are_a_person(data, hog, label):
    # one track whose box holds both people (aspect 1.3-1.9: "other" votes, neither upright
    # enough for a person nor wide enough for a vehicle), frames 21-120; HOG finds the two
    # people in it (benchmarks/classes.py: "PETS pairs")
    clf = TrackClassifier(ClassesConfig(hog=hog), FPS)
    for small, box in _side_by_side(data, 21, 120):
        (t,) = clf.update([Track(id=1, box=box, state=TrackState.CONFIRMED)],
                          image=small, scale=0.5)
    assert t.label == label
    if hog != "off":
        assert clf.hog_found >= clf.hog_looks / 2 > 0


@pytest.mark.data
def test_the_pipeline_gives_hog_the_frame_at_processing_scale(data):
    from motiontrack.config import load_config
    from motiontrack.pipeline import run

    # no box is upright enough for a person's vote (person_aspect 20): HOG looks at the
    # PETS walkers, and finds people centred in their boxes only if the pipeline hands it the
    # frame and the scale its boxes are in
    cfg = load_config(None, ["source.max_frames=40", "classes.person_aspect=20"])
    with run(str(data("pets09-s2l1", "video.avi")), cfg) as frames:
        labels = {t.id: t.label for res in frames for t in res.tracks}
        clf = frames.pipeline.classes
    assert clf.hog_looks >= 10
    assert clf.hog_found >= clf.hog_looks / 2
    assert "person" in labels.values()
