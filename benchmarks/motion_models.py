"""CPU cost of each motion model with its mask clean-up, per PETS frame at the default processing
scale (384x288, colour), OpenCV held to one thread.

The frames are decoded and preprocessed beforehand. Each round runs every model once over the
clip (a fresh model each time, the order reversed every other round so a busy phase of the machine
hits all alike); the CPU time of this process (user + sys) per frame is taken, and the median over
the rounds printed with the range. The "protect" rows pass the ground truth's boxes of each frame
(grown by 10 % on each side) as the do-not-learn mask, as the pipeline passes its tracks' boxes.

  knn              OpenCV KNN with the hold (the default), no boxes: the hold's own work when
                   no track is held
  knn + hold slow  the same with the boxes of the people slower than ``motion.knn.hold_speed``
                   (box heights a second, from the ground truth's previous frame) as protect
                   mask, as the pipeline passes its slow tracks' boxes
  knn + hold boxes the same with every person's box: an upper bound
  knn, hold=false  OpenCV KNN alone
  mog2             OpenCV MOG2 with shadow detection
  vibe             the sample-based model (motion.vibe defaults), no protect mask
  vibe + protect   the same with the boxes as protect mask
  vibe, n 6 / 12   other sample counts

Run: .venv/bin/python benchmarks/motion_models.py [--data ../shared/data] [--frames 300] [--repeat 7]
"""

from __future__ import annotations

import statistics
import time

import cv2
import numpy as np

from motiontrack.config import PipelineConfig, load_config
from motiontrack.imaging import pixel_window
from motiontrack.motion import create_detector
from motiontrack.motion.cleanup import clean_mask
from motiontrack.pipeline import Pipeline
from motiontrack.preprocess import preprocess
from motiontrack.types import frame_number

from _pets import pets_args  # benchmarks/ is on sys.path when a script here runs

MODELS = {
    "knn": (["motion.method=knn"], False),
    "knn + hold slow": (["motion.method=knn"], "slow"),
    "knn + hold boxes": (["motion.method=knn"], True),
    "knn, hold=false": (["motion.method=knn", "motion.knn.hold=false"], False),
    "mog2": (["motion.method=mog2"], False),
    "vibe": (["motion.method=vibe", "motion.vibe.protect=false"], False),
    "vibe + protect": (["motion.method=vibe"], True),
    "vibe, n_samples 6 + protect": (["motion.method=vibe", "motion.vibe.n_samples=6"], True),
    "vibe, n_samples 12 + protect": (["motion.method=vibe", "motion.vibe.n_samples=12"], True),
}


def protect_masks(gt, frames: int, scale: float, shape: tuple[int, int],
                  slower: float | None = None) -> list[np.ndarray]:
    """Each frame's ground-truth boxes, grown by 10 % a side, as a bool mask at ``scale``; with
    ``slower`` (box heights a frame) only the boxes that moved less than that since the same
    person's box in the previous frame."""
    out = []
    by_frame = gt.by_frame()
    for k in range(frames):
        mask = np.zeros(shape, bool)
        before = {int(gt.ids[i]): gt.boxes[i] for i in by_frame.get(frame_number(k - 1), [])}
        for i in by_frame.get(frame_number(k), []):
            x, y, w, h = gt.boxes[i]
            last = before.get(int(gt.ids[i]))
            if slower is not None and (last is None or np.hypot(
                    x + w / 2 - last[0] - last[2] / 2, y + h / 2 - last[1] - last[3] / 2) >= slower * h):
                continue
            box = (x - 0.1 * w, y - 0.1 * h, 1.2 * w, 1.2 * h)
            x1, y1, x2, y2 = pixel_window(box, scale, shape)
            mask[y1:y2, x1:x2] = True
        out.append(mask)
    return out


def cpu_ms(overrides: list[str], frames: list[np.ndarray], protect: list | None, fps: float) -> float:
    cfg = load_config(None, overrides)
    det = create_detector(cfg.motion, fps)
    t = time.process_time()
    for k, f in enumerate(frames):
        raw = det.apply(f, protect[k]) if protect is not None else det.apply(f)
        clean_mask(raw, cfg.cleanup)
    return (time.process_time() - t) / len(frames) * 1e3


def main() -> None:
    args, video, gt = pets_args(__doc__, repeat=7)
    cv2.setNumThreads(1)
    cap = cv2.VideoCapture(str(video))
    fps = cap.get(cv2.CAP_PROP_FPS) or 25.0
    images = []
    while len(images) < args.frames:
        ok, image = cap.read()
        if not ok:
            break
        images.append(image)
    h, w = images[0].shape[:2]
    pipe = Pipeline(PipelineConfig(), (w, h), None, fps)
    frames = [preprocess(im, pipe.pre_cfg) for im in images]
    masks = protect_masks(gt, len(frames), pipe.scale, frames[0].shape[:2])
    slow = protect_masks(gt, len(frames), pipe.scale, frames[0].shape[:2],
                         PipelineConfig().motion.knn.hold_speed / fps)
    names = list(MODELS)
    times: dict[str, list[float]] = {n: [] for n in names}
    cpu_ms(MODELS["vibe"][0], frames[:20], None, fps)   # first calls outside the timing
    for r in range(args.repeat):
        for n in (names if r % 2 == 0 else names[::-1]):
            overrides, protect = MODELS[n]
            boxes = slow if protect == "slow" else masks if protect else None
            times[n].append(cpu_ms(overrides, frames, boxes, fps))
    fh, fw = frames[0].shape[:2]
    print(f"PETS09-S2L1, {len(frames)} frames at {fw}x{fh}, OpenCV threads = 1, CPU ms per frame "
          f"(model + clean-up), median [min-max] of {args.repeat} interleaved rounds")
    for n in names:
        t = times[n]
        print(f"{n:<30}{statistics.median(t):>7.2f}  [{min(t):.2f}-{max(t):.2f}]")


if __name__ == "__main__":
    main()
