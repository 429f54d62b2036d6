"""What ``motiontrack track`` adds to a detections run's tracks file when the run ends: gaps
filled by interpolation (``tracker.fill_gaps_s``, hand-computed cases) and a track's tentative
frames (``tracker.backfill``), on a ``--detections`` run in which a person's detections go
missing for three frames."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.config import load_config
from motiontrack.io.mot import read_mot, write_mot
from motiontrack.pipeline import Pipeline, fill_gap_frames
from motiontrack.tracking.association import iou_matrix
from motiontrack.tracking.gaps import fill_gaps
from motiontrack.types import Annotations

from helpers import ann


def test_a_gap_is_filled_linearly_frame_by_frame():
    # id 1 seen at frames 1 and 4 (two frames missing), id 2 at 1 and 2 (no gap)
    t = ann([[1, 1, 0, 0, 10, 20, 0.9], [4, 1, 30, 6, 16, 20, 0.6],     # column 7: the score
             [1, 2, 50, 50, 10, 10, 1.0], [2, 2, 52, 50, 10, 10, 1.0]])
    out = fill_gaps(t, 2)
    assert len(out) == 6
    # sorted by frame, then id
    assert out.frames.tolist() == [1, 1, 2, 2, 3, 4] and out.ids.tolist() == [1, 2, 1, 2, 1, 1]
    f2, f3 = out.select((out.ids == 1) & (out.frames == 2)), out.select((out.ids == 1) & (out.frames == 3))
    np.testing.assert_allclose(f2.boxes[0], [10, 2, 12, 20])   # a third of the way
    np.testing.assert_allclose(f3.boxes[0], [20, 4, 14, 20])   # two thirds
    np.testing.assert_allclose([f2.scores[0], f3.scores[0]], [0.8, 0.7])
    # a filled row's world position is unknown: a linear path in the image is not one on the ground
    assert (f2.world == -1).all() and f2.consider.all()
    # the input is not modified
    assert len(t) == 4


def test_only_short_gaps_of_one_identity_are_filled():
    t = ann([[1, 1, 0, 0, 10, 10, 1], [5, 1, 40, 0, 10, 10, 1],     # 3 missing: too long
             [1, 2, 0, 50, 10, 10, 1], [3, 3, 20, 50, 10, 10, 1],    # two ids: never joined
             [1, -1, 0, 90, 10, 10, 1], [3, -1, 20, 90, 10, 10, 1]])  # anonymous rows
    assert len(fill_gaps(t, 2)) == len(t)
    filled = fill_gaps(t, 3)
    assert len(filled) == len(t) + 3
    assert sorted(filled.frames[filled.ids == 1].tolist()) == [1, 2, 3, 4, 5]
    assert fill_gaps(t, 0) is t


def test_many_gaps_in_one_call():
    rng = np.random.default_rng(0)
    frames = np.arange(1, 101)
    rows = []
    for tid in (1, 2, 3):
        seen = frames[rng.random(100) > 0.3]
        for f in seen:
            rows.append([f, tid, f * 2.0, tid * 40.0, 10, 20, 1])
    t = ann(rows)
    out = fill_gaps(t, 100)
    for tid in (1, 2, 3):
        mine = out.select(out.ids == tid)
        seen = t.frames[t.ids == tid]
        assert mine.frames.tolist() == list(range(seen.min(), seen.max() + 1))
        # the path is a straight line, so interpolation recovers every box exactly
        np.testing.assert_allclose(mine.boxes[:, 0], mine.frames * 2.0)


def test_filling_applies_to_external_detections_by_default():
    cfg = load_config(None, [])
    assert fill_gap_frames(cfg, 10.0, external=True) == 10       # 1 s at 10 fps
    assert fill_gap_frames(cfg, 30.0, external=True) == 30
    assert fill_gap_frames(cfg, None, external=True) == 25       # 25 fps when unknown
    assert fill_gap_frames(cfg, 10.0, external=False) == 0
    on = load_config(None, ["tracker.fill_motion=true", "tracker.fill_gaps_s=0.5"])
    assert fill_gap_frames(on, 10.0, external=False) == 5
    off = load_config(None, ["tracker.fill_gaps_s=0"])
    assert fill_gap_frames(off, 10.0, external=True) == 0
    # the same runs report the tentative boxes (the tracker keeps them for the classes too)
    det = Annotations.from_columns([1], [-1], [[10, 10, 20, 40]])
    assert Pipeline(cfg, (320, 240), detections=det)._report_earlier
    assert not Pipeline(cfg, (320, 240))._report_earlier
    assert Pipeline(cfg, (320, 240)).tracker.keep_tentative           # classes.enabled
    assert Pipeline(on, (320, 240))._report_earlier
    no = load_config(None, ["tracker.backfill=false"])
    assert not Pipeline(no, (320, 240), detections=det)._report_earlier
    plain = load_config(None, ["classes.enabled=false"])
    assert not Pipeline(plain, (320, 240)).tracker.keep_tentative


@pytest.fixture(scope="module")
def pets_run(tmp_path_factory, request):
    """``track --detections`` on PETS frames 1-40 from the people's ground-truth boxes, with one
    person's boxes removed at frames 20-22; with the default filling and with it off."""
    from helpers import require

    video = require("pets09-s2l1", "video.avi")
    gt = read_mot(video.parent / "gt_mot15.txt", kind="gt")
    people = gt.select((gt.consider != 0) & (gt.frames <= 40))
    counts = np.bincount(people.ids)
    who = int(np.argmax(counts))                         # someone seen in every frame
    hole = (people.ids == who) & (people.frames >= 20) & (people.frames <= 22)
    assert hole.sum() == 3
    tmp = tmp_path_factory.mktemp("gaps")
    det = people.select(~hole)
    det = Annotations.from_columns(det.frames, np.full(len(det), -1), det.boxes)
    write_mot(det, tmp / "det.txt")
    runs = {}
    for name, extra in (("filled", []), ("off", ["--set", "tracker.fill_gaps_s=0"])):
        out = tmp / name
        assert main(["track", str(video), "--max-frames", "40", "--no-video", "-o", str(out),
                     "--detections", str(tmp / "det.txt"),
                     "--camera", str(video.parent / "View_001.xml"),
                     "--gt", str(video.parent / "gt_mot15.txt"), *extra]) == 0
        runs[name] = (read_mot(out / "tracks.txt"), json.loads((out / "summary.json").read_text()))
    runs["gt"] = gt
    return people.select(hole), runs


def test_detection_run_fills_the_missing_frames(pets_run):
    missing, runs = pets_run
    tracks, summary = runs["filled"]
    off, off_summary = runs["off"]
    assert summary["filled_rows"] == 3 and off_summary["filled_rows"] == 0
    assert len(tracks) == len(off) + summary["filled_rows"]
    for f, box in zip(missing.frames, missing.boxes):
        # without filling nobody is reported on the person in the hole ...
        here = off.select(off.frames == f)
        assert (iou_matrix(box[None], here.boxes) < 0.5).all()
        # ... with it, one track covers them, with the id it has on both sides of the hole
        here = tracks.select(tracks.frames == f)
        iou = iou_matrix(box[None], here.boxes)[0]
        assert iou.max() > 0.8, (f, iou.max())
        tid = here.ids[iou.argmax()]
        seen = off.select(off.ids == tid).frames
        assert (seen < 20).any() and (seen > 22).any()
        # filled rows get a position on the ground plane from the camera, like the others
        w = here.world[iou.argmax()]
        assert -30 < w[0] < 20 and -30 < w[1] < 10 and w[2] == 0
    assert not (tracks.world == -1).all(axis=1).any()
    # the score reads the filled file
    assert summary["accuracy"]["recall"] > off_summary["accuracy"]["recall"]


def test_detection_run_reports_tracks_from_their_first_frame(pets_run):
    """Perfect detections: each track is confirmed at its third frame (confirm_hits = 3 in the
    detections preset that --detections runs) and then written at its two tentative frames
    too, so the people of frame 1 are in frame 1, and
    the file is sorted by frame although those rows were written late."""
    _, runs = pets_run
    tracks, summary = runs["filled"]
    assert summary["backfilled_rows"] >= 2 * summary["tracks"]
    # sorted by frame, then id, with or without gaps to fill
    for t in (tracks, runs["off"][0]):
        assert (np.diff(t.frames * 10_000 + t.ids) > 0).all()
    first = tracks.select(tracks.frames == 1)
    gt1 = runs["gt"].select((runs["gt"].frames == 1) & runs["gt"].consider)
    assert len(gt1) == 3 and len(first) == 3
    iou = iou_matrix(gt1.boxes, first.boxes)
    assert (iou.max(axis=1) > 0.9).all(), iou.max(axis=1)


def test_a_reidentified_track_is_backfilled_only_after_its_predecessor(data, tmp_path):
    # With tracker.fill_motion a confirmed motion track is also written at its tentative
    # frames. A track that takes over a lost track's id (re-identification) must not add rows
    # in frames where that id was already reported: on PETS the first takeover happens within
    # the first frames and wrote id 1 twice in frame 4.
    from motiontrack.cli import main

    out = tmp_path / "o"
    assert main(["track", str(data("pets09-s2l1", "video.avi")), "--max-frames", "60",
                 "--no-video", "--set", "tracker.fill_motion=true", "-o", str(out)]) == 0
    tracks = read_mot(out / "tracks.txt")
    pairs = list(zip(tracks.frames.tolist(), tracks.ids.tolist()))
    assert len(pairs) == len(set(pairs))
