"""Foreground that stops moving: stop-and-go synthetic scenes with exact boxes through the
pipeline, each motion model side by side; then the cost of the dual background (static foreground
for ``abandoned``) next to the motion detector.

Scenes (320x240 at 10 fps, noise 3.5 grey levels, built here from :mod:`motiontrack.synth`):

  person stops   walks in, stands ``--stand`` seconds (default 30) on plain ground, walks out.
                 Printed: track ids that cover the person (IoU >= 0.5) over the whole scene,
                 identity switches among them, recall while standing (frames with a matching
                 track / standing frames).
  bag set down   ``synth:leftbag``: someone sets a bag down and walks off. Printed: share of the
                 frames from the drop on where the pipeline's mask covers at least half the bag's
                 box (the bag stays foreground), and the first frame of a ``static`` object on it
                 (the dual background, whose ``confirm_s`` the ``abandoned`` rule counts from).
  car parks      a car (a 60x26 px box with windows) drives in at 4 px a frame and parks for
                 ``--park`` seconds (default 200). Printed: seconds after parking until the mask
                 covers less than a tenth of it (it became background).
  car leaves     the same car stands there from the first frame and drives off after 10 s.
                 Printed: frames after it left until its old place is out of the mask (ghost).

Rows: the default motion model (KNN with its hold, ``accept_s`` 180: the parked car's bound), KNN
alone (``motion.knn.hold=false``), ``vibe`` with its selective update (``accept_s`` 180), and
``vibe`` without it.

Run: .venv/bin/python benchmarks/static_foreground.py [--data ../shared/data] [--repeat 3]
         [--stand 30] [--park 200] [--no-cost] [--scenes person,bag,parks,leaves] [--rows ...]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import cv2
import numpy as np

from motiontrack.config import PipelineConfig, load_config
from motiontrack.motion import create_detector
from motiontrack.motion.static import DualBackground
from motiontrack.pipeline import Pipeline, open_configured_source
from motiontrack.synth import parse_synth_spec
from motiontrack.synth.render import Person
from motiontrack.synth.sequence import SyntheticScene
from motiontrack.tracking.association import iou_matrix
from motiontrack.types import Frame

FPS = 10.0
W, H = 320, 240
ROWS = {
    "knn + hold (default)": ["motion.method=knn"],
    "knn hold=false": ["motion.method=knn", "motion.knn.hold=false"],
    "vibe (selective update)": ["motion.method=vibe"],
    "vibe protect=false": ["motion.method=vibe", "motion.vibe.protect=false"],
}


def _pipeline(overrides: list[str], static: bool = False) -> Pipeline:
    return Pipeline(load_config(None, ["preprocess.scale=1.0", *overrides]), (W, H), fps=FPS,
                    static=static)


def person_stops(overrides: list[str], stand_s: float) -> str:
    walk_to, stand = 40, int(stand_s * FPS)
    p = Person(id=1, x0=-15.0, y0=200.0, vx=3.0, vy=0.0, height=70.0, t0=2.0,
               turns=((float(walk_to), 0.0, 0.0), (float(walk_to + stand), 3.0, 0.0)))
    scene = SyntheticScene("stop", 0, W, H, FPS, walk_to + stand + 70, people=(p,))
    gt = scene.ground_truth().by_frame()
    boxes = scene.ground_truth().boxes
    pipe = _pipeline(overrides)
    ids: list[int] = []
    still = 0
    for i in range(scene.n_frames):
        r = pipe.process(Frame(index=i, image=scene.frame(i), timestamp=i / FPS))
        rows = gt.get(i + 1, [])
        if not len(rows) or not r.tracks:
            continue
        iou = iou_matrix(boxes[rows[:1]], np.array([t.box.as_array() for t in r.tracks]))[0]
        k = int(np.argmax(iou))
        if iou[k] >= 0.5:
            if not ids or ids[-1] != r.tracks[k].id:
                ids.append(r.tracks[k].id)
            still += walk_to <= i < walk_to + stand
    switches = len(ids) - 1
    return (f"ids {len(set(ids))}, switches {max(switches, 0)}, recall while still "
            f"{still / stand:.3f}")


def bag_set_down(overrides: list[str]) -> str:
    scene = parse_synth_spec("synth:leftbag?seed=0&width=320&height=240")
    bag = scene.bags[0]
    gt = scene.ground_truth()
    rows = [k for k in range(len(gt.frames)) if gt.ids[k] == bag.id]
    box = gt.boxes[rows[-1]].astype(int)
    pipe = Pipeline(load_config(None, ["preprocess.scale=1.0", *overrides]),
                    (scene.width, scene.height), fps=scene.fps, static=True)
    covered = after = 0
    static_at = None
    for i in range(scene.n_frames):
        r = pipe.process(Frame(index=i, image=scene.frame(i), timestamp=i / scene.fps))
        if i < bag.t_drop:
            continue
        after += 1
        x, y, w, h = box
        m = r.mask[max(y, 0):y + h, max(x, 0):x + w] if r.mask is not None else None
        covered += m is not None and m.size and (m > 0).mean() >= 0.5
        if static_at is None and r.static is not None and any(
                iou_matrix(box[None].astype(float), o.box.as_array()[None])[0, 0] > 0.3
                for o in r.static.objects):
            static_at = i
    when = "never" if static_at is None else f"{(static_at - bag.t_drop) / scene.fps:.1f} s"
    return f"bag in the mask {covered / max(after, 1):.3f} of the frames; static object after {when}"


def _car_scene(n: int) -> SyntheticScene:
    return SyntheticScene("car", 1, W, H, FPS, n)


def _draw_car(img: np.ndarray, x: float) -> None:
    x = int(round(x))
    cv2.rectangle(img, (x, 150), (x + 60, 176), (40, 40, 170), -1)
    cv2.rectangle(img, (x + 12, 154), (x + 46, 162), (60, 50, 40), -1)


def car_parks(overrides: list[str], park_s: float) -> str:
    arrive, stop_x = 60, 130.0
    n = arrive + int(park_s * FPS)
    scene = _car_scene(n)
    pipe = _pipeline(overrides)
    gone = None
    for i in range(n):
        img = scene.frame(i).copy()
        _draw_car(img, min(-60 + 4 * (i - (arrive - 47)), stop_x) if i >= arrive - 47 else -100)
        r = pipe.process(Frame(index=i, image=img, timestamp=i / FPS))
        if i > arrive and gone is None and (r.mask[150:176, 130:190] > 0).mean() < 0.1:
            gone = i
    return "still foreground at the end" if gone is None else \
        f"background {(gone - arrive) / FPS:.1f} s after parking"


def car_leaves(overrides: list[str]) -> str:
    leave = 100
    n = leave + 120
    scene = _car_scene(n)
    pipe = _pipeline(overrides)
    clear = None
    for i in range(n):
        img = scene.frame(i).copy()
        _draw_car(img, 130.0 + max(0, i - leave) * 4.0)
        r = pipe.process(Frame(index=i, image=img, timestamp=i / FPS))
        if i > leave + 16 and clear is None and (r.mask[150:176, 130:190] > 0).mean() < 0.1:
            clear = i
    return "ghost to the end" if clear is None else \
        f"old place clear {clear - leave - 15} frames after the car left it"
REPO = Path(__file__).resolve().parents[1]


def best_ms(make, frames, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        model = make()
        t = time.perf_counter()
        for f in frames:
            model.apply(f)
        best = min(best, (time.perf_counter() - t) / len(frames) * 1e3)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=os.environ.get("MOTIONTRACK_DATA",
                                                     str(REPO.parent / "shared" / "data")))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--stand", type=float, default=30.0, help="seconds the person stands")
    ap.add_argument("--park", type=float, default=200.0, help="seconds the car stays parked")
    ap.add_argument("--no-cost", action="store_true", help="only the scenes")
    ap.add_argument("--scenes", default="person,bag,parks,leaves",
                    help="comma-separated: person, bag, parks, leaves")
    ap.add_argument("--rows", default=",".join(ROWS), help="comma-separated rows to run")
    args = ap.parse_args()
    scenes = args.scenes.split(",")
    for name in args.rows.split(","):
        overrides = ROWS[name]
        print(f"== {name}  ({' '.join('--set ' + o for o in overrides)})")
        if "person" in scenes:
            print(f"  person stops {args.stand:.0f} s: {person_stops(overrides, args.stand)}")
        if "bag" in scenes:
            print(f"  bag set down: {bag_set_down(overrides)}")
        if "parks" in scenes:
            print(f"  car parks {args.park:.0f} s: {car_parks(overrides, args.park)}")
        if "leaves" in scenes:
            print(f"  car leaves: {car_leaves(overrides)}")
    if args.no_cost:
        return
    sources = ["synth:leftbag?seed=0"]
    pets = Path(args.data) / "pets09-s2l1" / "video.avi"
    if pets.exists():
        sources.append(str(pets))
    cfg = PipelineConfig()
    print(f"{'source':42s} {'size':>9s} {'detector ms':>11s} {'dual ms':>8s} {'share':>6s}")
    for spec in sources:
        src = open_configured_source(spec, cfg.source)
        fps = src.info.fps or 25.0
        pipe = Pipeline(cfg, (src.info.width, src.info.height), fps=fps)
        frames = [pipe.prepare(f) for f in src]
        src.close()
        det = best_ms(lambda: create_detector(cfg.motion), frames, args.repeat)
        dual = best_ms(lambda: DualBackground(fps, pipe.scale), frames, args.repeat)
        h, w = frames[0].shape[:2]
        print(f"{spec[-42:]:42s} {w:>4d}x{h:<4d} {det:11.2f} {dual:8.2f} {dual / det:6.0%}")


if __name__ == "__main__":
    main()
