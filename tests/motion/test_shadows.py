"""The shadow test: OpenCV's threshold from the config, and a stricter one while the scene's
tracks are mostly vehicles (grey cars are darker copies of the asphalt)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiontrack.classify.scene_kind import VehicleScene
from motiontrack.config import load_config
from motiontrack.evaluate.masks import MaskCounts, compare_masks, read_roi
from motiontrack.motion import create_detector
from motiontrack.pipeline import run
from motiontrack.types import Box, Track, TrackState


def _track(i: int, label: str) -> Track:
    return Track(id=i, box=Box(0, 0, 10, 10), state=TrackState.CONFIRMED, label=label)


def test_a_scene_is_a_vehicles_scene_when_its_recent_tracks_are_mostly_vehicles():
    scene = VehicleScene()
    assert scene.update([_track(1, "vehicle")]) is False           # one vehicle is not a scene
    assert scene.update([_track(1, "vehicle"), _track(2, "vehicle")]) is True
    assert scene.update([_track(3, "person"), _track(4, "person")]) is False   # a tie: no
    assert scene.update([_track(5, "other"), _track(6, "")]) is False   # no kind: no vote
    assert scene.update([_track(3, "vehicle")]) is True            # a track's latest label counts


def test_only_the_recent_tracks_vote():
    scene = VehicleScene()
    for i in range(1, VehicleScene.RECENT + 1):
        scene.update([_track(i, "vehicle")])
    assert scene.update([]) is True
    for i in range(VehicleScene.RECENT + 1, VehicleScene.RECENT + 52):   # the cars give way
        decided = scene.update([_track(i, "person")])
    assert decided is False and len(scene._labels) == VehicleScene.RECENT


def test_the_model_takes_the_vehicles_threshold_and_keeps_it_through_a_new_model():
    cfg = load_config(None, ["motion.knn.shadow_threshold=0.4",
                             "motion.knn.vehicle_shadow_threshold=0.75"])
    det = create_detector(cfg.motion)
    assert det.switches_shadows and det.sub.getShadowThreshold() == pytest.approx(0.4)
    det.vehicle_scene(True)
    assert det.sub.getShadowThreshold() == pytest.approx(0.75)
    det.relearn(np.zeros((24, 32, 3), np.uint8))                  # a sudden change: a new model
    assert det.sub.getShadowThreshold() == pytest.approx(0.75)
    det.vehicle_scene(False)
    assert det.sub.getShadowThreshold() == pytest.approx(0.4)


def test_one_threshold_when_both_are_equal_or_shadows_are_off():
    for sets in (["motion.knn.vehicle_shadow_threshold=0.5"], ["motion.knn.detect_shadows=false"]):
        det = create_detector(load_config(None, sets).motion)
        det.vehicle_scene(True)
        assert not det.switches_shadows and det.sub.getShadowThreshold() == pytest.approx(0.5)


def test_a_grey_object_darker_than_the_ground_is_a_shadow_to_the_default_test_only():
    """A flat grey ground and a square 0.6 times as bright: a shadow by the default test (0.5),
    an object by the vehicles' (0.7)."""
    ground = np.full((60, 80, 3), 150, np.uint8)
    frame = ground.copy()
    frame[20:40, 30:50] = 90
    masks = {}
    for vehicles in (False, True):
        det = create_detector(load_config(None, []).motion)
        det.vehicle_scene(vehicles)
        for _ in range(30):
            det.apply(ground)
        masks[vehicles] = det.apply(frame)
    assert (masks[False][20:40, 30:50] == 0).all()
    assert (masks[True][22:38, 32:48] == 255).all()


HIGHWAY = "cdnet-highway"


@pytest.mark.data
@pytest.mark.slow
def test_on_cdnet_highway_the_cars_switch_the_test_and_the_mask_scores_higher(data):
    """The default pipeline over frames 1-1000, its mask scored over CDnet's 470-1000: the cars'
    grey bodies stay in the mask (recall 0.89, F 0.905 with the default test alone), the sun on
    the asphalt is no region, and the reported mask is the regions' silhouettes (F 0.938
    without either)."""
    folder = data(HIGHWAY)
    roi = read_roi(folder / "ROI.bmp")
    counts = MaskCounts()
    with run(str(folder / "input" / "*.jpg"), load_config(None, ["source.max_frames=1000"])) as r:
        for res in r:
            frame = res.index + 1
            if frame >= 470:
                gt = cv2.imread(str(folder / "groundtruth" / f"gt{frame:06d}.png"),
                                cv2.IMREAD_GRAYSCALE)
                counts = counts + compare_masks(gt, res.mask, roi)
        assert r.pipeline.detector.sub.getShadowThreshold() == pytest.approx(0.7)
        assert r.pipeline.ghosts.lit > 0
    m = counts.metrics()
    assert m["recall"] >= 0.96 and m["precision"] >= 0.93 and m["f_measure"] >= 0.95, m


@pytest.mark.data
def test_people_keep_the_default_test(data):
    """PETS: people only, so the model keeps its threshold (and the tracks their hashes in
    tools/track_hashes.json)."""
    cfg = load_config(None, ["source.max_frames=100"])
    with run(str(data("pets09-s2l1", "video.avi")), cfg) as r:
        labels = {t.label for res in r for t in res.tracks}
        assert r.pipeline.detector.switches_shadows and "person" in labels
        assert r.pipeline.detector.sub.getShadowThreshold() == pytest.approx(0.5)


def test_a_model_is_freed_as_soon_as_it_is_dropped():
    """No reference cycle through the model's factory: a serve camera makes a new detector for
    each segment, and a cycle kept each old one (megabytes of OpenCV's memory) alive until a
    full garbage collection, which a long run hardly ever makes."""
    import gc
    import weakref

    gc.disable()
    try:
        det = create_detector(load_config(None, []).motion)
        gone = weakref.ref(det)
        del det
        assert gone() is None
    finally:
        gc.enable()
