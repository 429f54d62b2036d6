"""Track-level class accuracy of the default pipeline (``classes.enabled``; docs/classes.md).

Each track's class is the one it has at its last frame; a track counts once per row it has
(frames weighted by track length), right when its class is the footage's class. On footage of
one class, ``other`` counts as wrong. Rows:

  PETS 2009 S2L1 1-300          all people, image evidence only
  PETS 2009 S2L1 1-300 + camera all people, with the Tsai calibration View_001.xml (metres)
  CDnet highway 1-1000          all vehicles (320x240)
  synth:mixed                   people and vehicles, each track's class that of the object
                                its boxes overlap most (IoU over the track's frames)

Then the classifier's cost on PETS 1-300 (ms a frame, best of 3, on the tracks of a run without
it), without and with the calibration.

Run: .venv/bin/python benchmarks/classes.py [--data ../shared/data]
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

from motiontrack.classify import TrackClassifier
from motiontrack.config import load_config
from motiontrack.pipeline import fitted_camera, run
from motiontrack.tracking.association import iou_matrix

from _pets import add_data_argument  # benchmarks/ is on sys.path when a script here runs


def final_labels(source: str, overrides: list[str]) -> tuple[dict[int, str], Counter, dict]:
    """Each track's class at its last frame, its number of rows and its boxes by frame."""
    cfg = load_config(None, overrides)
    label: dict[int, str] = {}
    rows: Counter = Counter()
    boxes: dict[int, dict[int, np.ndarray]] = defaultdict(dict)
    for res in run(source, cfg):
        for f, t in res.reported:
            label[t.id] = t.label
            rows[t.id] += 1
            boxes[t.id][f] = t.box.as_array()
    return label, rows, boxes


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


def cost(pets: Path, camera: Path) -> tuple[float, float]:
    """Milliseconds a frame of the classifier on PETS 1-300's tracks, without and with the
    camera."""
    cfg = load_config(None, ["source.max_frames=300", "classes.enabled=false"])
    frames = [r.tracks for r in run(str(pets), cfg)]
    cam = fitted_camera(load_config(None, [f"measure.camera='{camera}'"]), 768, 576)
    out = []
    for c in (None, cam):
        best = float("inf")
        for _ in range(3):
            clf = TrackClassifier(cfg.classes, 10.0, c)   # PETS is stored at 10 fps
            t = time.perf_counter()
            for tracks in frames:
                clf.update(tracks)
            best = min(best, (time.perf_counter() - t) * 1000 / len(frames))
        out.append(best)
    return out[0], out[1]


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
        label, n, _ = final_labels(source, overrides)
        acc, by_class = accuracy(label, n, dict.fromkeys(label, cls))
        print(f"{name:24s} {acc:8.3f}  {dict(by_class)}")
    from motiontrack.synth import make_scene

    scene = make_scene("mixed")
    label, n, boxes = final_labels("synth:mixed", [])
    acc, by_class = accuracy(label, n, mixed_truth(boxes, scene))
    print(f"{'synth:mixed':24s} {acc:8.3f}  {dict(by_class)}")
    plain, metric = cost(pets, camera)
    print(f"classifier cost on PETS: {plain:.2f} ms a frame, {metric:.2f} with the camera")


if __name__ == "__main__":
    main()
