"""Where a frame's time goes: each stage of the default pipeline timed on its own, in one thread.

The pipeline spreads its work over three threads (decoding; preprocessing + motion detector +
mask clean-up; regions, ghosts, head splitting and tracking), so its frame rate depends on how
those add up on the machine's cores. This script times the stages one after another in a single
thread with OpenCV held to one thread, frames decoded beforehand, and prints the milliseconds
per frame of each (best of ``--repeat`` runs over the clip):

  decode             cv2.VideoCapture.read()
  preprocess         resize to the processing scale (and blur)
  motion detector    the motion stage (Pipeline.feedback and Pipeline.stage.apply): the boxes
                     of the tracks that have slowed down, camera-motion compensation, the KNN
                     model with its hold, the sudden-change check
  mask clean-up      motion.cleanup
  ghosts + regions   the ghost filter and the mask's regions (Pipeline.regions_of, without
                     the head splitting)
  head splitting     merged regions split between heads (Pipeline._split_upright)
  tracker            Pipeline.track (association, Kalman update, appearance)
  classes            the track classifier (classes.enabled: votes of each measured track,
                     HOG on a few of their boxes)

The last three are the tracking thread's work. Stage times measured one at a time include cache
effects of the stages around them (the KNN model is 9 MB at 384x288), so they add up to more than
the motion-mask-only row of ``benchmarks/throughput.py``.

It then times the motion stage again without compensation and sudden-change check
(``stabilize.enabled=false``, ``motion.relearn_fraction=0``, ``motion.relearn_brightness=0``),
the two runs interleaved, and prints the medians over the repeats of both and of their
difference: what compensation costs a frame on a fixed camera (it measures the camera's motion
every frame and warps nothing); and, interleaved the same way, without the hold
(``motion.knn.hold=false``): what the hold costs a frame.

Run: .venv/bin/python benchmarks/stages.py [--data ../shared/data] [--frames 300] [--repeat 5]
"""

from __future__ import annotations

import statistics
import time

import cv2

from motiontrack.config import PipelineConfig, load_config
from motiontrack.motion.cleanup import clean_mask
from motiontrack.pipeline import Detection, Motion, Pipeline
from motiontrack.preprocess import preprocess
from motiontrack.types import Frame

from _pets import pets_args  # benchmarks/ is on sys.path when a script here runs

STAGES = ("preprocess", "motion detector", "mask clean-up", "ghosts + regions", "head splitting",
          "tracker", "classes")


def one_run(frames: list, cfg: PipelineConfig, fps: float) -> dict[str, float]:
    """Milliseconds per frame of each stage over ``frames``, with a fresh pipeline."""
    h, w = frames[0].shape[:2]
    pipe = Pipeline(cfg, (w, h), None, fps)
    classes, pipe.classes = pipe.classes, None   # timed on its own after the tracker
    spent = dict.fromkeys(STAGES, 0.0)
    clock = time.perf_counter
    for k, image in enumerate(frames):
        frame = Frame(index=k, timestamp=k / fps, image=image)
        t0 = clock()
        small = preprocess(image, pipe.pre_cfg)
        t1 = clock()
        fb = pipe.feedback(frame, small)
        out = pipe.stage.apply(small, fb.protect, fb.relearn)
        raw = out.raw
        t2 = clock()
        mask = clean_mask(raw, cfg.cleanup)
        t3 = clock()
        if pipe.ghosts is not None:
            mask, regions = pipe.ghosts.regions(small, mask, pipe._find, pipe.scale,
                                                keep=out.held)
            if pipe.detector.relearns:
                pipe._relearn = pipe.ghosts.ghost_pixels(mask.shape[:2])
        else:
            regions = pipe._find(mask)
        t4 = clock()
        heads = None
        if regions:
            regions, heads = pipe._split_upright(mask, regions)
        t5 = clock()
        result = pipe.track(frame, Detection(Motion(mask, raw, small), mask, regions, heads))
        t6 = clock()
        classes.update(result.tracks, image=small, scale=pipe.scale)
        t7 = clock()
        for name, a, b in zip(STAGES, (t0, t1, t2, t3, t4, t5, t6), (t1, t2, t3, t4, t5, t6, t7)):
            spent[name] += b - a
    return {k: v * 1000 / len(frames) for k, v in spent.items()}


def main() -> None:
    args, video, _ = pets_args(__doc__, repeat=5)
    cfg = PipelineConfig()
    if cfg.motion.method != "knn" or cfg.people.enabled:
        raise SystemExit("this script times the default configuration (KNN, people stage off)")
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        cap = cv2.VideoCapture(str(video))
        fps = cap.get(cv2.CAP_PROP_FPS) or 25.0
        frames = []
        while len(frames) < args.frames:
            ok, image = cap.read()
            if not ok:
                break
            frames.append(image)
        # decoding timed on a second pass that keeps no frame (storing them costs page faults)
        cap = cv2.VideoCapture(str(video))
        t = time.perf_counter()
        for _ in frames:
            cap.read()
        decode = (time.perf_counter() - t) * 1000 / max(len(frames), 1)
        bare = load_config(None, ["stabilize.enabled=false", "motion.relearn_fraction=0",
                                  "motion.relearn_brightness=0"])
        one_run(frames[:20], cfg, fps)   # imports and first calls outside the timing
        no_hold = load_config(None, ["motion.knn.hold=false"])
        runs, bares, plains = [], [], []
        for _ in range(args.repeat):
            runs.append(one_run(frames, cfg, fps))
            bares.append(one_run(frames, bare, fps))
            plains.append(one_run(frames, no_hold, fps))
    finally:
        cv2.setNumThreads(threads)
    best = {k: min(r[k] for r in runs) for k in STAGES}
    print(f"PETS09-S2L1, {len(frames)} frames, one thread, OpenCV threads = 1, best of "
          f"{args.repeat} runs (ms per frame)")
    print(f"{'decode':<20}{decode:>7.2f}  (one pass)")
    for k in STAGES:
        print(f"{k:<20}{best[k]:>7.2f}")
    work = sum(best.values())
    tracking = sum(best[k] for k in STAGES[3:])
    print(f"{'all stages':<20}{work:>7.2f}  (+ decode {work + decode:.2f}); tracking thread's "
          f"share {tracking:.2f}")
    key = "motion detector"
    with_, without = ([r[key] for r in rs] for rs in (runs, bares))
    print(f"motion stage, medians of {args.repeat}: {statistics.median(with_):.2f} ms, without "
          f"compensation and sudden-change check {statistics.median(without):.2f} ms, "
          f"difference {statistics.median(a - b for a, b in zip(with_, without)):.2f} ms")
    plain = [r[key] for r in plains]
    print(f"motion stage without the hold (motion.knn.hold=false), median {statistics.median(plain):.2f}"
          f" ms, difference {statistics.median(a - b for a, b in zip(with_, plain)):.2f} ms")


if __name__ == "__main__":
    main()
