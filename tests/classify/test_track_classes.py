"""A class per track from evidence over its life (motiontrack.classify), and where it is
written: tracks.txt's class column, summary.json, the annotated video's labels."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motiontrack.classify import TrackClassifier, class_id, class_name
from motiontrack.config import ClassesConfig
from motiontrack.io.mot import format_mot_rows, parse_mot, read_mot
from motiontrack.render.annotate import track_caption
from motiontrack.types import Box, Track, TrackState

FPS = 10.0


def _track(tid: int, x: float, y: float, w: float, h: float, missed: int = 0) -> Track:
    return Track(id=tid, box=Box(x, y, w, h), state=TrackState.CONFIRMED,
                 time_since_update=missed)


def _walk(clf: TrackClassifier, frames: int, w: float, h: float, step: float,
          tid: int = 1, start: int = 0) -> Track:
    """Track ``tid``, ``w`` x ``h`` px, moving ``step`` px a frame; its last snapshot."""
    for k in range(start, start + frames):
        (out,) = clf.update([_track(tid, 10 + step * k, 50, w, h)])
    return out


def test_a_track_is_classified_from_the_frame_it_is_confirmed_in() -> None:
    """The tentative frames of a track vote when it is confirmed (the tracker keeps them): with
    confirm_hits = min_frames = 5, its first reported frame has the five votes it needs, so its
    first events carry its class, not ``other``."""
    clf = TrackClassifier(ClassesConfig(min_frames=5), FPS)
    for f in range(4):                 # tentative: the tracker reports nothing, HOG sees nothing
        clf.update([])
    earlier = [(f, _track(1, 10 + 3 * f, 50, 30, 90)) for f in range(4)]
    clf.confirm(earlier, 4)
    (t,) = clf.update([_track(1, 22, 50, 30, 90)])
    assert (t.label, t.label_score) == ("person", 1.0)
    # without them, four frames short of evidence
    young = TrackClassifier(ClassesConfig(min_frames=5), FPS)
    for f in range(4):
        young.update([])
    assert young.update([_track(1, 22, 50, 30, 90)])[0].label == "other"


def test_the_tentative_frames_measure_the_pace_in_their_own_frames() -> None:
    """A box 10 px tall moving 20 px a frame (20 heights a second at 10 fps), of a shape that
    is neither class's, tentative for ten frames: its pace is known once half a second has
    passed (frame 5), so frames 0-4 vote other and frames 5-10 vehicle, counted in the frames
    they were seen in (with the wrong frame numbers no pace would ever be known)."""
    clf = TrackClassifier(ClassesConfig(min_frames=3, person_aspect=2.0, vehicle_aspect=0.1), FPS)
    for f in range(10):
        clf.update([])
    clf.confirm([(f, _track(1, 20 * f, 50, 8, 10)) for f in range(10)], 10)
    (t,) = clf.update([_track(1, 200, 50, 8, 10)])
    assert (t.label, t.label_score) == ("vehicle", round(6 / 11, 3))


def test_an_upright_walker_is_a_person_after_min_frames() -> None:
    clf = TrackClassifier(ClassesConfig(min_frames=5), FPS)
    # 4 frames of evidence: not enough yet
    assert (_walk(clf, 4, 30, 90, 3).label, clf.label(1)[1]) == ("other", 0.0)
    # 90 px tall, 3 px a frame at 10 fps = 30 px/s = 0.33 heights a second, aspect 3
    t = _walk(clf, 1, 30, 90, 3, start=4)
    assert (t.label, t.label_score) == ("person", 1.0)


def test_a_wide_box_is_a_vehicle_and_a_middle_aspect_is_other() -> None:
    clf = TrackClassifier(ClassesConfig(), FPS)
    assert _walk(clf, 8, 80, 40, 2).label == "vehicle"           # aspect 0.5 <= 1.2
    assert _walk(clf, 8, 40, 56, 2, tid=2).label == "other"       # aspect 1.4: neither


def test_an_upright_box_faster_than_a_person_is_a_vehicle() -> None:
    clf = TrackClassifier(ClassesConfig(), FPS)
    # aspect 3 but 40 px a frame = 400 px/s = 4.4 heights a second > person_max_speed 2.5
    # (the speed window needs half a second: from frame 6 on every vote is "vehicle")
    t = _walk(clf, 20, 30, 90, 40)
    assert t.label == "vehicle" and t.label_score == pytest.approx(15 / 20)


def test_a_person_merged_for_a_few_frames_keeps_its_class() -> None:
    clf = TrackClassifier(ClassesConfig(), FPS)
    _walk(clf, 10, 30, 90, 3)
    t = _walk(clf, 3, 90, 90, 3, start=10)   # merged with a neighbour: a square blob
    assert (t.label, t.label_score) == ("person", round(10 / 13, 3))


def test_frames_without_a_measurement_cast_no_vote_and_reset_forgets() -> None:
    clf = TrackClassifier(ClassesConfig(min_frames=1), FPS)
    (t,) = clf.update([_track(1, 0, 0, 30, 90, missed=1)])
    assert (t.label, t.label_score) == ("other", 0.0)
    _walk(clf, 2, 30, 90, 1)
    assert clf.label(1) == ("person", 1.0)
    clf.reset()
    assert clf.label(1) == ("other", 0.0)


def test_with_a_camera_the_metric_evidence_decides(data) -> None:
    from motiontrack.calibrate import load_camera
    from motiontrack.calibrate.measure import box_heights

    cam = load_camera(data("pets09-s2l1", "View_001.xml"))
    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")
    person = gt.boxes[gt.frames == 1][0]
    assert 1.4 < box_heights(person, cam)[0] < 2.1
    x, y, w, h = person
    clf = TrackClassifier(ClassesConfig(), FPS, camera=cam)
    for _ in range(5):
        a, b, c = clf.update([_track(1, x, y, w, h), _track(2, x - w, y, 3 * w, h),
                              _track(3, x, y + h / 2, w, h / 2)])
    # the person; the same height three times as wide (> 1.6 m: a vehicle); half the height
    # and half as tall (about 0.9 m, neither a person nor a vehicle's width): other
    assert (a.label, b.label, c.label) == ("person", "vehicle", "other")


def test_class_numbers_of_the_tracks_file() -> None:
    assert [class_id(n) for n in ("person", "vehicle", "other", "")] == [1, 3, 0, -1]
    assert [class_name(k) for k in (1, 3, 0, -1, 13)] == ["person", "vehicle", "other", "", ""]
    # MOT17 ground truth: static person 7, bicycle 4, distractor 8
    assert [class_name(k) for k in (7, 4, 8)] == ["person", "vehicle", "other"]


def test_the_class_column_is_an_eleventh_column_that_readers_keep() -> None:
    text = format_mot_rows([1, 2], [4, 5], np.array([[1, 2, 3, 4], [5, 6, 7, 8.]]),
                           classes=[1, 3])
    assert text == "1,4,1.00,2.00,3.00,4.00,1,-1,-1,-1,1\n2,5,5.00,6.00,7.00,8.00,1,-1,-1,-1,3\n"
    assert parse_mot(text).classes.tolist() == [1, 3]
    # with a comment the line-by-line reader runs: the same columns
    assert parse_mot("# tracks\n" + text).classes.tolist() == [1, 3]
    # the plain 10-column layout has no class
    assert parse_mot(text.replace(",1\n", "\n").replace(",3\n", "\n")).classes.tolist() == [-1, -1]


def test_the_annotated_label_names_the_class_once_known() -> None:
    t = _track(7, 0, 0, 10, 30)
    assert track_caption(t) == "7"
    assert track_caption(Track(**{**t.__dict__, "label": "person"})) == "7 person"
    assert track_caption(Track(**{**t.__dict__, "label": "other"})) == "7"


def test_a_camera_run_writes_each_tracks_class(pets_camera_run) -> None:
    tracks = read_mot(pets_camera_run / "tracks.txt", kind="results")
    summary = json.loads((pets_camera_run / "summary.json").read_text())
    # PETS S2L1 shows people only: each row has the class its track had in that frame, decided
    # from its first confirmed frame on (its tentative frames vote too); a box of two people
    # side by side may look like neither for a frame or two, and each track ends a person
    classes = tracks.classes.tolist()
    assert classes.count(1) >= 0.98 * len(classes)
    last = {int(t): int(k) for t, k in zip(tracks.ids, tracks.classes)}   # sorted by frame
    assert set(last.values()) == {1}
    assert {v["class"] for v in summary["classes"].values()} == {"person"}
    assert summary["class_counts"] == {"person": len(summary["classes"]), "vehicle": 0,
                                       "other": 0}


def test_the_classifiers_keys_say_they_need_it_on_and_the_detectors_a_model() -> None:
    from motiontrack.config import load_config
    from motiontrack.config_activity import activity

    off = load_config(None, ["classes.enabled=false"])
    assert activity(off, "classes.min_frames").message() == (
        "classes.min_frames has no effect while classes.enabled = false; "
        "add --set classes.enabled=true")
    assert activity(load_config(), "classes.min_frames").active
    assert not activity(load_config(), "detector.every").active
    assert activity(load_config(None, ["detector.model='onnx:m.onnx'"]), "detector.every").active


def test_the_class_column_goes_to_motiontrack_json_and_back(tmp_path) -> None:
    from motiontrack.io.annotations import read_annotations, write_annotations

    text = format_mot_rows([1, 2], [4, 5], np.array([[1, 2, 3, 4], [5, 6, 7, 8.]]),
                           classes=[1, 3])
    (tmp_path / "tracks.txt").write_text(text)
    write_annotations(read_annotations(tmp_path / "tracks.txt"), tmp_path / "tracks.json")
    doc = json.loads((tmp_path / "tracks.json").read_text())
    assert [b["class"] for t in doc["tracks"] for b in t["boxes"]] == [1, 3]
    assert read_annotations(tmp_path / "tracks.json").classes.tolist() == [1, 3]
    # and back to the tracks layout with its class column
    write_annotations(read_annotations(tmp_path / "tracks.json"), tmp_path / "again.txt")
    assert (tmp_path / "again.txt").read_text() == text
