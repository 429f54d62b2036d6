"""Public detections, different association: motiontrack against SORT, ByteTrack and OC-SORT.

The three MOT15 training sequences of ``../shared/data/mot15-dev`` (TUD-Campus, ETH-Sunnyday,
KITTI-17: ground truth, SORT's published Faster R-CNN detections, ``seqinfo.ini``; no images)
are tracked from the same ``det.txt`` by every tracker and scored with motiontrack's evaluator
(CLEAR-MOT, Identity and HOTA as TrackEval, sequences combined as TrackEval combines them):

* ``motiontrack``: what ``motiontrack track --detections det.txt`` runs, the ``detections``
  preset (ByteTrack's score stages with OC-SORT's observation-centric steps), with the rows
  ``tracks.txt`` gets (tentative frames of confirmed tracks, gaps of up to 0.3 s filled);
* ``motiontrack SORT settings``: the same tracker with SORT's settings (every detection in one
  IoU stage gated at 0.3, no direction term, no recovery or re-update, confirmed after 3 hits,
  deleted after 1 unseen frame, online rows only);
* when installed in the environment (they are no dependencies of motiontrack): ``supervision``'s
  ``ByteTrack`` and the ``trackers`` package's ``SORTTracker``, ``ByteTrackTracker`` and
  ``OCSORTTracker``, each with its defaults and the sequence's frame rate.

One setting for every sequence: no tracker is tuned per sequence. ``fps`` is detection frames
per second of the association alone: frames over the CPU time of this thread in the trackers'
update calls (one core; CPU time rather than wall time, so that other processes on a shared
machine do not count), the best of ``--repeat`` runs; ``split s`` is ``motiontrack track --detections-folder`` over the whole split in a new
process, from its start to its exit. SORT's own figures for these detections are in
``mot15-dev/README.md``.

``--pets`` runs ``benchmarks/detections_pets.py`` instead (PETS 2009 tracked from detections
made out of its ground truth, with a detector's errors).

Run: .venv/bin/python benchmarks/detections.py [--data ../shared/data] [--repeat 3]
     [--set stage.param=value ...]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable

import numpy as np

from motiontrack.config import load_config
from motiontrack.evaluate.benchmark import evaluate_tracker, flatten_benchmark
from motiontrack.io.mot import read_mot, read_seqinfo
from motiontrack.pipeline import fill_gap_frames
from motiontrack.tracking.detections import DetectionTracker
from motiontrack.tracking.gaps import fill_gaps
from motiontrack.types import Annotations

REPO = Path(__file__).resolve().parents[1]
SEQUENCES = ("ETH-Sunnyday", "KITTI-17", "TUD-Campus")
KEYS = ("HOTA", "MOTA", "IDF1", "IDSW")
#: SORT with our tracker: one IoU stage over every detection (Bewley et al. 2016: IoU gate 0.3,
#: min_hits 3, max_age 1), no score stages, direction, recovery, re-update or added rows
SORT_SETTINGS = ("tracker.detections.high_score=0", "tracker.detections.new_score=0",
                 "tracker.detections.low_score=0", "tracker.detections.inertia=0",
                 "tracker.detections.recover=false", "tracker.detections.reupdate=false",
                 "tracker.backfill=false", "tracker.fill_gaps_s=0", "tracker.confirm_hits=3")


class Sequence:
    """One sequence: its detections frame by frame, ground truth and seqinfo."""

    def __init__(self, root: Path, name: str) -> None:
        info = read_seqinfo(root / name)
        self.name = name
        self.size = (int(info["imwidth"]), int(info["imheight"]))
        self.fps = float(info["framerate"])
        self.length = int(info["seqlength"])
        det = read_mot(root / name / "det" / "det.txt", kind="det")
        index = det.by_frame()
        empty = np.zeros(0, np.int64)
        self.frames = [(det.boxes[index.get(f, empty)].astype(np.float64),
                        det.scores[index.get(f, empty)].astype(np.float64))
                       for f in range(1, self.length + 1)]
        self.gt = read_mot(root / name / "gt" / "gt.txt", kind="gt")


def _table(rows: list[tuple]) -> Annotations:
    a = np.array(rows, np.float64).reshape(-1, 6)
    return Annotations.from_columns(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), a[:, 2:6])


def ours(overrides: list[str], one_frame_max_lost: bool = False) -> Callable:
    """A runner of motiontrack's detection tracker with the ``detections`` preset and
    ``overrides``: ``(sequence) -> (tracks, seconds in update)``."""
    def run(seq: Sequence) -> tuple[Annotations, float]:
        extra = [f"tracker.max_lost_s={1.0 / seq.fps!r}"] if one_frame_max_lost else []
        cfg = load_config(None, [*overrides, *extra], preset="detections")
        trk = DetectionTracker(cfg.tracker, seq.size, seq.fps)
        trk.keep_tentative = cfg.tracker.backfill
        rows: list[tuple] = []
        spent = 0.0
        for f, (boxes, scores) in enumerate(seq.frames, start=1):
            t0 = time.thread_time()
            tracks = trk.update(boxes, scores)
            spent += time.thread_time() - t0
            rows += [(f, t.id, *t.box.as_array()) for t in tracks]
            rows += [(e + 1, t.id, *t.box.as_array()) for e, t in trk.confirmed_earlier]
        return fill_gaps(_table(rows), fill_gap_frames(cfg, seq.fps, True)), spent
    return run


def peer(make: Callable, sv) -> Callable:
    """A runner of a tracker of the ``trackers``/``supervision`` packages, made by
    ``make(fps)``, fed ``supervision.Detections`` (corners, confidence)."""
    def run(seq: Sequence) -> tuple[Annotations, float]:
        trk = make(seq.fps)
        rows: list[tuple] = []
        spent = 0.0
        for f, (boxes, scores) in enumerate(seq.frames, start=1):
            xyxy = np.column_stack([boxes[:, :2], boxes[:, :2] + boxes[:, 2:]]).astype(np.float32)
            d = sv.Detections(xyxy=xyxy.reshape(-1, 4), confidence=scores.astype(np.float32),
                              class_id=np.zeros(len(boxes), int))
            t0 = time.thread_time()
            out = trk.update_with_detections(d) if hasattr(trk, "update_with_detections") \
                else trk.update(d)
            spent += time.thread_time() - t0
            ids = out.tracker_id if out.tracker_id is not None else []
            rows += [(f, int(i), x1, y1, x2 - x1, y2 - y1)
                     for (x1, y1, x2, y2), i in zip(out.xyxy.tolist(), ids) if i is not None and i >= 0]
        return _table(rows), spent
    return run


def peers() -> list[tuple[str, Callable]]:
    """The peers installed in this environment (none when neither package is)."""
    out: list[tuple[str, Callable]] = []
    try:
        import supervision as sv
    except ImportError:
        return out
    if hasattr(sv, "ByteTrack"):
        out.append(("supervision ByteTrack",
                     peer(lambda fps: sv.ByteTrack(frame_rate=int(round(fps))), sv)))
    try:
        import trackers
    except ImportError:
        return out
    for label, name in (("trackers SORT", "SORTTracker"), ("trackers ByteTrack", "ByteTrackTracker"),
                        ("trackers OC-SORT", "OCSORTTracker")):
        cls = getattr(trackers, name, None)
        if cls is not None:
            out.append((label, peer(lambda fps, cls=cls: cls(frame_rate=fps), sv)))
    return out


def score(runner: Callable, seqs: list[Sequence], repeat: int) -> tuple[dict, float]:
    """COMBINED :data:`KEYS` of ``runner`` over ``seqs`` and its association frames a second
    (the best of ``repeat`` runs of each sequence)."""
    pred, seconds = {}, 0.0
    for seq in seqs:
        best = None
        for _ in range(repeat):
            tracks, spent = runner(seq)
            best = spent if best is None else min(best, spent)
        pred[seq.name] = tracks
        seconds += best
    res = flatten_benchmark(evaluate_tracker({s.name: s.gt for s in seqs},
                                             {s.name: s.length for s in seqs}, pred))
    frames = sum(s.length for s in seqs)
    return res["COMBINED"], frames / max(seconds, 1e-9)


def split_seconds(root: Path, overrides: list[str]) -> float:
    """Wall time of ``motiontrack track --detections-folder`` over ``root`` in a new process."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "motiontrack", "-q", "track", "--detections-folder", str(root),
               "-o", str(Path(tmp) / "data"), *[a for o in overrides for a in ("--set", o)]]
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each tracker (best time)")
    ap.add_argument("--set", dest="overrides", action="append", default=[],
                    metavar="STAGE.PARAM=VALUE", help="settings of motiontrack's row")
    ap.add_argument("--pets", action="store_true",
                    help="run benchmarks/detections_pets.py (the remaining options go to it)")
    args, rest = ap.parse_known_args()
    if args.pets:
        script = Path(__file__).with_name("detections_pets.py")
        sys.exit(subprocess.run([sys.executable, str(script), "--data", str(args.data), *rest,
                                 *[a for o in args.overrides for a in ("--set", o)]]).returncode)
    if rest:
        ap.error(f"unrecognized arguments: {' '.join(rest)}")
    root = args.data / "mot15-dev"
    seqs = [Sequence(root, name) for name in SEQUENCES]
    rows = [("motiontrack", ours(args.overrides)),
            ("motiontrack SORT settings", ours(list(SORT_SETTINGS), one_frame_max_lost=True)),
            *peers()]
    print(f"MOT15 {', '.join(SEQUENCES)} ({sum(s.length for s in seqs)} frames), SORT's "
          f"Faster R-CNN detections; COMBINED scores")
    print(f"{'tracker':28s}" + "".join(f"{k:>8}" for k in KEYS) + f"{'fps':>9}")
    for label, runner in rows:
        combined, fps = score(runner, seqs, args.repeat)
        print(f"{label:28s}" + "".join(f"{combined[k]:8.3f}" if k != "IDSW" else
                                       f"{combined[k]:8.0f}" for k in KEYS) + f"{fps:9.0f}")
    print(f"split s: motiontrack track --detections-folder, process start to exit: "
          f"{split_seconds(root, args.overrides):.2f}")


if __name__ == "__main__":
    main()
