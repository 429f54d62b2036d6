"""The detection-driven tracker (``tracker.method = detections``): one hand-built scenario per
association stage, each with its arithmetic, then the life cycle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motiontrack.config import load_config
from motiontrack.tracking import kalman
from motiontrack.tracking.association import iou_matrix
from motiontrack.tracking.detections import DetectionTracker, direction_cost


def _tracker(*overrides: str, fps: float = 25.0) -> DetectionTracker:
    cfg = load_config(None, list(overrides), preset="detections")
    return DetectionTracker(cfg.tracker, (640, 480), fps)


def _step(trk: DetectionTracker, boxes, scores) -> dict[int, tuple]:
    """One update; the reported tracks as {id: box}."""
    out = trk.update(np.array(boxes, float).reshape(-1, 4), np.array(scores, float))
    return {t.id: t.box.as_array().round(3).tolist() for t in out}


def _walk(trk: DetectionTracker, frames: int, step: float = 8.0, size: float = 40.0) -> list:
    """A 40x40 person walking right, ``step`` px a frame from x = 0: the reports of each frame."""
    return [_step(trk, [[step * f, 100.0, size, size]], [0.9]) for f in range(frames)]


def test_a_low_score_detection_continues_a_track_it_could_never_start():
    trk = _tracker("tracker.confirm_hits=1")
    # frame 1: a 0.9 box (>= new_score 0.8) starts track 1, confirmed at once (confirm_hits 1)
    assert list(_step(trk, [[0, 0, 10, 20]], [0.9])) == [1]
    # frame 2: only a 0.3 box (low_score 0.1 <= 0.3 < high_score 0.7): stage 2. The track is at
    # rest, so its prediction is (0, 0, 10, 20); IoU with (1, 0, 10, 20) = 9*20 / (200 + 200 -
    # 180) = 180 / 220 = 0.818 >= low_iou 0.5: the weak box continues track 1
    assert list(_step(trk, [[1, 0, 10, 20]], [0.3])) == [1]
    # the same 0.3 box alone never starts a track: below new_score 0.8, in any frame
    fresh = _tracker("tracker.confirm_hits=1")
    assert [_step(fresh, [[1, 0, 10, 20]], [0.3]) for _ in range(5)] == [{}] * 5


def test_a_low_score_detection_needs_the_stricter_stage_two_gate():
    trk = _tracker("tracker.confirm_hits=1")
    _step(trk, [[0, 0, 10, 20]], [0.9])
    # a 0.3 box shifted by 5 px: IoU = 5*20 / (400 - 100) = 100 / 300 = 0.333, above min_iou
    # 0.3 of the high-score stages but below low_iou 0.5: no match, track 1 is not reported
    assert _step(trk, [[5, 0, 10, 20]], [0.3]) == {}
    # the same box at score 0.9 passes stage 1's gate (0.333 >= 0.3)
    trk2 = _tracker("tracker.confirm_hits=1")
    _step(trk2, [[0, 0, 10, 20]], [0.9])
    assert list(_step(trk2, [[5, 0, 10, 20]], [0.9])) == [1]


@pytest.mark.parametrize("recover, same_id", [(True, True), (False, False)])
def test_an_occluded_person_who_stopped_is_recovered_at_the_last_observation(recover, same_id):
    trk = _tracker(f"tracker.detections.recover={str(recover).lower()}")
    # frames 1-8: x = 0, 8, ..., 56; confirmed at frame 3 (confirm_hits 3) as track 1
    reports = _walk(trk, 8)
    assert list(reports[-1]) == [1]
    # frames 9-13: occluded, no detection; the prediction coasts on at about 8 px a frame
    for _ in range(5):
        assert _step(trk, [], []) == {}
    # frame 14: the person stopped behind the occluder and reappears where last seen, x = 56.
    # The prediction has coasted 6 frames: x = 56 + 6 * v with v close to 8, about 104; two
    # 40-wide boxes 48 px apart do not overlap (IoU 0 < min_iou 0.3): stage 1 cannot match.
    pred = kalman.z_to_box(trk.x[:, :4] + trk.x[:, 4:8])
    seen = np.array([[56.0, 100.0, 40.0, 40.0]])
    assert iou_matrix(pred, seen)[0, 0] < 0.3
    # Stage 3 (OCR) compares the last observation, (56, 100, 40, 40), with the box: IoU 1.0
    assert iou_matrix(trk.last, seen)[0, 0] == pytest.approx(1.0)
    # with recovery the box continues track 1; without, it starts a tentative track (no report)
    assert (list(_step(trk, seen, [0.9])) == [1]) is same_id


def test_a_match_across_the_track_s_direction_loses_to_one_along_it():
    # delta_t 1: a track's direction is that of its last two observations, the anchor its last
    trk = _tracker("tracker.detections.delta_t=1")
    _walk(trk, 8)                         # last observation x = 56: centre (76, 120)
    pred = kalman.z_to_box(trk.x[:, :4] + trk.x[:, 4:8])[0]   # about x = 64: centre (84, 120)
    v = pred[0] + 20 - 76                 # the predicted step, about 8 px
    ahead = pred + [8, 0, 0, 0]           # along the walk, 8 px ahead of the prediction
    across = pred + [0, 7, 0, 0]          # 7 px below the prediction: across the walk
    # IoU of a 40x40 box shifted by d along one axis: (40 - d) / (40 + d)
    iou = iou_matrix(pred[None], np.array([ahead, across]))[0]
    assert iou == pytest.approx([32 / 48, 33 / 47])            # 0.667 < 0.702: IoU picks across
    # direction benefit (pi/2 - theta) / pi from the anchor (76, 120) along the direction (1, 0):
    # ahead (v + 8, 0): theta 0 -> 0.5; across (v, 7): theta = atan(7 / v), about 41 deg -> 0.27
    benefit = direction_cost(np.array([[1.0, 0.0]]), np.array([[76.0, 120.0]]),
                             np.array([ahead[:2] + 20, across[:2] + 20]), np.array([True]))[0]
    theta = math.atan2(7, v)
    assert benefit == pytest.approx([0.5, (math.pi / 2 - theta) / math.pi])
    # inertia 0.2 x score 0.9: 0.667 + 0.09 = 0.757 beats 0.702 + 0.18 * 0.27 = 0.751
    assert iou[0] + 0.18 * benefit[0] > iou[1] + 0.18 * benefit[1]
    _step(trk, [across, ahead], [0.9, 0.9])
    assert trk.last[0].tolist() == ahead.tolist()
    # without the direction term (inertia 0) the closer box across the walk is taken
    plain = _tracker("tracker.detections.delta_t=1", "tracker.detections.inertia=0")
    _walk(plain, 8)
    _step(plain, [across, ahead], [0.9, 0.9])
    assert plain.last[0].tolist() == across.tolist()


def test_a_track_seen_again_is_re_updated_along_the_line_from_its_last_observation():
    # frames 1-8 walking right at 8 px, frames 9-11 unseen, frame 12 seen at x = 56 + 4 * 8 = 88:
    # the person kept walking. The re-update runs the filter from frame 8's state through the
    # virtual observations x = 64, 72, 80 on the line, so the velocity stays about 8 px a frame;
    # without it the coasted prediction is corrected once and the velocity estimate is what the
    # single jump says.
    on, off = _tracker(), _tracker("tracker.detections.reupdate=false")
    for trk in (on, off):
        _walk(trk, 8)
        trk.x[:, 4] = 4.0                 # a velocity estimate half the truth, as after a stop
        for _ in range(3):
            _step(trk, [], [])
        assert list(_step(trk, [[88.0, 100.0, 40.0, 40.0]], [0.9])) == [1]
    # re-updated: 3 virtual steps of 8 px and a real one pull the velocity towards 8
    assert on.x[0, 4] > off.x[0, 4]
    assert abs(on.x[0, 4] - 8.0) < abs(off.x[0, 4] - 8.0)


def test_tentative_tracks_need_confirm_hits_and_die_on_a_miss():
    trk = _tracker()
    # confirm_hits 3: frames 1 and 2 report nothing, frame 3 reports track 1
    assert [r != {} for r in _walk(trk, 3)] == [False, False, True]
    fresh = _tracker()
    _walk(fresh, 2)
    assert _step(fresh, [], []) == {}          # a tentative track that misses a frame is deleted
    assert fresh.active_count == 0


def test_a_lost_track_is_deleted_after_max_lost_s():
    trk = _tracker("tracker.max_lost_s=0.2", fps=10)      # 0.2 s at 10 fps: 2 frames
    _walk(trk, 4)
    _step(trk, [], [])
    _step(trk, [], [])
    assert trk.active_count == 1
    _step(trk, [], [])                                   # unseen for 3 > 2 frames
    assert trk.active_count == 0


def test_every_step_handles_no_detections_and_no_tracks():
    trk = _tracker()
    assert _step(trk, [], []) == {}
    assert trk.update([]) == []
    assert direction_cost(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((3, 2)),
                          np.zeros(0, bool)).shape == (0, 3)


def _picture(*boxes_colours) -> np.ndarray:
    img = np.zeros((300, 300, 3), np.uint8)
    for (x, y, w, h), bgr in boxes_colours:
        img[y:y + h, x:x + w] = bgr
    return img


RED, BLUE = (0, 0, 255), (255, 0, 0)


@pytest.mark.parametrize("weight, taken", [(1.0, "red"), (0.0, "blue")])
def test_with_pictures_the_appearance_term_keeps_a_track_on_its_colour(weight, taken):
    trk = _tracker("tracker.confirm_hits=1", f"tracker.detections.appearance_weight={weight}")
    # frame 1: a red person at (100, 100, 40, 40) starts track 1 with a red histogram
    trk.update(np.array([[100.0, 100, 40, 40]]), np.array([0.9]),
               image=_picture(((100, 100, 40, 40), RED)))
    # frame 2: a blue box up-left and a red box down-right, 10 px off the prediction each way:
    # IoU 30*30 / (1600 + 1600 - 900) = 0.391 for both, no direction yet (one observation), so
    # IoU alone ties and the solver takes the first, blue; the Bhattacharyya distance to the red
    # histogram (about 1 for blue, 0 for red) breaks the tie for red
    blue, red = [90.0, 90, 40, 40], [110.0, 110, 40, 40]
    iou = iou_matrix(np.array([[100.0, 100, 40, 40]]), np.array([blue, red]))[0]
    assert iou == pytest.approx([900 / 2300, 900 / 2300])
    img = _picture(((90, 90, 40, 40), BLUE), ((110, 110, 40, 40), RED))
    trk.update(np.array([blue, red]), np.array([0.9, 0.9]), image=img)
    assert trk.meta[0].tid == 1      # the other box started a second track after it
    assert trk.last[0].tolist() == (red if taken == "red" else blue)


def test_the_pipeline_gives_the_tracker_the_picture_only_when_there_is_one():
    from motiontrack.pipeline import Pipeline
    from motiontrack.types import Annotations, Frame

    det = Annotations.from_columns([1], [-1], np.array([[100.0, 100, 40, 40]]), scores=[0.9])
    cfg = load_config(None, ["tracker.confirm_hits=1", "tracker.detections.appearance_weight=1"],
                      preset="detections")
    with_video = Pipeline(cfg, (300, 300), det, 25.0)
    with_video.process(Frame(0, _picture(((100, 100, 40, 40), RED))))
    assert with_video.tracker.meta[0].hist is not None
    # a source of detections alone: an empty image, no histogram
    alone = Pipeline(cfg, (300, 300), det, 25.0)
    alone.process(Frame(0, np.zeros((0, 0), np.uint8)))
    assert alone.tracker.meta[0].hist is None
