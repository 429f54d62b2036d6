"""A shaking camera, simulated on real footage: PETS 2009 S2L1 frames 1-300 and CDnet 2014
highway frames 1-1000, each frame seen through a window moved by a known random whole-pixel
offset (uniform in [-A, A] in x and y, drawn anew every frame, seeded), the ground truth moved
with it. Printed side by side: the steady window (fixed at the centre) with camera-motion
compensation (the default) and without it (``stabilize.enabled=false``: what compensation costs
a fixed camera), and the shaking window with and without it. One run's HOTA moves by a few hundredths with any change of the
masks (a swap of two identities), so each row is the mean over ``--seeds`` runs: run ``k`` draws
the shake with seed ``k`` and seeds the KNN model with ``k`` (``motion.knn.seed``), the steady
row too; the range over the runs follows the first score.

The window is the frame less A pixels on every side, so every row sees the same area of the
scene (PETS 760x568 at A = 4, processed at the automatic scale; highway 312x232). Scores:
PETS HOTA / MOTA / IDF1 against the moved MOT ground truth (rows with consider = 0 as ignore
regions, as benchmarks/_pets.py); highway the CDnet F-measure of the pipeline's motion mask
against the moved ground-truth masks over the temporal ROI (frames 470-1000, ROI.bmp moved too).

With ``--cost ROUNDS`` it instead times whole ``motiontrack track PETS --no-video`` processes
(300 frames, fixed camera) with and without compensation and sudden-change check, the two
alternating, and prints the medians over the rounds of wall time and CPU time (user + sys)
and of each round's difference; then, in one thread with OpenCV held to one thread and the
frames preprocessed beforehand, ms per frame (medians over the rounds) of the stabilizer alone
(``Stabilizer.apply``) on the steady and the shaking PETS window, and of the motion stage
(``Pipeline.stage.apply``) on the shaking window with and without compensation.

Run: .venv/bin/python benchmarks/jitter.py [--data ../shared/data] [--amplitude 4] [--seeds 3]
         [--set KEY=VALUE ...]   (config overrides for every row)
     .venv/bin/python benchmarks/jitter.py --cost 5
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from motiontrack.config import StabilizeConfig, load_config
from motiontrack.evaluate.masks import MaskCounts, compare_masks, read_temporal_roi
from motiontrack.evaluate.mot import evaluate_tracking
from motiontrack.io.mot import read_mot
from motiontrack.motion.stabilize import Stabilizer
from motiontrack.pipeline import Pipeline
from motiontrack.synth.camera import shake_offsets, shift_annotations
from motiontrack.types import Annotations, Frame, frame_number

from _pets import add_data_argument  # benchmarks/ is on sys.path when a script here runs

PETS_FRAMES = 300
HIGHWAY_FRAMES = 1000
OFF = ["stabilize.enabled=false"]


def _window(image: np.ndarray, a: int, offset) -> np.ndarray:
    """``image`` less ``a`` px on every side, moved by ``offset`` (dx, dy)."""
    h, w = image.shape[:2]
    x0, y0 = a + int(offset[0]), a + int(offset[1])
    return image[y0:y0 + h - 2 * a, x0:x0 + w - 2 * a]


def _frames(images: list[np.ndarray], a: int, offsets: np.ndarray, fps: float) -> list[Frame]:
    return [Frame(index=k, image=np.ascontiguousarray(_window(img, a, offsets[k])),
                  timestamp=k / fps) for k, img in enumerate(images)]


def _results(frames: list[Frame], overrides: list[str], fps: float):
    cfg = load_config(None, overrides)
    h, w = frames[0].image.shape[:2]
    return Pipeline(cfg, (w, h), fps=fps).results(frames)


def pets_scores(images, gt: Annotations, a: int, offsets, fps: float, overrides) -> dict:
    frames = _frames(images, a, offsets, fps)
    rows = [(frame_number(f), t.id, *t.box.as_array())
            for r in _results(frames, overrides, fps) for f, t in r.reported]
    arr = np.array(rows, float).reshape(-1, 6)
    pred = Annotations.from_columns(arr[:, 0], arr[:, 1], arr[:, 2:6])
    h, w = frames[0].image.shape[:2]
    moved = shift_annotations(gt, offsets, w, h, origin=(a, a))
    res = evaluate_tracking(moved, pred, ignore_zero_marked=True)
    return {k: res[k] for k in ("HOTA", "MOTA", "IDF1")}


def highway_f(images, gts, roi, first: int, a: int, offsets, fps: float, overrides) -> dict:
    frames = _frames(images, a, offsets, fps)
    total = MaskCounts()
    for k, r in enumerate(_results(frames, overrides, fps)):
        if k + 1 < first:
            continue
        gt = _window(gts[k], a, offsets[k])
        mask = r.mask if r.mask.shape == gt.shape else cv2.resize(
            r.mask, gt.shape[::-1], interpolation=cv2.INTER_NEAREST)
        total = total + compare_masks(gt, mask, _window(roi, a, offsets[k]))
    m = total.metrics()
    return {"F": m["f_measure"], "recall": m["recall"], "precision": m["precision"]}


def _read_video(path: Path, n: int) -> tuple[list[np.ndarray], float]:
    cap = cv2.VideoCapture(str(path))
    fps = cap.get(cv2.CAP_PROP_FPS) or 25.0
    out = []
    while len(out) < n:
        ok, img = cap.read()
        if not ok:
            break
        out.append(img)
    return out, fps


def _table(title: str, rows: list[tuple[str, list[dict], float]]) -> None:
    keys = list(rows[0][1][0])
    print(title)
    print(f"{'window (mean of the seeds)':<34}" + "".join(f"{k:>10}" for k in keys)
          + f"{'range ' + keys[0]:>16}{'s':>7}")
    for name, runs, secs in rows:
        first = [r[keys[0]] for r in runs]
        print(f"{name:<34}" + "".join(f"{np.mean([r[k] for r in runs]):>10.3f}" for k in keys)
              + f"{min(first):>10.3f}-{max(first):.3f}{secs:>7.1f}")


def _rows(score, a: int, n: int, seeds: int, extra: list[str]
          ) -> list[tuple[str, list[dict], float]]:
    out = []
    for name, shaking, ov in (("steady", False, []),
                              ("steady, not compensated", False, OFF),
                              (f"shaking +-{a} px, compensated", True, []),
                              (f"shaking +-{a} px, not compensated", True, OFF)):
        t = time.perf_counter()
        runs = [score(shake_offsets(n, a, k) if shaking else np.zeros((n, 2), int),
                      [*extra, *ov, f"motion.knn.seed={k}"]) for k in range(seeds)]
        out.append((name, runs, time.perf_counter() - t))
    return out


BARE = ["stabilize.enabled=false", "motion.relearn_fraction=0", "motion.relearn_brightness=0"]


def _process(video: Path, overrides: list[str]) -> tuple[float, float]:
    """Wall and CPU seconds of one ``motiontrack track VIDEO --no-video`` process."""
    exe = Path(sys.executable).with_name("motiontrack")
    with tempfile.TemporaryDirectory() as out:
        cmd = [str(exe), "track", str(video), "--no-video", "--max-frames", str(PETS_FRAMES),
               "-o", out, "--force", *[a for o in overrides for a in ("--set", o)]]
        t = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t
    if status != 0:
        sys.exit(f"{' '.join(cmd)} failed ({status})")
    return wall, usage.ru_utime + usage.ru_stime


def cost(video: Path, rounds: int) -> None:
    """Print the medians of :func:`_process` with and without compensation."""
    on, off = [], []
    for k in range(rounds):
        pair = [(on, []), (off, BARE)]
        for runs, ov in (pair if k % 2 == 0 else pair[::-1]):
            runs.append(_process(video, ov))
    med = statistics.median
    print(f"track --no-video, PETS frames 1-{PETS_FRAMES}, medians of {rounds} rounds")
    for name, runs in (("with compensation (default)", on), ("without", off)):
        print(f"{name:<30}wall {med(r[0] for r in runs):6.2f} s   CPU {med(r[1] for r in runs):6.2f} s")
    print(f"{'difference':<30}wall {med(a[0] - b[0] for a, b in zip(on, off)):6.2f} s   "
          f"CPU {med(a[1] - b[1] for a, b in zip(on, off)):6.2f} s")
    images, fps = _read_video(video, PETS_FRAMES)
    a = 4
    steady = _frames(images, a, np.zeros((len(images), 2), int), fps)
    shaken = _frames(images, a, shake_offsets(len(images), a, 0), fps)
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        on_ms, off_ms, alone = [], [], {"steady": [], "shaking": []}
        for _ in range(rounds):
            on_ms.append(_stage_ms(shaken, [], fps))
            off_ms.append(_stage_ms(shaken, BARE, fps))
            for name, frames in (("steady", steady), ("shaking", shaken)):
                alone[name].append(_stabilizer_ms(frames, fps))
    finally:
        cv2.setNumThreads(threads)
    print(f"one thread, ms per frame (medians of {rounds}):")
    for name, runs in alone.items():
        print(f"  stabilizer alone, {name} window{'':<14}{med(runs):6.2f}")
    print(f"  motion stage, shaking window, with     {med(on_ms):6.2f}")
    print(f"  motion stage, shaking window, without  {med(off_ms):6.2f}  (difference "
          f"{med(x - y for x, y in zip(on_ms, off_ms)):.2f})")


def _stabilizer_ms(frames: list[Frame], fps: float) -> float:
    """Milliseconds per frame of :meth:`Stabilizer.apply` over ``frames`` (preprocessed first)."""
    h, w = frames[0].image.shape[:2]
    pipe = Pipeline(load_config(), (w, h), fps=fps)
    smalls = [pipe.prepare(f) for f in frames]
    stab = Stabilizer(StabilizeConfig())
    t = time.perf_counter()
    for small in smalls:
        stab.apply(small)
    return (time.perf_counter() - t) * 1000 / len(smalls)


def _stage_ms(frames: list[Frame], overrides: list[str], fps: float) -> float:
    """Milliseconds per frame of ``Pipeline.stage.apply`` over ``frames`` (preprocessed first)."""
    h, w = frames[0].image.shape[:2]
    pipe = Pipeline(load_config(None, overrides), (w, h), fps=fps)
    smalls = [pipe.prepare(f) for f in frames]
    t = time.perf_counter()
    for small in smalls:
        pipe.stage.apply(small)
    return (time.perf_counter() - t) * 1000 / len(smalls)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    add_data_argument(ap)
    ap.add_argument("--amplitude", type=int, default=4, help="largest offset (px) in x and y")
    ap.add_argument("--seeds", type=int, default=3, help="runs per row (shake and KNN seeds)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="config override for every row (repeatable)")
    ap.add_argument("--cost", type=int, default=0, metavar="ROUNDS",
                    help="time whole track processes with and without compensation instead")
    args = ap.parse_args()
    data, a = Path(args.data), args.amplitude
    video = data / "pets09-s2l1" / "video.avi"
    if args.cost:
        if not video.is_file():
            sys.exit(f"PETS clip not found: {video} (set MOTIONTRACK_DATA or --data)")
        cost(video, args.cost)
        return
    highway = data / "cdnet-highway"
    if not video.is_file() or not (highway / "input").is_dir():
        sys.exit(f"PETS clip or CDnet highway not found in {data} (set MOTIONTRACK_DATA or --data)")

    images, fps = _read_video(video, PETS_FRAMES)
    gt = read_mot(video.parent / "gt_mot15.txt", kind="gt")
    gt = gt.select(gt.frames <= len(images))
    _table(f"PETS09-S2L1 frames 1-{len(images)}, window {images[0].shape[1] - 2 * a}x"
           f"{images[0].shape[0] - 2 * a}",
           _rows(lambda off, ov: pets_scores(images, gt, a, off, fps, ov), a, len(images),
                 args.seeds, args.set))

    first, last = read_temporal_roi(highway / "temporalROI.txt")
    last = min(last, HIGHWAY_FRAMES)
    names = sorted((highway / "input").glob("in*.jpg"))[:last]
    images = [cv2.imread(str(p)) for p in names]
    gts = [cv2.imread(str(highway / "groundtruth" / f"gt{k + 1:06d}.png"), cv2.IMREAD_GRAYSCALE)
           for k in range(len(images))]
    roi = cv2.imread(str(highway / "ROI.bmp"), cv2.IMREAD_GRAYSCALE)
    print()
    _table(f"CDnet highway frames {first}-{last} (run from 1), window "
           f"{images[0].shape[1] - 2 * a}x{images[0].shape[0] - 2 * a}",
           _rows(lambda off, ov: highway_f(images, gts, roi, first, a, off, 25.0, ov), a,
                 len(images), args.seeds, args.set))


if __name__ == "__main__":
    main()
