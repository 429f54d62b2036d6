"""The tracker alone: PETS 2009 S2L1 tracked from detections made out of its ground truth.

``--detections det.txt`` replaces the motion stage with any detector's boxes. To see what the
tracker itself does with them, apart from any detector, the detections here are the ground-truth
boxes of the people (rows with consider = 1), first perfect and then with the errors a real
detector makes, drawn with a seed:

* ``drop``: each box is missed with this probability (a weak detection);
* ``burst``: occlusion-like misses: at each frame a person's detections go missing with this
  probability for a run of 1 to 10 frames (uniform), so the gaps are as long as a person passing
  behind another;
* ``jitter``: each side of a box moves by a normal error of this fraction of the box's height;
* ``fp``: false boxes per frame (Poisson), of a person's typical size, anywhere in the image.

Every row runs the pipeline with these detections and the motion-blob tracker's defaults (``motiontrack
track VIDEO --detections det.txt --set tracker.method=kalman`` with no preset; ``--preset
detections`` runs what ``track --detections`` runs, see benchmarks/detections.py) and scores it
like the other PETS benchmarks: CLEAR-MOT, Identity
and HOTA at IoU 0.5 against gt_mot15.txt, rows with consider = 0 as ignore regions; noisy rows
average ``--seeds`` draws. The tracks scored are what ``motiontrack track`` writes for tracks
from detections: each track also at the first ``confirm_hits`` - 1 frames, where it was still
tentative (``tracker.backfill``), and its gaps of up to a second interpolated
(``tracker.fill_gaps_s``); ``--set tracker.backfill=false --set tracker.fill_gaps_s=0`` scores
the online output alone. The boxes are the Kalman filter's estimate (HOTA below 1 with perfect
detections measures that smoothing).

Run: .venv/bin/python benchmarks/detections_pets.py [--data ../shared/data] [--seeds 3]
     [--frames 300] [--preset NAME] [--set stage.param=value ...]
"""

from __future__ import annotations

import argparse

import numpy as np

from motiontrack.config import load_config
from motiontrack.io.mot import read_mot
from motiontrack.io.sources import open_source
from motiontrack.types import Annotations

from _pets import KEYS, add_data_argument, pets_video, score_tracks  # benchmarks/ is on sys.path when a script here runs

#: (drop, burst, jitter, fp) of each row
ROWS = ((0.0, 0.0, 0.0, 0.0), (0.1, 0.0, 0.0, 0.0), (0.0, 0.05, 0.0, 0.0), (0.0, 0.0, 0.05, 0.0),
        (0.0, 0.0, 0.0, 1.0), (0.1, 0.0, 0.05, 0.5), (0.0, 0.05, 0.05, 0.5), (0.2, 0.0, 0.1, 1.0))
#: longest run of frames an occlusion-like miss (``burst``) lasts
BURST_FRAMES = 10


def burst_misses(frames: np.ndarray, ids: np.ndarray, rate: float,
                 rng: np.random.Generator) -> np.ndarray:
    """Rows to drop: per id, in frame order, a miss starts at each frame with probability
    ``rate`` and lasts 1 to :data:`BURST_FRAMES` frames."""
    miss = np.zeros(len(frames), bool)
    order = np.lexsort((frames, ids))
    for rows in np.split(order, np.flatnonzero(np.diff(ids[order])) + 1):
        j = 0
        while j < len(rows):
            if rng.random() < rate:
                run = int(rng.integers(1, BURST_FRAMES + 1))
                miss[rows[j:j + run]] = True
                j += run
            j += 1
    return miss


def noisy_detections(gt: Annotations, drop: float, jitter: float, fp: float, seed: int,
                     image_size: tuple[int, int], burst: float = 0.0) -> Annotations:
    """Detections from the people in ``gt`` (consider != 0) with the errors above."""
    rng = np.random.default_rng(seed)
    people = gt.select(gt.consider != 0)
    keep = rng.random(len(people)) >= drop
    if burst > 0:
        keep &= ~burst_misses(people.frames, people.ids, burst, rng)
    frames, boxes = people.frames[keep], people.boxes[keep].astype(np.float64)
    if jitter > 0 and len(boxes):
        h = boxes[:, 3:4]
        x1, y1 = boxes[:, 0:1], boxes[:, 1:2]
        x2, y2 = x1 + boxes[:, 2:3], y1 + h
        x1, x2, y1, y2 = (v + rng.normal(0.0, jitter, v.shape) * h for v in (x1, x2, y1, y2))
        boxes = np.hstack([np.minimum(x1, x2), np.minimum(y1, y2),
                           np.maximum(np.abs(x2 - x1), 2.0), np.maximum(np.abs(y2 - y1), 2.0)])
    if fp > 0:
        all_frames = np.unique(gt.frames)
        n = rng.poisson(fp, len(all_frames))
        f_fp = np.repeat(all_frames, n)
        size = np.median(people.boxes[:, 2:4], axis=0)
        w, h = image_size
        pos = rng.uniform([0, 0], [w - size[0], h - size[1]], (len(f_fp), 2))
        frames = np.concatenate([frames, f_fp])
        boxes = np.vstack([boxes, np.hstack([pos, np.tile(size, (len(f_fp), 1))])])
    order = np.argsort(frames, kind="stable")
    return Annotations.from_columns(frames[order], np.full(len(order), -1), boxes[order],
                                    scores=np.ones(len(order)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_data_argument(ap)
    ap.add_argument("--seeds", type=int, default=3, help="draws of each noisy row")
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="STAGE.PARAM=VALUE")
    ap.add_argument("--preset", default=None, help="shipped preset to start from (default none)")
    args = ap.parse_args()
    video = pets_video(args.data)
    gt = read_mot(video.parent / "gt_mot15.txt", kind="gt")
    cfg = load_config(None, [*args.overrides, f"source.max_frames={args.frames}"],
                      preset=args.preset)
    src = open_source(str(video))
    size = (src.info.width, src.info.height)
    src.close()
    print(f"PETS09-S2L1 frames 1-{args.frames}, the {args.preset or 'default'} tracker on detections made from the "
          f"ground truth{' with ' + ' '.join(args.overrides) if args.overrides else ''}")
    print(f"{'drop':>5}{'burst':>6}{'jitter':>7}{'fp':>5}" + "".join(f"{k:>10}" for k in KEYS))
    for drop, burst, jitter, fp in ROWS:
        seeds = range(args.seeds) if (drop or burst or jitter or fp) else range(1)
        rs = [score_tracks(str(video), cfg, gt.select(gt.frames <= args.frames),
                           noisy_detections(gt, drop, jitter, fp, s, size, burst)) for s in seeds]
        print(f"{drop:>5.2f}{burst:>6.2f}{jitter:>7.2f}{fp:>5.1f}" + "".join(
            f"{np.mean([r[k] for r in rs]):>10.3f}" if k != "IDSW"
            else f"{np.mean([r[k] for r in rs]):>10.1f}" for k in KEYS))


if __name__ == "__main__":
    main()
