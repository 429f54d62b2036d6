"""HOG people detector: non-maximum suppression, and people found in a real PETS 2009 frame."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.people.hog import HOGParams, HOGPeopleDetector, nms
from motiontrack.types import Box, Region


@pytest.mark.parametrize(
    "boxes, scores, thr, keep",
    [
        ([], [], 0.4, []),
        ([[0, 0, 10, 10]], [1.0], 0.4, [0]),
        # two identical boxes: the better one survives
        ([[0, 0, 10, 10], [0, 0, 10, 10]], [0.2, 0.9], 0.4, [1]),
        # IoU = 50 / 150 = 1/3: below 0.4 both stay, above 0.3 the weaker goes
        ([[0, 0, 10, 10], [5, 0, 10, 10]], [0.9, 0.5], 0.4, [0, 1]),
        ([[0, 0, 10, 10], [5, 0, 10, 10]], [0.9, 0.5], 0.3, [0]),
        # a chain: 0 suppresses 1, 2 does not overlap 0 and stays
        ([[0, 0, 10, 10], [2, 0, 10, 10], [14, 0, 10, 10]], [0.9, 0.8, 0.7], 0.4, [0, 2]),
    ],
)
def test_nms(boxes, scores, thr, keep):
    assert nms(np.array(boxes, float).reshape(-1, 4), np.array(scores, float), thr).tolist() == keep


def test_nms_length_mismatch():
    with pytest.raises(ValueError, match="differ in length"):
        nms(np.zeros((2, 4)), np.zeros(3))


def test_blank_and_tiny_images_give_no_detections():
    det = HOGPeopleDetector()
    assert det.detect(np.zeros((200, 120, 3), np.uint8)) == []
    assert det.detect(np.zeros((50, 30), np.uint8)) == []
    assert det.detect_in_regions(np.zeros((200, 120, 3), np.uint8), []) == []


def test_params_validate():
    with pytest.raises(ValueError):
        HOGParams(upscale=0.0)
    with pytest.raises(ValueError):
        HOGParams(pyramid_scale=1.0)


def _pets(data, index: int):
    import cv2

    from motiontrack.io.mot import read_mot

    video = data("pets09-s2l1", "video.avi")
    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")
    cap = cv2.VideoCapture(str(video))
    cap.set(cv2.CAP_PROP_POS_FRAMES, index)
    ok, img = cap.read()
    cap.release()
    assert ok, "could not read the PETS frame"
    g = gt.at(index + 1)  # video frame index i = MOT frame i + 1
    return img, g.select(g.consider).boxes


def _recall(dets: list[Region], gt: np.ndarray, thr: float = 0.5) -> tuple[int, int]:
    from scipy.optimize import linear_sum_assignment

    from motiontrack.tracking.association import iou_matrix

    if len(gt) == 0 or not dets:
        return 0, len(gt)
    iou = iou_matrix(gt, np.array([d.box.as_array() for d in dets]))
    r, c = linear_sum_assignment(-iou)
    return int((iou[r, c] >= thr).sum()), len(gt)


@pytest.mark.data
def test_hog_finds_the_people_in_a_pets_frame(data):
    # PETS people are ~30x75 px; the default SVM wants ~96 px tall people in a 64x128 window:
    # upscale x1.5. Measured over frames 0, 30, ..., 270: recall 43/55 = 0.78 at IoU 0.5
    # (precision 0.67); x2: 45/55 = 0.82 (precision 0.64). Here two frames with 7 people each
    # (measured 5/7 and 6/7), whole image.
    det = HOGPeopleDetector(HOGParams(upscale=1.5))
    tp = n = 0
    for index in (120, 270):
        img, gt = _pets(data, index)
        dets = det.detect(img)
        assert all(d.score > 0 for d in dets)
        t, k = _recall(dets, gt)
        tp, n = tp + t, n + k
    assert n == 14
    assert tp / n >= 0.7


@pytest.mark.data
def test_hog_restricted_to_regions_finds_the_people(data):
    # Regions = ground-truth boxes (stand-ins for motion regions); only padded crops are scanned.
    img, gt = _pets(data, 150)
    regions = [Region(box=Box(*b), centroid=Box(*b).center, area=float(b[2] * b[3])) for b in gt]
    dets = HOGPeopleDetector(HOGParams(upscale=2.0)).detect_in_regions(img, regions)
    tp, n = _recall(dets, gt)
    assert n >= 4
    assert tp / n >= 0.6
    # every detection lies near some region
    for d in dets:
        cx, cy = d.box.center
        assert any(b[0] - b[3] <= cx <= b[0] + b[2] + b[3] for b in gt)


class _OneBoxHOG:
    """A HOG stand-in that finds one person at a fixed place and counts its scans."""

    def __init__(self, box: Box) -> None:
        self.box, self.scans = box, 0

    def _found(self) -> list[Region]:
        self.scans += 1
        return [Region(box=self.box, centroid=self.box.center, area=self.box.area, score=1.0)]

    def detect(self, image):
        return self._found()

    def detect_in_regions(self, image, regions):
        return self._found()


def _region(x: float) -> Region:
    box = Box(x, 100.0, 30.0, 80.0)
    return Region(box=box, centroid=box.center, area=box.area)


@pytest.mark.parametrize("mode, between", [
    # regions: the frames between two HOG scans keep their own motion region
    ("regions", [(45.0, 100.0, 30.0, 80.0), (50.0, 100.0, 30.0, 80.0)]),
    # alone: the detections are all there is, so the last ones stand in between
    ("alone", [(44.0, 104.0, 20.0, 70.0)] * 2),
])
def test_hog_every_n_frames_never_puts_a_moving_region_where_its_person_was(mode, between):
    from motiontrack.config import PeopleConfig
    from motiontrack.people import PeopleStage

    stage = PeopleStage(PeopleConfig(enabled=True, heads=False, split=False, shapes=False,
                                     hog=mode, hog_every=3))
    stage.hog = hog = _OneBoxHOG(Box(44.0, 104.0, 20.0, 70.0))   # the person at frame 0
    image = np.zeros((300, 400, 3), np.uint8)
    boxes = []
    for k in range(4):   # the person walks 5 px a frame; HOG scans at frames 0 and 3
        out, found = stage.process(image, None, None, [_region(40.0 + 5.0 * k)], [])
        boxes.append([tuple(float(v) for v in r.box.as_array()) for r in out])
    assert hog.scans == 2
    assert boxes[0] == [(44.0, 104.0, 20.0, 70.0)]
    # frames 1 and 2: the old box's centre (54, 139) is still inside the moved region
    assert [b[0] for b in boxes[1:3]] == between
    # frame 3: a new scan; its box's centre is outside the region at x 55..85
    expected_3 = (55.0, 100.0, 30.0, 80.0) if mode == "regions" else (44.0, 104.0, 20.0, 70.0)
    assert boxes[3] == [expected_3]


def test_params_name_a_known_model_and_a_sane_fill():
    with pytest.raises(ValueError, match="model must be one of"):
        HOGParams(model="inria")
    with pytest.raises(ValueError, match="fill"):
        HOGParams(fill=0.0)
    assert HOGPeopleDetector(HOGParams(model="daimler")).WINDOW == (48, 96)
    assert HOGPeopleDetector().WINDOW == (64, 128)


def test_a_box_with_no_size_or_off_the_image_finds_nobody():
    det = HOGPeopleDetector(HOGParams(model="daimler"))
    image = np.zeros((100, 100), np.uint8)
    assert det.people_in_box(image, (10, 10, 0, 40)) == []
    assert det.people_in_box(image, (500, 500, 20, 40)) == []


def _centred(found: list[Region], box) -> int:
    x, y, w, h = box
    return sum(1 for r in found if x <= r.box.center[0] <= x + w and y <= r.box.center[1] <= y + h)


@pytest.mark.data
def test_daimler_finds_pets_people_in_their_boxes_at_processing_scale(data):
    from motiontrack.config import PreprocessConfig
    from motiontrack.preprocess import preprocess

    # the pipeline's frame: 768x576 at its automatic processing scale 0.5 (people ~15x37 px),
    # blurred; the boxes in original pixels. Measured on frames 0, 60, ..., 240: 24 of the 27
    # people found
    det = HOGPeopleDetector(HOGParams(model="daimler", hit_threshold=0.3))
    found = n = 0
    for index in (0, 60, 120, 180, 240):
        img, gt = _pets(data, index)
        small = preprocess(img, PreprocessConfig(scale=0.5))
        for box in gt:
            found += _centred(det.people_in_box(small, box, 0.5), box) > 0
            n += 1
    assert n == 27
    assert found >= 22


@pytest.mark.data
def test_daimler_finds_no_person_in_the_boxes_of_highway_cars(data):
    import cv2

    from motiontrack.config import PreprocessConfig
    from motiontrack.preprocess import preprocess

    # every car of CDnet highway frames 500, 525, ..., 1000: the boxes of the ground truth's
    # motion (255) blobs of at least 150 px, in the pipeline's 320x240 frame (processing
    # scale 1, blurred)
    det = HOGPeopleDetector(HOGParams(model="daimler", hit_threshold=0.3))
    found = n = 0
    for i in range(500, 1001, 25):
        mask = cv2.imread(str(data("cdnet-highway", "groundtruth", f"gt{i:06d}.png")), 0)
        img = cv2.imread(str(data("cdnet-highway", "input", f"in{i:06d}.jpg")))
        _, _, stats, _ = cv2.connectedComponentsWithStats((mask == 255).astype(np.uint8))
        for box in stats[1:][stats[1:, 4] >= 150, :4].astype(float):
            found += _centred(det.people_in_box(preprocess(img, PreprocessConfig(scale=1.0)), box),
                              box)
            n += 1
    assert n == 69
    assert found == 0
