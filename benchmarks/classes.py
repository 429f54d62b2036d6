"""Track-level class accuracy of the default pipeline (``classes.enabled``; docs/classes.md).

Each track's class is the one it has at its last frame; a track counts once per row it has
(frames weighted by track length), right when its class is the footage's class. On footage of
one class, ``other`` counts as wrong. Rows:

  PETS 2009 S2L1 1-300          all people, image evidence only
  PETS 2009 S2L1 1-300 + camera all people, with the Tsai calibration View_001.xml (metres)
  CDnet highway 1-1000          all vehicles (320x240)
  synth:mixed                   people and vehicles, each track's class that of the object
                                its boxes overlap most (IoU over the track's frames)
  PETS pairs, HOG / no HOG      the classifier alone on tracks of two people walking side by
                                side as one blob: the union of the ground-truth boxes of each
                                pair within 10 px of each other at the same height in at
                                least 50 of frames 1-300, in the processing-scale frames; with
                                the default classes.hog and with classes.hog=off, and the
                                classifier's ms a frame

Each row ends with the number of boxes HOG looked at (``classes.hog``) and of the people it
found in them. Then each HOG model on single boxes (PETS track boxes, highway cars' boxes:
:func:`hog_models`), and the classifier's cost on PETS 1-300 (ms a frame, best of 3, OpenCV in
one thread, on the tracks of a run without it and its processing-scale frames, which HOG looks
at), without and with the calibration.

Run: .venv/bin/python benchmarks/classes.py [--data ../shared/data]
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter, defaultdict
from itertools import combinations
from pathlib import Path

import cv2
import numpy as np

from motiontrack.classify import TrackClassifier
from motiontrack.config import load_config
from motiontrack.pipeline import Pipeline, fitted_camera, run
from motiontrack.preprocess import preprocess
from motiontrack.io.mot import read_mot
from motiontrack.people.hog import HOGParams, HOGPeopleDetector
from motiontrack.tracking.association import iou_matrix
from motiontrack.types import Box, Track, TrackState

from _pets import add_data_argument  # benchmarks/ is on sys.path when a script here runs


def final_labels(source: str, overrides: list[str]) -> tuple[dict[int, str], Counter, dict, str]:
    """Each track's class at its last frame, its number of rows, its boxes by frame, and the
    number of boxes HOG looked at and of people it found in them."""
    cfg = load_config(None, overrides)
    label: dict[int, str] = {}
    rows: Counter = Counter()
    boxes: dict[int, dict[int, np.ndarray]] = defaultdict(dict)
    with run(source, cfg) as frames:
        for res in frames:
            for f, t in res.reported:
                label[t.id] = t.label
                rows[t.id] += 1
                boxes[t.id][f] = t.box.as_array()
        clf = frames.pipeline.classes
    return label, rows, boxes, f"{clf.hog_looks} (found {clf.hog_found})"


def accuracy(label: dict[int, str], rows: Counter, truth: dict[int, str]) -> tuple[float, Counter]:
    """Row-weighted share of tracks whose class is their truth, and the rows by class."""
    right = sum(rows[t] for t in label if label[t] == truth.get(t))
    by_class: Counter = Counter()
    for t in label:
        by_class[label[t]] += rows[t]
    return right / max(sum(rows.values()), 1), by_class


def mixed_truth(boxes: dict[int, dict[int, np.ndarray]], scene) -> dict[int, str]:
    """The class of the ground-truth object each track overlaps most over its frames."""
    gt = scene.ground_truth()
    classes = scene.object_classes()
    by_frame = gt.by_frame()
    truth = {}
    for tid, frames in boxes.items():
        score: Counter = Counter()
        for f, box in frames.items():
            idx = by_frame.get(f + 1)
            if idx is None or not len(idx):
                continue
            iou = iou_matrix(box[None], gt.boxes[idx])[0]
            k = int(np.argmax(iou))
            if iou[k] > 0.3:
                score[int(gt.ids[idx][k])] += 1
        truth[tid] = classes.get(score.most_common(1)[0][0], "other") if score else "other"
    return truth


def side_by_side(pets: Path, gt_file: Path) -> dict[int, dict[int, np.ndarray]]:
    """Boxes by frame (0-based) of each pair of PETS people walking side by side in frames
    1-300: the union of their ground-truth boxes where they are at most 10 px apart and their
    tops differ by less than 0.3 of a height, pairs so in at least 50 frames."""
    gt = read_mot(gt_file, kind="gt")
    pairs: dict[tuple, dict[int, np.ndarray]] = defaultdict(dict)
    for f in range(1, 301):
        ids, b = gt.ids[gt.frames == f], gt.boxes[gt.frames == f]
        for i, j in combinations(range(len(ids)), 2):
            x1, y1 = np.minimum(b[i, :2], b[j, :2])
            x2, y2 = np.maximum(b[i, :2] + b[i, 2:], b[j, :2] + b[j, 2:])
            gap = max(b[i, 0], b[j, 0]) - min(b[i, 0] + b[i, 2], b[j, 0] + b[j, 2])
            if gap < 10 and abs(b[i, 1] - b[j, 1]) < 0.3 * b[i, 3]:
                pairs[(ids[i], ids[j])][f - 1] = np.array([x1, y1, x2 - x1, y2 - y1])
    return {k + 1: v for k, v in enumerate(v for v in pairs.values() if len(v) >= 50)}


def pairs_accuracy(pets: Path, gt_file: Path, overrides: list[str]) -> tuple[float, Counter, str]:
    """:func:`accuracy` of the classifier alone on the tracks of :func:`side_by_side`, the
    boxes HOG looked at and the people it found in them, and the classifier's time (one
    OpenCV thread)."""
    pairs = side_by_side(pets, gt_file)
    cfg = load_config(None, overrides)
    pre = Pipeline(cfg, (768, 576), None, 10.0).pre_cfg
    clf = TrackClassifier(cfg.classes, 10.0)   # PETS is stored at 10 fps
    label: dict[int, str] = {}
    rows: Counter = Counter()
    spent = 0.0
    cv2.setNumThreads(1)
    cap = cv2.VideoCapture(str(pets))
    for f in range(300):
        ok, image = cap.read()
        if not ok:
            break
        tracks = [Track(id=k, box=Box(*v[f]), state=TrackState.CONFIRMED)
                  for k, v in pairs.items() if f in v]
        small = preprocess(image, pre)
        t0 = time.perf_counter()
        out = clf.update(tracks, image=small, scale=pre.scale)
        spent += time.perf_counter() - t0
        for t in out:
            label[t.id] = t.label
            rows[t.id] += 1
    cap.release()
    return (*accuracy(label, rows, dict.fromkeys(label, "person")),
            f"{clf.hog_looks} (found {clf.hog_found}), {spent * 1000 / 300:.2f} ms a frame")


def pets_frames(pets: Path) -> tuple[list, float]:
    """The tracks and processing-scale frame of each frame of a PETS 1-300 run without the
    classifier, and the processing scale."""
    cfg = load_config(None, ["source.max_frames=300", "classes.enabled=false"])
    pre = Pipeline(cfg, (768, 576), None, 10.0).pre_cfg
    return [(r.tracks, preprocess(r.frame, pre)) for r in run(str(pets), cfg)], pre.scale


def cost(frames: list, scale: float, camera: Path) -> tuple[float, float, int]:
    """Milliseconds a frame of the classifier on PETS 1-300's tracks and processing-scale
    frames (:func:`pets_frames`; HOG looks at those), without and with the camera; the boxes
    HOG looked at without it."""
    cam = fitted_camera(load_config(None, [f"measure.camera='{camera}'"]), 768, 576)
    classes = load_config(None, []).classes
    cv2.setNumThreads(1)   # HOG's pyramid would spread over every core
    out, looks = [], 0
    for c in (None, cam):
        best = float("inf")
        for _ in range(3):
            clf = TrackClassifier(classes, 10.0, c)   # PETS is stored at 10 fps
            t = time.perf_counter()
            for tracks, small in frames:
                clf.update(tracks, image=small, scale=scale)
            best = min(best, (time.perf_counter() - t) * 1000 / len(frames))
            looks = looks or clf.hog_looks
        out.append(best)
    return out[0], out[1], looks


def hog_models(frames: list, scale: float, highway: Path) -> None:
    """Each HOG model (``classes.hog``) on single boxes: the share of PETS track boxes (the
    measured tracks of every third frame of :func:`pets_frames`) with a person centred in
    them, the people found centred in the boxes of highway cars (the ground truth's motion
    blobs of at least 150 px, frames 500, 510, ..., 1000), and the milliseconds a look."""
    cars = []
    pre = Pipeline(load_config(), (320, 240), None, 25.0).pre_cfg
    for i in range(500, 1001, 10):
        mask = cv2.imread(str(highway / "groundtruth" / f"gt{i:06d}.png"), cv2.IMREAD_GRAYSCALE)
        small = preprocess(cv2.imread(str(highway / "input" / f"in{i:06d}.jpg")), pre)
        _, _, stats, _ = cv2.connectedComponentsWithStats((mask == 255).astype(np.uint8))
        cars += [(small, b) for b in stats[1:][stats[1:, 4] >= 150, :4].astype(float)]
    people = [(small, t.box.as_array()) for tracks, small in frames[::3]
              for t in tracks if t.time_since_update == 0]
    cv2.setNumThreads(1)
    for model in ("daimler", "default"):
        hog = HOGPeopleDetector(HOGParams(model=model, hit_threshold=0.3))
        found, t = [], time.perf_counter()
        for boxes, s in ((people, scale), (cars, 1.0)):
            found.append([sum(1 for r in hog.people_in_box(img, b, s)
                              if b[0] <= r.box.center[0] <= b[0] + b[2]
                              and b[1] <= r.box.center[1] <= b[1] + b[3]) for img, b in boxes])
        ms = (time.perf_counter() - t) * 1000 / (len(people) + len(cars))
        print(f"HOG {model}: a person in {sum(n > 0 for n in found[0])} of {len(people)} PETS "
              f"track boxes, {sum(found[1])} people in {len(cars)} highway cars' boxes, "
              f"{ms:.2f} ms a look")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    add_data_argument(ap)
    args = ap.parse_args()
    data = Path(args.data)
    pets = data / "pets09-s2l1" / "video.avi"
    highway = data / "cdnet-highway" / "input"
    if not pets.is_file() or not highway.is_dir():
        sys.exit(f"PETS or CDnet highway not found under {data} (set MOTIONTRACK_DATA or --data)")
    camera = data / "pets09-s2l1" / "View_001.xml"
    rows = [
        ("PETS 1-300", str(pets), ["source.max_frames=300"], "person"),
        ("PETS 1-300 + camera", str(pets),
         ["source.max_frames=300", f"measure.camera='{camera}'"], "person"),
        ("highway 1-1000", str(highway / "*.jpg"), ["source.max_frames=1000"], "vehicle"),
    ]
    print(f"{'footage':24s} {'accuracy':>8s}  rows by class")
    for name, source, overrides, cls in rows:
        label, n, _, looks = final_labels(source, overrides)
        acc, by_class = accuracy(label, n, dict.fromkeys(label, cls))
        print(f"{name:24s} {acc:8.3f}  {dict(by_class)}  HOG looks {looks}")
    from motiontrack.synth import make_scene

    scene = make_scene("mixed")
    label, n, boxes, looks = final_labels("synth:mixed", [])
    acc, by_class = accuracy(label, n, mixed_truth(boxes, scene))
    print(f"{'synth:mixed':24s} {acc:8.3f}  {dict(by_class)}  HOG looks {looks}")
    gt_file = data / "pets09-s2l1" / "gt_mot15.txt"
    for name, overrides in (("PETS pairs, HOG", []), ("PETS pairs, no HOG", ["classes.hog=off"])):
        acc, by_class, looks = pairs_accuracy(pets, gt_file, overrides)
        print(f"{name:24s} {acc:8.3f}  {dict(by_class)}  HOG looks {looks}")
    frames, scale = pets_frames(pets)
    hog_models(frames, scale, data / "cdnet-highway")
    plain, metric, looks = cost(frames, scale, camera)
    print(f"classifier cost on PETS: {plain:.2f} ms a frame, {metric:.2f} with the camera "
          f"(OpenCV in one thread; HOG looks {looks})")


if __name__ == "__main__":
    main()
